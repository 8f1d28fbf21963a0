"""Grasps from above of an upright object on an open top: across its narrow side, then turned a quarter; off centre
with the fingers opened wide; and how far one comes in over a drawer's front. An object with a grip feature, and a
wide container, are taken as `planners.grasps.features` says. No mujoco import.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from homer_sim.home.catalog import ObjectClass
from homer_sim.home.shapes import cavity, handle_boxes
from planners.grasps.candidate import (
    GRIPPER_OPEN,
    MAX_WIDTH,
    OFFSET_MARGIN,
    PAD_HALF,
    SUPPORT_CLEARANCE,
    TOP_MARGIN,
    TOP_NARROW_MARGIN,
    Family,
    Grasp,
    GraspKind,
)
from planners.grasps.features import handle_grasps, rim_grasps
from planners.grasps.geometry import extent, is_round, top_rotation

OFFSET_MIN = 0.01  # m: off-centre grasps that move the palm less are not worth a try
RAISED_HOLD = 0.015  # m of an object's top that the pads of a raised grasp hold
RAISE_MIN = 0.005  # m: grasps raised less than this are not worth a try
LYING_TILT = math.radians(15.0)  # rad a fallen object's resting face may lean off the level to be grasped as it lies
SQUARE_MIN_TURN = math.radians(3.0)  # rad a grasp from above must turn to square the palm to a drawer's walls for
# a squared grasp to be worth a try


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
        return rim_grasps(hollow, position, yaw, support, robot_xy, handle_boxes(cls))
    grasps = []
    narrow = yaw + (math.pi / 2 if sy < sx else 0.0)  # fingers close along the narrow side
    width = min(sx, sy)
    centre = np.array([position[0], position[1], grip_z])
    for margin, opened_narrow in ((TOP_MARGIN, False), (TOP_NARROW_MARGIN, True)):
        for finger_yaw, turned in ((narrow, False), (narrow + math.pi / 2, True)):
            span = max(sx, sy) if turned else width
            if span <= MAX_WIDTH:
                grasps.append(Grasp(centre, top_rotation(finger_yaw), min(GRIPPER_OPEN, span / 2 + margin),
                                    GraspKind(Family.TOP, turned=turned, narrow=opened_narrow)))
    return grasps


def lying_as(cls: ObjectClass, rotation: np.ndarray) -> tuple[ObjectClass, float] | None:
    """A solid object (no grip feature, no cavity) that has fallen over and rests on a side, with body `rotation`
    (shape (3, 3)), described as an upright box of the extents it has as it lies: (that class, the yaw of its
    body x, rad), for the grasps from above of an upright object (`top_grasps`); None where it lies otherwise (a
    box on an edge) or is no such object. A cylinder on its side lies with its axis level at any roll."""
    if cls.handle is not None or cls.is_container:
        return None
    sizes = np.asarray(cls.size, dtype=float)
    if is_round(cls):
        if abs(rotation[2, 2]) > math.sin(LYING_TILT):
            return None
        axes, extents = (2, 0, 0), (sizes[2], sizes[0], sizes[0])
    else:
        down = int(np.argmax(np.abs(rotation[2])))
        if abs(rotation[2, down]) < math.cos(LYING_TILT):
            return None
        axes = tuple(k for k in range(3) if k != down) + (down,)
        extents = tuple(sizes[k] for k in axes)
    yaw = math.atan2(rotation[1, axes[0]], rotation[0, axes[0]])
    return replace(cls, family="box", size=tuple(float(e) for e in extents)), yaw


def squared_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, wall_yaw: float) -> list[Grasp]:
    """The grasps from above of a box (see `top_grasps`) turned about the vertical, each the least, until the
    finger travel lies along `wall_yaw` (rad, the direction of a drawer's front normal) or square to it
    ("squared"), opened as far past the box's extent along the new travel: a palm turned with a box (up to 20
    degrees in a drawer) sweeps its 9 cm half length up to 3 cm sideways, into the wall beside a box in a
    corner; squared, it and its offset grasps (see `offset_grasps`) keep parallel to the walls. The pads meet
    two corners first and turn the box square as they close. Empty for round objects; none for a grasp less
    than SQUARE_MIN_TURN off square or wider than MAX_WIDTH squared."""
    if is_round(cls) or cls.handle is not None:
        return []
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    grasps = []
    for grasp in top_grasps(cls, position, quat, np.asarray(position[:2])):
        if grasp.kind.family is not Family.TOP:  # rim pinches of containers
            continue
        finger_yaw = math.atan2(grasp.rotation[1, 1], grasp.rotation[0, 1])
        turn = math.remainder(finger_yaw - wall_yaw, math.pi / 2)
        rotation = top_rotation(finger_yaw - turn)
        span = extent(rotation[:, 1], cls, yaw)
        if abs(turn) < SQUARE_MIN_TURN or span > MAX_WIDTH:
            continue
        margin = TOP_NARROW_MARGIN if grasp.kind.narrow else TOP_MARGIN
        grasps.append(replace(grasp, rotation=rotation, pre_opening=min(GRIPPER_OPEN, span / 2 + margin),
                              kind=replace(grasp.kind, squared=True)))
    return grasps


def raised_grasps(cls: ObjectClass, position: np.ndarray, grasps: list[Grasp]) -> list[Grasp]:
    """Copies of `grasps` from above (see `top_grasps`, `squared_grasps`) of a low object at `position` (m, body
    centre), those whose fingertips come down to SUPPORT_CLEARANCE over its support, with the grip site raised
    until the pads hold only RAISED_HOLD m of the object's top ("raised"): the fingertips, PAD_HALF below the
    grip site, then pass over a low neighbour lying close beside it (a CD flat beside a charger). None raised
    less than RAISE_MIN."""
    support = position[2] - cls.size[2] / 2
    z = position[2] + cls.size[2] / 2 - RAISED_HOLD + PAD_HALF
    return [replace(g, position=np.array([g.position[0], g.position[1], z]), kind=replace(g.kind, raised=True))
            for g in grasps if g.kind.family is Family.TOP and z - g.position[2] >= RAISE_MIN
            and g.position[2] - PAD_HALF <= support + SUPPORT_CLEARANCE + 1e-9]


def offset_grasps(cls: ObjectClass, quat: np.ndarray, grasp: Grasp) -> list[Grasp]:
    """`grasp` (from above) moved off the object's centre along the finger travel, either way, the fingers
    opened fully (GRIPPER_OPEN) so the near one still passes OFFSET_MARGIN beside the object: the 18 cm palm
    keeps clear of a wall or a drawer side on the other side; closing, the near finger slides the object
    (body `quat`, wxyz) to the middle. Empty where that moves the palm less than OFFSET_MIN."""
    y = grasp.rotation[:, 1]
    shift = GRIPPER_OPEN - extent(y, cls, 2.0 * math.atan2(quat[3], quat[0])) / 2 - OFFSET_MARGIN
    if shift < OFFSET_MIN:
        return []
    return [replace(grasp, position=grasp.position + sign * shift * y, pre_opening=GRIPPER_OPEN,
                    kind=replace(grasp.kind, offset=sign)) for sign in (1, -1)]


def rim_approach(grasp: Grasp, rim: float, clearance: float) -> float:
    """How far (m) a grasp from above (grip x straight down) inside a drawer approaches: at least
    `grasp.approach`, and far enough that the open fingertips (PAD_HALF below the grip site) start `clearance` m
    above the top of the drawer's front at `rim` (m): the hand then comes over the front, not into it (a finger
    striking it pushes the drawer shut and the object with it)."""
    return max(grasp.approach, rim + clearance + PAD_HALF - float(grasp.position[2]))
