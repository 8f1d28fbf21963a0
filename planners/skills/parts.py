"""Opening and closing doors and drawers in physics: grasp, follow the part's motion, release, retreat.

The part moves only because the closed fingers hold it (friction; no weld, no qpos writes). A grasp is a grip
pose fixed in the part's body frame; the motion is a list of part positions (hinge angle in rad, drawer travel
in m), and each waypoint's grip target is that grasp carried along by the part. For every waypoint a base pose
is chosen (free of walls, furniture and the moving door, close to the previous one) and the arm is solved by IK
with the base fixed there, so the base translates and turns as the door swings.

Grasps (all in the part frame, whose x axis is the closed part's outward front normal):
- `handle`: the handle bar from the front, fingers closing across the bar (the bar is a 2 cm box).
- `edge`: a hinge door's free vertical edge, pads on both faces of the panel, approached from beyond the edge.
  The fridge opens against a wall: with the door beyond about 40 degrees the space in front of its outer face
  (0.13 m at 90 degrees) is too narrow for the forearm, so the swing is finished (and a close is started) by
  holding the free edge instead of the handle, with the outer finger in that gap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from homer_sim.graph import INSIDE, ON, RELATION_NAMES
from homer_sim.home.furniture import Furniture, Place, furniture_geometry
from homer_sim.home.spots import Spots
from planners.grasps.geometry import axis_rotation, matrix_to_quat

OPEN_TARGET = 0.96  # openness the opening motion aims for (success: above OPEN_OK)
OPEN_OK = 0.9
CLOSED_OK = 0.05
CLOSE_OVERSHOOT = 0.02  # rad or m past the closed limit the motion aims for (the stop holds the part)
EDGE_FROM = 0.55  # rad: a door open at least this far is swung by its edge; below, by its handle
HANDLE_UNTIL = 0.7  # rad: how far the handle grasp swings a door before switching to the edge
STEP_HINGE = math.radians(4.0)  # rad between waypoints
STEP_SLIDE = 0.03  # m between waypoints
APPROACH = 0.10  # m the gripper comes from and leaves to, against the grasp's approach axis
HANDLE_OFFSET = 0.004  # m: grip site this far outward of the bar centre (fingertips clear of the panel)
EDGE_INSET = 0.025  # m from the free edge to the grip site
EDGE_ABOVE_HANDLE = 0.15  # m: the edge is held this far above the handle
PRE_OPENING = 0.03  # m per finger before closing on a 2 cm bar or panel
COVERED = 0.5  # share of a place's area under a higher place of the same furniture above which it is a shelf
MIN_HELD = 0.004  # m per finger: closed further means the fingers missed the 2 cm bar
SLIP = 0.03  # m between the grip site and the grasp point on the part before a motion is aborted
BASE_CLEARANCE = 0.05  # m between the base and the moving part


class PartHold(Enum):
    """Where the hand holds a door or drawer."""

    HANDLE = "handle"  # the handle bar, from the front
    EDGE = "edge"  # a hinge door's free vertical edge

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class PartGrasp:
    """A grip pose in the part's body frame: position (m, shape (3,)), rotation (shape (3, 3), columns = grip
    x (approach), y (finger travel), z), and the name of the grasp."""

    position: np.ndarray
    rotation: np.ndarray
    kind: PartHold


def _frame(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    x, y = np.asarray(x, float), np.asarray(y, float)
    return np.column_stack([x, y, np.cross(x, y)])


def handle_grasp(handle_local: np.ndarray, joint_type: str) -> PartGrasp:
    """The handle from the front: approach along -x (into the part). A door's bar is vertical, so the fingers
    close along y; a drawer's bar is horizontal, so they close along z."""
    y = np.array([0.0, 1.0, 0.0]) if joint_type == "hinge" else np.array([0.0, 0.0, 1.0])
    position = np.asarray(handle_local, float) + np.array([HANDLE_OFFSET, 0.0, 0.0])
    return PartGrasp(position, _frame(np.array([-1.0, 0.0, 0.0]), y), PartHold.HANDLE)


def edge_grasp(handle_local: np.ndarray, free_edge_y: float) -> PartGrasp:
    """A door's free edge at local y = `free_edge_y` (m, the hinge at y = 0), EDGE_ABOVE_HANDLE above the
    handle: approach along the panel towards the hinge, fingers closing across the panel (along x)."""
    toward_hinge = -math.copysign(1.0, free_edge_y)
    position = np.array([0.0, free_edge_y + toward_hinge * EDGE_INSET, handle_local[2] + EDGE_ABOVE_HANDLE])
    return PartGrasp(position, _frame(np.array([0.0, toward_hinge, 0.0]), np.array([1.0, 0.0, 0.0])), PartHold.EDGE)


class PartMotion:
    """Where a part's body frame is when its joint moves from the current value by `delta` (rad or m).

    Read from the live data once (joint anchor and axis in world, body pose); planning only, never steps.
    """

    def __init__(self, world, name: str) -> None:
        a = world.articulation(name)
        model, data = world.model, world.data
        self.name = name
        self.articulation = a
        self.body = int(model.jnt_bodyid[a.joint_id])
        self.anchor = data.xanchor[a.joint_id].copy()
        self.axis = data.xaxis[a.joint_id].copy()
        self.pos = data.xpos[self.body].copy()
        self.rot = data.xmat[self.body].reshape(3, 3).copy()
        self.value = float(data.qpos[a.qpos_adr])
        site = model.site(f"{name}/handle").id
        self.handle_local = model.site_pos[site].copy()
        geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == self.body]
        panel = max(geoms, key=lambda g: float(np.prod(model.geom_size[g])))  # the door or drawer front
        self.panel_center = model.geom_pos[panel].copy()
        self.panel_half = model.geom_size[panel].copy()

    def pose_at(self, value: float) -> tuple[np.ndarray, np.ndarray]:
        """(position m, rotation (3, 3)) of the part's body frame with the joint at `value`."""
        delta = value - self.value
        if self.articulation.joint_type == "slide":
            return self.pos + delta * self.axis, self.rot
        turn = axis_rotation(self.axis, delta)
        return self.anchor + turn @ (self.pos - self.anchor), turn @ self.rot

    def grip_target(self, grasp: PartGrasp, value: float) -> tuple[np.ndarray, np.ndarray]:
        """World grip pose (position m, wxyz quaternion) of `grasp` with the joint at `value`."""
        pos, rot = self.pose_at(value)
        return pos + rot @ grasp.position, matrix_to_quat(rot @ grasp.rotation)

    def panel_segment(self, value: float) -> tuple[np.ndarray, np.ndarray, float]:
        """The panel's horizontal footprint as a segment (two xy points, m) and its half thickness (m)."""
        pos, rot = self.pose_at(value)
        c, h = self.panel_center, self.panel_half
        long_axis = 1 if h[1] >= h[0] else 0
        offset = np.zeros(3)
        offset[long_axis] = h[long_axis]
        a, b = pos + rot @ (c - offset), pos + rot @ (c + offset)
        return a[:2], b[:2], float(h[1 - long_axis])

    def waypoints(self, target: float, step: float) -> np.ndarray:
        """Joint values from the current one to `target`, at most `step` apart (excluding the start)."""
        n = max(1, int(math.ceil(abs(target - self.value) / step)))
        return self.value + (target - self.value) * np.linspace(0.0, 1.0, n + 1)[1:]


def segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance in m from point p to segment ab (all shape (2,))."""
    ab = b - a
    t = float(np.clip(np.dot(p - a, ab) / max(float(np.dot(ab, ab)), 1e-12), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * ab)))


def drawer_rim(world, furniture: str, position: np.ndarray) -> float | None:
    """Height (m) of the top of the front of the drawer of `furniture` that holds the point `position` (m,
    shape (3,)) above its floor and below that top, or None where no drawer does. Something lifted out of a
    drawer must rise past it before it is carried towards the robot standing in front."""
    name = drawer_holding(world, furniture, position)
    if name is None:
        return None
    front = world.model.geom(f"{name}/front").id
    return float(world.data.geom_xpos[front][2] + world.model.geom_size[front][2])


def drawer_holding(world, furniture: str, position: np.ndarray) -> str | None:
    """The articulation name of the drawer of `furniture` that holds the point `position` (m, shape (3,)) above
    its floor and below the top of its front, or None where no drawer does."""
    model, data = world.model, world.data
    for a in world.articulations.values():
        if a.furniture != furniture or a.joint_type != "slide":
            continue
        floor, front = model.geom(f"{a.name}/bottom").id, model.geom(f"{a.name}/front").id
        local = data.geom_xmat[floor].reshape(3, 3).T @ (np.asarray(position) - data.geom_xpos[floor])
        half = model.geom_size[floor]
        rim = float(data.geom_xpos[front][2] + model.geom_size[front][2])
        if abs(local[0]) <= half[0] and abs(local[1]) <= half[1] and 0.0 < local[2] and position[2] < rim:
            return a.name
    return None


def behind_a_door(furniture: Furniture) -> bool:
    """Whether `furniture` keeps its shelves behind a hinged door (a cupboard, the fridge): what stands inside is
    reached from the front, the hand held level or pitched down under the shelf above."""
    return any(part.joint == "hinge" for part in furniture_geometry(furniture).parts)


def shelves_inside(spots: Spots, furniture: Furniture | None, node: str, relation: int | None) -> list[int]:
    """Indices of the shelves inside `furniture` (named `node`; None for a room) behind a door that a place with
    `relation` goes to; none for furniture without a door."""
    if furniture is None or not behind_a_door(furniture):
        return []
    return [k for k, p in spots.places_of(node, relation) if p.relation == INSIDE and p.part is None]


def covered_places(spots: Spots, node: str, relation: int | None) -> list[int]:
    """Indices of the fixed places of furniture `node` that a place with `relation` goes to and that lie under
    another fixed place of it covering most of their area (an open shelf's lower levels; not a shower's floor
    under its small soap shelf): a hand coming down from above meets the level above, so they are reached from
    the front, as shelves."""
    fixed = [p for relation_ in (ON, INSIDE) for _, p in spots.places_of(node, relation_) if p.part is None]
    return [k for k, p in spots.places_of(node, relation) if p.part is None and any(
        q.center[2] > p.center[2] and _overlap(q, p) > COVERED * 4.0 * p.half_xy[0] * p.half_xy[1] for q in fixed)]


def _overlap(a, b) -> float:
    """The area (m^2) two places' rectangles (furniture frame) share."""
    return math.prod(max(0.0, min(a.center[i] + a.half_xy[i], b.center[i] + b.half_xy[i])
                         - max(a.center[i] - a.half_xy[i], b.center[i] - b.half_xy[i])) for i in (0, 1))


def parts_to_open(world, graph, parts, obj: str) -> list[str]:
    """Of a piece of furniture's `parts` (doors or drawers, `<furniture>/<part>`) those to open to take `obj` out
    of it (`graph`: the observed scene graph): every door (a door covers every shelf behind it) and, of drawers,
    the one it lies in (the highest whose body is below it) if it (or what it rests on) is INSIDE, none if it is
    on the top. A drawer left open below or above another keeps the robot from reaching the other's handle as it
    closes."""
    movable = set(world.object_names)
    holder = obj
    while graph.parent_of(holder) in movable:
        holder = graph.parent_of(holder)
    inside = graph.relation_of(holder) == RELATION_NAMES[INSIDE]
    drawers = [p for p in parts if world.articulations[p].joint_type == "slide"]
    z = world.object_pose(obj)[0][2]
    height = {p: world.data.xpos[world.model.body(p).id][2] for p in drawers}
    lying_in = max((p for p in drawers if height[p] < z), key=height.get, default=None)
    return [p for p in parts if p not in drawers or (inside and p == lying_in)]


def parts_to_place(world, spots: Spots, parts, node: str) -> list[str]:
    """Of furniture `node`'s `parts` (doors or drawers, `<furniture>/<part>`) those to open to put something on
    or in it as `Place.place` does when no relation is asked for (on the places `Spots.places_of` gives then):
    every door where it is used inside (a door covers every shelf behind it), a drawer where one of those
    places is in it; none where it is used on its top (three drawers opened in front of a dresser whose top
    took the socks)."""
    if not parts:  # a room, an object, furniture with nothing that opens
        return []
    used = [place for _, place in spots.places_of(node, None)]
    drawers = {f"{node}/{place.part}" for place in used if place.part is not None}
    behind_doors = any(place.part is None and place.relation == INSIDE for place in used)
    return [p for p in parts if p in drawers or (behind_doors and world.articulations[p].joint_type == "hinge")]


def rim_above(furniture: Furniture, place: Place) -> float:
    """How high (m) the furniture's own boxes lying wholly between the front edge of `place` and the
    furniture's front rise above it, over its width (a sink's rim round its basin; nothing for a top): a hand
    held level lowering something that deep meets the rim with its wrist."""
    x0 = place.center[0] + place.half_xy[0]
    y0, y1 = place.center[1] - place.half_xy[1], place.center[1] + place.half_xy[1]
    tops = [b.center[2] + b.half[2] for b in furniture_geometry(furniture).boxes
            if b.center[0] - b.half[0] >= x0 - 1e-6 and b.center[1] - b.half[1] < y1 and b.center[1] + b.half[1] > y0]
    return max(tops, default=place.center[2]) - place.center[2]
