"""The robot described once: `RobotSpec`, the numbers of the mobile manipulator that the layout validator (the
apartment is built for it), grasp generation, the robot model and its inverse kinematics all take. Values only,
no simulator import; the robot's MJCF (`assets/robot/robot.xml`) agrees with them (`planners.robot.spec_mismatches`
compares the compiled model, and the IK refuses a model that disagrees).

Lengths in m, speeds in m/s or rad/s, forces in N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from homer_sim.errors import HomerError

# Fetch's published joint speed maxima; the base at Fetch's 1.0 m/s and ~1.7 rad/s.
FETCH_SPEEDS = (("base_x", 1.0), ("base_y", 1.0), ("base_yaw", 1.7), ("torso_lift", 0.1), ("shoulder_pan", 1.256),
                ("shoulder_lift", 1.454), ("upperarm_roll", 1.571), ("elbow_flex", 1.521), ("forearm_roll", 1.571),
                ("wrist_flex", 2.268), ("wrist_roll", 2.268))


@dataclass(frozen=True)
class RobotSpec:
    """A Fetch-like mobile manipulator: a round holonomic base, a lifting torso, a 7-joint arm and a parallel
    gripper whose two fingers move together."""

    base_radius: float = 0.28  # the base's cylinder
    footprint_radius: float = 0.3  # the disk kept free for the base wherever it stands or drives (2 cm to spare)
    reach: float = 0.65  # from the base centre to the nearest point of a place it serves, horizontally
    place_heights: tuple[float, float] = (0.05, 1.2)  # the lowest and highest place the hand serves
    min_doorway: float = 0.9  # the narrowest doorway the base passes
    torso_travel: float = 0.386  # how far the torso rises
    finger_stroke: float = 0.08  # per finger: 0.16 between the pads fully open
    max_grasp_width: float = 0.15  # the widest object the fingers close on (the stroke less a margin)
    min_grasp_height: float = 0.008  # thinner objects leave the pads nothing to hold above their support
    pad_half_length: float = 0.025  # half a finger pad's length along the approach
    pad_friction: float = 1.5  # the pads' sliding friction coefficient
    finger_half_thickness: float = 0.016  # half the finger links' extent across the pads' plane
    palm_half_size: tuple[float, float, float] = (0.045, 0.09, 0.03)  # along the approach, the finger travel, across
    palm_setback: float = 0.035  # from the grip site (between the pads) back to the palm's front face
    grip_force: float = 40.0  # per finger, at most
    joint_speeds: tuple[tuple[str, float], ...] = FETCH_SPEEDS  # (joint, speed limit) of every body joint

    def joint_speed(self, joint: str) -> float:
        """The speed limit (m/s or rad/s) of body joint `joint`; a HomerError names the joints."""
        speeds = dict(self.joint_speeds)
        if joint not in speeds:
            raise HomerError(f"{joint!r} is not a body joint; joints: {', '.join(speeds)}")
        return speeds[joint]

    def __post_init__(self) -> None:
        if not 0.0 < self.max_grasp_width <= 2.0 * self.finger_stroke:
            raise HomerError(f"max_grasp_width {self.max_grasp_width} m must be within the fingers' stroke "
                             f"(0, {2.0 * self.finger_stroke}] m")
        if self.footprint_radius < self.base_radius:
            raise HomerError(f"footprint_radius {self.footprint_radius} m is smaller than the base "
                             f"({self.base_radius} m)")
        if not all(math.isfinite(v) and v > 0.0 for _, v in self.joint_speeds):
            raise HomerError(f"joint speeds must be positive: {self.joint_speeds}")


ROBOT = RobotSpec()
"""The robot of homer-sim (`assets/robot/robot.xml`)."""
