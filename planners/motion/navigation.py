"""Navigation of the holonomic base over the floor plan's 2D occupancy grid.

Base poses are chosen in front of a furniture's access side (as the layout validator does, from
`homer_sim.home.validate`), centred on the target and free of walls, furniture, open doors and objects standing on
the floor (`obstacles`). Paths are A* on the grid inflated by the robot's radius, around the same obstacles; the
base follows them with the arm tucked, through `Controller`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from homer_sim.errors import HomerError
from homer_sim.home.catalog import CATALOG
from homer_sim.home.floorplan import find_path, floor_plan, inflate, path_length
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

    def path_to(self, goal: tuple[float, float, float], reach: float = 0.0) -> list[tuple[float, float]]:
        """Waypoints (x, y) in m from the base's current position to `goal`, keeping `reach` m (the base, or a
        carried object held out in front, whichever sticks out further) from open doors and drawers, and the base
        clear of objects standing on the floor and of `others`."""
        start = tuple(self.controller.q()[:2])
        reach, base = max(reach, self.radius), self.radius + CLEARANCE
        still = self._grid([(r, reach) for r in self.open_part_rects()]
                           + [(r, base) for r in self.floor_object_rects()])
        others = self._grid([(r, base) for r in self.others()])
        path = find_path(self.blocked, self.plan, start, goal[:2], still | others)
        if path is None:
            blocked = others.any() and find_path(self.blocked, self.plan, start, goal[:2], still) is not None
            raise self._failure(f"no path from {np.round(start, 2).tolist()} to {np.round(goal[:2], 2).tolist()}",
                                blocked)
        return path

    def _grid(self, grown_by: list[tuple[tuple[float, float, float, float], float]]) -> np.ndarray:
        """The grid cells (shape of `blocked`) of world rectangles (x0, y0, x1, y1, m) each grown by its m."""
        cells = np.zeros_like(self.blocked)
        for rect, grow in grown_by:
            i0, j0 = self.plan.cell(rect[0] - grow, rect[1] - grow)
            i1, j1 = self.plan.cell(rect[2] + grow, rect[3] + grow)
            cells[max(i0, 0) : i1 + 1, max(j0, 0) : j1 + 1] = True
        return cells

    def drive_to(self, goal: tuple[float, float, float], tuck: np.ndarray, reach: float = 0.0,
                 speed: float = SPEED_FRACTION, ramp: float | None = None) -> float:
        """Drive the base to `goal` (x m, y m, yaw rad) with the torso and arm at `tuck` (shape (13,)), keeping
        `reach` m from open doors (see `path_to`), every joint's peak speed at `speed` of its limit (cruising with
        `ramp`, see `Controller.move_through`); returns the path length in m."""
        path = self.path_to(goal, reach)
        keep = path[1:-1][::WAYPOINT_STRIDE] + [path[-1]]
        q0 = self.controller.target.copy()
        yaw0 = q0[2]
        dyaw = (goal[2] - yaw0 + math.pi) % (2 * math.pi) - math.pi
        waypoints = []
        for k, (x, y) in enumerate(keep, start=1):
            q = tuck.copy()
            q[:3] = (x, y, yaw0 + dyaw * min(1.0, 2.0 * k / len(keep)))  # turn during the first half
            waypoints.append(q)
        if np.max(np.abs(self.controller.target[3:11] - tuck[3:11])) > 1e-3:  # tuck first, on the spot
            q = tuck.copy()
            q[:3] = q0[:3]
            self.controller.move_through([q], speed=speed, ramp=ramp)
        self.controller.move_through(waypoints, speed=speed, ramp=ramp)
        self.controller.settle(0.005, max_seconds=2.0)
        return path_length(path)


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
            poses.sort(key=lambda p: float(np.linalg.norm(np.array(p[:2]) - previous_xy)) + 0.2 * abs(
                (p[2] - heading + math.pi) % (2 * math.pi) - math.pi))
        ordered += poses
    return ordered


def base_z(layout, node: str) -> float:
    """Height in m of the base of furniture `node` (0 for furniture on the floor)."""
    return base_height(layout, layout.furniture_by_name()[node])
