"""Grasps of an upright object on a shelf inside furniture, approached from its open front (see `shelf_grasps`).

Level side grasps; grasps pitched down into the compartment, the palm kept off the neighbours in its way (or moved
aside); "-along" grasps closing front to back; straight-down ones leaning aside ("-rolled"); for an object standing
turned, grasps square to its face ("-faced") and halfway to it ("-halfway"); slanted side grasps of round
objects. Grip features, rims and pot handles come from `planners.container_grasps`. No mujoco import.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from homer_sim.home.catalog import ObjectClass
from homer_sim.home.shapes import cavity
from planners.container_grasps import _tilted_rims, handle_grasps, pot_handle_grasps
from planners.grasps import (
    FINGER_HALF_THICKNESS,
    GRIPPER_OPEN,
    MAX_WIDTH,
    OFFSET_MARGIN,
    PAD_HALF,
    SHELF_APPROACH,
    SHELF_PITCHES,
    SUPPORT_CLEARANCE,
    TOP_DEPTH,
    TOP_NARROW_MARGIN,
    Grasp,
    _extent,
    _round,
    _shelf_frame,
    footprint,
)

SIDE_HEIGHTS = (0.4, 0.75)  # fractions of an object's height at which side grasps hold it, in the order tried
# (low holds steadier; high keeps the arm clear of a low shelf's edge and within reach near the floor)
SIDE_MIN_Z = 0.035  # m above the support: the palm (0.03 m half height) clears the shelf
SIDE_MARGIN = 0.01  # m per finger between an open pad and the object before a side grasp closes
SIDE_DEPTH = 0.022  # m from an object's near face to the grip site: the palm (0.035 m behind it) stays clear
PALM_SETBACK = 0.027  # m: the palm's front face lies 0.035 m behind the grip site; 8 mm to spare
SIDE_MIN_OVERLAP = 0.015  # m of the object's depth between the pads
ROUND_PAST = 0.01  # m: the pads reach this far past a round object's centre
FACE_MIN_TURN = math.radians(3.0)  # rad an object's face must turn off the furniture's front for "-faced" grasps
FACE_FIRST_TURN = math.radians(4.0)  # rad beyond which "-faced" grasps go first: pads closing on a box turned
# further turn it between them, and it keeps turning in the hand
ROUND_TURNS = tuple(math.radians(a) for a in (35.0, -35.0))  # rad off the furniture's front normal: slanted side
# grasps of round objects
PALM_LOW_EDGE = (0.035, 0.03)  # m: the palm's front-low edge lies this far behind the grip site and off its z
PALM_MARGIN = 0.01  # m between the palm's low edge and an object's front face
PALM_HALF_WIDTH = 0.09  # m: half the palm's extent along the finger travel
PALM_HALF_THICKNESS = 0.03  # m: half the palm's extent across the pads' plane (normal to the finger travel)
ALONG_BEHIND = 0.12  # m behind an object's back the in-finger and the palm's upper corner of an "-along" grasp
# may reach: a neighbour standing further back is out of their way
ROLL = math.radians(40.0)  # rad a straight-down shelf grasp closing front to back leans sideways ("-rolled"): the
# wrist, 0.29 m up the grip x, comes 0.29 (1 - cos ROLL) m lower, under a low shelf above a flat object
ROLL_TIP_CLEARANCE = 0.005  # m the open fingertips of a "-rolled" grasp pass over the object's top on the way in


def side_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray,
                front: float = np.inf) -> list[Grasp]:
    """Horizontal grasps of an upright object on a shelf inside furniture, approached from the front.

    outward: horizontal unit vector (shape (2,) or (3,)) out of the furniture's front, towards the robot. The
    grip x points into the furniture, the fingers close across the object (horizontally), the pads sit
    SIDE_HEIGHTS of the object's height above its support (at least SIDE_MIN_Z, so the palm clears the shelf).
    front: how far (m) the furniture's front plane lies out from the object's centre along `outward`; the palm
    (18 cm wide) stays in front of it, so the pads may hold only the object's front part (at least
    SIDE_MIN_OVERLAP deep).
    """
    sz = cls.size[2]
    out, across, yaw = _shelf_frame(outward, quat)
    width = _extent(across, cls, yaw)  # along the finger travel
    depth = _extent(out, cls, yaw)  # along the approach
    if width > MAX_WIDTH or sz < SIDE_MIN_Z + 0.01:
        return []
    support = position[2] - sz / 2
    rotation = np.column_stack([-out, across, np.cross(-out, across)])
    nominal = depth / 2 - SIDE_DEPTH
    if _round(cls):  # the pads reach past the centre, or closing squeezes the object out of the hand
        nominal = min(nominal, PAD_HALF - ROUND_PAST)
    along = max(nominal, front - PALM_SETBACK)  # grip site out from the centre, m
    too_shallow = along > nominal if _round(cls) else depth / 2 - (along - PAD_HALF) < SIDE_MIN_OVERLAP
    if too_shallow:
        return []
    heights = sorted({round(min(max(f * sz, SIDE_MIN_Z), sz - 0.015), 3) for f in SIDE_HEIGHTS},
                     key=lambda h: abs(h - SIDE_HEIGHTS[0] * sz))
    return [Grasp(np.array([position[0], position[1], support + h]) + out * along, rotation,
                  min(GRIPPER_OPEN, width / 2 + SIDE_MARGIN), "side" if k == 0 else "side-high")
            for k, h in enumerate(heights)]


def shelf_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray,
                 front: float = np.inf, neighbours: list[tuple[np.ndarray, float]] = ()) -> list[Grasp]:
    """Grasps of an object on a shelf inside furniture, approached from its open front: the horizontal side
    grasp (see `side_grasps`; with the palm inside the furniture where the front part alone is too shallow to
    hold), then approaches pitched SHELF_PITCHES down into the compartment with the fingers
    closing horizontally across the object near its top (short enough for the wrist to pass under the shelf
    above; whether it does is for a collision check of the arm); then the same square to the object's own face
    nearest the front where it stands turned ("-faced"; first where it is turned past FACE_FIRST_TURN), slanted
    side grasps of round objects (see `_turned_sides`), rim pinches of containers (only those for wide
    ones), and last the straight-down grasps closing front to back leaning aside (see `rolled_grasps`).

    outward: horizontal unit vector (shape (2,) or (3,)) out of the furniture's front; front: m from the
    object's centre to the front plane along it; neighbours: (footprint, see `footprint`; top z, m) of what
    stands beside the object on its shelf: a pitched grasp keeps the palm in front of those in its way. Best
    first; empty when no grasp fits the shape.
    """
    if cls.handle is not None:
        return handle_grasps(cls, position, quat, outward)
    sx, sy, sz = cls.size
    out, _, yaw = _shelf_frame(outward, quat)
    hollow = cavity(cls)
    rims = [] if hollow is None else _tilted_rims(hollow, position, yaw, position[2] - sz / 2, out)
    grasps = side_grasps(cls, position, quat, outward, front) or side_grasps(cls, position, quat, outward, -np.inf)
    if hollow is not None and min(sx, sy) > MAX_WIDTH - 0.02:
        return grasps + pot_handle_grasps(cls, position, quat, out) + rims
    along = _along_grasps(cls, position, quat, out, neighbours)
    if cls.family == "sphere":  # held across, pitched, a ball meets the pads past their tips and creeps out
        grasps, along = grasps + along, []
    grasps += _pitched_grasps(cls, position, quat, out, neighbours)
    face = _face_normal(out, yaw, cls)
    turn_cos = float(face @ out)
    if turn_cos < math.cos(FACE_MIN_TURN) or (not grasps and turn_cos < 1.0 - 1e-12):  # a hair off square
        faced = side_grasps(cls, position, quat, face, front / turn_cos) or side_grasps(cls, position, quat, face,
                                                                                          -np.inf)
        faced = [replace(g, kind=f"{g.kind}-faced") for g in faced + _pitched_grasps(cls, position, quat, face,
                                                                                       neighbours)]
        if turn_cos < math.cos(FACE_FIRST_TURN):
            faced += _halfway_sides(cls, position, quat, out, face, front)
        grasps = faced + grasps if turn_cos < math.cos(FACE_FIRST_TURN) else grasps + faced
        if cls.family != "sphere":  # in the object's own plane: square to the front, the pads meet one of its
            # faces across an edge and the box creeps round in them (a tea box turned 19 degrees, 8 mm in 3 s)
            faced = [replace(g, kind=f"{g.kind}-faced") for g in _along_grasps(cls, position, quat, face, neighbours)]
            along = faced + along if turn_cos < math.cos(FACE_FIRST_TURN) else along + faced
    rolled = [r for g in grasps if g.kind.startswith("shelf-90") and abs(g.rotation[:2, 1] @ out[:2]) >= 0.5
              for r in rolled_grasps(g, position[2] - sz / 2, position[2] + sz / 2)]
    return grasps + _turned_sides(cls, position, quat, out) + along + rims + rolled


def rolled_grasps(grasp: Grasp, support: float, top: float) -> list[Grasp]:
    """A straight-down `grasp` (grip x down, y horizontal) turned ROLL about its y axis, either way ("-90-rolled+",
    "-90-rolled-"): the pads still close horizontally on the same faces, but the wrist leans aside and comes lower,
    under a shelf too low above a flat object for a hand pointing straight down. The grip site is as high as
    the object's top less TOP_DEPTH allows, at least so high that the lowest fingertip corner stays
    SUPPORT_CLEARANCE above the `support` (m); the approach (along the leaning grip x) starts where it passes
    ROLL_TIP_CLEARANCE above the object's `top` (m)."""
    tip_drop = PAD_HALF * math.cos(ROLL) + FINGER_HALF_THICKNESS * math.sin(ROLL)
    z = max(top - TOP_DEPTH, support + tip_drop + SUPPORT_CLEARANCE)
    position = np.array([grasp.position[0], grasp.position[1], z])
    approach = max((top + ROLL_TIP_CLEARANCE - (z - tip_drop)) / math.cos(ROLL), 0.0)
    grasps = []
    for sign, label in ((1.0, "+"), (-1.0, "-")):
        rotation = _axis_rotation(grasp.rotation[:, 1], sign * ROLL) @ grasp.rotation
        grasps.append(replace(grasp, position=position, rotation=rotation, approach=approach,
                              kind=grasp.kind.replace("-90", f"-90-rolled{label}", 1)))
    return grasps


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation matrix (shape (3, 3)) turning `angle` rad about unit `axis` (shape (3,)) (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k


def _halfway_sides(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, out: np.ndarray, face: np.ndarray,
                   front: float) -> list[Grasp]:
    """Side grasps ("-halfway") of a box turned past FACE_FIRST_TURN approached halfway between the furniture's
    front normal `out` and the box's face normal `face` (each shape (3,)); `front` as for `side_grasps`. Where
    no base pose reaches the grasp square to the face, one square to the front pinches only the front corner,
    a wedge that turns the box between the pads (the rice, turned 18 degrees in a crowded cupboard); halfway,
    the pads meet its faces at half the turn."""
    mid = (out + face) / np.linalg.norm(out + face)
    turn_cos = float(mid @ out)
    grasps = side_grasps(cls, position, quat, mid, front / turn_cos) or side_grasps(cls, position, quat, mid, -np.inf)
    return [replace(g, kind=f"{g.kind}-halfway") for g in grasps]


def _pitched_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray,
                    neighbours: list[tuple[np.ndarray, float]] = ()) -> list[Grasp]:
    """Grasps approached SHELF_PITCHES down against `outward` (shape (3,)), the fingers closing horizontally
    across the object near its top (from straight above also along the approach); the palm's low front edge
    stays PALM_MARGIN in front of the object and of the `neighbours` (footprints) in its way; see `shelf_grasps`.
    """
    out, across, yaw = _shelf_frame(outward, quat)
    own = (footprint(cls, position, quat), position[2] + cls.size[2] / 2)
    blockers = palm_blockers([own, *neighbours], position, out, across)
    support, top = position[2] - cls.size[2] / 2, position[2] + cls.size[2] / 2
    grasps = []
    for pitch in SHELF_PITCHES[1:]:
        x = math.cos(pitch) * -out + np.array([0.0, 0.0, -math.sin(pitch)])
        for y in (across, np.cross(across, x))[: 2 if pitch == SHELF_PITCHES[-1] else 1]:
            width = _extent(y, cls, yaw)
            if width > MAX_WIDTH:
                continue
            tip_drop = PAD_HALF * math.sin(pitch) + FINGER_HALF_THICKNESS * math.cos(pitch)
            z = max(top - TOP_DEPTH, support + tip_drop + SUPPORT_CLEARANCE)
            depth = _extent(out, cls, yaw)
            shift = 0.0 if pitch == SHELF_PITCHES[-1] else palm_shift(pitch, z, blockers)
            aside, kind = 0.0, f"shelf-{math.degrees(pitch):.0f}"
            if shift > depth / 2 - SIDE_MIN_OVERLAP / 2:  # the pads would hold only the front edge
                moved = palm_aside(pitch, z, [own, *neighbours], position, out, across, width,
                                   depth / 2 - SIDE_MIN_OVERLAP / 2)
                if moved is None:
                    continue
                aside, shift = moved
                kind += "-aside"
            centre = np.array([position[0], position[1], z]) + out * shift + aside * across
            opening = min(GRIPPER_OPEN, width / 2 + abs(aside) + 0.025)
            grasps.append(Grasp(centre, np.column_stack([x, y, np.cross(x, y)]), opening, kind, SHELF_APPROACH))
    return grasps


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


def _along_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray,
                  neighbours: list[tuple[np.ndarray, float]] = ()) -> list[Grasp]:
    """Grasps approached SHELF_PITCHES down (not level, not straight down) against `outward` (shape (3,)), the
    fingers closing front to back in the approach's vertical plane ("-along"): the 18 cm palm then stands edge
    on to the shelf's front, 6 cm across, and passes between close neighbours (or a side wall) that leave no room
    for it face on; the wrist stays out in front of a low shelf above where one from straight down meets it.
    Skipped where a neighbour (footprints) stands within the fingers' half thickness plus PALM_MARGIN across the
    object, in front of it or less than ALONG_BEHIND behind it (the arm's collision check does not see the
    fingers). The grip site is at the object's centre near its top (as `_pitched_grasps`), moved across it
    as little as keeps the palm PALM_MARGIN off such neighbours (see `along_offset`), back along the approach
    as far as keeps the palm's face PALM_MARGIN off the object's top front corner (see `palm_gap`), and along
    the finger travel to the middle of what the pads sweep on the way in (see `along_span`); the fingers open
    TOP_NARROW_MARGIN past that. Skipped where the open out-finger's tip would come lower than
    SUPPORT_CLEARANCE above the support."""
    out, across, yaw = _shelf_frame(outward, quat)
    depth = _extent(out, cls, yaw)
    near = [a for a, o in _band_points(neighbours, position, out, across) if o > -depth / 2 - ALONG_BEHIND]
    if any(abs(a) < FINGER_HALF_THICKNESS + PALM_MARGIN for a in near):
        return []
    reach = ROUND_PAST if _round(cls) else _extent(across, cls, yaw) / 2 - FINGER_HALF_THICKNESS
    aside = along_offset(near, max(reach, 0.0))
    support, top = position[2] - cls.size[2] / 2, position[2] + cls.size[2] / 2
    grasps = []
    for pitch in SHELF_PITCHES[1:-1]:
        x = math.cos(pitch) * -out + np.array([0.0, 0.0, -math.sin(pitch)])
        y = np.cross(across, x)  # into the furniture and up
        tip_drop = PAD_HALF * math.sin(pitch) + FINGER_HALF_THICKNESS * math.cos(pitch)
        z = max(top - TOP_DEPTH, support + tip_drop + SUPPORT_CLEARANCE)
        least, greatest = along_span(depth, support - z, top - z, pitch, SHELF_APPROACH)
        inset = min(0.0, palm_gap(depth, support - z, top - z, pitch, (greatest + least) / 2) - PALM_MARGIN)
        least, greatest = along_span(depth, support - z, top - z, pitch, SHELF_APPROACH, inset)
        opening, middle = (greatest - least) / 2 + TOP_NARROW_MARGIN, (greatest + least) / 2
        if opening > GRIPPER_OPEN:
            continue
        centre = np.array([position[0], position[1], z]) + middle * y + aside * across + inset * x
        if centre[2] - opening * y[2] + PAD_HALF * x[2] < support + SUPPORT_CLEARANCE:
            continue  # the open out-finger's tip would strike the shelf and knock the object over
        grasps.append(Grasp(centre, np.column_stack([x, y, np.cross(x, y)]), opening,
                            f"shelf-{math.degrees(pitch):.0f}-along", SHELF_APPROACH))
    return grasps


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


def _band_points(neighbours: list[tuple[np.ndarray, float]], position: np.ndarray, out: np.ndarray,
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
    ys = [y for x, y in _along_section(depth, low, high, pitch) if -approach - PAD_HALF <= x - inset <= PAD_HALF]
    return (min(ys), max(ys)) if ys else (0.0, 0.0)


def palm_gap(depth: float, low: float, high: float, pitch: float, middle: float) -> float:
    """How far (m) the palm's front face (PALM_LOW_EDGE[0] behind the grip site) stands in front of an object
    `depth` m deep along the approach's horizontal, from `low` to `high` m (relative to the grip site's z), for an
    "-along" grasp pitched `pitch` rad down whose grip site stands `middle` m along the finger travel from the
    object's centre line; negative where the face cuts into the object (a deep or turned object's top front
    corner), within PALM_HALF_WIDTH of the grip site along the travel."""
    return min((PALM_LOW_EDGE[0] + x for x, y in _along_section(depth, low, high, pitch)
                if abs(y - middle) <= PALM_HALF_WIDTH), default=math.inf)


def _along_section(depth: float, low: float, high: float, pitch: float) -> list[tuple[float, float]]:
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


def _turned_sides(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray) -> list[Grasp]:
    """Side grasps of a round object approached ROUND_TURNS off `outward`: next to a furniture's side wall
    the 18 cm palm clears it only coming in at a slant (the fingers still close across the diameter)."""
    if not _round(cls):
        return []
    grasps = []
    for turn in ROUND_TURNS:
        c, s = math.cos(turn), math.sin(turn)
        turned = np.array([c * outward[0] - s * outward[1], s * outward[0] + c * outward[1]])
        grasps += [replace(g, kind=f"{g.kind}{math.degrees(turn):+.0f}")
                   for g in side_grasps(cls, position, quat, turned, -np.inf)]
    return grasps


def _face_normal(out: np.ndarray, yaw: float, cls: ObjectClass) -> np.ndarray:
    """The outward normal (shape (3,)) of the object's side face nearest horizontal unit `out` (shape (3,)),
    the object turned by `yaw` rad; a round object's is `out` itself."""
    if _round(cls):
        return out
    face = max((yaw + k * math.pi / 2 for k in range(4)), key=lambda a: math.cos(a) * out[0] + math.sin(a) * out[1])
    return np.array([math.cos(face), math.sin(face), 0.0])
