"""The layout validator: consistency of names and places, and the robot's envelope designed in.

Every error is a LayoutError naming the node. The robot (its numbers are a `RobotSpec`) needs
doorways of at least its `min_doorway` (0.9 m), places within its `place_heights` (0.05 to 1.2 m), each with a free
base pose within its `reach` in front of it, and door swings and drawer travel clear of other furniture.
"""

from __future__ import annotations

import math

import numpy as np

from homer_sim.errors import LayoutError
from homer_sim.graph import CATEGORIES, INSIDE, ON
from homer_sim.home.catalog import CATALOG
from homer_sim.home.floorplan import FloorPlan, floor_plan
from homer_sim.home.furniture import KINDS, Furniture, Part, Place, footprint, furniture_geometry, local_to_world
from homer_sim.home.layout import FACING_YAW, Layout
from homer_sim.home.placement import base_height, place_world, start_poses
from homer_sim.robot_spec import ROBOT, RobotSpec

BASE_DISTANCES = np.arange(0.35, 1.21, 0.05)  # m from the access edge to the base centre
BASE_OFFSETS = np.arange(-0.6, 0.61, 0.1)  # m along the access edge
FRONT_DEPTH = 0.5  # m in front of furniture where the robot's arm and what it holds pass to put things on it
BLOCKED_COVER = 0.5  # share of a front's width an open door or drawer must cover to stand in its way


def validate_layout(layout: Layout, robot: RobotSpec = ROBOT) -> None:
    """Raise LayoutError on the first problem found for `robot`; return None for a sound layout."""
    _check_names(layout)
    _check_walls(layout, robot)
    _check_furniture(layout)
    _check_objects(layout)
    start_poses(layout)  # every object fits on its place
    plan = floor_plan(layout)
    for f in layout.furniture:
        _check_swings(layout, plan, f)
        _check_places(layout, plan, f, robot)


def _check_names(layout: Layout) -> None:
    seen: set[str] = set()
    for name in layout.node_names():
        if not name:
            raise LayoutError("a node has an empty name")
        if name in seen:
            raise LayoutError(f"{name}: duplicate node name")
        seen.add(name)


def _check_walls(layout: Layout, robot: RobotSpec) -> None:
    for wall in layout.walls:
        (ax, ay), (bx, by) = wall.start, wall.end
        if ax != bx and ay != by:
            raise LayoutError(f"wall {wall.name or wall.start}: walls must be axis-aligned")
        for start, end in wall.doorways:
            if end - start < robot.min_doorway - 1e-9:
                raise LayoutError(f"wall {wall.name}: doorway at {start:.2f}-{end:.2f} m is {end - start:.2f} m "
                                  f"wide, narrower than the robot's {robot.min_doorway} m")
            if start < 0 or end > wall.length:
                raise LayoutError(f"wall {wall.name}: doorway {start}-{end} m lies beyond the wall")


def _check_furniture(layout: Layout) -> None:
    rooms = {r.name: r for r in layout.rooms}
    furniture = layout.furniture_by_name()
    for f in layout.furniture:
        if f.room not in rooms:
            raise LayoutError(f"{f.name}: unknown room {f.room!r}; known: {', '.join(rooms)}")
        if f.kind not in KINDS:
            raise LayoutError(f"{f.name}: unknown kind {f.kind!r}; known: {', '.join(sorted(KINDS))}")
        if f.facing not in FACING_YAW:
            raise LayoutError(f"{f.name}: facing must be one of {', '.join(FACING_YAW)}, not {f.facing!r}")
        if f.category not in ("furniture", "appliance", "decor"):
            raise LayoutError(f"{f.name}: category {f.category!r} is not furniture, appliance or decor")
        if f.on is not None and f.on not in furniture:
            raise LayoutError(f"{f.name}: stands on unknown furniture {f.on!r}")
        x0, y0, x1, y1 = footprint(f)
        rx0, ry0, rx1, ry1 = rooms[f.room].rect
        if x0 < rx0 - 1e-6 or y0 < ry0 - 1e-6 or x1 > rx1 + 1e-6 or y1 > ry1 + 1e-6:
            raise LayoutError(f"{f.name}: footprint ({x0:.2f}, {y0:.2f})-({x1:.2f}, {y1:.2f}) leaves room {f.room}")


def _check_objects(layout: Layout) -> None:
    rooms = set(layout.room_names())
    furniture = layout.furniture_by_name()
    objects = {o.name: o for o in layout.objects}
    for o in layout.objects:
        if o.cls not in CATALOG:
            raise LayoutError(f"{o.name}: unknown object class {o.cls!r}")
        if CATALOG[o.cls].category not in CATEGORIES:
            raise LayoutError(f"{o.name}: bad category {CATALOG[o.cls].category!r}")
        if o.relation not in (ON, INSIDE):
            raise LayoutError(f"{o.name}: relation must be ON or INSIDE")
        if o.parent in rooms:
            if o.relation != INSIDE:
                raise LayoutError(f"{o.name}: an object on a floor is INSIDE its room, not ON it")
            continue
        if o.parent in objects:
            if o.relation != ON or not CATALOG[objects[o.parent].cls].supports:
                raise LayoutError(f"{o.name}: {o.parent} is an object that does not hold others that way")
            continue
        if o.parent not in furniture:
            raise LayoutError(f"{o.name}: unknown parent {o.parent!r}")
        geometry = furniture_geometry(furniture[o.parent])
        if o.relation == INSIDE and not geometry.volumes:
            raise LayoutError(f"{o.name}: {o.parent} is not a container; nothing can be INSIDE it")


def access_sides(f: Furniture) -> list[tuple[np.ndarray, float, float]]:
    """(outward unit normal in the furniture frame, half depth along it, half width along the edge) per side."""
    w, d, _ = f.size
    sides = [(np.array([1.0, 0.0]), d / 2, w / 2)]
    if f.params.get("access") == "all":
        sides += [(np.array([-1.0, 0.0]), d / 2, w / 2), (np.array([0.0, 1.0]), w / 2, d / 2),
                  (np.array([0.0, -1.0]), w / 2, d / 2)]
    return sides


def _open_obstacles(layout: Layout, f: Furniture, place: Place) -> list[tuple]:
    """World rectangles occupied by the doors and drawers of `f` that must be open to reach `place`."""
    rects = []
    z0 = base_height(layout, f)
    for part in furniture_geometry(f).parts:
        needed = part.name == place.part or (place.part is None and place.relation == INSIDE and part.joint == "hinge")
        if not needed:
            continue
        pts = np.array([b.center for b in part.boxes] + [part.handle.center])
        world = _opened(f, part, pts, z0)
        rects.append((world[:, 0].min() - 0.03, world[:, 1].min() - 0.03, world[:, 0].max() + 0.03,
                      world[:, 1].max() + 0.03))
    return rects


def _opened(f: Furniture, part: Part, pts: np.ndarray, base_z: float = 0.0) -> np.ndarray:
    """Points of `part` (its frame, shape (N, 3)) in the world with the part wide open (m)."""
    if part.joint == "hinge":
        angle = part.range[1] * (1 if part.axis[2] > 0 else -1)
        c, s = math.cos(angle), math.sin(angle)
        pts = np.stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1], pts[:, 2]], axis=1)
    else:
        pts = pts + np.array(part.axis) * part.range[1]
    return local_to_world(f, pts + np.array(part.anchor), base_z)


def blocked_when_open(layout: Layout) -> dict[str, frozenset[str]]:
    """Furniture with doors or drawers -> the other furniture whose front they cover when wide open: the open
    door's or drawer's outline crosses the FRONT_DEPTH m in front of an access side over at least BLOCKED_COVER of
    that side's width (a bathroom cabinet's door swung open stands across the counter beside it; nothing held
    reaches over it). Doors that open beside a neighbour's edge cover little of it and block nothing."""
    blocked: dict[str, frozenset[str]] = {}
    for f in layout.furniture:
        parts = furniture_geometry(f).parts
        if not parts:
            continue
        outline = []
        for part in parts:
            box = part.boxes[0]  # the door leaf or the drawer front
            along = np.linspace(-1.0, 1.0, 21)
            pts = np.array([[box.center[0] + sx * box.half[0], box.center[1] + sy * box.half[1], 0.0]
                            for sx in (-1.0, 1.0) for sy in along])
            outline.append(_opened(f, part, pts)[:, :2])
        points = np.concatenate(outline)
        covered = set()
        for g in layout.furniture:
            if g is f:
                continue
            c, s = math.cos(g.yaw), math.sin(g.yaw)
            rel = points - np.asarray(g.pos[:2])
            local = np.stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]], axis=1)
            for normal, half_depth, half_width in access_sides(g):
                out, across = local @ normal, local @ np.array([-normal[1], normal[0]])
                front = (out >= half_depth) & (out <= half_depth + FRONT_DEPTH) & (np.abs(across) <= half_width)
                if front.any() and np.ptp(across[front]) >= BLOCKED_COVER * 2 * half_width:
                    covered.add(g.name)
        if covered:
            blocked[f.name] = frozenset(covered)
    return blocked


def _check_swings(layout: Layout, plan: FloorPlan, f: Furniture) -> None:
    """The area a door sweeps (a width x width square in front) or a drawer travels must be free floor."""
    w, d, _ = f.size
    for part in furniture_geometry(f).parts:
        reach = w if part.joint == "hinge" else part.range[1] + 0.05
        # A door's hinge edge swings a little beyond the side it hangs on.
        lo = -w / 2 - (0.03 if part.joint == "hinge" and part.anchor[1] < 0 else 0.0)
        hi = w / 2 + (0.03 if part.joint == "hinge" and part.anchor[1] > 0 else 0.0)
        corners = local_to_world(f, np.array([[d / 2, lo, 0], [d / 2 + reach, hi, 0]]))
        rect = (corners[:, 0].min(), corners[:, 1].min(), corners[:, 0].max(), corners[:, 1].max())
        if not plan.rect_is_free(rect):
            raise LayoutError(f"{f.name}: the {part.name} swing/travel area {tuple(round(float(v), 2) for v in rect)} "
                              "is blocked by furniture or a wall")


def _check_places(layout: Layout, plan: FloorPlan, f: Furniture, robot: RobotSpec) -> None:
    for k, place in enumerate(furniture_geometry(f).places):
        opened = _open_obstacles(layout, f, place)
        world = place_world(layout, f, place, opened=True)
        low, high = robot.place_heights
        if not low - 1e-9 <= world["z"] <= high + 1e-9:
            raise LayoutError(f"{f.name}: place {k} at {world['z']:.2f} m is out of the robot's reach "
                              f"({low}-{high} m)")
        if base_pose_for(layout, plan, f, world["rect"], opened, robot) is None:
            raise LayoutError(f"{f.name}: place {k} has no free robot base pose within "
                              f"{robot.reach} m in front of it")


def base_pose_for(layout: Layout, plan: FloorPlan, f: Furniture, rect: tuple, obstacles: list[tuple],
                  robot: RobotSpec = ROBOT):
    """A free base position of `robot` (x, y, yaw facing the furniture) from which `rect` is within its reach, or
    None."""
    z0 = base_height(layout, f)
    for normal, half_depth, half_width in access_sides(f):
        tangent = np.array([-normal[1], normal[0]])
        for dist in BASE_DISTANCES:
            for offset in BASE_OFFSETS:
                if abs(offset) > half_width:
                    continue
                local = normal * (half_depth + dist) + tangent * offset
                x, y, _ = local_to_world(f, np.array([local[0], local[1], 0.0]), z0)
                nearest_dx = max(rect[0] - x, 0.0, x - rect[2])
                nearest_dy = max(rect[1] - y, 0.0, y - rect[3])
                if math.hypot(nearest_dx, nearest_dy) > robot.reach:
                    continue
                if plan.disk_is_free(float(x), float(y), robot.footprint_radius, obstacles):
                    yaw = f.yaw + math.atan2(-normal[1], -normal[0])
                    return float(x), float(y), yaw
    return None
