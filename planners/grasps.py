"""Grasp poses for an object's shape: top grasps across its narrow side, and rim pinches for open containers.

A grasp is the grip site's world pose at the moment the fingers close: position (m) and rotation matrix
(shape (3, 3), columns = grip x (approach, out of the palm), y (finger travel), z). No mujoco import.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from homer_sim.catalog import ObjectClass
from homer_sim.shapes import WALL_THICKNESS, cavity, handle_boxes

MAX_WIDTH = 0.15  # m: widest grasp (stroke 0.16 m minus a margin)
MIN_HEIGHT = 0.008  # m: thinner objects leave the pads nothing to hold above the support
PAD_HALF = 0.025  # m: half length of a finger pad along the approach axis
SUPPORT_CLEARANCE = 0.003  # m between the fingertips and the supporting surface
SIDE_HEIGHTS = (0.4, 0.75)  # fractions of an object's height at which side grasps hold it, in the order tried
# (low holds steadier; high keeps the arm clear of a low shelf's edge and within reach near the floor)
SIDE_MIN_Z = 0.035  # m above the support: the palm (0.03 m half height) clears the shelf
SIDE_MARGIN = 0.01  # m per finger between an open pad and the object before a side grasp closes
SIDE_DEPTH = 0.022  # m from an object's near face to the grip site: the palm (0.035 m behind it) stays clear
PALM_SETBACK = 0.027  # m: the palm's front face lies 0.035 m behind the grip site; 8 mm to spare
SIDE_MIN_OVERLAP = 0.015  # m of the object's depth between the pads
ROUND_PAST = 0.01  # m: the pads reach this far past a round object's centre
FACE_MIN_TURN = math.radians(3.0)  # rad an object's face must turn off the furniture's front for "-faced" grasps
FACE_FIRST_TURN = math.radians(8.0)  # rad beyond which "-faced" grasps go first: pads closing on a box turned
# further turn it between them, and it keeps turning in the hand
ROUND_TURNS = tuple(math.radians(a) for a in (35.0, -35.0))  # rad off the furniture's front normal: slanted side
# grasps of round objects
GRIPPER_OPEN = 0.08  # m per finger, the gripper's stroke
SHELF_PITCHES = (0.0, math.radians(30), math.radians(45), math.radians(60), math.radians(90))  # rad below the
# horizontal of an in-furniture grasp's approach: 0 is the side grasp, 90 degrees straight down
FINGER_HALF_THICKNESS = 0.016  # m: half the finger links' extent across the pads' plane
TOP_DEPTH = 0.02  # m: a grasp from above holds this far below the object's top
SHELF_APPROACH = 0.05  # m: the approach onto a grasp under a shelf
PALM_LOW_EDGE = (0.035, 0.03)  # m: the palm's front-low edge lies this far behind the grip site and off its z
PALM_MARGIN = 0.01  # m between the palm's low edge and an object's front face
ROUND_FAMILIES = ("cylinder", "sphere", "cup", "bowl")  # families whose upright footprint is a disk
TOP_MARGIN = 0.025  # m per finger between an open pad and the object before a grasp from above closes,
TOP_NARROW_MARGIN = 0.005  # m: the same where a neighbour stands too close for the wide opening
HANDLE_APPROACH = 0.06  # m: the approach onto a handle from above (nothing else stands as high)
PALM_HALF_WIDTH = 0.09  # m: half the palm's extent along the finger travel
PALM_HALF_THICKNESS = 0.03  # m: half the palm's extent across the pads' plane (normal to the finger travel)
ALONG_BEHIND = 0.12  # m behind an object's back the in-finger and the palm's upper corner of an "-along" grasp
# may reach: a neighbour standing further back is out of their way
ROUND_POINTS = 16  # points on the outline of a round footprint
OFFSET_MARGIN = 0.005  # m between the object and the near finger of an off-centre grasp, opened wide
OFFSET_MIN = 0.01  # m: off-centre grasps that move the palm less are not worth a try
RIM_DEPTH = 0.015  # m below the rim of the grip site of a rim pinch (a flared wall leans away lower down)
RIM_DEEP = PAD_HALF + 0.003  # m: the same on a straight wall: the pads' whole length on it, their top ends
# 3 mm under the rim (the palm 7 mm above it)
RIM_CLEARANCE = 0.03  # m the hand rises a straight-walled container's far bottom edge above its support
POT_HANDLE_FACING = math.radians(60.0)  # rad: a pot's side handle is taken from the front when it points at
# most this far off the furniture's front normal
POT_HANDLE_GAP = 0.003  # m between the pads' inner ends and the pot's wall
POT_HANDLE_MARGIN = 0.015  # m per finger between an open pad and the handle plate
POT_HANDLE_PITCHES = (math.radians(30.0), math.radians(45.0), math.radians(60.0))  # rad below the horizontal
ROLL = math.radians(40.0)  # rad a straight-down shelf grasp closing front to back leans sideways ("-rolled"): the
# wrist, 0.29 m up the grip x, comes 0.29 (1 - cos ROLL) m lower, under a low shelf above a flat object
ROLL_TIP_CLEARANCE = 0.005  # m the open fingertips of a "-rolled" grasp pass over the object's top on the way in
DISTURBED_MOVE = 0.005  # m an object must have moved for a failed grasp to count as having shoved it
DISTURBED_TURN = math.radians(3.0)  # rad: the same for a turn about the vertical
HANG_RISE = 0.15  # m a hung object's centre is to end above where it stood (its drop as it swings added)


@dataclass(frozen=True)
class Grasp:
    """A grip-site pose in world coordinates, the finger opening before closing (m per finger), a label, the
    approach and the least lift."""

    position: np.ndarray
    rotation: np.ndarray
    pre_opening: float
    kind: str
    approach: float = 0.12  # m the gripper travels along its x axis onto the grasp (short inside furniture)
    lift: float = 0.0  # m the hand rises at least in all after closing (the last upward leg lengthened; out
    # of a drawer, past its front)
    hang: bool = False  # lifted, the hand turns about its z axis until the object hangs (see `hang_rotation`)

    def quat(self) -> np.ndarray:
        """The rotation as a unit wxyz quaternion."""
        return matrix_to_quat(self.rotation)


def matrix_to_quat(r: np.ndarray) -> np.ndarray:
    """Unit wxyz quaternion of a rotation matrix (shape (3, 3)), w >= 0; exact for half turns too (Shepperd's
    method: the largest of w, x, y, z is taken from the diagonal, the others from the off-diagonal terms)."""
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    k = int(np.argmax([trace, r[0, 0], r[1, 1], r[2, 2]]))
    if k == 0:
        s = 2.0 * math.sqrt(max(1.0 + trace, 0.0))
        q = np.array([s / 4, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s])
    elif k == 1:
        s = 2.0 * math.sqrt(max(1.0 + r[0, 0] - r[1, 1] - r[2, 2], 0.0))
        q = np.array([(r[2, 1] - r[1, 2]) / s, s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s])
    elif k == 2:
        s = 2.0 * math.sqrt(max(1.0 - r[0, 0] + r[1, 1] - r[2, 2], 0.0))
        q = np.array([(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s])
    else:
        s = 2.0 * math.sqrt(max(1.0 - r[0, 0] - r[1, 1] + r[2, 2], 0.0))
        q = np.array([(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4])
    q = q if q[0] >= 0 else -q
    return q / np.linalg.norm(q)


def slerp(q0: np.ndarray, q1: np.ndarray, s: float) -> np.ndarray:
    """The unit wxyz quaternion a fraction `s` (0..1) of the way from q0 to q1 along the shorter arc."""
    q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
    dot = float(np.dot(q0, q1))
    if dot < 0.0:
        q1, dot = -q1, -dot
    angle = math.acos(min(dot, 1.0))
    if angle < 1e-6:
        return q1 / np.linalg.norm(q1)
    q = (math.sin((1.0 - s) * angle) * q0 + math.sin(s * angle) * q1) / math.sin(angle)
    return q / np.linalg.norm(q)


def top_rotation(finger_yaw: float) -> np.ndarray:
    """Grip x pointing down, fingers closing along the horizontal direction at `finger_yaw` (rad)."""
    x = np.array([0.0, 0.0, -1.0])
    y = np.array([math.cos(finger_yaw), math.sin(finger_yaw), 0.0])
    return np.column_stack([x, y, np.cross(x, y)])


def ungraspable_reason(cls: ObjectClass) -> str | None:
    """Why a parallel gripper cannot pick this class from a surface, or None if it can."""
    sx, sy, sz = cls.size
    if sz < MIN_HEIGHT:
        return f"flat, {sz * 1000:.0f} mm thin: thinner than {MIN_HEIGHT * 1000:.0f} mm"
    if cls.is_container:
        return None if cavity(cls) is not None else "container without a cavity"
    if cls.handle is not None:  # taken by its grip feature
        width = min(cls.handle[:2])
        return None if width <= MAX_WIDTH else f"its {width * 100:.0f} cm handle is wider than the grasp"
    if min(sx, sy) > MAX_WIDTH:
        return f"{min(sx, sy) * 100:.0f} cm across its narrow side, wider than the {MAX_WIDTH * 100:.0f} cm grasp"
    return None


def top_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, robot_xy: np.ndarray) -> list[Grasp]:
    """Grasp candidates from above for an upright object at `position` (m, body centre) with body `quat`
    (wxyz), best first: across its narrow side, then turned a quarter, the fingers open TOP_MARGIN past it, then
    both again opened only TOP_NARROW_MARGIN past it; rim pinches for containers (on the rim nearest the robot
    at `robot_xy`)."""
    if cls.handle is not None:
        return handle_grasps(cls, position, quat)
    sx, sy, sz = cls.size
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    support = position[2] - sz / 2
    top = position[2] + sz / 2
    grip_z = max(top - 0.02, support + PAD_HALF + SUPPORT_CLEARANCE)
    hollow = cavity(cls)
    if hollow is not None and min(sx, sy) > MAX_WIDTH - 0.02:
        return _rim_grasps(hollow, position, yaw, support, robot_xy)
    grasps = []
    narrow = yaw + (math.pi / 2 if sy < sx else 0.0)  # fingers close along the narrow side
    width = min(sx, sy)
    centre = np.array([position[0], position[1], grip_z])
    for margin, suffix in ((TOP_MARGIN, ""), (TOP_NARROW_MARGIN, "-narrow")):
        for finger_yaw, kind in ((narrow, "top"), (narrow + math.pi / 2, "top-turned")):
            span = width if kind == "top" else max(sx, sy)
            if span <= MAX_WIDTH:
                grasps.append(Grasp(centre, top_rotation(finger_yaw), min(GRIPPER_OPEN, span / 2 + margin),
                                    kind + suffix))
    return grasps


def handle_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray,
                  outward: np.ndarray | None = None) -> list[Grasp]:
    """Grasps of the grip feature on top of an upright object of a class with one (`ObjectClass.handle`), at
    `position` (m, body centre) with body `quat` (wxyz), best first. The fingertips stop SUPPORT_CLEARANCE
    above the body under the feature.

    On an open top (`outward` None): from straight above, the fingers closing across the feature's width, open
    TOP_MARGIN past it, then TOP_NARROW_MARGIN; a square feature (a tie) also turned a quarter. Inside furniture
    (`outward`, a horizontal unit vector out of its front, shape (2,) or (3,)): approached SHELF_PITCHES down
    against `outward` (not level: the hand must come over the body), the fingers closing along the front.
    """
    length, width, height = cls.handle
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    top = position[2] + cls.size[2] / 2
    if outward is None:
        centre = np.array([position[0], position[1], max(top - TOP_DEPTH, top - height + PAD_HALF + SUPPORT_CLEARANCE)])
        turns = ((0.0, width), (math.pi / 2, length)) if length <= MAX_WIDTH else ((0.0, width),)
        return [Grasp(centre, top_rotation(yaw + math.pi / 2 + turn), min(GRIPPER_OPEN, span / 2 + margin),
                      f"handle{'-turned' if turn else ''}{suffix}", HANDLE_APPROACH)
                for margin, suffix in ((TOP_MARGIN, ""), (TOP_NARROW_MARGIN, "-narrow")) for turn, span in turns]
    out, across, _ = _shelf_frame(outward, quat)
    span = _box_extent(across, length, width, yaw)  # the feature's extent along the front
    if span > MAX_WIDTH:
        return []
    grasps = []
    for pitch in SHELF_PITCHES[1:]:
        x = math.cos(pitch) * -out + np.array([0.0, 0.0, -math.sin(pitch)])
        tip_drop = PAD_HALF * math.sin(pitch) + FINGER_HALF_THICKNESS * math.cos(pitch)
        z = max(top - TOP_DEPTH, top - height + tip_drop + SUPPORT_CLEARANCE)
        grasps.append(Grasp(np.array([position[0], position[1], z]), np.column_stack([x, across, np.cross(x, across)]),
                            min(GRIPPER_OPEN, span / 2 + TOP_MARGIN), f"handle-{math.degrees(pitch):.0f}",
                            SHELF_APPROACH))
    return grasps


def offset_grasps(cls: ObjectClass, quat: np.ndarray, grasp: Grasp) -> list[Grasp]:
    """`grasp` (from above) moved off the object's centre along the finger travel, either way, the fingers
    opened fully (GRIPPER_OPEN) so the near one still passes OFFSET_MARGIN beside the object: the 18 cm palm
    keeps clear of a wall or a drawer side on the other side; closing, the near finger slides the object
    (body `quat`, wxyz) to the middle. Empty where that moves the palm less than OFFSET_MIN."""
    y = grasp.rotation[:, 1]
    shift = GRIPPER_OPEN - _extent(y, cls, 2.0 * math.atan2(quat[3], quat[0])) / 2 - OFFSET_MARGIN
    if shift < OFFSET_MIN:
        return []
    return [replace(grasp, position=grasp.position + sign * shift * y, pre_opening=GRIPPER_OPEN,
                    kind=f"{grasp.kind}-offset{'+' if sign > 0 else '-'}") for sign in (1.0, -1.0)]


def rim_approach(grasp: Grasp, rim: float, clearance: float) -> float:
    """How far (m) a grasp from above (grip x straight down) inside a drawer approaches: at least
    `grasp.approach`, and far enough that the open fingertips (PAD_HALF below the grip site) start `clearance` m
    above the top of the drawer's front at `rim` (m): the hand then comes over the front, not into it (a finger
    striking it pushes the drawer shut and the object with it)."""
    return max(grasp.approach, rim + clearance + PAD_HALF - float(grasp.position[2]))


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


def disturbed(position: np.ndarray, quat: np.ndarray, now: np.ndarray, quat_now: np.ndarray) -> bool:
    """Whether an object that stood at `position` (m) turned `quat` (wxyz) and now stands at `now` turned
    `quat_now` has moved more than DISTURBED_MOVE or turned more than DISTURBED_TURN about the vertical: grasps
    planned for where it stood would pinch it off centre (a failed side grasp turns a box between the pads)."""
    turn = 2.0 * (math.atan2(quat_now[3], quat_now[0]) - math.atan2(quat[3], quat[0]))
    turn = abs(math.remainder(turn, 2.0 * math.pi))
    return bool(np.linalg.norm(np.asarray(now) - np.asarray(position)) > DISTURBED_MOVE or turn > DISTURBED_TURN)


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


def footprint(cls: ObjectClass, position: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """The outline of an upright object's footprint at `position` (m) turned by body `quat` (wxyz): world xy
    points (m, shape (n, 2)), the box's four corners or ROUND_POINTS on a round one's circle."""
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    if _round(cls):
        angles = np.linspace(0.0, 2.0 * math.pi, ROUND_POINTS, endpoint=False)
        local = cls.size[0] / 2 * np.column_stack([np.cos(angles), np.sin(angles)])
    else:
        local = np.array([[sx, sy] for sx in (-1, 1) for sy in (-1, 1)])[[0, 1, 3, 2]] * np.asarray(cls.size[:2]) / 2
    c, s = math.cos(yaw), math.sin(yaw)
    return np.asarray(position[:2]) + local @ np.array([[c, s], [-s, c]])


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


def _shelf_frame(outward: np.ndarray, quat: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(out, across, yaw): the horizontal unit vector out of the furniture's front (shape (3,)), the one along
    its front (shape (3,)), and the object's yaw (rad) from its body `quat` (wxyz, upright)."""
    out = np.array([outward[0], outward[1], 0.0]) / np.linalg.norm(outward[:2])
    return out, np.array([-out[1], out[0], 0.0]), 2.0 * math.atan2(quat[3], quat[0])


def _face_normal(out: np.ndarray, yaw: float, cls: ObjectClass) -> np.ndarray:
    """The outward normal (shape (3,)) of the object's side face nearest horizontal unit `out` (shape (3,)),
    the object turned by `yaw` rad; a round object's is `out` itself."""
    if _round(cls):
        return out
    face = max((yaw + k * math.pi / 2 for k in range(4)), key=lambda a: math.cos(a) * out[0] + math.sin(a) * out[1])
    return np.array([math.cos(face), math.sin(face), 0.0])


def _round(cls: ObjectClass) -> bool:
    """Whether the class stands on a round footprint (its horizontal extent is its diameter at any yaw)."""
    return cls.family in ROUND_FAMILIES and cls.size[0] == cls.size[1]


def _extent(direction: np.ndarray, cls: ObjectClass, yaw: float) -> float:
    """Extent (m) along horizontal unit `direction` (shape (3,)) of the footprint of `cls` turned by `yaw`."""
    if _round(cls):
        return cls.size[0]
    return _box_extent(direction, cls.size[0], cls.size[1], yaw)


def _box_extent(direction: np.ndarray, sx: float, sy: float, yaw: float) -> float:
    """Extent (m) along horizontal unit `direction` (shape (3,)) of an sx by sy m rectangle turned by `yaw`
    rad, to the micrometre (a box square to `direction` measures its side, not a hair more)."""
    return round(abs(direction[0] * math.cos(yaw) + direction[1] * math.sin(yaw)) * sx + abs(
        -direction[0] * math.sin(yaw) + direction[1] * math.cos(yaw)) * sy, 6)


def _tilted_rims(hollow, position: np.ndarray, yaw: float, support: float, out: np.ndarray) -> list[Grasp]:
    """Pinches of a wide container's front rim from the compartment's front, pitched down SHELF_PITCHES (not
    horizontal), the fingers closing across the wall along the outward direction."""
    c, s = math.cos(yaw), math.sin(yaw)
    centre = position[:2] + np.array([c * hollow.center_xy[0] - s * hollow.center_xy[1],
                                      s * hollow.center_xy[0] + c * hollow.center_xy[1]])
    rim_z = position[2] + hollow.rim_z
    across = np.array([-out[1], out[0], 0.0])
    grasps = []
    for pitch in SHELF_PITCHES[:0:-1]:
        x = math.cos(pitch) * -out + np.array([0.0, 0.0, -math.sin(pitch)])
        y = np.cross(across, x)  # in the vertical plane of the approach, pointing out of the compartment
        xy = centre + out[:2] * (hollow.rim_radius + 0.004)
        z = max(rim_z - 0.015, support + PAD_HALF + SUPPORT_CLEARANCE)
        grasps.append(Grasp(np.array([xy[0], xy[1], z]), np.column_stack([x, y, np.cross(x, y)]), 0.03,
                            f"rim-{math.degrees(pitch):.0f}", SHELF_APPROACH))
    return grasps


def _rim_grasps(hollow, position: np.ndarray, yaw: float, support: float, robot_xy: np.ndarray) -> list[Grasp]:
    """Pinches of a container's wall at the rim, the fingers closing radially: the rim point nearest the robot
    at `robot_xy` first, then 30 degrees either side. A straight wall (a bin) is pinched RIM_DEEP at the rim
    point farthest from the robot instead: held at one point of its rim, the container's weight tilts it about
    the tangent there (a 44 cm bin some 20 degrees, its far side on the floor after a 15 cm lift) and keeps it
    creeping round in the pads while its centre of mass is off to the side (4-5 mm in 3 s); so the hand rises
    `rim_lift` (the lowest edge clears the floor; at least `hang_lift`) and turns towards where the container
    would hang (`hang`, see `hang_rotation`), its bottom swinging away from the robot (from the near rim it
    swings onto the robot's base). Seen in the grasp suite: the 44 cm bin turns only part of the way, the pads
    turn about its wall and jam it (slip under 1 mm)."""
    c, s = math.cos(yaw), math.sin(yaw)
    centre = position[:2] + np.array([c * hollow.center_xy[0] - s * hollow.center_xy[1],
                                      s * hollow.center_xy[0] + c * hollow.center_xy[1]])
    toward = math.atan2(robot_xy[1] - centre[1], robot_xy[0] - centre[0])
    rim_z = position[2] + hollow.rim_z
    straight = _straight(hollow)
    z = max(rim_z - (RIM_DEEP if straight else RIM_DEPTH), support + PAD_HALF + SUPPORT_CLEARANCE)
    lift = 0.0
    if straight:  # the grip site lies rim_radius out and z - position[2] up from the body centre
        lift = max(rim_lift(hollow, rim_z - support, rim_z - z),
                   hang_lift(np.array([hollow.rim_radius + 0.004, 0.0, z - position[2]])))
    grasps = []
    for delta in (0.0, math.radians(30), -math.radians(30)):
        angle = toward + delta + (math.pi if straight else 0.0)
        radial = np.array([math.cos(angle), math.sin(angle)])
        xy = centre + radial * (hollow.rim_radius + 0.004)
        grasps.append(Grasp(np.array([xy[0], xy[1], z]), top_rotation(angle), 0.03, "rim", lift=lift,
                            hang=straight))
    return grasps


def _straight(hollow) -> bool:
    """Whether a container's inner wall is vertical (as wide at the floor as at the rim)."""
    return abs(hollow.floor_radius - hollow.rim_radius) < 1e-6


def rim_lift(hollow, height: float, depth: float) -> float:
    """How far (m) the hand must rise after pinching a straight-walled container of `height` m at `depth` m
    below its rim so that, whatever it tilts about the pinch, its far bottom edge stays RIM_CLEARANCE above
    the support: the grip site ends the edge's distance from it (the wall's diameter by its height) above."""
    far = math.hypot(2.0 * hollow.rim_radius, height - depth)
    return float(far + RIM_CLEARANCE - (height - depth))


def hang_lift(offset: np.ndarray) -> float:
    """How far (m) the hand must rise so that an object gripped `offset` (m, shape (3,)) from its centre ends
    with its centre HANG_RISE above where it stood once it hangs straight below the grip site."""
    return float(HANG_RISE + np.linalg.norm(offset) - offset[2])


def hang_rotation(rotation: np.ndarray, grip: np.ndarray, com: np.ndarray) -> np.ndarray:
    """The grip rotation (shape (3, 3)) turned about the grip site, by the least turn (about a horizontal axis),
    until a held object's centre of mass `com` (m, shape (3,)) lies straight below the grip site `grip` (m,
    shape (3,)), the object turning with the hand: then its weight pulls through the grasp instead of twisting
    it (a rim pinch's pads hold that twist only while they creep)."""
    v = (com - grip) / np.linalg.norm(com - grip)
    down = np.array([0.0, 0.0, -1.0])
    axis = np.cross(v, down)
    sin, cos = float(np.linalg.norm(axis)), float(v @ down)
    if sin < 1e-9:
        return rotation.copy()
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]]) / sin
    turn = np.eye(3) + sin * k + (1.0 - cos) * k @ k  # Rodrigues
    return turn @ rotation


def pot_handle_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray) -> list[Grasp]:
    """Grasps of an upright pot at `position` (m, body centre; body `quat`, wxyz) by a flat side handle (see
    `homer_sim.shapes.handle_boxes`) pointing within POT_HANDLE_FACING of horizontal unit `outward` (shape (3,),
    out of the furniture's front), along the handle towards the pot: first level, the fingers closing
    vertically on the plate (the pads' length along it); then pitched POT_HANDLE_PITCHES down, the fingers
    closing across the plate's width on its side faces (a level hand that low is often out of the arm's reach
    from a base pose clear of the cabinet). The pads end POT_HANDLE_GAP short of the wall. Lifted, the hand
    turns until the pot hangs (`hang`): a 1.5 kg pot held 13 cm out twists in the pads."""
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    c, s = math.cos(yaw), math.sin(yaw)
    body = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    up = np.array([0.0, 0.0, 1.0])
    grasps = []
    for centre, half in handle_boxes(cls):
        h = body @ np.array([math.copysign(1.0, centre[0]), 0.0, 0.0])  # horizontal, out along the handle
        if float(h @ outward) < math.cos(POT_HANDLE_FACING):
            continue
        face = abs(centre[0]) - half[0] + WALL_THICKNESS[cls.family]  # m from the axis: the wall's outer face
        for pitch in (0.0, *POT_HANDLE_PITCHES):
            x = -math.cos(pitch) * h - math.sin(pitch) * up
            y = up if pitch == 0.0 else np.cross(up, h)
            # the grip site: the pads' low inner end POT_HANDLE_GAP off the wall, at least half of them on the plate
            along = min(face + POT_HANDLE_GAP + PAD_HALF * math.cos(pitch), abs(centre[0]) + half[0])
            offset = body @ np.array([0.0, centre[1], centre[2]]) + h * along  # from the body centre
            opening = (half[2] if pitch == 0.0 else half[1]) + POT_HANDLE_MARGIN
            grasps.append(Grasp(position + offset, np.column_stack([x, y, np.cross(x, y)]), opening,
                                f"pot-handle-{math.degrees(pitch):.0f}", SHELF_APPROACH, lift=hang_lift(offset),
                                hang=True))
    return grasps
