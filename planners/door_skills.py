"""The `open_articulation` and `close_articulation` skills of `planners.skills.Robot`, in physics.

A skill runs one or two phases. Each phase grasps the part (see `planners.articulate`), follows the part's
motion with the grip while the base moves as planned, releases and retreats with the arm tucked. A drawer
is moved by its handle. A door below EDGE_FROM rad is swung by its handle up to HANDLE_UNTIL rad; beyond, by its
free edge. Success is read back from the simulation: openness above OPEN_OK, or below CLOSED_OK.
"""

from __future__ import annotations

import copy
import logging
from dataclasses import dataclass

import mujoco
import numpy as np

from homer_sim.home.validate import ROBOT_RADIUS
from planners.articulate import (
    APPROACH,
    BASE_CLEARANCE,
    CLOSE_OVERSHOOT,
    CLOSED_OK,
    EDGE_FROM,
    HANDLE_UNTIL,
    MIN_HELD,
    OPEN_OK,
    OPEN_TARGET,
    PRE_OPENING,
    SLIP,
    STEP_HINGE,
    STEP_SLIDE,
    PartGrasp,
    PartMotion,
    base_candidates,
    edge_grasp,
    handle_grasp,
    segment_distance,
)
from planners.control import FREE_MOTION, robot_geom_ids
from planners.navigation import CLEARANCE, NavigationError
from planners.robot import ARM_GEOMS, PREFIX

log = logging.getLogger(__name__)
ARC_BASE_COST = 1e4  # IK damping on the base: the base is placed by the planner, the arm reaches
MAX_ARM_JUMP = 0.8  # rad: largest joint change between consecutive waypoints of a followed motion
PATH_SECONDS_PER_STEP = 0.25  # s per waypoint of a followed motion (slow: the part has inertia and damping)


class PhaseFailed(Exception):
    """A phase could not be planned or executed; the message says where and why."""


@dataclass(frozen=True)
class Held:
    """An object in the hand: its geoms, its free joint's qpos address, and its pose in the grip site's frame
    (position m, shape (3,); rotation, shape (3, 3)); it moves with the hand in clearance checks."""

    geoms: frozenset[int]
    qpos_adr: int
    position: np.ndarray
    rotation: np.ndarray


class ClearanceCheck:
    """Whether a robot configuration touches the apartment, on a scratch copy of the data (never the live one).

    Contacts of the fingers are ignored (they are meant to touch the part); every other robot geom must keep
    MARGIN m from everything. With a held object, the fingers are checked too, and the object must keep MARGIN
    from everything but the robot.

    Collisions run on a copy of the model whose filter keeps only the pairs a check reads (robot or held object
    against the rest): apartment geoms lose their conaffinity, so the ~100 resting objects and the furniture are
    not collided with each other at every check.
    """

    MARGIN = 0.005  # m
    FINGER_GRAZE = 0.002  # m: an open finger may graze a neighbour's edge this deep (it slides off)

    def __init__(self, world, controller) -> None:
        self.world = world
        self.model = copy.copy(world.model)
        self.scratch = mujoco.MjData(self.model)
        self.qpos_adr = controller.qpos_adr
        robot = robot_geom_ids(world.model)
        fingers = [world.model.geom(PREFIX + n).id for n in ARM_GEOMS if n.startswith("finger")]
        self.robot = np.zeros(world.model.ngeom, dtype=bool)
        self.robot[robot] = True
        self.fingers = np.zeros(world.model.ngeom, dtype=bool)
        self.fingers[fingers] = True
        self.checked = self.robot & ~self.fingers
        self.conaffinity = world.model.geom_conaffinity.copy()
        self.model.geom_conaffinity[~self.robot] = 0
        assert _same_filter(world.model, self.robot), "the robot-only collision filter would drop pairs"
        self.grip = world.model.site(PREFIX + "grip").id

    def fingers_clear(self, q: np.ndarray) -> bool:
        """True if the fingers at configuration q (shape (13,), the finger openings included) touch nothing: an
        open hand about to close round an object has both fingers beside it, on nothing else (a graze of at most
        FINGER_GRAZE m aside)."""
        return not self.finger_contacts(q)

    def finger_contacts(self, q: np.ndarray) -> set[int]:
        """Ids of the geoms outside the robot that the fingers at configuration q (shape (13,), the finger
        openings included) touch deeper than FINGER_GRAZE m."""
        d = self.scratch
        d.qpos[:] = self.world.data.qpos
        d.qpos[self.qpos_adr] = q
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_collision(self.model, d)
        g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
        touching = ((self.fingers[g1] != self.fingers[g2]) & ~(self.robot[g1] & self.robot[g2])
                    & (d.contact.dist[: d.ncon] < -self.FINGER_GRAZE))
        return {int(g) for g in np.concatenate([g1[touching], g2[touching]]) if not self.robot[g]}

    def clear(self, q: np.ndarray, articulation=None, value: float = 0.0, held: Held | None = None,
              fingers: bool = False) -> bool:
        """True if configuration q (shape (13,)) keeps MARGIN from the apartment, with `articulation` (if
        given) at joint value `value` (rad or m), `held` (if given) in the hand, and everything else where it
        is now. With `fingers`, the fingers are checked too (a hand swinging free touches nothing at all)."""
        d = self.scratch
        d.qpos[:] = self.world.data.qpos
        d.qpos[self.qpos_adr] = q
        if articulation is not None:
            d.qpos[articulation.qpos_adr] = value
        mujoco.mj_kinematics(self.model, d)
        robot, checked = self.robot, self.robot if fingers else self.checked
        if held is None:
            mujoco.mj_collision(self.model, d)
        else:
            rotation = d.site_xmat[self.grip].reshape(3, 3)
            d.qpos[held.qpos_adr:held.qpos_adr + 3] = d.site_xpos[self.grip] + rotation @ held.position
            mujoco.mju_mat2Quat(d.qpos[held.qpos_adr + 3:held.qpos_adr + 7], (rotation @ held.rotation).ravel())
            mujoco.mj_kinematics(self.model, d)
            geoms = list(held.geoms)
            robot = checked = robot.copy()  # the fingers are checked too, against all but the object
            robot[geoms] = True
            self.model.geom_conaffinity[geoms] = self.conaffinity[geoms]  # the object collides with the rest
            try:
                mujoco.mj_collision(self.model, d)
            finally:
                self.model.geom_conaffinity[geoms] = 0
        g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
        touching = (checked[g1] != checked[g2]) & ~(robot[g1] & robot[g2]) & (d.contact.dist[: d.ncon] < self.MARGIN)
        return not touching.any()


def _same_filter(model: mujoco.MjModel, robot: np.ndarray) -> bool:
    """Whether MuJoCo's contype/conaffinity test passes the same pairs (any geom that may be in or on the robot,
    against any geom off it) when the geoms off the robot have conaffinity 0, as in `ClearanceCheck.model`."""
    kinds = np.unique(np.stack([model.geom_contype, model.geom_conaffinity], axis=1), axis=0)
    off = np.unique(np.stack([model.geom_contype[~robot], model.geom_conaffinity[~robot]], axis=1), axis=0)
    for contype, conaffinity in kinds:
        before = (contype & off[:, 1]) | (off[:, 0] & conaffinity)
        after = off[:, 0] & conaffinity
        if not np.array_equal(before != 0, after != 0):
            return False
    return True


class PartMover:
    """Runs open/close phases for a `planners.skills.Robot`."""

    def __init__(self, robot) -> None:
        self.robot = robot
        self.world = robot.world
        self.controller = robot.controller
        self.navigator = robot.navigator
        self.check = ClearanceCheck(self.world, self.controller)

    # --- public --------------------------------------------------------------------------------------------
    def move_to(self, name: str, opening: bool) -> tuple[bool, str]:
        """Open (or close) articulation `name`; returns (success, reason)."""
        a = self.world.articulation(name)
        lo, hi = a.range
        goal = lo + OPEN_TARGET * (hi - lo) if opening else lo - CLOSE_OVERSHOOT
        try:
            for grasp_kind, target in self._phases(a, goal, opening):
                self._phase(a.name, grasp_kind, target)
        except (PhaseFailed, NavigationError) as error:
            self._let_go()
            openness = self.world.openness(a.name)
            if not (openness >= OPEN_OK if opening else openness <= CLOSED_OK):  # a slip at the end is no failure
                return False, f"{'open' if opening else 'close'} {a.name}: {error}"
        openness = self.world.openness(a.name)
        if opening and openness < OPEN_OK:
            return False, f"open {a.name}: openness {openness:.2f}, below {OPEN_OK}"
        if not opening and openness > CLOSED_OK:
            return False, f"close {a.name}: openness {openness:.2f}, above {CLOSED_OK}"
        return True, ""

    def _phases(self, a, goal: float, opening: bool) -> list[tuple[str, float]]:
        """(grasp kind, joint target) for each phase: drawers by the handle; doors by handle and edge."""
        if a.joint_type == "slide":
            return [("handle", goal)]
        value = float(self.world.data.qpos[a.qpos_adr])
        if opening:
            return ([("handle", HANDLE_UNTIL)] if value < EDGE_FROM else []) + [("edge", goal)]
        return ([("edge", HANDLE_UNTIL - 0.1)] if value > EDGE_FROM else []) + [("handle", goal)]

    # --- one phase -----------------------------------------------------------------------------------------
    def _phase(self, name: str, kind: str, target: float) -> None:
        motion = PartMotion(self.world, name)
        if kind == "handle":
            grasp = handle_grasp(motion.handle_local, motion.articulation.joint_type)
        else:
            grasp = edge_grasp(motion.handle_local, self._free_edge_y(motion))
        q_grasp, q_pre = self._plan_grasp(motion, grasp)
        self._grasp(motion, grasp, q_pre, q_grasp)
        step = STEP_SLIDE if motion.articulation.joint_type == "slide" else STEP_HINGE
        path = self._plan_follow(motion, grasp, motion.waypoints(target, step), q_grasp)
        body = motion.body

        def slipped() -> bool:
            data = self.world.data
            point = data.xpos[body] + data.xmat[body].reshape(3, 3) @ grasp.position
            return float(np.linalg.norm(data.site("robot/grip").xpos - point)) > SLIP

        done = self.controller.move_through(path, duration=PATH_SECONDS_PER_STEP * len(path) + 0.5, grip=0.0,
                                            abort=slipped)
        self.controller.settle(0.01, max_seconds=0.5)
        self._let_go()
        if not done:
            raise PhaseFailed(f"the {kind} slipped out of the fingers at openness "
                              f"{self.world.openness(name):.2f}")
        log.info("%s: %s phase to %.2f, openness now %.2f", name, kind, target, self.world.openness(name))

    def _free_edge_y(self, motion: PartMotion) -> float:
        """Local y (m) of the door panel's edge farthest from the hinge axis (the body origin)."""
        c, h = motion.panel_center, motion.panel_half
        return float(c[1] + np.sign(c[1]) * h[1])

    def _free(self, xy: np.ndarray, motion: PartMotion, value: float) -> bool:
        """The base disk at xy (m) is clear of the floor plan, other open parts and the part at `value`."""
        others = [r for name, r in zip(self.navigator.part_geoms, self._open_rects(), strict=True)
                  if name != motion.name and r is not None]
        if not self.navigator.plan.disk_is_free(float(xy[0]), float(xy[1]), ROBOT_RADIUS + CLEARANCE, others):
            return False
        a, b, half = motion.panel_segment(value)
        return segment_distance(np.asarray(xy), a, b) > ROBOT_RADIUS + half + BASE_CLEARANCE

    def _open_rects(self) -> list[tuple[float, float, float, float] | None]:
        rects = iter(self.navigator.open_part_rects())
        return [next(rects) if self.world.openness(n) >= 0.02 else None for n in self.navigator.part_geoms]

    def _solve_at(self, q_from: np.ndarray, base: tuple[float, float, float], pos: np.ndarray, quat: np.ndarray,
                  seeds: bool):
        q = q_from.copy()
        q[:3] = base
        return self.robot.ik.solve(q, pos, quat, base_cost=ARC_BASE_COST, seeds=seeds)

    def _plan_grasp(self, motion: PartMotion, grasp: PartGrasp) -> tuple[np.ndarray, np.ndarray]:
        """IK configurations at the grasp and APPROACH m before it, with a free base pose behind them."""
        pos, quat = motion.grip_target(grasp, motion.value)
        rot = motion.pose_at(motion.value)[1] @ grasp.rotation
        before = pos - APPROACH * rot[:, 0]
        q0 = self.robot.tuck.copy()
        for base in base_candidates(pos, rot, None):
            if not self._free(np.array(base[:2]), motion, motion.value):
                continue
            pre = self._solve_at(q0, base, before, quat, seeds=True)
            if not pre.converged or not self.check.clear(pre.q, motion.articulation, motion.value):
                continue
            at = self._solve_at(pre.q, base, pos, quat, seeds=False)
            if at.converged and self.check.clear(at.q, motion.articulation, motion.value):
                return at.q, pre.q
        raise PhaseFailed(f"no free base pose from which the {grasp.kind} at {np.round(pos, 2).tolist()} is "
                          "reachable")

    def _grasp(self, motion: PartMotion, grasp: PartGrasp, q_pre: np.ndarray, q_grasp: np.ndarray) -> None:
        """Drive to the planned base pose, reach in front of the grasp, move in and close the fingers."""
        robot = self.robot
        robot.retract()
        self.navigator.drive_to(tuple(q_pre[:3]), robot.tucked(), **FREE_MOTION)
        robot.reach(q_pre, grip=PRE_OPENING)
        self.controller.settle(0.003)
        self.controller.move_through([q_grasp])
        self.controller.settle(0.002)
        opening = self.controller.set_grip(0.0)
        if opening < MIN_HELD:
            self._let_go()
            raise PhaseFailed(f"the fingers closed on nothing at the {grasp.kind} (opening {opening * 1000:.1f} mm)")

    def _plan_follow(self, motion: PartMotion, grasp: PartGrasp, values: np.ndarray,
                     q_start: np.ndarray) -> list[np.ndarray]:
        """IK configurations holding the grasp at each joint value, each with a free base pose."""
        path, q = [], q_start
        for value in values:
            pos, quat = motion.grip_target(grasp, float(value))
            rot = motion.pose_at(float(value))[1] @ grasp.rotation
            for base in base_candidates(pos, rot, q[:2]):
                if not self._free(np.array(base[:2]), motion, float(value)):
                    continue
                result = self._solve_at(q, base, pos, quat, seeds=False)
                if (result.converged and np.max(np.abs(result.q[3:11] - q[3:11])) < MAX_ARM_JUMP
                        and self.check.clear(result.q, motion.articulation, float(value))):
                    q = result.q
                    break
            else:
                raise PhaseFailed(f"the {grasp.kind} cannot be followed to {value:.2f} (no free, reachable base "
                                  "pose)")
            path.append(q)
        return path

    def _let_go(self) -> None:
        """Open the fingers, back the grip off along its approach axis, tuck the arm."""
        robot = self.robot
        if robot.folded:
            return
        self.controller.set_grip(PRE_OPENING, seconds=0.3)
        grip = self.world.data.site("robot/grip")
        rot = grip.xmat.reshape(3, 3)
        result = robot.ik.solve(self.controller.target, grip.xpos - APPROACH * rot[:, 0], robot._held_quat(),
                                base_cost=ARC_BASE_COST, seeds=False)
        if result.converged:
            self.controller.move_through([result.q])
        robot.retract()
