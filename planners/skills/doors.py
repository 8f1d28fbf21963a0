"""The `open_articulation` and `close_articulation` skills of `planners.skills.Robot`, in physics.

A skill runs one or two phases. Each phase grasps the part (see `planners.skills.parts`), follows the part's
motion with the grip while the base moves as planned, releases and retreats with the arm tucked. A drawer
is moved by its handle. A door below EDGE_FROM rad is swung by its handle up to HANDLE_UNTIL rad; beyond, by its
free edge. Success is read back from the simulation: openness above OPEN_OK, or below CLOSED_OK.
"""

from __future__ import annotations

import logging

import numpy as np

from planners.motion.arm import Arm
from planners.motion.clearance import ARC_BASE_COST, ClearanceCheck
from planners.motion.control import FREE_MOTION
from planners.motion.navigation import CLEARANCE, NavigationError, base_candidates
from planners.skills.parts import (
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
    PartHold,
    PartMotion,
    drawer_holding,
    edge_grasp,
    handle_grasp,
    segment_distance,
)

log = logging.getLogger(__name__)
MAX_ARM_JUMP = 0.8  # rad: largest joint change between consecutive waypoints of a followed motion
PATH_SECONDS_PER_STEP = 0.25  # s per waypoint of a followed motion (slow: the part has inertia and damping)


class PhaseFailed(Exception):
    """A phase could not be planned or executed; the message says where and why."""


class PartMover:
    """Runs open/close phases with the robot's `arm` (see `planners.motion.arm.Arm`)."""

    def __init__(self, arm: Arm) -> None:
        self.arm = arm
        self.world = arm.world
        self.controller = arm.controller
        self.navigator = arm.navigator
        self.check = ClearanceCheck(self.world, self.controller)

    # --- public --------------------------------------------------------------------------------------------
    def move_to(self, name: str, opening: bool) -> tuple[bool, str]:
        """Open (or close) articulation `name`; returns (success, reason)."""
        a = self.world.articulation(name)
        lo, hi = a.range
        goal = lo + OPEN_TARGET * (hi - lo) if opening else lo - CLOSE_OVERSHOOT
        try:
            for hold, target in self._phases(a, goal, opening):
                self._phase(a.name, hold, target)
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

    def _phases(self, a, goal: float, opening: bool) -> list[tuple[PartHold, float]]:
        """(where the hand holds, joint target) for each phase: drawers by the handle; doors by handle and edge."""
        if a.joint_type == "slide":
            return [(PartHold.HANDLE, goal)]
        value = float(self.world.data.qpos[a.qpos_adr])
        if opening:
            return ([(PartHold.HANDLE, HANDLE_UNTIL)] if value < EDGE_FROM else []) + [(PartHold.EDGE, goal)]
        return ([(PartHold.EDGE, HANDLE_UNTIL - 0.1)] if value > EDGE_FROM else []) + [(PartHold.HANDLE, goal)]

    # --- one phase -----------------------------------------------------------------------------------------
    def _phase(self, name: str, hold: PartHold, target: float) -> None:
        motion = PartMotion(self.world, name)
        if hold is PartHold.HANDLE:
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
            raise PhaseFailed(f"the {hold} slipped out of the fingers at openness "
                              f"{self.world.openness(name):.2f}")
        log.info("%s: %s phase to %.2f, openness now %.2f", name, hold, target, self.world.openness(name))

    def _riders(self, motion: PartMotion) -> tuple[int, ...]:
        """The qpos addresses of the objects in the drawer being moved (none for a door): they move with it, so
        the clearance checks of the followed motion move them too (a dress in the dresser's middle drawer, left
        where it lay, stood in the palm's way as the drawer closed, and the close gave up at 0.10 m)."""
        a = motion.articulation
        if a.joint_type != "slide":
            return ()
        positions = self.world.data.xpos[self.world.object_body_ids]
        return tuple(int(self.world.object_qpos_adr[k]) for k, position in enumerate(positions)
                     if drawer_holding(self.world, a.furniture, position) == a.name)

    def _free_edge_y(self, motion: PartMotion) -> float:
        """Local y (m) of the door panel's edge farthest from the hinge axis (the body origin)."""
        c, h = motion.panel_center, motion.panel_half
        return float(c[1] + np.sign(c[1]) * h[1])

    def _free(self, xy: np.ndarray, motion: PartMotion, value: float) -> bool:
        """The base disk at xy (m) is clear of the floor plan, open parts of other furniture, objects standing on
        the floor and the part at `value`. The furniture's own other open parts (a drawer open above the one being
        moved) are left to the clearance check of each configuration: their footprints overlap the part's, and the
        base may stand under them."""
        furniture = self.world.articulations[motion.name].furniture
        others = [r for name, r in zip(self.navigator.part_geoms, self._open_rects(), strict=True)
                  if self.world.articulations[name].furniture != furniture and r is not None]
        others += self.navigator.floor_object_rects()
        free = self.navigator.radius + CLEARANCE
        if not self.navigator.plan.disk_is_free(float(xy[0]), float(xy[1]), free, others):
            return False
        a, b, half = motion.panel_segment(value)
        return segment_distance(np.asarray(xy), a, b) > self.navigator.radius + half + BASE_CLEARANCE

    def _open_rects(self) -> list[tuple[float, float, float, float] | None]:
        rects = iter(self.navigator.open_part_rects())
        return [next(rects) if self.world.openness(n) >= 0.02 else None for n in self.navigator.part_geoms]

    def _solve_at(self, q_from: np.ndarray, base: tuple[float, float, float], pos: np.ndarray, quat: np.ndarray,
                  seeds: bool):
        q = q_from.copy()
        q[:3] = base
        return self.arm.ik.solve(q, pos, quat, base_cost=ARC_BASE_COST, seeds=seeds)

    def _plan_grasp(self, motion: PartMotion, grasp: PartGrasp) -> tuple[np.ndarray, np.ndarray]:
        """IK configurations at the grasp and APPROACH m before it, with a free base pose behind them that the
        robot can drive to from where it stands (an open dishwasher door parts the kitchen: the first free pose
        by its edge lay on the far side of it, out of reach of a robot that had carried a glass to a counter)."""
        pos, quat = motion.grip_target(grasp, motion.value)
        rot = motion.pose_at(motion.value)[1] @ grasp.rotation
        before = pos - APPROACH * rot[:, 0]
        q0 = self.arm.tuck.copy()
        riders = self._riders(motion)
        for base in base_candidates(pos, rot, None):
            if not self._free(np.array(base[:2]), motion, motion.value):
                continue
            pre = self._solve_at(q0, base, before, quat, seeds=True)
            if not pre.converged or not self.check.clear(pre.q, motion.articulation, motion.value, riders=riders):
                continue
            at = self._solve_at(pre.q, base, pos, quat, seeds=False)
            if at.converged and self.check.clear(at.q, motion.articulation, motion.value, riders=riders):
                try:
                    self.navigator.path_to(base)
                except NavigationError:
                    continue
                return at.q, pre.q
        raise PhaseFailed(f"no free base pose from which the {grasp.kind} at {np.round(pos, 2).tolist()} is "
                          "reachable")

    def _grasp(self, motion: PartMotion, grasp: PartGrasp, q_pre: np.ndarray, q_grasp: np.ndarray) -> None:
        """Drive to the planned base pose, reach in front of the grasp, move in and close the fingers."""
        arm = self.arm
        arm.retract()
        self.navigator.drive_to(tuple(q_pre[:3]), arm.tucked(), **FREE_MOTION)
        arm.reach(q_pre, grip=PRE_OPENING)
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
        path, q, riders = [], q_start, self._riders(motion)
        for value in values:
            pos, quat = motion.grip_target(grasp, float(value))
            rot = motion.pose_at(float(value))[1] @ grasp.rotation
            for base in base_candidates(pos, rot, q[:2]):
                if not self._free(np.array(base[:2]), motion, float(value)):
                    continue
                result = self._solve_at(q, base, pos, quat, seeds=False)
                if (result.converged and np.max(np.abs(result.q[3:11] - q[3:11])) < MAX_ARM_JUMP
                        and self.check.clear(result.q, motion.articulation, float(value), riders=riders)):
                    q = result.q
                    break
            else:
                raise PhaseFailed(f"the {grasp.kind} cannot be followed to {value:.2f} (no free, reachable base "
                                  "pose)")
            path.append(q)
        return path

    def _let_go(self) -> None:
        """Open the fingers, back the grip off along its approach axis, tuck the arm."""
        arm = self.arm
        if arm.folded:
            return
        self.controller.set_grip(PRE_OPENING, seconds=0.3)
        grip = self.world.data.site("robot/grip")
        rot = grip.xmat.reshape(3, 3)
        result = arm.ik.solve(self.controller.target, grip.xpos - APPROACH * rot[:, 0], arm.grip_quat(),
                                base_cost=ARC_BASE_COST, seeds=False)
        if result.converged:
            self.controller.move_through([result.q])
        arm.retract()
