"""Grasp poses for an object's shape: top grasps across its narrow side, and rim pinches for open containers.

A grasp is the grip site's world pose at the moment the fingers close: position (m) and rotation matrix
(shape (3, 3), columns = grip x (approach, out of the palm), y (finger travel), z). No mujoco import.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from homer_sim.catalog import ObjectClass
from homer_sim.shapes import cavity

MAX_WIDTH = 0.13  # m: widest grasp (stroke 0.14 m minus a margin)
MIN_HEIGHT = 0.008  # m: thinner objects leave the pads nothing to hold above the support
PAD_HALF = 0.025  # m: half length of a finger pad along the approach axis
SUPPORT_CLEARANCE = 0.006  # m between the fingertips and the supporting surface


@dataclass(frozen=True)
class Grasp:
    """A grip-site pose in world coordinates, the finger opening before closing (m per finger) and a label."""

    position: np.ndarray
    rotation: np.ndarray
    pre_opening: float
    kind: str

    def quat(self) -> np.ndarray:
        """The rotation as a unit wxyz quaternion."""
        return matrix_to_quat(self.rotation)


def matrix_to_quat(r: np.ndarray) -> np.ndarray:
    """Unit wxyz quaternion of a rotation matrix (shape (3, 3))."""
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    q = np.array([w, x, y, z])
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
    if cls.family in ("bowl", "pot", "bin", "cup", "mug"):
        return None if cavity(cls) is not None else "container without a cavity"
    if min(sx, sy) > MAX_WIDTH:
        return f"{min(sx, sy) * 100:.0f} cm across its narrow side, wider than the {MAX_WIDTH * 100:.0f} cm grasp"
    return None


def top_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, robot_xy: np.ndarray) -> list[Grasp]:
    """Grasp candidates from above for an upright object at `position` (m, body centre) with body `quat`
    (wxyz), best first; rim pinches for containers (on the rim nearest the robot at `robot_xy`)."""
    sx, sy, sz = cls.size
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    support = position[2] - sz / 2
    top = position[2] + sz / 2
    grip_z = max(top - 0.02, support + PAD_HALF + SUPPORT_CLEARANCE)
    hollow = cavity(cls) if cls.family in ("bowl", "pot", "bin", "cup", "mug") else None
    if hollow is not None and min(sx, sy) > MAX_WIDTH - 0.02:
        return _rim_grasps(hollow, position, yaw, support, robot_xy)
    grasps = []
    narrow = yaw + (math.pi / 2 if sy < sx else 0.0)  # fingers close along the narrow side
    width = min(sx, sy)
    for finger_yaw, kind in ((narrow, "top"), (narrow + math.pi / 2, "top-turned")):
        span = width if kind == "top" else max(sx, sy)
        if span > MAX_WIDTH:
            continue
        centre = np.array([position[0], position[1], grip_z])
        grasps.append(Grasp(centre, top_rotation(finger_yaw), min(0.07, span / 2 + 0.025), kind))
    return grasps


def _rim_grasps(hollow, position: np.ndarray, yaw: float, support: float, robot_xy: np.ndarray) -> list[Grasp]:
    """Pinches of a container's wall at the rim, the nearest rim point first, then 30 degrees either side."""
    c, s = math.cos(yaw), math.sin(yaw)
    centre = position[:2] + np.array([c * hollow.center_xy[0] - s * hollow.center_xy[1],
                                      s * hollow.center_xy[0] + c * hollow.center_xy[1]])
    toward = math.atan2(robot_xy[1] - centre[1], robot_xy[0] - centre[0])
    rim_z = position[2] + hollow.rim_z
    grasps = []
    for delta in (0.0, math.radians(30), -math.radians(30)):
        angle = toward + delta
        radial = np.array([math.cos(angle), math.sin(angle)])
        xy = centre + radial * (hollow.rim_radius + 0.004)
        z = max(rim_z - 0.015, support + PAD_HALF + SUPPORT_CLEARANCE)
        grasps.append(Grasp(np.array([xy[0], xy[1], z]), top_rotation(angle), 0.03, "rim"))
    return grasps
