"""Geometry of furniture kinds as plain data: boxes, articulated parts, places and interior volumes.

Everything is in the furniture's local frame: x points out of the front (depth axis, front face at
x = +depth/2), y runs along the width, z up from the base. `homer_sim.home.build` turns this into MuJoCo bodies;
`homer_sim.home.validate` checks places and door swings against the robot's envelope. No mujoco import here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from homer_sim.errors import LayoutError
from homer_sim.graph import INSIDE, ON
from homer_sim.home.layout import Furniture

PANEL = 0.02  # m, carcass panel and door thickness
GAP = 0.004  # m, clearance between a moving part and the carcass
HANDLE = 0.02  # m, handle bar cross-section
WOOD = (0.62, 0.47, 0.33, 1.0)
WHITE = (0.92, 0.92, 0.9, 1.0)
DARK = (0.25, 0.25, 0.28, 1.0)
METAL = (0.7, 0.72, 0.75, 1.0)


@dataclass(frozen=True)
class Box:
    """A box in a body's frame: centre and half sizes in m."""

    name: str
    center: tuple[float, float, float]
    half: tuple[float, float, float]
    rgba: tuple[float, float, float, float] = WOOD


@dataclass(frozen=True)
class Volume:
    """An interior volume (box) that makes what lies in it INSIDE the furniture; `part` moves it."""

    center: tuple[float, float, float]
    half: tuple[float, float, float]
    part: str | None = None


@dataclass(frozen=True)
class Place:
    """A surface that holds objects, in the furniture frame (closed parts).

    center: middle of the usable area at the surface height (z, m above the furniture base).
    half_xy: half extents of the usable area (x along depth, y along width), m.
    clearance: free height above the surface, m. part: the moving part (drawer) carrying it, or None.
    open_ends: nothing stands beside the surface at its ends (a chair's seat), so an object longer than the
    surface is wide may lie across it, its middle on it (a guitar across a chair).
    """

    relation: int
    center: tuple[float, float, float]
    half_xy: tuple[float, float]
    clearance: float
    part: str | None = None
    open_ends: bool = False


@dataclass(frozen=True)
class Part:
    """An articulated part: a door (hinge) or a drawer (slide), with boxes in the part's frame.

    anchor: joint position in the furniture frame; axis: joint axis (unit) in the furniture frame;
    range: joint limits (rad or m); handle: the handle box, also in the part frame.
    """

    name: str
    joint: str
    anchor: tuple[float, float, float]
    axis: tuple[float, float, float]
    range: tuple[float, float]
    boxes: tuple[Box, ...]
    handle: Box
    damping: float
    mass: float


@dataclass(frozen=True)
class FurnitureGeometry:
    boxes: tuple[Box, ...]
    parts: tuple[Part, ...] = ()
    places: tuple[Place, ...] = ()
    volumes: tuple[Volume, ...] = ()


def _box(name: str, lo: tuple, hi: tuple, rgba=WOOD) -> Box:
    """A box from its low and high corners."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return Box(name, tuple((lo + hi) / 2), tuple((hi - lo) / 2), rgba)


def _top_place(d: float, w: float, h: float, margin: float = 0.04, clearance: float = 0.6) -> Place:
    return Place(ON, (0.0, 0.0, h), (d / 2 - margin, w / 2 - margin), clearance)


def table(f: Furniture) -> FurnitureGeometry:
    w, d, h = f.size
    t, leg = 0.03, 0.05
    boxes = [_box("top", (-d / 2, -w / 2, h - t), (d / 2, w / 2, h))]
    for sx in (-1, 1):
        for sy in (-1, 1):
            cx, cy = sx * (d / 2 - leg), sy * (w / 2 - leg)
            boxes.append(_box(f"leg_{sx}{sy}", (cx - leg / 2, cy - leg / 2, 0), (cx + leg / 2, cy + leg / 2, h - t)))
    return FurnitureGeometry(tuple(boxes), places=(_top_place(d, w, h),))


def block(f: Furniture) -> FurnitureGeometry:
    """A solid block (counter, stove, bench, bed, toilet, small appliance); top place unless no_place."""
    w, d, h = f.size
    rgba = tuple(f.params.get("rgba", WOOD))
    boxes = (_box("body", (-d / 2, -w / 2, 0), (d / 2, w / 2, h), rgba),)
    places = () if f.params.get("no_place") else (_top_place(d, w, h),)
    return FurnitureGeometry(boxes, places=places)


def seat(f: Furniture) -> FurnitureGeometry:
    """A sofa or chair: a seat block with a backrest (a cushion on a sofa, a board on a chair; and arms for a
    sofa). Things are put on the seat; a chair's has open ends."""
    w, d, h = f.size
    seat_h, back = f.params.get("seat_height", 0.45), 0.18 if f.kind == "sofa" else 0.06
    arm = 0.15 if f.kind == "sofa" else 0.0
    rgba = tuple(f.params.get("rgba", (0.35, 0.42, 0.55, 1.0)))
    boxes = [
        _box("seat", (-d / 2, -w / 2, 0), (d / 2, w / 2, seat_h), rgba),
        _box("back", (-d / 2, -w / 2, seat_h), (-d / 2 + back, w / 2, h), rgba),
    ]
    if arm:
        boxes += [
            _box("arm_l", (-d / 2 + back, -w / 2, seat_h), (d / 2, -w / 2 + arm, seat_h + 0.2), rgba),
            _box("arm_r", (-d / 2 + back, w / 2 - arm, seat_h), (d / 2, w / 2, seat_h + 0.2), rgba),
        ]
    if f.kind == "sofa":
        place = Place(ON, (back / 2, 0.0, seat_h), ((d - back) / 2 - 0.04, w / 2 - arm - 0.04), 0.5)
    else:
        place = Place(ON, (back / 2, 0.0, seat_h), ((d - back) / 2 - 0.02, w / 2 - 0.02), 0.5, open_ends=True)
    return FurnitureGeometry(tuple(boxes), places=(place,))


def _carcass(d: float, w: float, h: float, plinth: float, rgba) -> list[Box]:
    """Back, sides, bottom and top panels of an open-front box."""
    return [
        _box("back", (-d / 2, -w / 2, plinth), (-d / 2 + PANEL, w / 2, h), rgba),
        _box("side_l", (-d / 2, -w / 2, 0), (d / 2, -w / 2 + PANEL, h), rgba),
        _box("side_r", (-d / 2, w / 2 - PANEL, 0), (d / 2, w / 2, h), rgba),
        _box("bottom", (-d / 2, -w / 2 + PANEL, 0), (d / 2, w / 2 - PANEL, plinth + PANEL), rgba),
        _box("top", (-d / 2, -w / 2 + PANEL, h - PANEL), (d / 2, w / 2 - PANEL, h), rgba),
    ]


def _levels(f: Furniture, floor_z: float, ceiling_z: float) -> list[tuple[float, float]]:
    """(surface z, clearance) of the bottom and each shelf board."""
    surfaces = [floor_z] + [float(z) for z in f.params.get("shelves", ())]
    tops = [z - PANEL for z in surfaces[1:]] + [ceiling_z]
    return [(z, top - z) for z, top in zip(surfaces, tops, strict=True)]


def _door(f: Furniture, d: float, w: float, h: float, plinth: float) -> Part:
    """A hinge door over the whole front; hinge on the left (-y) or right (+y) edge, opening outward."""
    hinge = f.params.get("hinge", "left")
    side = -1.0 if hinge == "left" else 1.0
    x = d / 2 + GAP + PANEL / 2
    anchor = (x, side * w / 2, plinth)
    # In the part frame the door runs from the hinge towards the other edge along -side * y.
    door = _box("door", (-PANEL / 2, min(0, -side * w), 0), (PANEL / 2, max(0, -side * w), h - plinth), WHITE)
    handle_y = -side * (w - 0.06)
    handle_z = min((h - plinth) / 2, 1.0 - plinth)
    handle = _box("handle", (PANEL / 2 + 0.02, handle_y - HANDLE / 2, handle_z - 0.08),
                  (PANEL / 2 + 0.02 + HANDLE, handle_y + HANDLE / 2, handle_z + 0.08), METAL)
    stems = tuple(_box(f"stem_{k}", (PANEL / 2, handle_y - 0.006, handle_z + dz - 0.006),
                       (PANEL / 2 + 0.02, handle_y + 0.006, handle_z + dz + 0.006), METAL) for k, dz in
                  enumerate((-0.06, 0.06)))
    axis = (0.0, 0.0, side)  # positive angle swings the free edge out of the front
    return Part("door", "hinge", anchor, axis, (0.0, 1.57), (door, *stems), handle,
                damping=f.params.get("door_damping", 1.0), mass=f.params.get("door_mass", 3.0))


def cabinet(f: Furniture) -> FurnitureGeometry:
    """A carcass with shelves and one hinge door (cupboards, cabinets, fridge, dishwasher, washer); with
    door=False its front stays open (the bays of a coffee maker: the mug under the spout, the filter above)."""
    w, d, h = f.size
    plinth = f.params.get("plinth", 0.06)
    rgba = tuple(f.params.get("rgba", WOOD))
    boxes = _carcass(d, w, h, plinth, rgba)
    inner_w = w / 2 - PANEL
    x_back, x_front = -d / 2 + PANEL, d / 2
    places = []
    for k, (z, clearance) in enumerate(_levels(f, plinth + PANEL, h - PANEL)):
        if k > 0:
            boxes.append(_box(f"shelf_{k}", (x_back, -inner_w, z - PANEL), (x_front - 0.01, inner_w, z), rgba))
        places.append(Place(INSIDE, ((x_back + x_front) / 2, 0.0, z), ((x_front - x_back) / 2 - 0.03,
                                                                        inner_w - 0.03), clearance))
    if f.params.get("top_place"):
        places.append(_top_place(d, w, h))
    z0, z1 = plinth + PANEL, h - PANEL
    volume = Volume(((x_back + x_front) / 2, 0.0, (z0 + z1) / 2), ((x_front - x_back) / 2, inner_w, (z1 - z0) / 2))
    doors = (_door(f, d, w, h, plinth),) if f.params.get("door", True) else ()
    return FurnitureGeometry(tuple(boxes), doors, tuple(places), (volume,))


def _drawer(name: str, d: float, w: float, z0: float, z1: float, x_front: float, travel: float) -> tuple:
    """A drawer body (in its own frame, origin at its closed front-bottom-centre) and its place/volume."""
    inner_d, half_w = d - 2 * PANEL - 0.02, w / 2 - 2 * PANEL - GAP
    outer = w / 2 - PANEL - GAP
    front = _box("front", (-PANEL, -outer, 0), (0, outer, z1 - z0 - GAP), WHITE)
    bottom = _box("bottom", (-inner_d, -half_w, 0), (-PANEL, half_w, PANEL))
    back = _box("back", (-inner_d - PANEL, -half_w, 0), (-inner_d, half_w, (z1 - z0) * 0.7))
    sides = [_box(f"side_{s}", (-inner_d, min(s * half_w, s * outer), 0), (-PANEL, max(s * half_w, s * outer),
                  (z1 - z0) * 0.7)) for s in (-1, 1)]
    hz = (z1 - z0) / 2
    handle = _box("handle", (0.02, -0.08, hz - HANDLE / 2), (0.02 + HANDLE, 0.08, hz + HANDLE / 2), METAL)
    stems = [_box(f"stem_{k}", (0, y - 0.006, hz - 0.006), (0.02, y + 0.006, hz + 0.006), METAL)
             for k, y in enumerate((-0.07, 0.07))]
    part = Part(name, "slide", (x_front, 0.0, z0), (1.0, 0.0, 0.0), (0.0, travel),
                (front, bottom, back, *sides, *stems), handle, damping=5.0, mass=2.0)
    cx = x_front - PANEL - inner_d / 2
    wall = (z1 - z0) * 0.7
    place = Place(INSIDE, (cx, 0.0, z0 + PANEL), (inner_d / 2 - 0.03, half_w - 0.03), wall - PANEL, name)
    volume = Volume((cx, 0.0, z0 + PANEL + wall / 2), (inner_d / 2, half_w, wall / 2 + 0.03), name)
    return part, place, volume


def drawers(f: Furniture) -> FurnitureGeometry:
    """A dresser: a carcass with `drawers` stacked drawers on slide joints, and a top place."""
    w, d, h = f.size
    n, plinth = int(f.params.get("drawers", 3)), 0.06
    boxes = _carcass(d, w, h, plinth, tuple(f.params.get("rgba", WOOD)))
    pitch = (h - PANEL - plinth - PANEL) / n
    parts, places, volumes = [], [], []
    for k in range(n):
        z0 = plinth + PANEL + k * pitch
        part, place, volume = _drawer(f"drawer_{k}", d, w, z0, z0 + pitch, d / 2, 0.75 * d)
        parts.append(part), places.append(place), volumes.append(volume)
    places.append(_top_place(d, w, h))
    return FurnitureGeometry(tuple(boxes), tuple(parts), tuple(places), tuple(volumes))


def desk(f: Furniture) -> FurnitureGeometry:
    """A table with one drawer hanging under the top (slide joint)."""
    geometry = table(f)
    w, d, h = f.size
    dw = min(0.6, w - 0.2)
    part, place, volume = _drawer("drawer_0", d - 0.1, dw, h - 0.2, h - 0.03 - GAP, d / 2 - 0.02, 0.45)
    return FurnitureGeometry(geometry.boxes, (part,), geometry.places + (place,), (volume,))


def shelf(f: Furniture) -> FurnitureGeometry:
    """Open shelves (bookshelf, tv stand, shoe rack): sides, back, boards; every board and the top hold objects."""
    w, d, h = f.size
    rgba = tuple(f.params.get("rgba", WOOD))
    boxes = _carcass(d, w, h, 0.04, rgba)
    places = []
    inner_w = w / 2 - PANEL
    for k, (z, clearance) in enumerate(_levels(f, 0.04 + PANEL, h - PANEL)):
        if k > 0:
            boxes.append(_box(f"board_{k}", (-d / 2 + PANEL, -inner_w, z - PANEL), (d / 2, inner_w, z), rgba))
        places.append(Place(ON, (PANEL / 2, 0.0, z), ((d - PANEL) / 2 - 0.03, inner_w - 0.03), clearance))
    places.append(_top_place(d, w, h))
    return FurnitureGeometry(tuple(boxes), places=tuple(places))


def sink(f: Furniture) -> FurnitureGeometry:
    """A sink unit: a base block with a basin let into its top; the basin's inside is INSIDE the sink."""
    w, d, h = f.size
    depth, rim = f.params.get("basin_depth", 0.16), 0.07
    bx, by = d / 2 - rim, w / 2 - rim
    base = h - depth - PANEL
    boxes = [
        _box("base", (-d / 2, -w / 2, 0), (d / 2, w / 2, base), WHITE),
        _box("basin_floor", (-bx, -by, base), (bx, by, base + PANEL), METAL),
        _box("rim_back", (-d / 2, -w / 2, base), (-bx, w / 2, h), WHITE),
        _box("rim_front", (bx, -w / 2, base), (d / 2, w / 2, h), WHITE),
        _box("rim_l", (-bx, -w / 2, base), (bx, -by, h), WHITE),
        _box("rim_r", (-bx, by, base), (bx, w / 2, h), WHITE),
    ]
    floor = base + PANEL
    place = Place(INSIDE, (0.0, 0.0, floor), (bx - 0.03, by - 0.03), depth + 0.3)
    volume = Volume((0.0, 0.0, floor + (depth + 0.1) / 2), (bx, by, (depth + 0.1) / 2))
    return FurnitureGeometry(tuple(boxes), places=(place,), volumes=(volume,))


def shower(f: Furniture) -> FurnitureGeometry:
    """A shower tray with a low curb, two glass sides, and a corner shelf; its inside is INSIDE the shower."""
    w, d, h = f.size
    tray, curb, glass = 0.06, 0.12, (0.75, 0.85, 0.9, 0.3)
    boxes = [
        _box("tray", (-d / 2, -w / 2, 0), (d / 2, w / 2, tray), WHITE),
        _box("curb", (d / 2 - 0.04, -w / 2, tray), (d / 2, w / 2, curb), WHITE),
        _box("glass_l", (-d / 2, -w / 2, tray), (d / 2, -w / 2 + 0.01, h), glass),
        _box("shelf", (d / 2 - 0.3, w / 2 - 0.3, 0.98), (d / 2 - 0.05, w / 2, 1.0), WHITE),
    ]
    places = (
        Place(INSIDE, (-0.05, -0.05, tray), (d / 2 - 0.15, w / 2 - 0.15), 1.0),
        Place(INSIDE, (d / 2 - 0.175, w / 2 - 0.15, 1.0), (0.1, 0.12), 0.4),
    )
    volume = Volume((0.0, 0.0, (tray + h) / 2), (d / 2, w / 2, (h - tray) / 2))
    return FurnitureGeometry(tuple(boxes), places=places, volumes=(volume,))


def flat(f: Furniture) -> FurnitureGeometry:
    """A mat or rug: a thin slab that holds nothing the robot plans for."""
    w, d, h = f.size
    return FurnitureGeometry((_box("slab", (-d / 2, -w / 2, 0), (d / 2, w / 2, h), (0.5, 0.2, 0.2, 1.0)),))


KINDS = {
    "table": table,
    "block": block,
    "sofa": seat,
    "chair": seat,
    "cabinet": cabinet,
    "drawers": drawers,
    "desk": desk,
    "shelf": shelf,
    "sink": sink,
    "shower": shower,
    "flat": flat,
}


def furniture_geometry(f: Furniture) -> FurnitureGeometry:
    """The geometry of `f` in its local frame; raises LayoutError for an unknown kind."""
    try:
        builder = KINDS[f.kind]
    except KeyError:
        raise LayoutError(f"{f.name}: unknown furniture kind {f.kind!r}; known: {', '.join(sorted(KINDS))}") from None
    return builder(f)


def local_to_world(f: Furniture, p: np.ndarray, base_z: float = 0.0) -> np.ndarray:
    """Furniture-frame points, shape (..., 3), to world (m)."""
    c, s = math.cos(f.yaw), math.sin(f.yaw)
    p = np.asarray(p, float)
    x = f.pos[0] + c * p[..., 0] - s * p[..., 1]
    y = f.pos[1] + s * p[..., 0] + c * p[..., 1]
    return np.stack([x, y, p[..., 2] + base_z], axis=-1)


def footprint(f: Furniture) -> tuple[float, float, float, float]:
    """World axis-aligned footprint (x0, y0, x1, y1) of the closed furniture, m."""
    w, d, _ = f.size
    corners = local_to_world(f, np.array([[sx * d / 2, sy * w / 2, 0] for sx in (-1, 1) for sy in (-1, 1)]))
    return (corners[:, 0].min(), corners[:, 1].min(), corners[:, 0].max(), corners[:, 1].max())
