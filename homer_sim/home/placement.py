"""Where objects go: places in world coordinates and free spots on them.

The start layout is packed deterministically (front row first, left to right); the avatar and robot later
sample free spots with an explicit random generator. No mujoco here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from homer_sim.errors import LayoutError
from homer_sim.graph import INSIDE, ON
from homer_sim.home.catalog import CATALOG, ObjectClass
from homer_sim.home.furniture import Place, footprint, furniture_geometry, local_to_world
from homer_sim.home.layout import Furniture, Layout, ObjectDecl
from homer_sim.home.shapes import cavity
from homer_sim.robot_spec import ROBOT

SPOT_GAP = 0.025  # m between neighbouring objects
ROW_GAP = 0.065  # m between rows on an open top at the start: a finger (3.2 cm) and its margin come down between
# an object and the one behind it, also after the grasp suite shifts the object 2.5 cm (a knife 2.5 cm in front of
# a dish rack left no room for the finger between them)
PALM_ROOM = ROBOT.palm_half_size[1]  # m beside each object on a shelf holding one lower than the palm is thick:
# such an object is held only by a palm pitched down over it, 18 cm wide along the finger travel, which passes
# between two neighbours this far either side of any object (a razor 6.5 cm from a painkillers bottle and a shaving
# cream can, 17.5 cm apart, was out of the hand's reach)
SPAWN_LIFT = 0.001  # m above the surface an object is spawned


@dataclass(frozen=True)
class StartPose:
    """Body pose of an object at spawn: position in m (world), quaternion wxyz."""

    name: str
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]


def base_height(layout: Layout, f: Furniture) -> float:
    """World z of the base of `f` (0 on the floor, the top of the furniture it stands on)."""
    if f.on is None:
        return 0.0
    return base_height(layout, layout.furniture_by_name()[f.on]) + layout.furniture_by_name()[f.on].size[2]


def yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    return (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))


def yaw_of(quat) -> float:
    """Yaw (rad) of a wxyz quaternion (the inverse of `yaw_quat` for a turn about z)."""
    w, x, y, z = quat
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def _obstacles_on(layout: Layout, f: Furniture, place: Place) -> list[tuple[float, float, float, float]]:
    """Place-frame (x0, y0, x1, y1) rectangles of furniture standing on `f`, if `place` is its top (shelves and
    the inside of a cabinet under an appliance standing on it are free)."""
    rects = []
    if place.center[2] < f.size[2] - 1e-6:
        return rects
    for other in layout.furniture:
        if other.on == f.name:
            x0, y0, x1, y1 = footprint(other)
            corners = np.array([[x0, y0], [x1, y1]])
            local = _world_to_local_xy(f, corners)
            rects.append((local[:, 0].min(), local[:, 1].min(), local[:, 0].max(), local[:, 1].max()))
    return rects


def _world_to_local_xy(f: Furniture, xy: np.ndarray) -> np.ndarray:
    c, s = math.cos(f.yaw), math.sin(f.yaw)
    dx, dy = xy[:, 0] - f.pos[0], xy[:, 1] - f.pos[1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy], axis=1)


def _overlaps(a: tuple, b: tuple, gap_x: float, gap_y: float) -> bool:
    return a[0] < b[2] + gap_x and b[0] < a[2] + gap_x and a[1] < b[3] + gap_y and b[1] < a[3] + gap_y


def lengthwise(f: Furniture, place: Place, cls: ObjectClass) -> bool:
    """Whether an object on `place` of `f` stands lengthwise (its x front to back, like books on a shelf):
    a long object inside a cabinet, which keeps its narrow side to the open front and leaves room beside it."""
    return f.kind == "cabinet" and place.relation == INSIDE and cls.size[0] > cls.size[1]


def stored_yaw(f: Furniture, place: Place, cls: ObjectClass) -> float:
    """Yaw (rad, world) of an object put on `place` of `f`: its x along the furniture's width, or front to
    back if it stands `lengthwise`."""
    return f.yaw + (0.0 if lengthwise(f, place, cls) else math.pi / 2)


def pack_spot(place: Place, cls: ObjectClass, taken: list[tuple], step: float = 0.01,
              lengthwise: bool = False, centre_first: bool = False, row_gap: float = SPOT_GAP,
              side_gap: float = SPOT_GAP) -> tuple[float, float] | None:
    """First free (x, y) in the place frame for an object whose width (its x) runs along the place's y, or
    along its x (the depth) if `lengthwise`, `side_gap` from its neighbours beside it and `row_gap` from those in
    front of or behind it.

    Scans from the front edge backwards, left to right (-y first) or, if `centre_first`, from the middle out;
    None if the object does not fit.
    """
    if cls.size[2] > place.clearance - 0.005:
        return None
    half_y, half_x = cls.size[0] / 2, cls.size[1] / 2  # along place y (width) and x (depth)
    if lengthwise:
        half_y, half_x = half_x, half_y
    cx, cy, _ = place.center
    hx, hy = place.half_xy
    if half_x > hx or half_y > hy:
        return None
    for x in np.arange(cx + hx - half_x, cx - hx + half_x - 1e-9, -step):
        ys = np.arange(cy - hy + half_y, cy + hy - half_y + 1e-9, step)
        for y in ys[np.argsort(np.abs(ys - cy), kind="stable")] if centre_first else ys:
            rect = (x - half_x, y - half_y, x + half_x, y + half_y)
            if not any(_overlaps(rect, t, row_gap, side_gap) for t in taken):
                taken.append(rect)
                return float(x), float(y)
    return None


@cache
def inside_side_gap(layout: Layout, f: Furniture, level: int, place: Place) -> float:
    """The gap (m) the start layout leaves beside each object on place `level` inside `f` where a hand comes in
    from the front (a cabinet's shelf, the shower's corner shelf; not a drawer, reached from above): ROW_GAP,
    a finger's room (a side grasp's pads open 1 cm past the object, its fingers 3.2 cm thick) also after the
    grasp suite shifts the object 2.5 cm, where the objects declared on that place fit side by side with that
    much room between them and the walls; else as much as they leave spread evenly, at least SPOT_GAP (the
    cheese packed 2.5 cm beside the milk left the fingers no room); less in 5 mm steps where, packed on the 1 cm
    grid of `pack_spot`, one of them would leave the front row that SPOT_GAP keeps it in (spread evenly, 4.2 cm
    apart, the dry pasta went behind the oil on the cupboard's bottom shelf, reached only over it). On a place
    holding an object lower than the palm is thick (too low for a level side grasp), PALM_ROOM instead of ROW_GAP
    where there is room for it."""
    objects = [CATALOG[o.cls] for o in layout.objects if o.parent == f.name and o.level == level]
    widths = [cls.size[1] if lengthwise(f, place, cls) else cls.size[0] for cls in objects]
    spare = 2 * place.half_xy[1] - sum(widths)
    front = place.center[0] + place.half_xy[0]

    def in_front(gap: float) -> int:
        taken: list[tuple] = []
        for cls in objects:
            long = lengthwise(f, place, cls)
            if pack_spot(place, cls, taken, lengthwise=long, centre_first=f.kind == "cabinet", side_gap=gap) is None:
                pack_spot(place, cls, taken, lengthwise=long, side_gap=gap)
        return sum(rect[2] > front - 1e-6 for rect in taken)

    low = any(cls.size[2] < 2 * ROBOT.palm_half_size[2] for cls in objects)
    widest = min(PALM_ROOM if low else ROW_GAP, max(SPOT_GAP, spare / (len(widths) + 1)))
    least = in_front(SPOT_GAP)
    return next((float(gap) for gap in np.arange(widest, SPOT_GAP, -0.005) if in_front(gap) >= least), SPOT_GAP)


def _candidate_places(f: Furniture, decl: ObjectDecl) -> list[tuple[int, Place]]:
    places = list(enumerate(furniture_geometry(f).places))
    if decl.level is not None:
        if not 0 <= decl.level < len(places):
            raise LayoutError(f"{decl.name}: {f.name} has no place level {decl.level} (it has {len(places)})")
        places = [places[decl.level]]
    matching = [(k, p) for k, p in places if p.relation == decl.relation]
    if not matching:
        relation = "INSIDE" if decl.relation == INSIDE else "ON"
        raise LayoutError(f"{decl.name}: cannot be {relation} {f.name} ({f.cls} has no such place"
                          f"{'' if decl.level is None else f' at level {decl.level}'})")
    return matching


def start_poses(layout: Layout) -> dict[str, StartPose]:
    """Spawn pose of every declared object, packed onto its parent's places; raises LayoutError if one does not fit."""
    return dict(_start_poses_cached(layout))


@cache
def _start_poses_cached(layout: Layout) -> tuple[tuple[str, StartPose], ...]:
    furniture = layout.furniture_by_name()
    taken: dict[tuple[str, int], list[tuple]] = {}
    poses: dict[str, StartPose] = {}
    rooms = set(layout.room_names())
    declared = {o.name: o for o in layout.objects}

    def depth(decl: ObjectDecl) -> int:  # how many objects it stands on, one on another (bounded for a cycle)
        k = 0
        while decl.parent in declared and k <= len(declared):
            decl, k = declared[decl.parent], k + 1
        return k

    # what stands on an object is placed after it, whatever the order of declaration
    for decl in sorted(layout.objects, key=depth):
        cls = CATALOG[decl.cls]
        if decl.parent in rooms:
            if decl.at is None:
                raise LayoutError(f"{decl.name}: an object on the floor of {decl.parent} needs `at` (x, y)")
            poses[decl.name] = StartPose(decl.name, (*decl.at, cls.size[2] / 2 + SPAWN_LIFT), yaw_quat(0.0))
            continue
        if decl.parent in poses:  # on an object: packed on its top, turned as it is, or in a container, on its floor
            below, base = poses[decl.parent], CATALOG[_decl(layout, decl.parent).cls]
            hollow, inside = cavity(base), taken.setdefault((decl.parent, 1), [])
            reach = cls.size[0] / 2 if cls.is_round else math.hypot(*cls.size[:2]) / 2
            if hollow is not None and not inside and reach <= hollow.floor_radius:
                # the first that fits inside its walls at the floor stands there, centred (a trash bag put in a
                # trash can at its top stood on its rim, and the can fell over)
                inside.append(decl.name)
                centre, floor, spot = (hollow.center_xy[1], hollow.center_xy[0]), hollow.floor_z, (0.0, 0.0)
            else:
                # the place frame's x runs along the object's y, so what lies on it keeps the object's yaw
                top = Place(ON, (0.0, 0.0, 0.0), (base.size[1] / 2, base.size[0] / 2), math.inf)
                spots = taken.setdefault((decl.parent, 0), [])
                spot = pack_spot(top, cls, spots, step=0.005, centre_first=True)
                if spot is None and not spots:  # alone, it may reach over the edge (a spoon across a bowl)
                    spot = (0.0, 0.0)
                    spots.append((-top.half_xy[0], -top.half_xy[1], top.half_xy[0], top.half_xy[1]))
                if spot is None:
                    raise LayoutError(f"{decl.name}: does not fit beside what lies on {decl.parent} (size {cls.size} "
                                      f"m)")
                centre, floor = (0.0, 0.0), base.size[2] / 2
            yaw = yaw_of(below.quat)
            dx, dy = centre[1] + spot[1], centre[0] + spot[0]  # in the object's frame
            x = below.pos[0] + math.cos(yaw) * dx - math.sin(yaw) * dy
            y = below.pos[1] + math.sin(yaw) * dx + math.cos(yaw) * dy
            z = below.pos[2] + floor + cls.size[2] / 2 + SPAWN_LIFT
            poses[decl.name] = StartPose(decl.name, (x, y, z), below.quat)
            continue
        f = furniture[decl.parent]
        for k, place in _candidate_places(f, decl):
            spots = taken.setdefault((f.name, k), list(_obstacles_on(layout, f, place)))
            long = lengthwise(f, place, cls)
            # in a cabinet the first declared (the everyday things) stand front and centre, where a hand reaches
            # past the open door and the side walls
            # on an open top the robot's hand comes down from above: rows keep a finger's room between them where
            # the top has room for that
            # inside furniture but for a drawer the hand comes in from the front: neighbours keep a finger's room
            # beside them where the place has room for that (`inside_side_gap`)
            side_gap = inside_side_gap(layout, f, k, place) if place.relation == INSIDE and place.part is None \
                else SPOT_GAP
            for row_gap in (ROW_GAP, SPOT_GAP) if place.relation == ON else (SPOT_GAP,):
                spot = pack_spot(place, cls, spots, lengthwise=long, centre_first=f.kind == "cabinet",
                                 row_gap=row_gap, side_gap=side_gap)
                if spot is None and f.kind == "cabinet":  # what does not fit beside them packs from the side
                    spot = pack_spot(place, cls, spots, lengthwise=long, row_gap=row_gap, side_gap=side_gap)
                if spot is not None:
                    break
            if spot is not None:
                world = local_to_world(f, np.array([spot[0], spot[1], place.center[2]]), base_height(layout, f))
                pos = (float(world[0]), float(world[1]), float(world[2] + cls.size[2] / 2 + SPAWN_LIFT))
                poses[decl.name] = StartPose(decl.name, pos, yaw_quat(stored_yaw(f, place, cls)))
                break
        else:
            raise LayoutError(f"{decl.name}: does not fit on any place of {f.name} (size {cls.size} m)")
    return tuple((o.name, poses[o.name]) for o in layout.objects)


def _decl(layout: Layout, name: str) -> ObjectDecl:
    return next(o for o in layout.objects if o.name == name)


def place_world(layout: Layout, f: Furniture, place: Place, opened: bool = False) -> dict:
    """World description of a place: surface z, rectangle corners (x0, y0, x1, y1) and centre, all m.

    With `opened`, a drawer place is shown pulled out to the end of its travel.
    """
    shift = 0.0
    if opened and place.part is not None:
        part = next(p for p in furniture_geometry(f).parts if p.name == place.part)
        shift = part.range[1]
    cx, cy, z = place.center
    hx, hy = place.half_xy
    corners = np.array([[cx + shift + sx * hx, cy + sy * hy, z] for sx in (-1, 1) for sy in (-1, 1)])
    world = local_to_world(f, corners, base_height(layout, f))
    return {
        "z": float(world[0, 2]),
        "rect": (world[:, 0].min(), world[:, 1].min(), world[:, 0].max(), world[:, 1].max()),
        "center": world[:, :2].mean(axis=0),
    }


__all__ = ["ON", "INSIDE", "StartPose", "start_poses", "pack_spot", "stored_yaw", "place_world", "base_height",
           "yaw_quat"]
