"""The robot's MJCF names and `add_robot`, which puts the robot into an apartment spec before it is compiled.

Every MJCF name the planners use lives here, and `spec_mismatches`: where the robot file disagrees with the
`homer_sim.robot_spec.RobotSpec` the planners take. The robot file (`assets/robot/robot.xml`) has its base joints at
the world origin; `add_robot` places the base at a start pose so that the base joints read world coordinates:
qpos of `base_x`, `base_y` is the base centre in m and `base_yaw` its heading in rad, both in the robot-only
model and in the apartment.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from pathlib import Path

import mujoco
import numpy as np

from homer_sim.robot_spec import ROBOT, RobotSpec

ROBOT_XML = Path(__file__).resolve().parent.parent / "assets" / "robot" / "robot.xml"
PREFIX = "robot/"
BASE_JOINTS = ("base_x", "base_y", "base_yaw")
TORSO_JOINT = "torso_lift"
ARM_JOINTS = ("shoulder_pan", "shoulder_lift", "upperarm_roll", "elbow_flex", "forearm_roll", "wrist_flex",
              "wrist_roll")
FINGER_JOINTS = ("finger_left", "finger_right")
BODY_JOINTS = BASE_JOINTS + (TORSO_JOINT,) + ARM_JOINTS  # joints the IK moves, in actuator order
ACTUATORS = BODY_JOINTS + ("gripper",)
GRIP_SITE = "grip"  # between the finger pads; x points out of the palm, y along the finger travel
PAD_GEOMS = ("finger_left_pad", "finger_right_pad")
BASE_GEOMS = ("base_shell", "torso_sleeve", "torso_column")
ARM_GEOMS = ("upperarm_col", "elbow_col", "forearm_col", "wrist_flex_col", "palm", "finger_left_link",
             "finger_right_link", "finger_left_pad", "finger_right_pad")
FINGER_GEOMS = ("finger_left_link", "finger_right_link", "finger_left_pad", "finger_right_pad")  # of ARM_GEOMS
HOME_KEY = "home"
# MuJoCo's noslip solver passes in every world the robot acts in: without them an object held by friction creeps
# through the pads while carried and may fall out. Set only where the robot is added: the person's days carry by
# weld, and noslip in the apartment alone made generating them 1.3 to 1.5 times slower.
NOSLIP_ITERATIONS = 5
DEFAULT_POSE = (3.0, 1.3, 0.0)  # (x m, y m, yaw rad): dining room, facing east into free floor
ROBOT_CLEARANCE_M = 0.55  # the person neither walks nor sets anything down within this distance (m) of the
# robot's base centre


def load_robot_spec() -> mujoco.MjSpec:
    """The robot's MjSpec, read from the package's asset file."""
    return mujoco.MjSpec.from_file(str(ROBOT_XML))


def add_robot(spec: mujoco.MjSpec, pose: tuple[float, float, float] = DEFAULT_POSE, prefix: str = PREFIX) -> None:
    """Attach the robot to `spec` with its base at `pose` = (x m, y m, yaw rad).

    At reset (qpos0, ctrl 0) the base stands at `pose` with the arm stretched forward (all arm joints 0) and
    holds still: the base joints' references are the start pose, so their qpos read world coordinates, and the
    base actuators carry a bias so that ctrl = target - start (see `RobotHandles.ctrl_offset`). The arm is then
    tucked by the controller. Use as `World(extras=[add_robot])` or `World(extras=[robot_at((x, y, yaw))])`.
    """
    x, y, yaw = (float(v) for v in pose)
    robot = load_robot_spec()
    robot.delete(robot.key(HOME_KEY))
    base = robot.body("base")
    base.pos = (x, y, 0.0)
    base.quat = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
    c, s = math.cos(yaw), math.sin(yaw)
    starts = {"base_x": ((c, -s, 0.0), x), "base_y": ((s, c, 0.0), y), "base_yaw": ((0.0, 0.0, 1.0), yaw)}
    for name, (axis, ref) in starts.items():  # slide axes are given in the rotated base frame
        robot.joint(name).axis, robot.joint(name).ref = axis, ref
        actuator = robot.actuator(name)
        actuator.biasprm[0] = actuator.gainprm[0] * ref
    spec.option.noslip_iterations = NOSLIP_ITERATIONS
    frame = spec.worldbody.add_frame()
    frame.attach_body(base, prefix, "")


def spec_mismatches(model: mujoco.MjModel, robot: RobotSpec = ROBOT, prefix: str = "") -> list[str]:
    """Where compiled `model` (the robot alone, or an apartment with the robot under `prefix`) disagrees with
    `robot`: each a message naming the value in the model and in the spec; empty where they agree (to 1e-9 m, N
    or of a coefficient)."""
    geom, joint = (lambda n: model.geom(prefix + n)), (lambda n: model.joint(prefix + n))
    palm, grip = geom("palm"), model.site(prefix + GRIP_SITE)
    found = {
        "base_radius": geom("base_shell").size[0],
        "torso_travel": joint(TORSO_JOINT).range[1],
        "finger_stroke": min(joint(n).range[1] for n in FINGER_JOINTS),
        "pad_half_length": geom(PAD_GEOMS[0]).size[0],
        "pad_friction": geom(PAD_GEOMS[0]).friction[0],
        "finger_half_thickness": geom(FINGER_GEOMS[0]).size[2],
        "palm_half_size": tuple(palm.size),
        "palm_setback": grip.pos[0] - (palm.pos[0] + palm.size[0]),
        "grip_force": model.actuator(prefix + "gripper").forcerange[1] / len(FINGER_JOINTS),
    }
    wrong = [f"{name}: the model has {np.round(value, 6).tolist()}, the spec {getattr(robot, name)}"
             for name, value in found.items() if not np.allclose(value, getattr(robot, name), rtol=0.0, atol=1e-9)]
    speeds = sorted(name for name, _ in robot.joint_speeds)
    if speeds != sorted(BODY_JOINTS):
        wrong.append(f"joint_speeds: the spec limits {speeds}, the model's body joints are {sorted(BODY_JOINTS)}")
    return wrong


def robot_at(pose: tuple[float, float, float], prefix: str = PREFIX) -> Callable[[mujoco.MjSpec], None]:
    """An `extras` function for `World` that adds the robot at `pose` = (x m, y m, yaw rad)."""
    return partial(add_robot, pose=pose, prefix=prefix)
