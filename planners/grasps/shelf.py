"""Grasps of an upright object on a shelf inside furniture, approached from its open front (see `shelf_grasps`).

Level side grasps; grasps pitched down into the compartment, the palm kept off the neighbours in its way (or moved
aside, see `planners.grasps.palm`); grasps closing front to back ("along"); straight-down ones leaning aside
("rolled"); for an object standing turned, grasps square to its face ("faced") and halfway to it; slanted side
grasps of round objects. Grip features, rims and pot handles come from `planners.grasps.features`; the order is
`planners.grasps.ranking`'s. No mujoco import.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from homer_sim.home.catalog import ObjectClass
from homer_sim.home.shapes import cavity, handle_boxes
from planners.grasps.candidate import (
    FINGER_HALF_THICKNESS,
    GRIPPER_OPEN,
    MAX_WIDTH,
    PAD_HALF,
    SHELF_APPROACH,
    SHELF_PITCHES,
    SUPPORT_CLEARANCE,
    TOP_DEPTH,
    TOP_NARROW_MARGIN,
    Family,
    Grasp,
    GraspKind,
)
from planners.grasps.features import handle_grasps, pot_handle_grasps, tilted_rims
from planners.grasps.geometry import axis_rotation, extent, footprint, is_round, shelf_frame
from planners.grasps.palm import (
    PALM_MARGIN,
    along_offset,
    along_span,
    band_points,
    palm_aside,
    palm_blockers,
    palm_gap,
    palm_shift,
)
from planners.grasps.ranking import ShelfCase, rank_in_shelf, shelf_case

SIDE_HEIGHTS = (0.4, 0.75)  # fractions of an object's height at which side grasps hold it, in the order tried
# (low holds steadier; high keeps the arm clear of a low shelf's edge and within reach near the floor)
SIDE_MIN_Z = 0.035  # m above the support: the palm (0.03 m half height) clears the shelf
SIDE_MARGIN = 0.01  # m per finger between an open pad and the object before a side grasp closes
SIDE_DEPTH = 0.022  # m from an object's near face to the grip site: the palm (0.035 m behind it) stays clear
PALM_SETBACK = 0.027  # m: the palm's front face lies 0.035 m behind the grip site; 8 mm to spare
SIDE_MIN_OVERLAP = 0.015  # m of the object's depth between the pads
ROUND_PAST = 0.01  # m: the pads reach this far past a round object's centre
FACE_MIN_TURN = math.radians(3.0)  # rad an object's face must turn off the furniture's front for "-faced" grasps
ROUND_TURNS = tuple(math.radians(a) for a in (35.0, -35.0))  # rad off the furniture's front normal: slanted side
# grasps of round objects
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
    out, across, yaw = shelf_frame(outward, quat)
    width = extent(across, cls, yaw)  # along the finger travel
    depth = extent(out, cls, yaw)  # along the approach
    if width > MAX_WIDTH or sz < SIDE_MIN_Z + 0.01:
        return []
    support = position[2] - sz / 2
    rotation = np.column_stack([-out, across, np.cross(-out, across)])
    nominal = depth / 2 - SIDE_DEPTH
    if is_round(cls):  # the pads reach past the centre, or closing squeezes the object out of the hand
        nominal = min(nominal, PAD_HALF - ROUND_PAST)
    along = max(nominal, front - PALM_SETBACK)  # grip site out from the centre, m
    too_shallow = along > nominal if is_round(cls) else depth / 2 - (along - PAD_HALF) < SIDE_MIN_OVERLAP
    if too_shallow:
        return []
    heights = sorted({round(min(max(f * sz, SIDE_MIN_Z), sz - 0.015), 3) for f in SIDE_HEIGHTS},
                     key=lambda h: abs(h - SIDE_HEIGHTS[0] * sz))
    return [Grasp(np.array([position[0], position[1], support + h]) + out * along, rotation,
                  min(GRIPPER_OPEN, width / 2 + SIDE_MARGIN), GraspKind(Family.SIDE, high=k > 0))
            for k, h in enumerate(heights)]


def shelf_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray,
                 front: float = np.inf, neighbours: list[tuple[np.ndarray, float]] = ()) -> list[Grasp]:
    """Grasps of an object on a shelf inside furniture, approached from its open front, in the order
    `planners.grasps.ranking.SHELF_ORDER` gives: horizontal side grasps (see `side_grasps`; with the palm inside
    the furniture where the front part alone is too shallow to hold); approaches pitched SHELF_PITCHES down into
    the compartment with the fingers closing horizontally across the object near its top (short enough for the
    wrist to pass under the shelf above; whether it does is for a collision check of the arm); the same square
    to the object's own face nearest the front where it stands turned (see `_faced_grasps`); slanted side grasps
    of round objects (see `_turned_sides`); grasps closing front to back (see `_along_grasps`); rim pinches of
    containers (only those for wide ones, with a pot's side handles); the straight-down grasps closing front to
    back leaning aside (see `rolled_grasps`).

    outward: horizontal unit vector (shape (2,) or (3,)) out of the furniture's front; front: m from the
    object's centre to the front plane along it; neighbours: (footprint, see `footprint`; top z, m) of what
    stands beside the object on its shelf: a pitched grasp keeps the palm in front of those in its way. Best
    first; empty when no grasp fits the shape.
    """
    if cls.handle is not None:
        return handle_grasps(cls, position, quat, outward)
    sx, sy, sz = cls.size
    out, _, yaw = shelf_frame(outward, quat)
    support, top = position[2] - sz / 2, position[2] + sz / 2
    hollow = cavity(cls)
    rims = [] if hollow is None else tilted_rims(hollow, position, yaw, support, out, handle_boxes(cls))
    level = side_grasps(cls, position, quat, outward, front) or side_grasps(cls, position, quat, outward, -np.inf)
    face = _face_normal(out, yaw, cls)
    turn_cos = float(face @ out)
    case = shelf_case(cls, turn_cos)
    if hollow is not None and min(sx, sy) > MAX_WIDTH - 0.02:  # a wide container: by a pot handle or the rim
        return rank_in_shelf(level + pot_handle_grasps(cls, position, quat, out) + rims, case)
    pitched = _pitched_grasps(cls, position, quat, out, neighbours)
    grasps = level + pitched + _along_grasps(cls, position, quat, out, neighbours) + _turned_sides(cls, position,
                                                                                                   quat, out)
    if turn_cos < math.cos(FACE_MIN_TURN) or (not level + pitched and turn_cos < 1.0 - 1e-12):  # a hair off square
        grasps += _faced_grasps(cls, position, quat, out, face, front, neighbours, case is ShelfCase.TURNED)
    rolled = [r for g in grasps if g.kind.family is Family.SHELF and g.kind.pitch == 90
              and abs(g.rotation[:2, 1] @ out[:2]) >= 0.5 for r in rolled_grasps(g, support, top)]
    return rank_in_shelf(grasps + rims + rolled, case)


def _faced_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, out: np.ndarray, face: np.ndarray,
                  front: float, neighbours: list[tuple[np.ndarray, float]], halfway: bool) -> list[Grasp]:
    """Level, pitched and front-to-back grasps square to the face (outward normal `face`, shape (3,)) of an
    object standing turned off the furniture's front (normal `out`); with `halfway` (turned past
    FACE_FIRST_TURN) also those halfway between (see `_halfway_sides`). In the object's own vertical plane, the
    pads of a grasp closing front to back meet one face, not two across an edge, where the box creeps round (a
    tea box turned 19 degrees, 8 mm in 3 s). `front`, `neighbours` as for `shelf_grasps`."""
    turn_cos = float(face @ out)
    level = side_grasps(cls, position, quat, face, front / turn_cos) or side_grasps(cls, position, quat, face,
                                                                                      -np.inf)
    grasps = level + _pitched_grasps(cls, position, quat, face, neighbours) + _along_grasps(cls, position, quat,
                                                                                              face, neighbours)
    faced = [replace(g, kind=replace(g.kind, faced=True)) for g in grasps]
    return faced + (_halfway_sides(cls, position, quat, out, face, front) if halfway else [])


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
    for sign in (1, -1):
        rotation = axis_rotation(grasp.rotation[:, 1], sign * ROLL) @ grasp.rotation
        grasps.append(replace(grasp, position=position, rotation=rotation, approach=approach,
                              kind=replace(grasp.kind, roll=sign)))
    return grasps


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
    return [replace(g, kind=replace(g.kind, halfway=True)) for g in grasps]


def _pitched_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray,
                    neighbours: list[tuple[np.ndarray, float]] = ()) -> list[Grasp]:
    """Grasps approached SHELF_PITCHES down against `outward` (shape (3,)), the fingers closing horizontally
    across the object near its top (from straight above also along the approach); the palm's low front edge
    stays PALM_MARGIN in front of the object and of the `neighbours` (footprints) in its way; see `shelf_grasps`.
    """
    out, across, yaw = shelf_frame(outward, quat)
    own = (footprint(cls, position, quat), position[2] + cls.size[2] / 2)
    blockers = palm_blockers([own, *neighbours], position, out, across)
    support, top = position[2] - cls.size[2] / 2, position[2] + cls.size[2] / 2
    grasps = []
    for pitch in SHELF_PITCHES[1:]:
        x = math.cos(pitch) * -out + np.array([0.0, 0.0, -math.sin(pitch)])
        for y in (across, np.cross(across, x))[: 2 if pitch == SHELF_PITCHES[-1] else 1]:
            width = extent(y, cls, yaw)
            if width > MAX_WIDTH:
                continue
            tip_drop = PAD_HALF * math.sin(pitch) + FINGER_HALF_THICKNESS * math.cos(pitch)
            z = max(top - TOP_DEPTH, support + tip_drop + SUPPORT_CLEARANCE)
            depth = extent(out, cls, yaw)
            shift = 0.0 if pitch == SHELF_PITCHES[-1] else palm_shift(pitch, z, blockers)
            aside, kind = 0.0, GraspKind(Family.SHELF, pitch=round(math.degrees(pitch)))
            if shift > depth / 2 - SIDE_MIN_OVERLAP / 2:  # the pads would hold only the front edge
                moved = palm_aside(pitch, z, [own, *neighbours], position, out, across, width,
                                   depth / 2 - SIDE_MIN_OVERLAP / 2)
                if moved is None:
                    continue
                aside, shift = moved
                kind = replace(kind, aside=True)
            centre = np.array([position[0], position[1], z]) + out * shift + aside * across
            opening = min(GRIPPER_OPEN, width / 2 + abs(aside) + 0.025)
            grasps.append(Grasp(centre, np.column_stack([x, y, np.cross(x, y)]), opening, kind, SHELF_APPROACH))
    return grasps


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
    out, across, yaw = shelf_frame(outward, quat)
    depth = extent(out, cls, yaw)
    near = [a for a, o in band_points(neighbours, position, out, across) if o > -depth / 2 - ALONG_BEHIND]
    if any(abs(a) < FINGER_HALF_THICKNESS + PALM_MARGIN for a in near):
        return []
    reach = ROUND_PAST if is_round(cls) else extent(across, cls, yaw) / 2 - FINGER_HALF_THICKNESS
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
                            GraspKind(Family.SHELF, pitch=round(math.degrees(pitch)), along=True), SHELF_APPROACH))
    return grasps


def _turned_sides(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray) -> list[Grasp]:
    """Side grasps of a round object approached ROUND_TURNS off `outward`: next to a furniture's side wall
    the 18 cm palm clears it only coming in at a slant (the fingers still close across the diameter)."""
    if not is_round(cls):
        return []
    grasps = []
    for turn in ROUND_TURNS:
        c, s = math.cos(turn), math.sin(turn)
        turned = np.array([c * outward[0] - s * outward[1], s * outward[0] + c * outward[1]])
        grasps += [replace(g, kind=replace(g.kind, slant=round(math.degrees(turn))))
                   for g in side_grasps(cls, position, quat, turned, -np.inf)]
    return grasps


def _face_normal(out: np.ndarray, yaw: float, cls: ObjectClass) -> np.ndarray:
    """The outward normal (shape (3,)) of the object's side face nearest horizontal unit `out` (shape (3,)),
    the object turned by `yaw` rad; a round object's is `out` itself."""
    if is_round(cls):
        return out
    face = max((yaw + k * math.pi / 2 for k in range(4)), key=lambda a: math.cos(a) * out[0] + math.sin(a) * out[1])
    return np.array([math.cos(face), math.sin(face), 0.0])
