"""Collision geometry of one object class on an `mujoco.MjSpec` body.

Every geom is a primitive or a convex hull (built with trimesh), visible in group 0, with the same contact
parameters. Containers (bowl, cup, mug, pot, bin) get a real open cavity: a flat bottom disc plus a closed
ring of convex wall segments that share their side faces, so nothing falls through. All coordinates are in
the body frame, whose origin is the center of the class's bounding box (z up); lengths in m, masses in kg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import mujoco
import numpy as np
import trimesh

from homer_sim.home.catalog import ObjectClass, rest_height

__all__ = ["Cavity", "add_object_geoms", "cavity", "handle_boxes", "rest_height"]

FRICTION = (1.0, 0.005, 0.0001)  # sliding, torsional (m), rolling (m)
CONDIM = 4
SOLREF = (0.005, 1.0)  # contact time constant (s; MuJoCo default 0.02), damping ratio: see add_object_geoms
WALL_THICKNESS = {"bowl": 0.005, "cup": 0.003, "mug": 0.004, "pot": 0.004, "bin": 0.008}  # m, horizontal
FLOOR_THICKNESS = {"bowl": 0.005, "cup": 0.005, "mug": 0.006, "pot": 0.006, "bin": 0.012}  # m
FOOT_RATIO = {"bowl": 0.55}  # outer bottom radius / outer rim radius (flared walls); 1.0 otherwise
HANDLE_SPACE = {"mug": 0.03, "pot": 0.035}  # m of bounding box reserved for handles (mug: +x; pot: each side)
BAR = 0.008  # m, thickness of handle bars

_FLAT_FAMILIES = ("box", "cloth", "flat", "utensil")
_LYING_QUAT = (math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0)  # wxyz: rotates the geom z axis onto body x


@dataclass(frozen=True)
class Cavity:
    """The open-topped interior of a container, in the body frame.

    center_xy: (x, y) of the cavity axis in m.
    floor_radius: radius in m of the largest circle inside the walls at the floor.
    rim_radius: radius in m of the largest circle inside the walls at the rim.
    floor_z: height in m of the inner floor (top of the bottom disc).
    rim_z: height in m of the rim (top of the walls).
    """

    center_xy: tuple[float, float]
    floor_radius: float
    rim_radius: float
    floor_z: float
    rim_z: float


@dataclass(frozen=True)
class _Part:
    """One collision geom before it is added: a primitive (size, pos, quat) or a convex hull (mesh)."""

    name: str
    geom_type: mujoco.mjtGeom
    volume: float  # m^3, for the mass split
    size: tuple[float, ...] = ()  # MuJoCo geom size, unused entries omitted
    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    hull: trimesh.Trimesh | None = None


def _segments(cls: ObjectClass) -> int:
    """Number of wall segments of a container: 12 for small ones, 16 above 0.2 m across."""
    return 16 if min(cls.size[:2]) > 0.2 else 12


def _outer_geometry(cls: ObjectClass) -> tuple[float, float]:
    """(center x, outer rim radius) in m of a container's round body, leaving room for handles."""
    sx, sy = cls.size[0], cls.size[1]
    space = HANDLE_SPACE.get(cls.family, 0.0)
    if cls.family == "mug":
        radius = min(sy / 2.0, (sx - space) / 2.0)
        return -sx / 2.0 + radius, radius
    if cls.family == "pot":
        return 0.0, min(sy / 2.0, sx / 2.0 - space)
    return 0.0, min(sx, sy) / 2.0


def cavity(cls: ObjectClass) -> Cavity | None:
    """The interior volume of a container class in its body frame, or None for solid classes."""
    if not cls.is_container:
        return None
    center_x, rim_outer = _outer_geometry(cls)
    wall = WALL_THICKNESS[cls.family]
    inscribe = math.cos(math.pi / _segments(cls))  # polygon inradius / circumradius
    foot_outer = rim_outer * FOOT_RATIO.get(cls.family, 1.0)
    half_z = cls.size[2] / 2.0
    return Cavity(
        center_xy=(center_x, 0.0),
        floor_radius=(foot_outer - wall) * inscribe,
        rim_radius=(rim_outer - wall) * inscribe,
        floor_z=-half_z + FLOOR_THICKNESS[cls.family],
        rim_z=half_z,
    )


def _ring(radius: float, angles: np.ndarray, z: float, center_x: float) -> np.ndarray:
    """Points (len(angles), 3) in m on a horizontal circle of `radius` at height z around (center_x, 0)."""
    return np.stack(
        [center_x + radius * np.cos(angles), radius * np.sin(angles), np.full(len(angles), z)], axis=1
    )


def _wall_parts(cls: ObjectClass) -> list[_Part]:
    """The ring of convex wall segments; neighbours share their radial side faces (no gaps)."""
    center_x, rim_outer = _outer_geometry(cls)
    wall = WALL_THICKNESS[cls.family]
    foot_outer = rim_outer * FOOT_RATIO.get(cls.family, 1.0)
    half_z = cls.size[2] / 2.0
    z_low = -half_z + FLOOR_THICKNESS[cls.family] / 2.0  # overlaps the bottom disc, clear of the ground
    count = _segments(cls)
    parts = []
    for index in range(count):
        angles = np.array([index, index + 1]) * (2.0 * math.pi / count)
        corners = np.concatenate(
            [
                _ring(foot_outer, angles, z_low, center_x),
                _ring(foot_outer - wall, angles, z_low, center_x),
                _ring(rim_outer, angles, half_z, center_x),
                _ring(rim_outer - wall, angles, half_z, center_x),
            ]
        )
        hull = trimesh.convex.convex_hull(corners)
        parts.append(_Part(f"wall{index:02d}", mujoco.mjtGeom.mjGEOM_MESH, float(hull.volume), hull=hull))
    return parts


def _bottom_part(cls: ObjectClass) -> _Part:
    """The flat bottom disc of a container, resting on the ground plane of the bounding box."""
    center_x, rim_outer = _outer_geometry(cls)
    radius = rim_outer * FOOT_RATIO.get(cls.family, 1.0)
    half_thick = FLOOR_THICKNESS[cls.family] / 2.0
    return _Part(
        "bottom",
        mujoco.mjtGeom.mjGEOM_CYLINDER,
        _cylinder_volume(radius, half_thick),
        size=(radius, half_thick),
        pos=(center_x, 0.0, -cls.size[2] / 2.0 + half_thick),
    )


def _bar(name: str, low: tuple[float, float, float], high: tuple[float, float, float]) -> _Part:
    """An axis-aligned box geom spanning the corners `low` and `high` (m)."""
    half = tuple((h - lo) / 2.0 for lo, h in zip(low, high, strict=True))
    center = tuple((h + lo) / 2.0 for lo, h in zip(low, high, strict=True))
    return _Part(name, mujoco.mjtGeom.mjGEOM_BOX, 8.0 * half[0] * half[1] * half[2], size=half, pos=center)


def _mug_handle(cls: ObjectClass) -> list[_Part]:
    """A C-shaped handle of three bars on the +x side, inside the bounding box."""
    center_x, rim_outer = _outer_geometry(cls)
    sx, half_z = cls.size[0] / 2.0, cls.size[2] / 2.0
    inner_x = center_x + rim_outer - WALL_THICKNESS["mug"]  # reaches into the wall
    top, bottom = half_z - 0.015, -half_z + 0.02
    half_w = 0.006
    return [
        _bar("handle_top", (inner_x, -half_w, top - BAR), (sx, half_w, top)),
        _bar("handle_bottom", (inner_x, -half_w, bottom), (sx, half_w, bottom + BAR)),
        _bar("handle_grip", (sx - BAR, -half_w, bottom), (sx, half_w, top)),
    ]


def _pot_handles(cls: ObjectClass) -> list[_Part]:
    """Two flat side handles on -x and +x near the rim, inside the bounding box."""
    _, rim_outer = _outer_geometry(cls)
    sx, half_z = cls.size[0] / 2.0, cls.size[2] / 2.0
    inner = rim_outer - WALL_THICKNESS["pot"]
    top, half_w = half_z - 0.015, 0.03
    return [
        _bar("handle_pos", (inner, -half_w, top - 1.5 * BAR), (sx, half_w, top)),
        _bar("handle_neg", (-sx, -half_w, top - 1.5 * BAR), (-inner, half_w, top)),
    ]


def handle_boxes(cls: ObjectClass) -> list[tuple[tuple[float, float, float], tuple[float, float, float]]]:
    """(centre, half extents) in m, body frame, of each box handle on a pot's side (-x, +x); [] for other
    classes (a mug's C-shaped handle is not a box)."""
    return [(part.pos, part.size) for part in _pot_handles(cls)] if cls.family == "pot" else []


def _cylinder_volume(radius: float, half_length: float) -> float:
    """Volume in m^3 of a cylinder of `radius` and `half_length` (m)."""
    return math.pi * radius**2 * 2.0 * half_length


def _solid_part(cls: ObjectClass) -> _Part:
    """The single primitive geom of a solid class (box-like, cylinder, sphere or plate)."""
    sx, sy, sz = cls.size
    if cls.family in _FLAT_FAMILIES:
        return _Part("main", mujoco.mjtGeom.mjGEOM_BOX, sx * sy * sz, size=(sx / 2.0, sy / 2.0, sz / 2.0))
    cylinder = mujoco.mjtGeom.mjGEOM_CYLINDER
    if cls.family == "sphere":
        radius = min(cls.size) / 2.0
        return _Part("main", mujoco.mjtGeom.mjGEOM_SPHERE, 4.0 / 3.0 * math.pi * radius**3, size=(radius,))
    if cls.lying:
        radius, half_len = min(sy, sz) / 2.0, sx / 2.0
        volume = _cylinder_volume(radius, half_len)
        return _Part("main", cylinder, volume, size=(radius, half_len), quat=_LYING_QUAT)
    assert cls.family in ("cylinder", "plate"), cls.family
    radius, half_len = min(sx, sy) / 2.0, sz / 2.0
    return _Part("main", cylinder, _cylinder_volume(radius, half_len), size=(radius, half_len))


def _handled_parts(cls: ObjectClass) -> list[_Part]:
    """A solid body under the class's grip feature (`ObjectClass.handle`, a box centred on top), both inside the
    bounding box."""
    length, width, height = cls.handle
    sx, sy, sz = cls.size
    body = _solid_part(replace(cls, size=(sx, sy, sz - height), handle=None))
    return [replace(body, pos=(0.0, 0.0, -height / 2.0)),
            _Part("handle", mujoco.mjtGeom.mjGEOM_BOX, length * width * height,
                  size=(length / 2.0, width / 2.0, height / 2.0), pos=(0.0, 0.0, (sz - height) / 2.0))]


def _object_parts(cls: ObjectClass) -> list[_Part]:
    """Collision parts of `cls` in its body frame: one for solids (two with a grip feature); bottom, walls,
    handles for containers."""
    if not cls.is_container:
        return [_solid_part(cls)] if cls.handle is None else _handled_parts(cls)
    parts = [_bottom_part(cls), *_wall_parts(cls)]
    if cls.family == "mug":
        parts += _mug_handle(cls)
    elif cls.family == "pot":
        parts += _pot_handles(cls)
    return parts


def add_object_geoms(spec: mujoco.MjSpec, body: mujoco.MjsBody, cls: ObjectClass, prefix: str) -> None:
    """Add the collision geoms (visible, group 0) of `cls` to `body` and give it the mass cls.mass (kg).

    Geoms are named f"{prefix}/{part}", hull meshes f"{prefix}_{part}", so several instances of one class can
    share a spec. The mass is split over the geoms in proportion to their volume; MuJoCo derives the inertia.
    The caller owns the body (its pose and free joint). Contacts use solref SOLREF, stiffer than MuJoCo's
    default 0.02 s: with the default, a small object dropped 0.3 m into a bin sinks 1-3 cm into the floor
    and tunnels through it at a 2 ms step; at 0.005 s it sinks under 1 cm.
    """
    parts = _object_parts(cls)
    total_volume = sum(part.volume for part in parts)
    for part in parts:
        geom = body.add_geom(name=f"{prefix}/{part.name}", type=part.geom_type)
        if part.hull is not None:
            mesh_name = f"{prefix}_{part.name}"
            spec.add_mesh(
                name=mesh_name,
                uservert=part.hull.vertices.ravel().tolist(),
                userface=part.hull.faces.ravel().tolist(),
            )
            geom.meshname = mesh_name
        else:
            geom.size = [*part.size, *[0.0] * (3 - len(part.size))]
            geom.pos = list(part.pos)
            geom.quat = list(part.quat)
        geom.mass = cls.mass * part.volume / total_volume
        geom.rgba = list(cls.rgba)
        geom.friction = list(FRICTION)
        geom.condim = CONDIM
        geom.solref = list(SOLREF)
        geom.group = 0
