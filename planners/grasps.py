"""What a grasp is (`Grasp`), the gripper's numbers and the shape helpers the grasp modules share.

A grasp is the grip site's world pose at the moment the fingers close: position (m) and rotation matrix
(shape (3, 3), columns = grip x (approach, out of the palm), y (finger travel), z). The candidates for an object's
shape come from `planners.top_grasps` (from above), `planners.shelf_grasps` (inside furniture, from its front) and
`planners.container_grasps` (grip features, rims, a pot's side handles). Also here: why a class cannot be picked,
and whether a failed grasp shoved its object. No mujoco import.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from homer_sim.home.catalog import ObjectClass
from homer_sim.home.shapes import cavity

MAX_WIDTH = 0.15  # m: widest grasp (stroke 0.16 m minus a margin)
MIN_HEIGHT = 0.008  # m: thinner objects leave the pads nothing to hold above the support
PAD_HALF = 0.025  # m: half length of a finger pad along the approach axis
SUPPORT_CLEARANCE = 0.003  # m between the fingertips and the supporting surface
GRIPPER_OPEN = 0.08  # m per finger, the gripper's stroke
SHELF_PITCHES = (0.0, math.radians(30), math.radians(45), math.radians(60), math.radians(90))  # rad below the
# horizontal of an in-furniture grasp's approach: 0 is the side grasp, 90 degrees straight down
FINGER_HALF_THICKNESS = 0.016  # m: half the finger links' extent across the pads' plane
TOP_DEPTH = 0.02  # m: a grasp from above holds this far below the object's top
SHELF_APPROACH = 0.05  # m: the approach onto a grasp under a shelf
ROUND_FAMILIES = ("cylinder", "sphere", "cup", "bowl")  # families whose upright footprint is a disk
TOP_MARGIN = 0.025  # m per finger between an open pad and the object before a grasp from above closes,
TOP_NARROW_MARGIN = 0.005  # m: the same where a neighbour stands too close for the wide opening
ROUND_POINTS = 16  # points on the outline of a round footprint
OFFSET_MARGIN = 0.005  # m between the object and the near finger of an off-centre grasp, opened wide
DISTURBED_MOVE = 0.005  # m an object must have moved for a failed grasp to count as having shoved it
DISTURBED_TURN = math.radians(3.0)  # rad: the same for a turn about the vertical


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


def disturbed(position: np.ndarray, quat: np.ndarray, now: np.ndarray, quat_now: np.ndarray) -> bool:
    """Whether an object that stood at `position` (m) turned `quat` (wxyz) and now stands at `now` turned
    `quat_now` has moved more than DISTURBED_MOVE or turned more than DISTURBED_TURN about the vertical: grasps
    planned for where it stood would pinch it off centre (a failed side grasp turns a box between the pads)."""
    turn = 2.0 * (math.atan2(quat_now[3], quat_now[0]) - math.atan2(quat[3], quat[0]))
    turn = abs(math.remainder(turn, 2.0 * math.pi))
    return bool(np.linalg.norm(np.asarray(now) - np.asarray(position)) > DISTURBED_MOVE or turn > DISTURBED_TURN)


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


def _shelf_frame(outward: np.ndarray, quat: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(out, across, yaw): the horizontal unit vector out of the furniture's front (shape (3,)), the one along
    its front (shape (3,)), and the object's yaw (rad) from its body `quat` (wxyz, upright)."""
    out = np.array([outward[0], outward[1], 0.0]) / np.linalg.norm(outward[:2])
    return out, np.array([-out[1], out[0], 0.0]), 2.0 * math.atan2(quat[3], quat[0])


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
