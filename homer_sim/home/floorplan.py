"""A 2D occupancy grid of the floor plan: walls, furniture footprints and the space outside the rooms.

Shared by the layout validator (robot envelope), and later the avatar's and the robot's navigation.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from homer_sim.home.furniture import footprint
from homer_sim.home.layout import Layout

RESOLUTION = 0.05  # m per cell


@dataclass(frozen=True)
class FloorPlan:
    """occupied[i, j] is True where cell (x index i, y index j) is blocked.

    origin: world (x, y) in m of the lower corner of cell (0, 0); resolution: m per cell.
    """

    occupied: np.ndarray
    origin: tuple[float, float]
    resolution: float = RESOLUTION

    def cell(self, x: float, y: float) -> tuple[int, int]:
        return int((x - self.origin[0]) / self.resolution), int((y - self.origin[1]) / self.resolution)

    def cell_centers(self, i0: int, i1: int, j0: int, j1: int) -> tuple[np.ndarray, np.ndarray]:
        xs = self.origin[0] + (np.arange(i0, i1) + 0.5) * self.resolution
        ys = self.origin[1] + (np.arange(j0, j1) + 0.5) * self.resolution
        return np.meshgrid(xs, ys, indexing="ij")

    def disk_cells(self, x: float, y: float, radius: float) -> np.ndarray:
        """A grid of the plan's shape, True at the cells whose centre lies within `radius` m of (x, y)."""
        xs, ys = self.cell_centers(0, self.occupied.shape[0], 0, self.occupied.shape[1])
        return np.hypot(xs - x, ys - y) < radius

    def disk_is_free(self, x: float, y: float, radius: float, extra: list[tuple] = (),
                     blocked: np.ndarray | None = None) -> bool:
        """True if no blocked cell (of the plan, or of `blocked`, a grid of the plan's shape: a robot standing there)
        nor `extra` rectangle (x0, y0, x1, y1) has its centre within `radius` m."""
        for x0, y0, x1, y1 in extra:
            dx = max(x0 - x, 0.0, x - x1)
            dy = max(y0 - y, 0.0, y - y1)
            if dx * dx + dy * dy < radius * radius:
                return False
        i0, j0 = self.cell(x - radius, y - radius)
        i1, j1 = self.cell(x + radius, y + radius)
        if i0 < 0 or j0 < 0 or i1 >= self.occupied.shape[0] or j1 >= self.occupied.shape[1]:
            return False
        cx, cy = self.cell_centers(i0, i1 + 1, j0, j1 + 1)
        inside = (cx - x) ** 2 + (cy - y) ** 2 <= radius * radius
        grid = self.occupied if blocked is None else self.occupied | blocked
        return not np.any(grid[i0 : i1 + 1, j0 : j1 + 1] & inside)

    def rect_is_free(self, rect: tuple[float, float, float, float], shrink: float = 0.02) -> bool:
        """True if no blocked cell centre lies inside the world rectangle shrunk by `shrink` m on each side."""
        x0, y0, x1, y1 = rect[0] + shrink, rect[1] + shrink, rect[2] - shrink, rect[3] - shrink
        i0, j0 = self.cell(x0, y0)
        i1, j1 = self.cell(x1, y1)
        i0, j0 = max(i0, 0), max(j0, 0)
        cx, cy = self.cell_centers(i0, i1 + 1, j0, j1 + 1)
        inside = (cx >= x0) & (cx <= x1) & (cy >= y0) & (cy <= y1)
        return not np.any(self.occupied[i0 : i1 + 1, j0 : j1 + 1] & inside)


def _fill(occupied: np.ndarray, origin, res: float, rect, value: bool) -> None:
    """Set every cell whose centre lies in the world rectangle (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = rect
    i0 = max(int(np.ceil((x0 - origin[0]) / res - 0.5)), 0)
    j0 = max(int(np.ceil((y0 - origin[1]) / res - 0.5)), 0)
    i1 = int(np.floor((x1 - origin[0]) / res - 0.5))
    j1 = int(np.floor((y1 - origin[1]) / res - 0.5))
    occupied[i0 : i1 + 1, j0 : j1 + 1] = value


def wall_segments(layout: Layout) -> list[tuple[float, float, float, float]]:
    """World rectangles (x0, y0, x1, y1) of the solid parts of all walls (doorways cut out)."""
    half = layout.wall_thickness / 2
    rects = []
    for wall in layout.walls:
        (ax, ay), (bx, by) = wall.start, wall.end
        ux, uy = (bx - ax) / wall.length, (by - ay) / wall.length
        cuts = sorted(wall.doorways)
        spans, at = [], 0.0
        for start, end in cuts:
            spans.append((at, start))
            at = end
        spans.append((at, wall.length))
        for s0, s1 in spans:
            if s1 - s0 <= 1e-9:
                continue
            p0 = (ax + ux * s0, ay + uy * s0)
            p1 = (ax + ux * s1, ay + uy * s1)
            ext0 = half if s0 == 0 else 0.0
            ext1 = half if s1 == wall.length else 0.0
            x0 = min(p0[0] - ux * ext0, p1[0] + ux * ext1) - abs(uy) * half
            x1 = max(p0[0] - ux * ext0, p1[0] + ux * ext1) + abs(uy) * half
            y0 = min(p0[1] - uy * ext0, p1[1] + uy * ext1) - abs(ux) * half
            y1 = max(p0[1] - uy * ext0, p1[1] + uy * ext1) + abs(ux) * half
            rects.append((x0, y0, x1, y1))
    return rects


def floor_plan(layout: Layout, resolution: float = RESOLUTION, skip: tuple[str, ...] = ()) -> FloorPlan:
    """The occupancy grid of `layout`: everything is blocked except room floors not covered by a wall or by
    furniture standing on the floor (decor such as mats is walkable). `skip` leaves named furniture out."""
    xs = [r.rect[0] for r in layout.rooms] + [r.rect[2] for r in layout.rooms]
    ys = [r.rect[1] for r in layout.rooms] + [r.rect[3] for r in layout.rooms]
    origin = (min(xs) - 0.5, min(ys) - 0.5)
    shape = (int(np.ceil((max(xs) - origin[0] + 0.5) / resolution)),
             int(np.ceil((max(ys) - origin[1] + 0.5) / resolution)))
    occupied = np.ones(shape, dtype=bool)
    for room in layout.rooms:
        _fill(occupied, origin, resolution, room.rect, False)
    for rect in wall_segments(layout):
        _fill(occupied, origin, resolution, rect, True)
    for f in layout.furniture:
        if f.on is None and f.category != "decor" and f.name not in skip:
            _fill(occupied, origin, resolution, footprint(f), True)
    return FloorPlan(occupied, origin, resolution)


def inflate(plan: FloorPlan, radius: float) -> np.ndarray:
    """Occupancy grown by `radius` m: True where a disk of that radius centred on the cell would touch a wall."""
    r = int(np.ceil(radius / plan.resolution))
    blocked = plan.occupied.copy()
    offsets = [(di, dj) for di in range(-r, r + 1) for dj in range(-r, r + 1) if di * di + dj * dj <= r * r]
    padded = np.pad(plan.occupied, r, constant_values=True)
    n, m = plan.occupied.shape
    for di, dj in offsets:
        blocked |= padded[r + di : r + di + n, r + dj : r + dj + m]
    return blocked


def find_path(blocked: np.ndarray, plan: FloorPlan, start: tuple[float, float], goal: tuple[float, float],
              extra_blocked: np.ndarray | None = None, penalty: np.ndarray | None = None,
              penalty_cost: float = 0.0) -> list[tuple[float, float]] | None:
    """A collision-free path (world (x, y) waypoints, m) from start to goal over free cells of `blocked`
    (8-connected A*), or None. Start and goal snap to the nearest free cell within 0.5 m. Where `penalty` (a
    boolean grid of the same shape) is given, a step onto one of its cells costs 1 + `penalty_cost` times its
    length: the path keeps out of them where a detour is shorter than that."""
    grid = blocked if extra_blocked is None else blocked | extra_blocked
    s, g = nearest_free(grid, plan, start), nearest_free(grid, plan, goal)
    if s is None or g is None:
        return None
    cells = _astar(grid, s, g, penalty, penalty_cost)
    if cells is None:
        return None
    path = [(plan.origin[0] + (i + 0.5) * plan.resolution, plan.origin[1] + (j + 0.5) * plan.resolution)
            for i, j in cells]
    return [start] + path[1:-1] + [goal] if len(path) > 1 else [start, goal]


def nearest_free(grid: np.ndarray, plan: FloorPlan, xy: tuple[float, float]) -> tuple[int, int] | None:
    """The free cell nearest to the cell of `xy` within 0.5 m (squared cell distance; on a tie, the first in
    (i, j) order), or None."""
    i, j = plan.cell(*xy)
    reach = int(np.ceil(0.5 / plan.resolution))
    i0, j0 = max(i - reach, 0), max(j - reach, 0)
    i1, j1 = min(i + reach + 1, grid.shape[0]), min(j + reach + 1, grid.shape[1])
    if i0 >= i1 or j0 >= j1:
        return None
    di, dj = np.arange(i0, i1)[:, None] - i, np.arange(j0, j1)[None, :] - j
    d = np.where(grid[i0:i1, j0:j1], np.iinfo(np.int64).max, di * di + dj * dj)
    k = int(np.argmin(d))  # the first minimum in row-major order, as a loop over (di, dj) keeps it
    a, b = divmod(k, j1 - j0)
    return None if grid[i0 + a, j0 + b] else (i0 + a, j0 + b)


_DIAGONAL = 2 ** 0.5
_FREE_CACHE: dict[tuple, list[bool]] = {}  # grid shape and bytes -> its padded, flattened free cells
_FREE_CACHE_SIZE = 8


def _padded_free(grid: np.ndarray) -> list[bool]:
    """The free cells of `grid` padded with one blocked cell on every side, flattened into a list (fast to index);
    kept for the last few grids by content, so a grid changed in place is never served stale."""
    key = (grid.shape, grid.tobytes())
    free = _FREE_CACHE.pop(key, None)
    if free is None:
        free = (~np.pad(grid, 1, constant_values=True)).ravel().tolist()
        while len(_FREE_CACHE) >= _FREE_CACHE_SIZE:
            del _FREE_CACHE[next(iter(_FREE_CACHE))]  # the least recently used
    _FREE_CACHE[key] = free
    return free


def _astar(grid: np.ndarray, start: tuple[int, int], goal: tuple[int, int], penalty: np.ndarray | None = None,
           penalty_cost: float = 0.0) -> list[tuple[int, int]] | None:
    """8-connected A* with the octile distance, no corner cutting. Cells are flat indices into the grid padded
    with one blocked cell on every side (so no bounds checks); a flat index orders cells as their (i, j) tuples
    do, so ties on the heap break as they would on cell tuples."""
    width = grid.shape[1] + 2
    free = _padded_free(grid)
    pen = np.pad(penalty, 1).ravel().tolist() if penalty is not None else None
    penalized = 1.0 + penalty_cost
    # (offset, step length, offsets of the two cells a diagonal step must not cut; the step's own if straight)
    moves = ((width, 1.0, width, width), (-width, 1.0, -width, -width), (1, 1.0, 1, 1), (-1, 1.0, -1, -1),
             (width + 1, _DIAGONAL, width, 1), (width - 1, _DIAGONAL, width, -1),
             (-width + 1, _DIAGONAL, -width, 1), (-width - 1, _DIAGONAL, -width, -1))
    gi, gj = goal[0] + 1, goal[1] + 1
    source = (start[0] + 1) * width + start[1] + 1
    target = gi * width + gj
    diagonal_extra = _DIAGONAL - 1

    def heuristic(c: int) -> float:  # octile distance to the goal
        dx, dy = abs(c // width - gi), abs(c % width - gj)
        return max(dx, dy) + diagonal_extra * min(dx, dy)

    inf = float("inf")
    cost = [inf] * len(free)
    cost[source] = 0.0
    came: dict[int, int] = {}
    frontier = [(heuristic(source), source, 0.0)]  # (f, cell, cost when pushed)
    pop, push = heapq.heappop, heapq.heappush
    while frontier:
        _, cell, pushed = pop(frontier)
        if cell == target:
            path = [cell]
            while cell in came:
                cell = came[cell]
                path.append(cell)
            return [(c // width - 1, c % width - 1) for c in reversed(path)]
        here = cost[cell]
        if pushed > here:
            continue  # stale: the entry at the present cost came off the heap first, expanding again changes nothing
        for offset, step, a, b in moves:
            nxt = cell + offset
            if not free[nxt] or not free[cell + a] or not free[cell + b]:
                continue
            new = here + (step * penalized if pen is not None and pen[nxt] else step)
            if new < cost[nxt]:
                cost[nxt] = new
                came[nxt] = cell
                dx, dy = abs(nxt // width - gi), abs(nxt % width - gj)  # heuristic(nxt), inlined: the hot loop
                push(frontier, (new + ((dx if dx > dy else dy) + diagonal_extra * (dy if dx > dy else dx)), nxt, new))
    return None


def path_length(path: list[tuple[float, float]]) -> float:
    """Length of a waypoint path in m."""
    return float(sum(np.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(path, path[1:], strict=False)))
