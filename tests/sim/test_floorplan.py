"""The grid path finder is a faster form of a plain A*: on random grids it returns exactly the reference's paths.

The reference below is the path finder as it was before it was made faster (tuple cells, a dict of costs, numpy
indexing). Exact equality matters: paths decide where the person walks, so any difference would change datasets.
"""

from __future__ import annotations

import heapq

import numpy as np
import pytest

from homer_sim.home import floorplan
from homer_sim.home.floorplan import FloorPlan, find_path, inflate


def _reference_astar(grid, start, goal, penalty=None, penalty_cost=0.0):
    diagonal = 2 ** 0.5
    moves = [(1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0),
             (1, 1, diagonal), (1, -1, diagonal), (-1, 1, diagonal), (-1, -1, diagonal)]

    def heuristic(c):
        dx, dy = abs(c[0] - goal[0]), abs(c[1] - goal[1])
        return max(dx, dy) + (diagonal - 1) * min(dx, dy)

    came, cost = {}, {start: 0.0}
    frontier = [(heuristic(start), start)]
    n, m = grid.shape
    while frontier:
        _, cell = heapq.heappop(frontier)
        if cell == goal:
            path = [cell]
            while cell in came:
                cell = came[cell]
                path.append(cell)
            return path[::-1]
        for di, dj, step in moves:
            nxt = (cell[0] + di, cell[1] + dj)
            if not (0 <= nxt[0] < n and 0 <= nxt[1] < m) or grid[nxt]:
                continue
            if di and dj and (grid[cell[0] + di, cell[1]] or grid[cell[0], cell[1] + dj]):
                continue
            new = cost[cell] + (step * (1.0 + penalty_cost) if penalty is not None and penalty[nxt] else step)
            if new < cost.get(nxt, np.inf):
                cost[nxt], came[nxt] = new, cell
                heapq.heappush(frontier, (new + heuristic(nxt), nxt))
    return None


def _reference_nearest_free(grid, plan, xy):
    i, j = plan.cell(*xy)
    reach = int(np.ceil(0.5 / plan.resolution))
    best, best_d = None, None
    for di in range(-reach, reach + 1):
        for dj in range(-reach, reach + 1):
            a, b = i + di, j + dj
            if 0 <= a < grid.shape[0] and 0 <= b < grid.shape[1] and not grid[a, b]:
                d = di * di + dj * dj
                if best_d is None or d < best_d:
                    best, best_d = (a, b), d
    return best


def _random_grid(rng: np.random.Generator, shape: tuple[int, int], density: float) -> np.ndarray:
    """Blocked rectangles and scattered cells: open floors, corridors and dead ends with many equal-cost ties."""
    grid = rng.random(shape) < density / 4
    for _ in range(int(density * 40)):
        i, j = rng.integers(0, shape[0]), rng.integers(0, shape[1])
        grid[i : i + rng.integers(1, 12), j : j + rng.integers(1, 4)] = True
    return grid


@pytest.mark.parametrize("seed", range(12))
def test_astar_returns_the_reference_paths_on_random_grids(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(8, 60)), int(rng.integers(8, 60)))
    grid = _random_grid(rng, shape, float(rng.uniform(0.1, 0.6)))
    penalty = rng.random(shape) < 0.3 if seed % 3 == 0 else None
    found = 0
    for _ in range(25):
        free = np.argwhere(~grid)
        s, g = (tuple(int(v) for v in free[rng.integers(len(free))]) for _ in range(2))
        expected = _reference_astar(grid, s, g, penalty, 4.0)
        assert floorplan._astar(grid, s, g, penalty, 4.0) == expected
        found += expected is not None
    assert found > 0  # some goals reachable, so the comparison covers paths and not only None


def test_find_path_matches_the_reference_on_the_apartment(apartment) -> None:
    """The person's real grid: the start and goal snap and the A* both give the reference's cells."""
    plan = floorplan.floor_plan(apartment.layout)
    blocked = inflate(plan, 0.25)
    rng = np.random.default_rng(0)
    free = np.argwhere(~blocked)
    for _ in range(15):
        xy = [tuple(float(v) for v in plan.origin + (free[rng.integers(len(free))] + rng.random(2)) * plan.resolution)
              for _ in range(2)]
        xy = [(x + rng.normal(0, 0.2), y + rng.normal(0, 0.2)) for x, y in xy]  # off free cells, to snap
        cells = [_reference_nearest_free(blocked, plan, p) for p in xy]
        assert [floorplan.nearest_free(blocked, plan, p) for p in xy] == cells
        path = find_path(blocked, plan, xy[0], xy[1])
        expected = _reference_astar(blocked, *cells)
        if expected is None:
            assert path is None
            continue
        centres = [(plan.origin[0] + (i + 0.5) * plan.resolution, plan.origin[1] + (j + 0.5) * plan.resolution)
                   for i, j in expected]
        assert path == ([xy[0]] + centres[1:-1] + [xy[1]] if len(centres) > 1 else [xy[0], xy[1]])


def test_nearest_free_at_the_grid_edge_and_outside() -> None:
    grid = np.ones((12, 9), dtype=bool)
    grid[0, 8] = grid[11, 0] = grid[5, 4] = False
    plan = FloorPlan(grid, (0.0, 0.0), 0.05)
    for xy in [(0.0, 0.4), (0.55, 0.0), (0.3, 0.2), (-0.3, 0.1), (0.1, -0.2), (5.0, 5.0), (-5.0, 0.2)]:
        assert floorplan.nearest_free(grid, plan, xy) == _reference_nearest_free(grid, plan, xy)


def test_a_grid_changed_in_place_is_searched_afresh() -> None:
    """The flattened free cells are cached by the grid's content, so blocking a door in place reroutes the path
    (or ends it) rather than reusing the old grid's cells."""
    grid = np.zeros((20, 20), dtype=bool)
    grid[10, :] = True
    grid[10, 15] = False  # a doorway
    before = floorplan._astar(grid, (2, 2), (18, 2))
    assert before is not None and (10, 15) in before
    grid[10, 15] = True  # the door closes
    assert floorplan._astar(grid, (2, 2), (18, 2)) is None
    grid[10, 4] = False  # another opens
    after = floorplan._astar(grid, (2, 2), (18, 2))
    assert after == _reference_astar(grid, (2, 2), (18, 2)) and (10, 4) in after


def test_astar_from_a_blocked_start_steps_off_it_as_the_reference_does() -> None:
    grid = np.zeros((6, 6), dtype=bool)
    grid[2, 2] = True
    assert floorplan._astar(grid, (2, 2), (5, 5)) == _reference_astar(grid, (2, 2), (5, 5))
