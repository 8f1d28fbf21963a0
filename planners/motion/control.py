"""Joint-space control of the robot in the apartment: IK configurations become smooth `data.ctrl` targets.

`Controller` maps the robot-only configuration (shape (13,), `IKSolver.model` order) to the apartment's robot
joints and actuators (looked up once by name), and moves along min-jerk trajectories through configurations,
writing the position targets into `data.ctrl` every control step while physics runs. It never writes qpos.
"""

from __future__ import annotations

import bisect
from collections.abc import Callable, Sequence

import mujoco
import numpy as np

from homer_sim.robot_spec import ROBOT, RobotSpec
from planners.robot import ACTUATORS, BODY_JOINTS, FINGER_JOINTS, PREFIX

CONTROL_STEPS = 5  # physics steps per control step (0.01 s at the apartment's 2 ms timestep)
SPEED_FRACTION = 0.5  # planned peak joint speed as a fraction of the limit
FREE_SPEED_FRACTION = 0.9  # the same for moves with nothing in the hand and nothing to touch (tuck, unfold, drive)
FREE_RAMP = 1.0  # s over which such a move reaches and leaves that speed when it is long enough to cruise
FREE_MOTION = {"speed": FREE_SPEED_FRACTION, "ramp": FREE_RAMP}  # keyword arguments of move_through, drive_to
CARRY_MOTION = {"speed": SPEED_FRACTION, "ramp": 2.0}  # a drive with an object in the hand: gently up to speed
MIN_DURATION = 0.3  # s
MIN_JERK_PEAK = 1.875  # peak speed of a min-jerk profile over its mean speed


def min_jerk(s: np.ndarray | float) -> np.ndarray | float:
    """Min-jerk time scaling: 0 -> 0, 1 -> 1 with zero velocity and acceleration at both ends."""
    s = min(max(s, 0.0), 1.0) if isinstance(s, float) else np.clip(s, 0.0, 1.0)  # scalar: 10x faster, same bits
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def cruise(t: float, duration: float, ramp: float) -> float:
    """Cruise time scaling over `duration` s (more than 2 `ramp`): 0 -> 1, the speed rising smoothly (smoothstep)
    over the first `ramp` s, constant, and falling over the last `ramp` s (zero velocity at both ends)."""
    peak = 1.0 / (duration - ramp)
    t = min(max(t, 0.0), duration)
    edge = min(t, duration - t) / ramp
    if edge < 1.0:  # on a ramp: the integral of the smoothstep speed
        part = peak * ramp * (edge**3 - edge**4 / 2.0)
        return part if t < duration / 2.0 else 1.0 - part
    return peak * (ramp / 2.0 + t - ramp)


class Controller:
    """Position targets for the robot in a World with the robot attached under `prefix`, within the joint speeds
    and finger stroke of `robot`."""

    def __init__(self, world, prefix: str = PREFIX, robot: RobotSpec = ROBOT) -> None:
        model = world.model
        self.world = world
        self.qpos_adr = np.array([model.joint(prefix + n).qposadr[0] for n in BODY_JOINTS + FINGER_JOINTS])
        self.dof_adr = np.array([model.joint(prefix + n).dofadr[0] for n in BODY_JOINTS + FINGER_JOINTS])
        self.actuator_ids = np.array([model.actuator(prefix + n).id for n in ACTUATORS])
        gain = model.actuator_gainprm[self.actuator_ids, 0]
        # ctrl = target - offset: the base actuators are biased by their start pose (see planners.robot)
        self.ctrl_offset = model.actuator_biasprm[self.actuator_ids, 0] / gain
        self.robot = robot
        self.speeds = np.array([robot.joint_speed(n) for n in BODY_JOINTS])
        self.n_body = len(BODY_JOINTS)
        self.target = self.q()
        self.grip_target = float(np.mean(self.target[self.n_body:]))
        self._ctrl = np.zeros(self.n_body + 1)  # actuator targets (body joints, then the gripper) before offsets

    def q(self) -> np.ndarray:
        """Current robot configuration, shape (13,), in the robot-only model's order."""
        return self.world.data.qpos[self.qpos_adr].copy()

    def command(self, q_body: np.ndarray, grip: float | None = None) -> None:
        """Write targets: q_body shape (11,) or (13,) (base, torso, arm[, fingers]); grip: opening per finger, m.
        The target's finger entries are not written (the gripper is driven by `grip` alone)."""
        self.target[: self.n_body] = q_body[: self.n_body]
        if grip is not None:
            self.grip_target = min(max(float(grip), 0.0), self.robot.finger_stroke)
        self._ctrl[: self.n_body] = self.target[: self.n_body]
        self._ctrl[self.n_body] = self.grip_target
        self.world.data.ctrl[self.actuator_ids] = self._ctrl - self.ctrl_offset

    def duration(self, q_from: np.ndarray, q_to: np.ndarray, speed: float = SPEED_FRACTION) -> float:
        """Time in s for a min-jerk move whose peak joint speed stays at `speed` of the limits."""
        delta = np.abs(q_to[: self.n_body] - q_from[: self.n_body])
        return max(MIN_DURATION, float(np.max(MIN_JERK_PEAK * delta / (speed * self.speeds))))

    def move_through(self, waypoints: Sequence[np.ndarray], duration: float | None = None,
                     grip: float | None = None, abort: Callable[[], bool] | None = None,
                     speed: float = SPEED_FRACTION, ramp: float | None = None) -> bool:
        """Follow configurations (each shape (13,)) from the current target, piecewise linear in joint space
        with one min-jerk time scaling over the whole path; returns False if `abort()` became True. Without a
        `duration`, each segment takes as long as a min-jerk move of its own at `speed` (see `duration`). With
        `ramp` (s; no `duration`), a path longer than 2 `ramp` at `speed` is cruised instead: each joint at most
        at `speed` of its limit, that speed reached and left over `ramp` s (see `cruise`)."""
        path = np.array([self.target] + [np.asarray(w, dtype=float) for w in waypoints])
        seg = np.linalg.norm((path[1:] - path[:-1])[:, : self.n_body] / self.speeds, axis=1)
        total = float(seg.sum())
        cruising = duration is None and ramp is not None and total / speed > 2.0 * ramp
        if cruising:
            duration = total / speed + ramp
        elif duration is None:
            duration = sum(self.duration(a, b, speed) for a, b in zip(path[:-1], path[1:], strict=True))
            duration = max(duration, MIN_DURATION)
        cumulative = (np.concatenate([[0.0], np.cumsum(seg)]) / (total if total > 0 else 1.0)).tolist()
        steps = path[1:] - path[:-1]
        dt = CONTROL_STEPS * self.world.model.opt.timestep
        for k in range(1, int(np.ceil(duration / dt)) + 1):
            if total == 0:
                s = 1.0
            else:
                s = cruise(k * dt, duration, ramp) if cruising else min_jerk(k * dt / duration)
            i = min(bisect.bisect_right(cumulative, s) - 1, len(seg) - 1)
            u = 0.0 if seg[i] == 0 else (s - cumulative[i]) / (cumulative[i + 1] - cumulative[i])
            self.command(path[i] + min(max(u, 0.0), 1.0) * steps[i], grip)
            self.world.step(CONTROL_STEPS)
            if abort is not None and abort():
                return False
        return True

    def stop(self) -> None:
        """Hold the body joints where they are now (the targets move back to the measured configuration: a servo
        trailing a moving target would go on another 0.06-0.2 s of the move), the grip as it was commanded."""
        self.command(self.q()[: self.n_body])

    def settle(self, tolerance: float = 0.01, max_seconds: float = 1.0) -> float:
        """Step until every body joint is within `tolerance` (m or rad) of its target; returns the final error."""
        error = np.inf
        start = self.world.data.time
        while self.world.data.time - start < max_seconds:
            self.world.step(CONTROL_STEPS)
            error = float(np.max(np.abs(self.q()[: self.n_body] - self.target[: self.n_body])))
            if error < tolerance:
                break
        return error

    def set_grip(self, opening: float, seconds: float = 0.6) -> float:
        """Drive the fingers to `opening` m per finger (0 closes with the actuator's force limit) and wait;
        returns the measured opening per finger in m."""
        self.command(self.target, grip=opening)
        self.world.step(int(round(seconds / self.world.model.opt.timestep)))
        return float(np.mean(self.q()[self.n_body:]))

    def finger_speed(self) -> float:
        """Largest finger joint speed, m/s."""
        return float(np.max(np.abs(self.world.data.qvel[self.dof_adr[self.n_body:]])))


def robot_geom_ids(model: mujoco.MjModel, prefix: str = PREFIX) -> np.ndarray:
    """Ids of every geom on a robot body (a body in the tree under the robot's base)."""
    base = model.body(prefix + "base").id
    return np.flatnonzero(model.body_rootid[model.geom_bodyid] == base).astype(np.int32)
