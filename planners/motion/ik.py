"""Inverse kinematics of the robot: the only module of homer-sim that imports mink.

IK runs on a robot-only model compiled from `assets/robot/robot.xml` (13 joints, base at the world origin, so
base qpos read world coordinates exactly as in the apartment). A solve integrates mink's differential IK from a
start configuration until the grip site reaches the target pose, or reports why it cannot. Tasks: a frame task
on the grip site, a posture task towards the start configuration, and damping on the base (heavy while
grasping, so the arm and torso do the work). Limits: joint ranges, joint speeds, and collision avoidance
between the arm and the base and torso.
"""

from __future__ import annotations

from ctypes import c_int
from dataclasses import dataclass

import daqp
import mink
import mujoco
import numpy as np

from homer_sim.errors import HomerError
from homer_sim.robot_spec import ROBOT, RobotSpec
from planners.robot import (
    ARM_GEOMS,
    ARM_JOINTS,
    BASE_GEOMS,
    BASE_JOINTS,
    FINGER_JOINTS,
    GRIP_SITE,
    TORSO_JOINT,
    load_robot_spec,
    spec_mismatches,
)

POSITION_TOL = 0.005  # m
ORIENTATION_TOL = np.deg2rad(2.0)  # rad
SOLVER = "daqp"  # DAQP, called directly (see IKSolver._velocity)
NO_LOWER_BOUND = -1e30  # DAQP's "unbounded below", as qpsolvers passes it
# Arm seeds (torso, then the 7 arm joints) tried after the start configuration: elbow up in front, and low.
SEEDS = (np.array([0.2, 0.0, -0.8, 0.0, 1.6, 0.0, 0.8, 0.0]), np.array([0.0, 0.0, 0.5, 0.0, 1.2, 0.0, -0.2, 0.0]))


class IKError(HomerError):
    """An IK request that is malformed (bad shape, non-unit quaternion, unknown option)."""


@dataclass(frozen=True)
class IKResult:
    """The outcome of one solve.

    q: final configuration, shape (nq,) of the robot-only model. converged: both tolerances met.
    position_error: m; orientation_error: rad; iterations: steps taken; errors: position error (m) after
    each step, shape (iterations,); reason: empty when converged, else why not.
    """

    q: np.ndarray
    converged: bool
    position_error: float
    orientation_error: float
    iterations: int
    errors: np.ndarray
    reason: str = ""


def robot_model(robot: RobotSpec = ROBOT) -> mujoco.MjModel:
    """The robot-only model; robot geoms may collide with each other here so mink can keep the arm off the base.
    An IKError where the robot file disagrees with `robot` (see `planners.robot.spec_mismatches`)."""
    spec = load_robot_spec()
    for geom in spec.geoms:
        if geom.contype:
            geom.conaffinity = geom.conaffinity | geom.contype
    model = spec.compile()
    wrong = spec_mismatches(model, robot)
    if wrong:
        raise IKError(f"the robot file disagrees with its spec: {'; '.join(wrong)}")
    return model


class FixedLimit(mink.Limit):
    """A mink limit whose constraint does not depend on the configuration (a velocity limit at a fixed dt in s):
    computed once and reused at every step."""

    def __init__(self, limit: mink.Limit, configuration: mink.Configuration, dt: float) -> None:
        self.dt = dt
        self.constraint = limit.compute_qp_inequalities(configuration, dt)

    def compute_qp_inequalities(self, configuration: mink.Configuration, dt: float) -> mink.Constraint:
        assert dt == self.dt, f"a FixedLimit made for dt {self.dt} s asked for dt {dt} s"
        return self.constraint


class IKSolver:
    """Differential IK on the robot-only model (its own MjData: IK never touches the live simulation).

    dt: integration step of one IK iteration in s (bounds each step through the speed limits); robot: the spec
    whose joint speed limits bound the steps and whose numbers the robot file must agree with.
    """

    def __init__(self, dt: float = 0.05, posture_cost: float = 1e-2, robot: RobotSpec = ROBOT) -> None:
        self.robot = robot
        self.model = robot_model(robot)
        self.dt = dt
        self.configuration = mink.Configuration(self.model)
        self.frame_task = mink.FrameTask(GRIP_SITE, "site", position_cost=1.0, orientation_cost=0.5,
                                         lm_damping=1e-3)
        self.posture_task = mink.PostureTask(self.model, cost=posture_cost)
        self.base_dofs = np.array([self.model.joint(n).dofadr[0] for n in BASE_JOINTS])
        self.finger_qpos = np.array([self.model.joint(n).qposadr[0] for n in FINGER_JOINTS])
        self.limits = [
            mink.ConfigurationLimit(self.model),
            FixedLimit(mink.VelocityLimit(self.model, dict(robot.joint_speeds)), self.configuration, dt),
            mink.CollisionAvoidanceLimit(self.model, [(list(ARM_GEOMS), list(BASE_GEOMS))],
                                         minimum_distance_from_collisions=0.02, collision_detection_distance=0.1),
        ]
        self._damping: dict[float, mink.DampingTask] = {}
        self._blower = np.zeros(0)
        self._sense = np.zeros(0, dtype=c_int)

    def _damping_task(self, base_cost: float) -> mink.DampingTask:
        if base_cost not in self._damping:
            cost = np.full(self.model.nv, 1e-3)
            cost[self.base_dofs] = base_cost
            self._damping[base_cost] = mink.DampingTask(self.model, cost)
        return self._damping[base_cost]

    def grip_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position m shape (3,), quaternion wxyz shape (4,)) of the grip site at configuration q."""
        self.configuration.update(np.asarray(q, dtype=float))
        pose = self.configuration.get_transform_frame_to_world(GRIP_SITE, "site")
        return pose.translation().copy(), pose.rotation().wxyz.copy()

    def solve(self, q_start: np.ndarray, position: np.ndarray, quat: np.ndarray, base_cost: float = 10.0,
              max_iters: int = 150, position_tol: float = POSITION_TOL,
              orientation_tol: float = ORIENTATION_TOL, seeds: bool = True) -> IKResult:
        """Move the grip site to (position m shape (3,), quat wxyz shape (4,)) from q_start (shape (nq,)).

        base_cost: damping cost of the base joints (large while grasping: the base barely moves).
        Stops when both tolerances are met; when a start stalls in a local minimum, tries the arm SEEDS (same
        base) if `seeds`; reports the target unreachable (converged False, with a reason) when all fail.
        """
        q_start, position, quat = self._check(q_start, position, quat)
        starts = [q_start]
        if seeds:
            arm = np.array([self.model.joint(n).qposadr[0] for n in (TORSO_JOINT, *ARM_JOINTS)])
            for seed in SEEDS:
                q = q_start.copy()
                q[arm] = seed
                starts.append(q)
        best = None
        for start in starts:
            result = self._solve_from(start, position, quat, base_cost, max_iters, position_tol, orientation_tol)
            if result.converged:
                return result
            best = result if best is None or result.position_error < best.position_error else best
        return best

    def _solve_from(self, q_start: np.ndarray, position: np.ndarray, quat: np.ndarray, base_cost: float,
                    max_iters: int, position_tol: float, orientation_tol: float) -> IKResult:
        target = mink.SE3.from_rotation_and_translation(mink.SO3(quat), position)
        self.frame_task.set_target(target)
        self.configuration.update(q_start)
        self.posture_task.set_target(q_start)
        tasks = [self.frame_task, self.posture_task, self._damping_task(base_cost)]
        errors: list[float] = []
        fingers = q_start[self.finger_qpos]
        for iteration in range(1, max_iters + 1):
            qpos = self.configuration.data.qpos  # integrated in place, fingers held, then one forward kinematics
            mujoco.mj_integratePos(self.model, qpos, self._velocity(tasks), self.dt)
            qpos[self.finger_qpos] = fingers
            self.configuration.update()
            q = self.configuration.q
            pos_err, rot_err = self._pose_error(position, quat)
            errors.append(pos_err)
            if pos_err < position_tol and rot_err < orientation_tol:
                return IKResult(q.copy(), True, pos_err, rot_err, iteration, np.array(errors))
            if iteration >= 20 and errors[-20] - pos_err < 1e-4:
                break  # stalled: 20 iterations gained less than 0.1 mm
        pos_err, rot_err = self._pose_error(position, quat)
        reason = (f"unreachable: grip site stays {pos_err * 1000:.1f} mm and {np.rad2deg(rot_err):.1f} deg from "
                  f"the target {np.round(position, 3).tolist()} after {len(errors)} iterations")
        return IKResult(self.configuration.q.copy(), False, pos_err, rot_err, len(errors), np.array(errors), reason)

    def _velocity(self, tasks: list[mink.Task]) -> np.ndarray:
        """One differential-IK step at the current configuration: joint velocities, shape (nv,).

        The QP of `mink.solve_ik` (same H, c, G, h from `mink.build_ik`), handed to DAQP as qpsolvers hands it, but
        without qpsolvers' checks and dispatch and mink's limit check, which cost more than the solve itself.
        """
        problem = mink.build_ik(self.configuration, tasks, self.dt, damping=1e-3, limits=self.limits)
        rows = problem.h.size
        if self._blower.size != rows:
            self._blower, self._sense = np.full(rows, NO_LOWER_BOUND), np.zeros(rows, dtype=c_int)
        x, _, exitflag, _ = daqp.solve(problem.P, problem.q, problem.G, problem.h, self._blower, self._sense)
        if exitflag <= 0:
            raise mink.NoSolutionFound(SOLVER)
        return x / self.dt

    def _pose_error(self, position: np.ndarray, quat: np.ndarray) -> tuple[float, float]:
        """(position error m, orientation error rad) of the grip site against the target."""
        pose = self.configuration.get_transform_frame_to_world(GRIP_SITE, "site")
        pos_err = float(np.linalg.norm(pose.translation() - position))
        dot = abs(float(np.dot(pose.rotation().wxyz, quat)))
        return pos_err, 2.0 * float(np.arccos(min(dot, 1.0)))

    def _check(self, q_start, position, quat) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q_start = np.asarray(q_start, dtype=float)
        position = np.asarray(position, dtype=float)
        quat = np.asarray(quat, dtype=float)
        if q_start.shape != (self.model.nq,):
            raise IKError(f"q_start has shape {q_start.shape}; the robot has nq = {self.model.nq}")
        if position.shape != (3,) or not np.all(np.isfinite(position)):
            raise IKError(f"target position {position.tolist()} is not 3 finite numbers (m)")
        if quat.shape != (4,) or abs(np.linalg.norm(quat) - 1.0) > 1e-3:
            raise IKError(f"target quaternion {quat.tolist()} is not a unit wxyz quaternion")
        return q_start, position, quat
