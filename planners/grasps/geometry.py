"""The shape geometry grasp generation and the skills share: rotations and quaternions, an object's yaw, its
footprint and extent along a direction, and the frame of a furniture's front. Pure numpy, no mujoco import.

Rotation matrices are shape (3, 3) with the frame's axes as columns; quaternions are unit wxyz, shape (4,).
"""

from __future__ import annotations

import math

import numpy as np

from homer_sim.home.catalog import ObjectClass

ROUND_POINTS = 16  # points on the outline of a round footprint


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


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation matrix turning `angle` rad about unit `axis` (shape (3,)) (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k


def yaw_matrix(angle: float) -> np.ndarray:
    """The rotation by `angle` rad about the vertical."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def is_round(cls: ObjectClass) -> bool:
    """Whether the class stands on a round footprint (see `ObjectClass.is_round`)."""
    return cls.is_round


def extent(direction: np.ndarray, cls: ObjectClass, yaw: float) -> float:
    """Extent (m) along horizontal unit `direction` (shape (3,)) of the footprint of `cls` turned by `yaw`."""
    if is_round(cls):
        return cls.size[0]
    return box_extent(direction, cls.size[0], cls.size[1], yaw)


def box_extent(direction: np.ndarray, sx: float, sy: float, yaw: float) -> float:
    """Extent (m) along horizontal unit `direction` (shape (3,)) of an sx by sy m rectangle turned by `yaw`
    rad, to the micrometre (a box square to `direction` measures its side, not a hair more)."""
    return round(abs(direction[0] * math.cos(yaw) + direction[1] * math.sin(yaw)) * sx + abs(
        -direction[0] * math.sin(yaw) + direction[1] * math.cos(yaw)) * sy, 6)


def shelf_frame(outward: np.ndarray, quat: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(out, across, yaw): the horizontal unit vector out of the furniture's front (shape (3,)), the one along
    its front (shape (3,)), and the object's yaw (rad) from its body `quat` (wxyz, upright)."""
    out = np.array([outward[0], outward[1], 0.0]) / np.linalg.norm(outward[:2])
    return out, np.array([-out[1], out[0], 0.0]), 2.0 * math.atan2(quat[3], quat[0])


def footprint(cls: ObjectClass, position: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """The outline of an upright object's footprint at `position` (m) turned by body `quat` (wxyz): world xy
    points (m, shape (n, 2)), the box's four corners or ROUND_POINTS on a round one's circle."""
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    if is_round(cls):
        angles = np.linspace(0.0, 2.0 * math.pi, ROUND_POINTS, endpoint=False)
        local = cls.size[0] / 2 * np.column_stack([np.cos(angles), np.sin(angles)])
    else:
        local = np.array([[sx, sy] for sx in (-1, 1) for sy in (-1, 1)])[[0, 1, 3, 2]] * np.asarray(cls.size[:2]) / 2
    c, s = math.cos(yaw), math.sin(yaw)
    return np.asarray(position[:2]) + local @ np.array([[c, s], [-s, c]])
