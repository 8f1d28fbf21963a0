"""Where a hand pitched in from a furniture's front keeps its 18 cm palm clear of what stands on the shelf: the
footprints in the palm's way and how far the grip site must stand out or aside for it (`palm_blockers`,
`palm_shift`, `palm_aside`), and the section of an object that a grasp closing front to back sweeps
(`along_span`, `palm_gap`, `along_offset`). Footprints are (outline, top z m) pairs, the outline world xy points
(m, shape (n, 2)) as `planners.grasps.geometry.footprint` gives them. No mujoco import.
"""

from __future__ import annotations

import math

import numpy as np

from homer_sim.robot_spec import ROBOT
from planners.grasps.candidate import GRIPPER_OPEN, OFFSET_MARGIN, PAD_HALF

PALM_LOW_EDGE = (ROBOT.palm_setback, ROBOT.palm_half_size[2])  # m: the palm's front-low edge lies this far behind
# the grip site and off its z
PALM_MARGIN = 0.01  # m between the palm's low edge and an object's front face
PALM_HALF_WIDTH = ROBOT.palm_half_size[1]  # m: half the palm's extent along the finger travel
PALM_HALF_THICKNESS = ROBOT.palm_half_size[2]  # m: half the palm's extent across the pads' plane (normal to the
# finger travel)


def palm_aside(pitch: float, grip_z: float, footprints: list[tuple[np.ndarray, float]], position: np.ndarray,
               out: np.ndarray, across: np.ndarray, width: float, limit: float) -> tuple[float, float] | None:
    """(aside, shift) m for a pitched grasp (see `_pitched_grasps`) whose palm, centred on the object, must stand
    further out than `limit` m in front of it (a neighbour in front and to one side overlaps the 18 cm palm's
    band): the least move `aside` along `across` (shape (3,), the finger travel) that brings the palm's `shift`
    (see `palm_shift`; `footprints` the object's own and its neighbours') within `limit`, no further than the
    open near finger still passes OFFSET_MARGIN beside the object `width` m across (closing, it slides the
    object to the middle, as `offset_grasps`); None if no such move."""
    reach = GRIPPER_OPEN - width / 2 - OFFSET_MARGIN
    for aside in sorted(np.linspace(-reach, reach, 17), key=abs) if reach > 0.0 else []:
        shift = palm_shift(pitch, grip_z, palm_blockers(footprints, position + aside * across, out, across))
        if shift <= limit:
            return float(aside), shift
    return None


def along_offset(near: list[float], reach: float) -> float:
    """How far (m) along the shelf's front to move an "-along" grasp's grip site off the object's centre so the
    palm (PALM_HALF_THICKNESS either side) keeps PALM_MARGIN from neighbour points `near` (m along the front from
    the centre): the least such move within `reach` either way (the pads still on the object), else the one
    that leaves the palm the most room (the arm's collision check decides)."""
    shifts = sorted(np.linspace(-reach, reach, 9), key=abs)
    room = [min((abs(a - shift) for a in near), default=math.inf) for shift in shifts]
    for shift, free in zip(shifts, room, strict=True):
        if free >= PALM_HALF_THICKNESS + PALM_MARGIN:
            return float(shift)
    return float(shifts[int(np.argmax(room))])


def band_points(neighbours: list[tuple[np.ndarray, float]], position: np.ndarray, out: np.ndarray,
                 across: np.ndarray) -> list[tuple[float, float]]:
    """(across, out) m from `position` along horizontal units `across` and `out` (each shape (3,)) of points on
    the outlines of `neighbours` (footprints; each edge sampled at 11 points) within PALM_HALF_WIDTH of it."""
    points = []
    for outline, _ in neighbours:
        closed = np.vstack([outline, outline[:1]])
        for a, b in zip(closed[:-1], closed[1:], strict=False):
            rel = a + np.linspace(0.0, 1.0, 11)[:, None] * (b - a) - np.asarray(position[:2])
            points += [(float(p @ across[:2]), float(p @ out[:2])) for p in rel
                       if abs(p @ across[:2]) < PALM_HALF_WIDTH]
    return points


def along_span(depth: float, low: float, high: float, pitch: float, approach: float, inset: float = 0.0
               ) -> tuple[float, float]:
    """(least, greatest) distance (m) along the finger travel of an "-along" grasp (see `_along_grasps`; grip y:
    into the furniture and up) from the grip site of the points of an object `depth` m deep along the approach's
    horizontal, from `low` to `high` m (its support and top, relative to the grip site's z before the inset),
    the hand pitched `pitch` rad down, the grip site `inset` m along the approach (grip x; negative: back out)
    from the object's centre line: of the points the pads (PAD_HALF either side of the grip site along the
    grip x) sweep on their last `approach` m onto the grasp."""
    ys = [y for x, y in along_section(depth, low, high, pitch) if -approach - PAD_HALF <= x - inset <= PAD_HALF]
    return (min(ys), max(ys)) if ys else (0.0, 0.0)


def palm_gap(depth: float, low: float, high: float, pitch: float, middle: float) -> float:
    """How far (m) the palm's front face (PALM_LOW_EDGE[0] behind the grip site) stands in front of an object
    `depth` m deep along the approach's horizontal, from `low` to `high` m (relative to the grip site's z), for an
    "-along" grasp pitched `pitch` rad down whose grip site stands `middle` m along the finger travel from the
    object's centre line; negative where the face cuts into the object (a deep or turned object's top front
    corner), within PALM_HALF_WIDTH of the grip site along the travel."""
    return min((PALM_LOW_EDGE[0] + x for x, y in along_section(depth, low, high, pitch)
                if abs(y - middle) <= PALM_HALF_WIDTH), default=math.inf)


def along_section(depth: float, low: float, high: float, pitch: float) -> list[tuple[float, float]]:
    """(x, y) m along an "-along" grasp's grip x (in and down) and y (in and up), pitched `pitch` rad, from a
    grip site on the object's centre line, of a 9 by 17 grid over the object's section in the approach's
    vertical plane: `depth` m deep, from `low` to `high` m (relative to the grip site's z)."""
    c, s = math.cos(pitch), math.sin(pitch)
    return [(-c * a - s * h, -s * a + c * h) for a in np.linspace(-depth / 2, depth / 2, 9)
            for h in np.linspace(low, high, 17)]


def palm_blockers(neighbours: list[tuple[np.ndarray, float]], position: np.ndarray, out: np.ndarray,
                  across: np.ndarray, half_width: float = PALM_HALF_WIDTH) -> list[tuple[float, float]]:
    """(front, top) of each of the `neighbours` ((footprint, see `footprint`; top z, m)) in the palm's way: within
    `half_width` (m, the palm's half extent across) plus PALM_MARGIN either side of `position` along `across`
    (shape (3,)); front: how far (m) its foremost part in that band lies out from `position` along horizontal
    unit `out` (shape (3,))."""
    blockers = []
    for outline, top in neighbours:
        closed = np.vstack([outline, outline[:1]])
        fronts = []
        for a, b in zip(closed[:-1], closed[1:], strict=False):  # each edge sampled densely: it may cross the band
            points = a + np.linspace(0.0, 1.0, 11)[:, None] * (b - a) - np.asarray(position[:2])
            inside = np.abs(points @ across[:2]) < half_width + PALM_MARGIN
            fronts += list(points[inside] @ out[:2])
        if fronts:
            blockers.append((max(fronts), float(top)))
    return blockers


def palm_shift(pitch: float, grip_z: float, blockers: list[tuple[float, float]]) -> float:
    """How far (m) out along the approach's horizontal the grip site must stand from an object's centre so that
    the palm's front face, pitched `pitch` rad down with the grip site at `grip_z` m, keeps PALM_MARGIN in front
    of every blocker ((front m out from the centre, top z m), see `palm_blockers`) where it is lower than the
    blocker's top plus PALM_MARGIN (the face leans in as it rises: its upper edge counts for a tall one)."""
    c, s = math.cos(pitch), math.sin(pitch)
    back, half = PALM_LOW_EDGE
    low = (back * c + half * s, back * s - half * c)  # (out, up) of the face's low and high edges from the grip
    high = (back * c - half * s, back * s + half * c)
    shift = 0.0
    for front, top in blockers:
        h = min(high[1], top + PALM_MARGIN - grip_z)
        if h < low[1]:
            continue  # the whole face passes above it
        along = low[0] + (high[0] - low[0]) * (h - low[1]) / (high[1] - low[1])
        shift = max(shift, front + PALM_MARGIN - along)
    return shift
