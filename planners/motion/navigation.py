"""Navigation of the holonomic base over the floor plan's 2D occupancy grid.

Base poses are chosen in front of a furniture's access side (as the layout validator does, from
`homer_sim.home.validate`), centred on the target and free of walls, furniture, open doors and objects standing on
the floor (`obstacles`). Paths are A* on the grid inflated by the robot's radius, around the same obstacles; the
base follows them with the arm tucked, through `Controller`.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable

import numpy as np

from homer_sim.errors import HomerError
from homer_sim.home.catalog import CATALOG
from homer_sim.home.floorplan import find_path, floor_plan, inflate, nearest_free, path_length
from homer_sim.home.furniture import local_to_world
from homer_sim.home.placement import base_height
from homer_sim.home.validate import access_sides
from homer_sim.robot_spec import ROBOT, RobotSpec
from planners.motion.control import SPEED_FRACTION, Controller

STAND_DISTANCES = np.arange(0.34, 0.81, 0.02)  # m from the furniture's front face to the base centre
STAND_OFFSETS = np.array([0.0, 0.05, -0.05, 0.1, -0.1, 0.15, -0.15, 0.2, -0.2, 0.3, -0.3, 0.4, -0.4, 0.5,
                          -0.5])  # m along the face
NEAR_DISTANCES = (0.5, 0.6, 0.7)  # m from an object on the floor to the base centre
NEAR_TURNS = np.radians(np.arange(0, 360, 30))  # rad around an object on the floor, from the robot's side
WAYPOINT_STRIDE = 4  # keep every 4th grid cell of a path
CLEARANCE = 0.02  # m beyond the robot's footprint radius
BASE_DISTANCES = (0.55, 0.65, 0.45, 0.75, 0.85)  # m from the grip site to the base centre, horizontally
FAR_DISTANCES = (0.95, 1.05)  # m, tried after all of those: the arm reaches 1.1 m with a level hand, 1.0 m pitched
BASE_TURNS = np.radians([0, 15, -15, 30, -30, 45, -45, 60, -60, 75, -75])  # rad off the grasp's approach
ON_THE_FLOOR = 0.05  # m: an object whose underside is lower than this stands on the floor (the base drives into it)
FLOOR_MARGIN = 0.03  # m kept beyond such an object's footprint
NEAR_COST = 4.0  # extra cost per m of path along which a held object sticking out past the base would come within
# its reach of a wall or furniture (`Navigator.path_to`): the carry keeps to the middle of rooms and doorways
CARRY_TURN = 0.6  # m of path over which a base carrying an object turns from its start heading to the way ahead,
# and at the end from the way ahead to its goal heading (`Navigator.drive_to`)
SWEEP_STEP = 0.05  # m between the configurations of a carry checked for touching (`Navigator.drive_to`)
HEADING_STEP = 0.15  # m between the points of a carry whose headings are the way ahead (`_carry_poses`)
TURN_BACK = 0.5  # m a base carrying an object backs up at most to turn on the spot clear of everything
POCKET = 0.5  # m^2 of floor an object set down may cut off from the rest (behind it, in a corner)
TURN_ALONG = 2.0  # m along its way a base carrying an object may keep its heading before it turns to face ahead
IN_THE_WAY = "someone is in the way"  # ends a navigation failure that only `Navigator.others` caused


class NavigationError(HomerError):
    """No free base pose or no path (its message ends with IN_THE_WAY where only `Navigator.others` blocked it)."""


class Navigator:
    """Base poses and base motion in one World for a base of `robot`'s footprint; `controller` drives the robot.

    `others`: a function giving the world rectangles (x0, y0, x1, y1, m) of what moves by itself and must not be
    driven into (a person); whoever runs the robot among them sets it. Nothing by default.
    """

    def __init__(self, world, controller: Controller, robot: RobotSpec = ROBOT) -> None:
        self.world = world
        self.robot = robot
        self.radius = robot.footprint_radius  # m kept free around the base centre
        self.controller = controller
        self.layout = world.layout
        self.furniture = self.layout.furniture_by_name()
        self.plan = floor_plan(self.layout)
        self.blocked = inflate(self.plan, self.radius + CLEARANCE)
        model = world.model
        self.part_geoms = {name: [g for g in range(model.ngeom) if model.geom_bodyid[g] == model.body(name).id]
                           for name in world.articulations}
        self.half_sizes = np.array([CATALOG[o.cls].size for o in self.layout.objects]) / 2  # (n_objects, 3), m
        self.others: Callable[[], list[tuple[float, float, float, float]]] = list
        self.exempt: frozenset[int] = frozenset()  # objects (indices) base poses may stand next to: the one picked
        self._near: dict[int, np.ndarray] = {}  # cells within n grid cells of a wall or furniture, by n

    def obstacles(self) -> list[tuple[float, float, float, float]]:
        """World rectangles (x0, y0, x1, y1) in m the base must keep out of beyond the floor plan: open doors and
        drawers (`open_part_rects`), objects standing on the floor (`floor_object_rects`, but the `exempt` ones: the
        base stands next to what it picks, as it did before they counted) and `others`."""
        return self.open_part_rects() + self.floor_object_rects(self.exempt) + self.others()

    def _free(self, xy: np.ndarray, radius: float, still: list, others: list, blocked: list[bool]) -> bool:
        """Whether the base disk of `radius` m at xy (m) is clear of the floor plan, `still` and `others` (world
        rectangles); where only `others` block it, blocked[0] becomes True."""
        if not self.plan.disk_is_free(float(xy[0]), float(xy[1]), radius, still):
            return False
        if others and not self.plan.disk_is_free(float(xy[0]), float(xy[1]), radius, others):
            blocked[0] = True
            return False
        return True

    @staticmethod
    def _failure(message: str, blocked: bool) -> NavigationError:
        return NavigationError(f"{message}: {IN_THE_WAY}" if blocked else message)

    def floor_object_rects(self, skip: frozenset[int] = frozenset()) -> list[tuple[float, float, float, float]]:
        """World rectangles (x0, y0, x1, y1) in m, FLOOR_MARGIN beyond the footprints of the objects whose underside
        is lower than ON_THE_FLOOR (a bin, a vacuum cleaner, a basket set down on the floor) and stands outside
        the floor plan's furniture (not on a cabinet's bottom shelf): the floor plan holds only furniture, and a
        base driving into them pushes them away. `skip`: object indices left out."""
        data = self.world.data
        rects = []
        for index, (body, half) in enumerate(zip(self.world.object_body_ids, self.half_sizes, strict=True)):
            if index in skip:
                continue
            extent = np.abs(data.xmat[body].reshape(3, 3)) @ half
            centre = data.xpos[body]
            i, j = self.plan.cell(float(centre[0]), float(centre[1]))
            inside = not (0 <= i < self.plan.occupied.shape[0] and 0 <= j < self.plan.occupied.shape[1]) or bool(
                self.plan.occupied[i, j])
            if centre[2] - extent[2] < ON_THE_FLOOR and not inside:
                low, high = centre[:2] - extent[:2] - FLOOR_MARGIN, centre[:2] + extent[:2] + FLOOR_MARGIN
                rects.append((float(low[0]), float(low[1]), float(high[0]), float(high[1])))
        return rects

    def open_part_rects(self) -> list[tuple[float, float, float, float]]:
        """World rectangles (x0, y0, x1, y1) in m covered by doors and drawers that are not closed."""
        data, model = self.world.data, self.world.model
        rects = []
        for name, geoms in self.part_geoms.items():
            if self.world.openness(name) < 0.02:
                continue
            corners = []
            for g in geoms:
                half = np.abs(data.geom_xmat[g].reshape(3, 3)) @ model.geom_size[g]
                corners += [data.geom_xpos[g][:2] - half[:2], data.geom_xpos[g][:2] + half[:2]]
            pts = np.array(corners)
            rects.append((*pts.min(axis=0), *pts.max(axis=0)))
        return rects

    def stand_pose(self, node: str, target_xy: tuple[float, float], reach: float = 0.0) -> tuple[float, float, float]:
        """A free base pose (x m, y m, yaw rad) facing furniture `node` from its front (or, for furniture used
        from all sides, from the side nearest `target_xy`), nearest in front of `target_xy` (m, world), at
        least `reach` m from the furniture (what the robot holds out in front stays clear of it)."""
        if node not in self.furniture:
            raise NavigationError(f"{node!r} is not furniture; known: {', '.join(sorted(self.furniture))}")
        f = self.furniture[node]
        centre = np.array(f.pos)
        front_normal = self.front_normal(node)
        rotation = np.column_stack([front_normal, [-front_normal[1], front_normal[0]]])  # furniture frame -> world
        sides = sorted(access_sides(f), key=lambda side: side[1] - float(
            np.dot(rotation.T @ (np.asarray(target_xy) - centre), side[0])))
        still, others, blocked = self.open_part_rects() + self.floor_object_rects(self.exempt), self.others(), [False]
        for local_normal, half_depth, _ in sides:
            normal = rotation @ local_normal
            tangent = np.array([-normal[1], normal[0]])
            front = centre + normal * half_depth
            along = float(np.dot(np.asarray(target_xy) - front, tangent))
            for offset in STAND_OFFSETS:
                for distance in STAND_DISTANCES[STAND_DISTANCES >= min(reach, STAND_DISTANCES[-1])]:
                    xy = front + tangent * (along + offset) + normal * distance
                    if self._free(xy, self.radius, still, others, blocked):
                        return float(xy[0]), float(xy[1]), math.atan2(-normal[1], -normal[0])
        raise self._failure(f"no free base pose in front of {node} near {np.round(target_xy, 2).tolist()}", blocked[0])

    def stand_near(self, target_xy: tuple[float, float]) -> tuple[float, float, float]:
        """A free base pose (x m, y m, yaw rad) facing `target_xy` (m, world) from NEAR_DISTANCES away, for an
        object on the floor: the side nearest the base's current position first."""
        target = np.asarray(target_xy, dtype=float)
        here = self.controller.q()[:2]
        toward_here = math.atan2(here[1] - target[1], here[0] - target[0])
        still, others, blocked = self.open_part_rects() + self.floor_object_rects(self.exempt), self.others(), [False]
        for turn in NEAR_TURNS:
            for distance in NEAR_DISTANCES:
                angle = toward_here + float(turn)
                xy = target + distance * np.array([math.cos(angle), math.sin(angle)])
                if self._free(xy, self.radius + CLEARANCE, still, others, blocked):
                    return float(xy[0]), float(xy[1]), angle + math.pi
        raise self._failure(f"no free base pose near {np.round(target, 2).tolist()} on the floor", blocked[0])

    def front_normal(self, node: str) -> np.ndarray:
        """Unit horizontal vector (shape (2,)) out of the front of furniture `node`."""
        f = self.furniture[node]
        normal = local_to_world(f, np.array([[1.0, 0.0, 0.0]])) - local_to_world(f, np.zeros((1, 3)))
        return normal[0, :2] / np.linalg.norm(normal[0, :2])

    def path_to(self, goal: tuple[float, float, float], reach: float = 0.0,
                start: tuple[float, float] | None = None) -> list[tuple[float, float]]:
        """Waypoints (x, y) in m from `start` (default: the base's current position) to `goal`, keeping `reach` m
        (the base, or a carried object held out in front, whichever sticks out further) from open doors and
        drawers, and the base clear of objects standing on the floor and of `others`. Where `reach` sticks out past
        the base, the path keeps that far from walls and furniture too where it can (NEAR_COST): a base passing
        them at its own clearance knocked a carried object against a door frame and out of the fingers."""
        start = tuple(self.controller.q()[:2]) if start is None else start
        still, others, near = self._grids(reach)
        path = find_path(self.blocked, self.plan, start, goal[:2], still | others, near, NEAR_COST)
        if path is None:
            blocked = others.any() and find_path(self.blocked, self.plan, start, goal[:2], still) is not None
            raise self._failure(f"no path from {np.round(start, 2).tolist()} to {np.round(goal[:2], 2).tolist()}",
                                blocked)
        return path

    def clear_of(self, points: np.ndarray, distance: float) -> tuple[float, float, float] | None:
        """The base pose (x m, y m, current yaw) nearest along the floor to the base's position, reachable from it
        and at least `distance` m from every one of `points` (shape (k, 2), m, world): where to wait out of the
        way of someone walking through them. The base's own position if it is already; None if no free cell
        reachable from it is."""
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        still, others, _ = self._grids(0.0)
        grid = self.blocked | still | others
        q = self.controller.q()
        xs, ys = self.plan.cell_centers(0, grid.shape[0], 0, grid.shape[1])
        far = np.ones_like(grid)
        for x, y in points:
            far &= np.hypot(xs - x, ys - y) >= distance
        if all(math.hypot(q[0] - x, q[1] - y) >= distance for x, y in points):
            return float(q[0]), float(q[1]), float(q[2])
        start = nearest_free(grid, self.plan, (float(q[0]), float(q[1])))
        if start is None:
            return None
        seen = np.zeros_like(grid)
        seen[start] = True
        frontier = deque([start])
        while frontier:  # breadth first: the nearest such cell in steps over the grid
            cell = frontier.popleft()
            if far[cell]:
                return float(xs[cell]), float(ys[cell]), float(q[2])
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                nxt = (cell[0] + di, cell[1] + dj)
                if 0 <= nxt[0] < grid.shape[0] and 0 <= nxt[1] < grid.shape[1] and not grid[nxt] and not seen[nxt]:
                    seen[nxt] = True
                    frontier.append(nxt)
        return None

    def leaves_way(self, rect: tuple[float, float, float, float]) -> bool:
        """Whether an object on the floor over world rectangle `rect` (x0, y0, x1, y1, m) leaves the floor the base
        reaches from where it stands reachable still, but for pockets of at most POCKET m^2 (behind the object, in
        a corner): a laundry basket set down just inside the bathroom's doorway shut the robot in."""
        still, _, _ = self._grids(0.0)
        grid = self.blocked | still
        start = nearest_free(grid, self.plan, (float(self.controller.q()[0]), float(self.controller.q()[1])))
        if start is None:
            return True
        now = _flood(grid, [start])
        grid = grid | self._grid([(rect, self.radius + CLEARANCE)])
        left = now & ~grid
        if not left.any():
            return False
        if not grid[start]:  # the base stays on its own side: all but pockets must be reachable from there
            return bool((left & ~_flood(grid, [start])).sum() * self.plan.resolution ** 2 <= POCKET)
        lost = left & ~_flood(grid, [tuple(c) for c in np.argwhere(left)[:1]])
        if lost.sum() * self.plan.resolution ** 2 <= POCKET:
            return True
        # the object covers where the base stands, so it may end on either side: what is left must be one piece but
        # for pockets
        return bool((left & ~_flood(grid, [tuple(np.argwhere(lost)[0])])).sum() * self.plan.resolution ** 2 <= POCKET)

    def _grids(self, reach: float) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(still, others, near) grids (shape of `blocked`) of a base whose held object sticks out `reach` m:
        open parts grown by `reach` and floor objects by the base's clearance; `others` by the same; the cells
        closer than `reach` to a wall or furniture (None where `reach` does not stick out past the base)."""
        reach, base = max(reach, self.radius), self.radius + CLEARANCE
        still = self._grid([(r, reach) for r in self.open_part_rects()]
                           + [(r, base) for r in self.floor_object_rects()])
        others = self._grid([(r, base) for r in self.others()])
        near = None
        if reach > base:
            cells = int(np.ceil(reach / self.plan.resolution))
            near = self._near.setdefault(cells, inflate(self.plan, reach))
        return still, others, near

    def _grid(self, grown_by: list[tuple[tuple[float, float, float, float], float]]) -> np.ndarray:
        """The grid cells (shape of `blocked`) of world rectangles (x0, y0, x1, y1, m) each grown by its m."""
        cells = np.zeros_like(self.blocked)
        for rect, grow in grown_by:
            i0, j0 = self.plan.cell(rect[0] - grow, rect[1] - grow)
            i1, j1 = self.plan.cell(rect[2] + grow, rect[3] + grow)
            cells[max(i0, 0) : i1 + 1, max(j0, 0) : j1 + 1] = True
        return cells

    def _clearance(self, cell: tuple[int, int], reach: float) -> float:
        """How far (m, in steps of the grid's resolution, at most `reach`) the grid cell `cell` is from every wall
        and furniture, from the base's own clearance up."""
        clear = self.radius + CLEARANCE
        for radius in np.arange(clear + self.plan.resolution, reach + 1e-9, self.plan.resolution):
            cells = int(np.ceil(radius / self.plan.resolution))
            if self._near.setdefault(cells, inflate(self.plan, float(radius)))[cell]:
                break
            clear = float(radius)
        return clear

    def _turn_spot(self, xy: tuple[float, float], yaw: float, reach: float, grids: tuple,
                   pose_clear: Callable[[float, float, float], bool] | None = None
                   ) -> tuple[tuple[float, float], bool] | None:
        """Where straight behind `xy` (against heading `yaw`, rad; at most TURN_BACK m, the base free all the way
        there) a base whose held object sticks out `reach` m turns best: the nearest point from which it turns on
        the spot touching nothing (True: `reach` from walls, furniture and open doors and drawers), else (False)
        the one furthest from them among those out of the open parts' grown cells (where a path from there starts
        without first snapping to a free cell, which may lie ahead) if any, or None where that is `xy` itself.
        With `pose_clear` (whether the robot and what it holds touch nothing at base pose x, y, yaw), points where
        they touch something come last. `grids`: from `_grids`."""
        still = grids[0]
        parts = self.open_part_rects()
        fixed, moving = parts + self.floor_object_rects(self.exempt), self.others()
        back = np.array([-math.cos(yaw), -math.sin(yaw)])
        best, best_clear = None, (False, False, -1.0)
        for distance in np.arange(0.0, TURN_BACK + 1e-9, self.plan.resolution):
            x, y = np.asarray(xy) + distance * back
            i, j = self.plan.cell(float(x), float(y))
            if not (0 <= i < still.shape[0] and 0 <= j < still.shape[1]) or (
                    distance > 0.0 and not self._free(np.array([x, y]), self.radius, fixed, moving, [False])):
                break  # the base's own footprint, as for a base pose (`stand_pose`)
            clear = min([self._clearance((i, j), reach)]
                        + [math.hypot(max(r[0] - x, 0.0, x - r[2]), max(r[1] - y, 0.0, y - r[3])) for r in parts])
            touching = pose_clear is not None and not pose_clear(float(x), float(y), yaw)
            if clear >= reach - 1e-9 and not touching:
                return (float(x), float(y)), True
            rank = (not touching, not still[i, j], clear)  # out of the open parts' reach next (a path starts there)
            if best is None or rank > best_clear:
                best, best_clear = ((float(x), float(y)), False), rank
        return None if best is None or best[0] == (float(xy[0]), float(xy[1])) else best

    def drive_to(self, goal: tuple[float, float, float], tuck: np.ndarray, reach: float = 0.0,
                 speed: float = SPEED_FRACTION, ramp: float | None = None,
                 clear: Callable[[np.ndarray], bool] | None = None) -> float:
        """Drive the base to `goal` (x m, y m, yaw rad) with the torso and arm at `tuck` (shape (13,)), keeping
        `reach` m from open doors (see `path_to`), every joint's peak speed at `speed` of its limit (cruising with
        `ramp`, see `Controller.move_through`); returns the path length in m. The base turns to the goal heading
        during the first half of the way. Where `reach` sticks out past the base (an object held out in front),
        it may face the way ahead instead, so that the object leads through doorways rather than sticking out
        sideways (`_carry_poses`): it first backs straight out to where it turns best (`_turn_spot`), and at the
        end reaches the goal heading at such a spot straight behind the goal and drives straight in. With `clear`
        (whether a configuration, shape (13,), keeps the arm and the held object clear of the apartment), of
        these two ways and a third (the start heading kept, turned to the goal's over the last CARRY_TURN m) the
        one whose poses, checked every SWEEP_STEP m (or rad at the held object's reach), touch something least
        often is taken (in that order on a tie); without it, facing ahead where the way is longer than 2
        CARRY_TURN."""
        q0 = self.controller.target.copy()
        yaw0 = float(q0[2])
        path = self.path_to(goal, reach)
        keep = path[1:-1][::WAYPOINT_STRIDE] + [path[-1]]
        dyaw = _wrap(goal[2] - yaw0)
        ways = [([(x, y, yaw0 + dyaw * min(1.0, 2.0 * k / len(keep))) for k, (x, y) in enumerate(keep, start=1)],
                 path)]
        if reach > self.radius + CLEARANCE:
            grids = self._grids(reach)
            pose_clear = None
            if clear is not None:
                def pose_clear(x: float, y: float, yaw: float) -> bool:
                    q = tuck.copy()
                    q[:3] = (x, y, yaw)
                    return clear(q)
            first = self._turn_spot(tuple(q0[:2]), yaw0, reach, grids, pose_clear)
            last = self._turn_spot(tuple(goal[:2]), goal[2], reach, grids)
            try:
                ahead = self.path_to(goal if last is None else (*last[0], goal[2]), reach,
                                     start=None if first is None else first[0])
            except NavigationError:
                ahead = []
            if ahead and (clear is not None or path_length(ahead) > 2.0 * CARRY_TURN):
                points = [ahead[0], *ahead[1:-1][::WAYPOINT_STRIDE], ahead[-1]]
                ways.insert(0, (_carry_poses(points, yaw0, goal, first, last),
                                [tuple(q0[:2]), *ahead, tuple(goal[:2])]))
                if clear is not None and first is None:  # or turned on the way, where that touches nothing
                    ways[1:1] = [(poses, ways[0][1]) for poses in _turned_on_the_way(points, yaw0, goal, last)]
        if clear is not None and reach > self.radius + CLEARANCE:  # also: the heading kept, turned at the end
            along = np.cumsum(np.hypot(*np.diff(np.asarray([tuple(q0[:2]), *keep]), axis=0).T))
            ends = np.clip((along - along[-1] + CARRY_TURN) / CARRY_TURN, 0.0, 1.0)
            ways.append(([(x, y, yaw0 + dyaw * float(f)) for (x, y), f in zip(keep, ends, strict=True)], path))
        if clear is not None and len(ways) > 1:
            best = None
            for way in ways:  # the first that touches nothing, else the one that touches least often
                touches = self._touches(q0, tuck, way[0], reach, clear)
                if best is None or touches < best[0]:
                    best = (touches, way)
                if touches == 0:
                    break
            ways = [best[1]]
        poses, path = ways[0]
        waypoints = []
        for pose in poses:
            q = tuck.copy()
            q[:3] = pose
            waypoints.append(q)
        if np.max(np.abs(self.controller.target[3:11] - tuck[3:11])) > 1e-3:  # tuck first, on the spot
            q = tuck.copy()
            q[:3] = q0[:3]
            self.controller.move_through([q], speed=speed, ramp=ramp)
        self.controller.move_through(waypoints, speed=speed, ramp=ramp)
        self.controller.settle(0.005, max_seconds=2.0)
        return path_length(path)

    @staticmethod
    def _touches(q0: np.ndarray, tuck: np.ndarray, poses: list[tuple[float, float, float]], reach: float,
                 clear: Callable[[np.ndarray], bool]) -> int:
        """How many configurations along base `poses` (x m, y m, yaw rad; from q0's, shape (13,)) with the arm at
        `tuck`, every SWEEP_STEP m of the base or of a point `reach` m out as it turns, are not `clear`."""
        touched, previous = 0, np.asarray(q0[:3], dtype=float)
        for pose in poses:
            pose = np.asarray(pose, dtype=float)
            move = max(float(np.hypot(*(pose[:2] - previous[:2]))), abs(float(pose[2] - previous[2])) * reach)
            for s in np.linspace(0.0, 1.0, max(1, int(np.ceil(move / SWEEP_STEP))) + 1)[1:]:
                q = tuck.copy()
                q[:3] = previous + s * (pose - previous)
                touched += not clear(q)
            previous = pose
        return touched


def _flood(grid: np.ndarray, starts: list[tuple[int, int]]) -> np.ndarray:
    """The cells (shape of `grid`) reachable from `starts` over free (False) cells of `grid`, 4-connected."""
    seen = np.zeros_like(grid)
    frontier = deque(starts)
    for cell in starts:
        seen[cell] = True
    while frontier:
        i, j = frontier.popleft()
        for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
            if 0 <= a < grid.shape[0] and 0 <= b < grid.shape[1] and not grid[a, b] and not seen[a, b]:
                seen[a, b] = True
                frontier.append((a, b))
    return seen


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _carry_poses(points: list[tuple[float, float]], yaw0: float, goal: tuple[float, float, float],
                 first: tuple | None, last: tuple | None) -> list[tuple[float, float, float]]:
    """Base poses (x m, y m, yaw rad) along `points` (x, y in m) for a base at heading `yaw0` carrying an object
    held out in front to `goal`: each facing the way ahead (the next point; the last one the way it came).
    With a `first` turn spot (see `Navigator._turn_spot`), points[0] is that point straight behind the base: it
    backs there, then turns on it where it turns touching nothing; else the heading is blended from `yaw0` over
    the first CARRY_TURN m. With a `last` turn spot, points[-1] is that point straight behind the goal: the base
    reaches the goal heading there (turning on it where that touches nothing, else over the last CARRY_TURN m
    before it) and drives straight in; without one, the heading is blended into the goal's over the last
    CARRY_TURN m. Each heading is within pi of the one before (the base turns the short way)."""
    pts = [points[0]]
    for p in points[1:]:  # points closer than HEADING_STEP to the one before give no heading (a grid cell beside)
        if math.dist(p, pts[-1]) >= HEADING_STEP:
            pts.append(p)
    if math.dist(points[-1], pts[-1]) > 1e-6:
        pts[-1 if len(pts) > 1 else len(pts):] = [points[-1]]
    xy = np.asarray(pts, dtype=float)
    steps = np.diff(xy, axis=0)
    ahead = [math.atan2(d[1], d[0]) for d in steps] or [yaw0]
    ahead.append(ahead[-1])
    done = np.concatenate([[0.0], np.cumsum(np.hypot(steps[:, 0], steps[:, 1]))])
    total = float(done[-1])
    headings = []
    for heading, along in zip(ahead, done, strict=True):
        yaw = heading
        if not (first and first[1]) and along < CARRY_TURN:
            yaw = yaw0 + _wrap(yaw - yaw0) * along / CARRY_TURN
        if not (last and last[1]) and total - along < CARRY_TURN:  # after the start's blend: the goal heading
            # is reached on a way shorter than CARRY_TURN too (blended back towards the start's, a base stopped
            # 6 degrees off the heading a lowering was planned at, and the vegetable lowered pushed a loaf 5.8 cm)
            yaw = goal[2] + _wrap(yaw - goal[2]) * (total - along) / CARRY_TURN
        headings.append(yaw)
    poses = [(*pts[0], yaw0)] if first else []  # backed out (then turned on the spot where that is clear)
    poses += [(*p, yaw) for p, yaw in zip(pts, headings, strict=True)][0 if first else 1:]
    if last:
        poses += [(*pts[-1], goal[2]), (goal[0], goal[1], goal[2])]
    unwrapped, previous = [], yaw0
    for x, y, yaw in poses:
        previous = previous + _wrap(yaw - previous)
        unwrapped.append((float(x), float(y), previous))
    return unwrapped


def _turned_on_the_way(points: list[tuple[float, float]], yaw0: float, goal: tuple[float, float, float],
                       last: tuple | None) -> list[list[tuple[float, float, float]]]:
    """Base poses (x m, y m, yaw rad) along `points` (as for `_carry_poses`) for a base at heading `yaw0` that keeps
    its heading to one of the points within TURN_ALONG m along the way, turns on the spot there to face the way
    ahead, and goes on as `_carry_poses` from there: one list per such point, nearest first. A base with an object
    held out in front that turned where it started swept it into the bed it had picked it beside, and one that kept
    its heading carried a laundry basket sideways into a door frame."""
    ways, along = [], 0.0
    for k in range(1, len(points) - 1):
        along += math.dist(points[k - 1], points[k])
        if along > TURN_ALONG:
            break
        kept = [(float(x), float(y), yaw0) for x, y in points[1:k + 1]]
        ways.append(kept + _carry_poses(points[k:], yaw0, goal, (points[k], True), last)[1:])
    return ways


def base_candidates(grip_pos: np.ndarray, grip_rot: np.ndarray, previous_xy: np.ndarray | None,
                    reach_in: np.ndarray | None = None) -> list[tuple[float, float, float]]:
    """Base poses (x m, y m, yaw rad) behind a grip pose, facing it: nearest `previous_xy` first, or, without
    one, straight behind the grasp first (BASE_TURNS, then BASE_DISTANCES order); then, in the same order, those
    FAR_DISTANCES away, for where no nearer one is free or reaches. "Behind" is against the grip x's horizontal
    part, or against `reach_in` (a horizontal direction, shape (2,) or (3,)) where given."""
    approach = grip_rot[:2, 0] if reach_in is None else np.asarray(reach_in, dtype=float)[:2]
    norm = float(np.linalg.norm(approach))
    if norm > 0.3 or previous_xy is None:
        heading = math.atan2(approach[1], approach[0])
    else:
        heading = math.atan2(grip_pos[1] - previous_xy[1], grip_pos[0] - previous_xy[0])
    ordered = []
    for distances in (BASE_DISTANCES, FAR_DISTANCES):
        poses = []
        for turn in BASE_TURNS:
            for distance in distances:
                yaw = heading + float(turn)
                xy = grip_pos[:2] - distance * np.array([math.cos(yaw), math.sin(yaw)])
                poses.append((float(xy[0]), float(xy[1]), yaw))
        if previous_xy is not None:
            poses.sort(key=lambda p: float(np.linalg.norm(np.array(p[:2]) - previous_xy))
                       + 0.2 * abs(_wrap(p[2] - heading)))
        ordered += poses
    return ordered


def base_z(layout, node: str) -> float:
    """Height in m of the base of furniture `node` (0 for furniture on the floor)."""
    return base_height(layout, layout.furniture_by_name()[node])
