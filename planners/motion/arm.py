"""The arm's movement primitives (`Arm`), which the skills in `planners.skills` are built from.

`Arm` owns how the robot moves: IK onto grip-site poses, straight grip-site lines, the tuck and the raised arm,
joint-space swings checked for clearance, driving to furniture (with or without a held object) or to a base pose
from which the way into a grasp is clear, the carry path; and what the hand holds (where an object sits in it,
whether it is empty, whether an object has fallen over). Constants the pick and place skills share live here.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import mujoco
import numpy as np

from homer_sim.home.catalog import CATALOG
from planners.grasps.candidate import Grasp
from planners.grasps.geometry import matrix_to_quat, slerp, yaw_matrix
from planners.motion.clearance import ARC_BASE_COST, ClearanceCheck, Held
from planners.motion.control import CARRY_MOTION, FREE_MOTION, Controller
from planners.motion.ik import IKResult, IKSolver
from planners.motion.navigation import CLEARANCE, Navigator, base_candidates
from planners.motion.swing import plan_swing

MIN_HELD_OPENING = 0.001  # m per finger: closed further means the fingers missed
GRASP_BASE_COST = 100.0  # IK damping on the base while grasping
RAISED_TORSO = 0.3  # m
CARRY_REACHES = (0.35, 0.45, 0.55)  # m from the base centre to the carry point, the nearest first (the farther ones
# for a hand held level only, see `Arm.carry_path`)
LEVEL_HAND = 0.7  # horizontal part of the grip x axis above which the hand counts as held level
CARRY_HEIGHT = 1.05  # m
CARRY_CLEAR = 0.95  # m: a held object is carried with its lowest point this high at least, where the arm reaches
# (over counters, tables and dressers, 0.9 m at most): a dress hanging 35 cm from its fold, carried with the grip
# at CARRY_HEIGHT, swept a jacket off the dresser and was caught on the oven on the way
CARRY_ARM_SPEED = 0.2  # peak joint speed (fraction of the limit) moving a held object to the carry point: a wine
# glass pinched at its rim slipped out of the fingers at SPEED_FRACTION
CARRY_STEP = 0.05  # m between IK waypoints on the way to the carry point
TURN_STEP = 0.15  # rad the hand turns at most between IK waypoints of a move between poses
RAISED_SHOULDER = -1.0  # rad: upper arm raised above the tuck
RETRACT_RISE = 0.3  # m the hand rises at most before a retract swings it into the raised arm (`Arm.retract`),
RETRACT_STEP = 0.05  # m between the heights checked on the way
SIDE_LIFT = 0.03  # m: a side grasp first lifts the object this much off its shelf,
LOW_SIDE_LIFT = 0.015  # m: or only this much where the wrist would come within ClearanceCheck.MARGIN of the
# compartment's top or the shelf above (a trash bag's tie 3.5 cm under a cabinet's top)
ENTRY_OUT = 0.12  # m: a grasp inside furniture is entered from this far in front of its front plane
ENTRY_STEP = 0.05  # m between checked configurations on the way in
BACK_OFF = (0.15, 0.3)  # m a base holding an object backs away before the carry where the way to the carry point
# touches something (`Arm.carry`)
PASS_OVER = 0.03  # m between a carried object and a surface it is carried over before it is put down
PULL_BASE_COST = 0.1  # IK damping on the base while drawing an object out: the base backs away
LEAD_HEIGHTS = (0.15, 0.3)  # m above a grasp's entry point the arm may first swing to, then come down
SWING_TILT = math.radians(30.0)  # rad a held object may tilt from upright on a planned swing (`Arm.swing_way`)
SWING_STEP = 0.02  # rad between checked configurations of a joint-space swing (a fingertip 0.9 m out moves
# under 2 cm: it cannot pass through a drawer front unseen)
UPRIGHT = 0.7  # z component of an object's up axis below which a put-down object has fallen over
PITCHED_HAND = 0.25  # horizontal part of the grip x axis above which the hand does not count as pointing down
ASIDE_LEAN = math.radians(45.0)  # rad: a pitched hand whose grip x leans further than this off the way into the
# furniture (a "-rolled" grasp leans 90 degrees aside) is also reached from base poses in front of it
WAYPOINT_TOL = (0.015, np.deg2rad(5.0))  # m, rad: IK tolerance of a straight line's intermediate points (the end
# point is exact); tight ones stall near joint limits on the way


class Arm:
    """The arm's movement primitives and what the hand holds, for the skills in `planners.skills`.

    Inputs, declared: the World, the IK solver, the controller that drives the robot in it, the navigator that
    drives its base, and the clearance check of configurations against the apartment. State: `held` (the name of
    the object in the hand, or None; the skills set it) and `folded` (the arm is in, or moving from, the tuck).
    """

    def __init__(self, world, ik: IKSolver, controller: Controller, navigator: Navigator,
                 clearance: ClearanceCheck) -> None:
        self.world = world
        self.ik = ik
        self.controller = controller
        self.navigator = navigator
        self.clearance = clearance
        self.tuck = ik.model.key("home").qpos.copy()
        self.shoulder_lift = ik.model.joint("shoulder_lift").qposadr[0]
        self.held: str | None = None
        self.folded = True
        self.lower, self.upper = np.zeros(ik.model.nq), np.zeros(ik.model.nq)  # joint ranges, by qpos address
        self.lower[ik.model.jnt_qposadr], self.upper[ik.model.jnt_qposadr] = ik.model.jnt_range.T

    def solve(self, position: np.ndarray, rotation_quat: np.ndarray, seeds: bool = True) -> IKResult:
        """IK onto a grip-site pose (m; wxyz) from the controller's target, the base damped as while grasping."""
        return self.ik.solve(self.controller.target, position, rotation_quat, base_cost=GRASP_BASE_COST,
                             seeds=seeds)

    def line(self, start: np.ndarray, end: np.ndarray, quat: np.ndarray, steps: int = 4,
              base_cost: float = GRASP_BASE_COST, loose_end: bool = False,
              partial: bool = False, seed: np.ndarray | None = None,
              from_quat: np.ndarray | None = None, exact: bool = False) -> list[np.ndarray] | None:
        """IK configurations along the straight grip-site line start -> end (m), or None if any is unreachable
        (with `partial`, those up to the last reachable point instead); base_cost: IK damping on the base (low
        lets the base back away, e.g. drawing an object off a shelf). Points before the end are solved within
        WAYPOINT_TOL, the end exactly unless `loose_end`. seed: the configuration at `start` (default: the
        controller's target). from_quat: the orientation at `start`, turned evenly into `quat` on the way (default:
        `quat` all along). exact: every point exact."""
        q = (self.controller.target if seed is None else seed).copy()
        path = []
        for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
            loose = {} if exact or (s == 1.0 and not loose_end) else {"position_tol": WAYPOINT_TOL[0],
                                                            "orientation_tol": WAYPOINT_TOL[1]}
            turned = quat if from_quat is None else slerp(from_quat, quat, s)
            result = self.ik.solve(q, start + s * (end - start), turned, base_cost=base_cost, seeds=False, **loose)
            if not result.converged:
                return path if partial else None
            q = result.q
            path.append(q)
        return path

    def raised(self, torso: float) -> np.ndarray:
        """The tuck posture with the upper arm raised and the torso at `torso` m, at the current base pose: the
        waypoint between tuck and any reach, so the folded arm never sweeps through a counter."""
        q = self.tuck.copy()
        q[:3] = self.controller.target[:3]
        q[3] = max(torso, RAISED_TORSO)
        q[self.shoulder_lift] = RAISED_SHOULDER
        return q

    def reach(self, q_goal: np.ndarray, grip: float | None = None, abort: Callable[[], bool] | None = None
              ) -> bool:
        """Move to configuration q_goal (shape (13,)); from the tuck posture straight there if that swing, the
        fingers opening to `grip` (m per finger) on the way, touches nothing, else through `raised`, quicker (the
        hand is empty). From `raised` the fingers open on the way only if that leg is clear with them open, else
        once the arm is there: the open pads of a hand coming down from the raised arm swept a keyboard 77 cm
        across a desk; where that leg touches something, through a configuration from which it is clear, where
        `_swing_via` finds one (with the fingers open, else closed): straight from the raised arm, a hand
        reaching for a microwave door's edge pushed the door 10 degrees shut. The arm not tucked, it swings
        straight to q_goal, through what `_swing_via` finds where that swing touches something. Returns False where
        `abort()` stopped the move (see `Controller.move_through`)."""
        moved = True
        if self.folded:
            opened = q_goal.copy()
            if grip is not None:
                opened[self.controller.n_body:] = grip
            if self.swing_clear(self.controller.target, opened):
                moved = self.controller.move_through([q_goal], grip=grip, abort=abort, **FREE_MOTION)
            else:
                raised = self.raised(q_goal[3])
                early = grip is None or self.swing_clear(raised, opened)
                if grip is None:
                    via = self._swing_via(raised, q_goal)
                else:
                    via = [] if early else self._swing_via(raised, opened) or self._swing_via(raised, q_goal)
                moved = self.controller.move_through([raised, *via, q_goal], grip=grip if early else None,
                                                     abort=abort, **FREE_MOTION)
                if moved and not early:
                    self.controller.set_grip(grip)
        else:
            moved = self.controller.move_through([*self._swing_via(self.controller.target, q_goal), q_goal], grip=grip,
                                                 abort=abort)
        self.folded = False
        return moved

    def retract(self) -> None:
        """Tuck the arm (the torso stays): with an empty hand straight there if that swing touches nothing,
        quicker; else through `raised`, the hand first risen clear for that swing where it must (`_rise_to_swing`),
        along what `swing_way` finds, every check on the hand as `_seen`. With an empty hand, where no way is found
        the base first backs straight away, the arm held as it is (`_backed_off`), and the way is sought again
        from there (swung straight from beside a dresser's drawer it had just pulled open, the open hand pushed
        the drawer shut); straight where there is none then."""
        if not self.folded:
            tucked = self._seen(self.tucked())
            if self.held is None and self.swing_clear(self._seen(self.controller.target), tucked):
                self.controller.move_through([tucked], **FREE_MOTION)
            else:
                self._rise_to_swing()
                held = None if self.held is None else self.held_object(self.held)

                def way() -> list[np.ndarray] | None:  # from where the arm is now into the raised arm
                    target = self.controller.target
                    return self.swing_way(self._seen(target), self._seen(self.raised(target[3])), held)

                via = way()
                back = self._backed_off(None) if via is None and held is None else None
                if back:
                    self.controller.move_through(back)
                    via = way()
                self.controller.move_through([*(via or []), self.raised(self.controller.target[3]), self.tucked()])
        self.folded = True

    def _seen(self, q: np.ndarray) -> np.ndarray:
        """Configuration q (shape (13,)) as a retract's checks see it: with an empty hand, the fingers as they are
        now (a move through q leaves them so; checked at the target's start value, closed, a hand opened wide to
        let go of a cd swung back from the tv stand and dragged the radio beside it onto the floor); holding
        something, as planned (seeing the fingers round a side-held box of wipes as they are, the retract took
        another way, and carried on to its set-down the box swept a sauce pan off the stove)."""
        q = q.copy()
        if self.held is None:
            q[self.controller.n_body:] = self.controller.q()[self.controller.n_body:]
        return q

    def _swing_via(self, q_from: np.ndarray, q_to: np.ndarray) -> list[np.ndarray]:
        """`swing_way` from q_from to q_to with what the hand holds; none where it finds no way."""
        return self.swing_way(q_from, q_to, None if self.held is None else self.held_object(self.held)) or []

    def swing_way(self, q_from: np.ndarray, q_to: np.ndarray, held: Held | None = None) -> list[np.ndarray] | None:
        """The configurations (each shape (13,)) strictly between q_from and q_to (base at q_to's) of a joint-space
        way on which the arm, the fingers and `held` touch nothing: none where the straight swing is clear; else
        the first configuration with one, then two of the torso and arm joints at q_to's values and the others at
        q_from's through which the two swings are clear (a hand that let a glass go on a counter, its wrist and
        upper arm turned far from the raised arm's, swept the knife block beside the glass off the counter on the
        straight swing, however high it first rose); else one found by `plan_swing` over the joints' ranges (a
        pot held pitched, eased from the carry point down to a kitchen cabinet's shelf, swung its handle through
        the cabinet's open door on every straight way); None where there is none of those. A held object is kept
        within SWING_TILT of upright on the vias' ways (or as upright as it is at either end): a pot pinched by its
        wall, turned over on the way, slipped out of the fingers however slowly it swung."""
        if self.swing_clear(q_from, q_to, held):
            return []
        least = -1.0 if held is None else min(math.cos(SWING_TILT), self._held_up(q_from, held),
                                              self._held_up(q_to, held))
        joints = range(3, self.controller.n_body)
        for subset in [*((j,) for j in joints), *itertools.combinations(joints, 2)]:
            via = q_from.copy()
            via[list(subset)] = q_to[list(subset)]
            if all(self.swing_clear(a, b, held) and self._kept_up(a, b, held, least)
                   for a, b in ((q_from, via), (via, q_to))):
                return [via]
        arm = slice(3, self.controller.n_body)
        return plan_swing(q_from, q_to, lambda a, b: self.swing_clear(a, b, held) and self._kept_up(a, b, held, least),
                          self.lower[arm], self.upper[arm], arm)

    def _held_up(self, q: np.ndarray, held: Held) -> float:
        """The vertical part of the up axis of `held`, in the hand at configuration q (shape (13,))."""
        rotation = np.empty(9)
        mujoco.mju_quat2Mat(rotation, self.ik.grip_pose(q)[1])
        return float((rotation.reshape(3, 3) @ held.rotation)[2, 2])

    def _kept_up(self, q_from: np.ndarray, q_to: np.ndarray, held: Held | None, least: float) -> bool:
        """Whether `held` (if any) keeps the vertical part of its up axis at `least` at every SWING_STEP of the
        joint-space move q_from -> q_to (each shape (13,))."""
        if held is None:
            return True
        return all(self._held_up(q_from + s * (q_to - q_from), held) >= least
                   for s in np.linspace(0.0, 1.0, _swing_steps(q_from, q_to) + 1))

    def _rise_to_swing(self) -> None:
        """Where the joint-space swing into `raised` would touch something, first move the hand straight up, every
        RETRACT_STEP m as long as the arm (and what it holds) touches nothing, RETRACT_RISE m at most, to the
        first height from which that swing is clear (or the highest clear one): a hand let go low over a low
        table swung sideways into the raised arm across it and pushed a violin 18 cm. The fingers are checked too
        (as `_seen`): risen from below the handle of a drawer it had just let go of,
        the open hand rose into the handle and the swing from there pushed the drawer 10 cm shut."""
        held = None if self.held is None else self.held_object(self.held)
        start = self._seen(self.controller.target)
        if self.swing_clear(start, self._seen(self.raised(start[3])), held):
            return
        grip, quat = self.ik.grip_pose(start)
        steps = int(round(RETRACT_RISE / RETRACT_STEP))
        path = self.line(grip, grip + np.array([0.0, 0.0, RETRACT_RISE]), quat, steps=steps, partial=True, seed=start)
        up = []
        for q in path:
            if not self.clearance.clear(q, held=held, fingers=True):
                break
            up.append(q)
            if self.swing_clear(q, self._seen(self.raised(q[3])), held):
                break
        if up:
            self.controller.move_through(up)

    def tucked(self) -> np.ndarray:
        """The tuck posture at the current base pose and torso height (at least the tuck's): the torso is the
        slowest joint (0.1 m/s), so it stays up between skills instead of going down and up again."""
        q = self.tuck.copy()
        q[:3] = self.controller.target[:3]
        q[3] = max(float(self.controller.target[3]), float(self.tuck[3]))
        return q

    def go_to(self, node: str, target_xy: np.ndarray, surface_z: float | None = None) -> bool:
        """Drive to a free base pose in front of furniture `node`, facing `target_xy`: with the arm tucked, or
        while holding an object at the carry point (see `carry_path`). A held object keeps clear of open doors,
        and, if it hangs lower than PASS_OVER above `surface_z` (m, the surface it is for), of the furniture itself:
        then the robot stops short and returns True."""
        if self.folded:
            posture = self.tucked()
        else:
            posture = self.carry()
        reach, short = 0.0, False
        if self.held is not None:  # the held object sticks out past the base
            size = self.world.object_class(self.held).size
            body = self.world.object_body_ids[self.world.object_index(self.held)]
            position = self.world.object_pose(self.held)[0]
            half_height = float(np.abs(self.world.data.xmat[body].reshape(3, 3)[2]) @ np.asarray(size) / 2)
            reach = self.held_reach()
            short = surface_z is not None and position[2] - half_height < surface_z + PASS_OVER
            if short:  # the carry stalled low: lifted straight up clear, as far as the arm reaches (one joint-space
                # move there swung a dress held by its fold out of the fingers)
                grip = self.world.data.site("robot/grip").xpos
                lift = surface_z + PASS_OVER + half_height - position[2]
                higher = self.hand_line(grip + np.array([0.0, 0.0, lift + 0.02]), self.grip_quat(), GRASP_BASE_COST,
                                        partial=True)
                if higher:
                    self.controller.move_through(higher, speed=CARRY_ARM_SPEED)
                    posture = higher[-1]
                    position = self.world.object_pose(self.held)[0]
                    short = position[2] - half_height < surface_z + PASS_OVER
        self.navigator.drive_to(self.navigator.stand_pose(node, tuple(target_xy), reach if short else 0.0), posture,
                                reach, **(FREE_MOTION if self.held is None else CARRY_MOTION), clear=self.carry_clear())
        return short

    def carry_clear(self):
        """Whether a configuration (shape (13,)) keeps the arm and the object in the hand, as it sits there now,
        clear of the apartment (a function for `Navigator.drive_to`); None with an empty hand."""
        if self.held is None:
            return None
        held = self.held_object(self.held)
        return lambda q: self.clearance.clear(q, held=held)

    def go_to_grasp(self, grasp: Grasp, pull: np.ndarray, entry: float, here_first: bool = False,
                     direct: bool = False, rise: float = 0.0, held: Held | None = None
                     ) -> tuple[list[np.ndarray], float] | None:
        """Drive (arm tucked) to a free base pose from which the way into `grasp` is reachable with the arm
        clear of the apartment: the grip `entry` m out along `pull` (a horizontal unit vector out of the
        furniture, shape (3,)) from the approach point, in along a straight line, the approach (within the arm's
        reach only: the fingers close round the object there; from a base pose that did not reach it, the arm
        went out over a laundry basket on the floor and gave up above the dress in it), and SIDE_LIFT m
        (else, out of furniture, LOW_SIDE_LIFT m) above the grasp. Returns the configurations (each shape (13,))
        from the entry to the approach point and that lift (m), or None (the robot stays) if no base pose works.
        Base poses face the grasp along its approach, then, where the approach leans more than ASIDE_LEAN aside
        (see `rolled_grasps`), also into the furniture (against `pull`): beside it often no base pose is free.
        With `here_first`, where the robot stands is tried first; with `direct`, the arm may also swing straight
        from the tuck (see `way_in`). `rise`: m the object must rise before it is drawn out (over what stands in
        front of it, `rise_to_pass`, or a basin's rim): where it is more than SIDE_LIFT, that lift is tried first,
        the object (`held`, as the grasp would hold it) checked clear of the compartment at its top, from every base
        pose; the others where none reaches it (the neighbour's outline is a box round it: a trash bag drawn out
        low passed the can beside it)."""
        quat = grasp.quat()
        above = grasp.position - grasp.approach * grasp.rotation[:, 0]
        obstacles = self.navigator.obstacles()
        here = [tuple(self.controller.target[:3])] if here_first else []
        candidates = self._grasp_bases(grasp, pull)
        lifts = (SIDE_LIFT, LOW_SIDE_LIFT) if np.linalg.norm(pull) > 0.0 else (SIDE_LIFT,)  # a shelf grasp's first leg
        free = self.navigator.radius + CLEARANCE
        passes = [(rise,), lifts] if rise > SIDE_LIFT else [lifts]  # over what stands in front first, where it reaches
        for lifts, base in [(heights, base) for heights in passes for base in [*here, *candidates]]:
            if base not in here and not self.navigator.plan.disk_is_free(base[0], base[1], free, obstacles):
                continue
            q = self.tuck.copy()
            q[:3] = base
            start = self.ik.solve(q, above + entry * pull, quat, base_cost=ARC_BASE_COST)
            if not start.converged or not self.clearance.clear(start.q):
                continue
            path = self.checked_line(start.q, [above + entry * pull, above], quat)
            if path is not None and self.line(above, grasp.position, quat, seed=path[-1]) is None:
                continue  # the approach onto the grasp leaves the arm's reach from here
            lift = None if path is None else next((h for h in lifts if self._lift_clear(
                path[-1], above, grasp, h, held if h > SIDE_LIFT else None)), None)
            if lift is None:
                continue
            lead = self.way_in(base, start.q, above + entry * pull, quat, direct)
            if lead is None:
                continue
            self.retract()
            self.navigator.drive_to(base, self.tucked(), **FREE_MOTION)
            path_in = [*lead, *path]
            for q_in in path_in:
                q_in[:3] = self.controller.target[:3]  # where the base really stopped
            return path_in, lift
        return None

    def _lift_clear(self, q: np.ndarray, above: np.ndarray, grasp: Grasp, lift: float, held: Held | None) -> bool:
        """Whether the arm, from configuration q (shape (13,)) at the approach point `above` (m), comes down onto
        `grasp` and lifts `lift` m clear of the apartment, and `held` (if given, the object in the hand) is clear
        there at the top (it rests on its shelf at the grasp)."""
        top = grasp.position + np.array([0.0, 0.0, lift])
        path = self.checked_line(q, [above, grasp.position, top], grasp.quat())
        return path is not None and (held is None or self.clearance.clear(path[-1], held=held))

    def _grasp_bases(self, grasp: Grasp, pull: np.ndarray) -> list[tuple[float, float, float]]:
        """Base poses (x m, y m, yaw rad) to try for `grasp` (see `base_candidates`): facing it along its
        approach, then, where the approach leans more than ASIDE_LEAN aside of the way into the furniture
        (against `pull`, shape (3,)), also facing into the furniture."""
        lean = grasp.rotation[:2, 0]
        aside = (np.linalg.norm(lean) > PITCHED_HAND and np.linalg.norm(pull) > 0.0
                 and float(lean @ -pull[:2]) < math.cos(ASIDE_LEAN) * float(np.linalg.norm(lean)))
        candidates = base_candidates(grasp.position, grasp.rotation, self.controller.q()[:2])
        if aside:  # then also those facing into the furniture
            candidates += base_candidates(grasp.position, grasp.rotation, self.controller.q()[:2], -pull)
        return candidates

    def way_in(self, base: np.ndarray, q: np.ndarray, point: np.ndarray, quat: np.ndarray, direct: bool = False
                ) -> list[np.ndarray] | None:
        """The way from the tuck at base pose `base` (x m, y m, yaw rad) to configuration q (shape (13,), the grip
        site at `point`, m, orientation `quat`): unfolded, then `lead_in`; else, with `direct` (where unfolding
        touches: close to a tall cupboard or its open door), straight from the tuck to q if that swing is clear
        (`reach` takes it); None if neither."""
        if self.unfold_clear(base, q[3]):
            lead = self.lead_in(q, point, quat)
            if lead is not None:
                return lead
        if not direct:
            return None
        tucked = self.tucked()
        tucked[:3] = base
        return [q] if self.swing_clear(tucked, q) else None

    def unfold_clear(self, base: np.ndarray, torso: float) -> bool:
        """Whether the arm unfolds from the tuck to `raised(torso)` at base pose `base` (x m, y m, yaw rad)
        without touching anything: next to a table the folded elbow swings out over its top."""
        tucked, raised = self.tucked(), self.raised(torso)
        tucked[:3] = raised[:3] = base
        return self.swing_clear(tucked, raised)

    def lead_in(self, q: np.ndarray, point: np.ndarray, quat: np.ndarray) -> list[np.ndarray] | None:
        """The way from the raised arm to configuration q (shape (13,), the grip site at `point`, m): q alone if
        the joint-space swing there touches nothing, else down onto `point` from a LEAD_HEIGHTS m higher one
        (the swing passes over what stands on a table); None if neither is clear."""
        if self.swing_clear(self.raised(q[3]), q):
            return [q]
        for height in LEAD_HEIGHTS:
            high = point + np.array([0.0, 0.0, height])
            via = self.ik.solve(q, high, quat, base_cost=ARC_BASE_COST, seeds=False)
            if not via.converged or not self.swing_clear(self.raised(q[3]), via.q):
                continue
            down = self.checked_line(via.q, [high, point], quat)
            if down is not None:
                return [via.q, *down]
        return None

    def swing_clear(self, q_from: np.ndarray, q_to: np.ndarray, held: Held | None = None) -> bool:
        """Whether the joint-space move q_from -> q_to (each shape (13,), base at q_to's) keeps the arm, the
        fingers (they swing free) and `held`, an object in the hand, clear (of the robot too, but its hand),
        checked every SWING_STEP rad of the largest joint change."""
        q_from = q_from.copy()
        q_from[:3] = q_to[:3]
        steps = _swing_steps(q_from, q_to)
        return all(self.clearance.clear(q_from + s * (q_to - q_from), held=held, fingers=True, itself=True)
                   for s in np.linspace(0.0, 1.0, steps + 1)[1:])

    def checked_line(self, q: np.ndarray, points: list[np.ndarray], quat: np.ndarray, held: Held | None = None
                      ) -> list[np.ndarray] | None:
        """IK configurations (base held, each shape (13,)) from q through grip-site points (m, each shape (3,)),
        ENTRY_STEP m apart on the straight lines between them; None if one is unreachable or touches anything
        (`held`, an object in the hand, included)."""
        path = []
        for a, b in zip(points[:-1], points[1:], strict=False):
            steps = max(1, int(np.ceil(np.linalg.norm(b - a) / ENTRY_STEP)))
            for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
                result = self.ik.solve(q, a + s * (b - a), quat, base_cost=ARC_BASE_COST, seeds=False)
                if not result.converged or not self.clearance.clear(result.q, held=held):
                    return None
                q = result.q
                path.append(q)
        return path

    def carry(self) -> np.ndarray:
        """Move the held object to the carry point along `carry_path`, at CARRY_ARM_SPEED; returns the posture there
        (shape (13,)). Where that way touches something with an object in the hand, the base first backs straight
        away with the arm held as it is (`_backed_off`), and the way is planned again from there: a vegetable
        lifted off a cutting board was carried down to the carry point against the knife block beside it (pushed
        4 cm), right where the base stood."""
        path = self.carry_path()
        if self.held is not None:
            held = self.held_object(self.held)
            if not all(self.clearance.clear(q, held=held) for q in path):
                back = self._backed_off(held)
                if back is not None:
                    self.controller.move_through(back, speed=CARRY_ARM_SPEED)
                    path = self.carry_path()
        self.controller.move_through(path, speed=CARRY_ARM_SPEED)
        return path[-1]

    def _backed_off(self, held: Held | None) -> list[np.ndarray] | None:
        """Configurations (each shape (13,)) that back the base straight away from where it faces, the arm and
        the torso held as they are (the hand moves with the base), by the first of BACK_OFF m whose way is free
        for the base and keeps the arm and `held` (an object in the hand, if any) clear all along, checked every
        ENTRY_STEP m; None if none is."""
        q0 = self.controller.target.copy()
        heading = np.array([math.cos(q0[2]), math.sin(q0[2])])
        obstacles = self.navigator.obstacles()
        free = self.navigator.radius + CLEARANCE
        for distance in BACK_OFF:
            steps = max(1, int(np.ceil(distance / ENTRY_STEP)))
            path = []
            for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
                q = q0.copy()
                q[:2] -= s * distance * heading
                if not self.navigator.plan.disk_is_free(q[0], q[1], free, obstacles) or \
                        not self.clearance.clear(q, held=held):
                    break
                path.append(q)
            else:
                return path
        return None

    def carry_path(self) -> list[np.ndarray]:
        """Configurations (each shape (13,)) along a straight grip-site line from where the hand is to the carry
        point CARRY_REACHES[0] m in front of the base at CARRY_HEIGHT m (higher where the held object hangs lower
        than CARRY_CLEAR m then), stopped at the last reachable point; a
        joint-space move there could swing the held object down through the furniture or out of the fingers. A
        hand held level that stops short of that height (pointing ahead, it reaches no higher than 0.9 m there)
        goes to the first farther carry point it reaches instead, if the arm and the held object touch nothing on
        the way (the line may pass over what stands in front), else along the clear line that ends highest. A hand
        pointing behind the base's front (and not down) turns on the way about the vertical to point ahead of it:
        a later move into a shelf the base faces would swing the object past the base and knock it out of the
        fingers. Otherwise the orientation is kept. Where the straight line to the nearest carry point touches
        something with an object in the hand, it is drawn out level first if that way is clear (`_drawn_out`)."""
        x, y, yaw = self.controller.target[:3]
        rotation = self.world.data.site("robot/grip").xmat.reshape(3, 3)
        ahead = np.array([np.cos(yaw), np.sin(yaw)])
        if np.linalg.norm(rotation[:2, 0]) > PITCHED_HAND and rotation[:2, 0] @ ahead < 0.0:  # points back: turn it
            rotation = yaw_matrix(yaw - math.atan2(rotation[1, 0], rotation[0, 0])) @ rotation
        level = np.linalg.norm(rotation[:2, 0]) > LEVEL_HAND
        held = None if self.held is None else self.held_object(self.held)
        carry_height = CARRY_HEIGHT if self.held is None else max(CARRY_HEIGHT, CARRY_CLEAR + self._hang())
        best, height = [self.controller.target.copy()], -np.inf
        for k, reach in enumerate(CARRY_REACHES if level else CARRY_REACHES[:1]):
            point = np.array([x + reach * ahead[0], y + reach * ahead[1], carry_height])
            path = self.hand_line(point, matrix_to_quat(rotation), GRASP_BASE_COST, partial=True)
            touching = 0 if held is None or k else sum(not self.clearance.clear(q, held=held) for q in path)
            if touching:
                path = self._drawn_out(point, matrix_to_quat(rotation), held, touching) or path
            end = self.ik.grip_pose(path[-1])[0][2] if path else -np.inf
            if end > height and (k == 0 or all(self.clearance.clear(q, held=held) for q in path)):
                best, height = path, end
            if height > carry_height - WAYPOINT_TOL[0]:
                break
        return best

    def _drawn_out(self, point: np.ndarray, quat: np.ndarray, held: Held, touching: int) -> list[np.ndarray] | None:
        """The way of the held object to the carry point `point` (m) at `quat` in two straight legs: level to above
        or below it (out of the furniture, towards the base), then up or down to it (as far as the arm reaches),
        if fewer than `touching` (those of the straight line) of its configurations touch anything; else None.
        The straight line up and across dragged a cup picked from a dishwasher's rack along the underside of the
        counter top over it, out of the fingers."""
        grip = self.world.data.site("robot/grip").xpos
        out = self.hand_line(np.array([point[0], point[1], grip[2]]), quat, GRASP_BASE_COST)
        if out is None:
            return None
        up = self.hand_line(point, quat, GRASP_BASE_COST, partial=True, seed=out[-1]) or []
        path = [*out, *up]
        return path if sum(not self.clearance.clear(q, held=held) for q in path) < touching else None

    def _hang(self) -> float:
        """How far (m) the held object reaches below the grip site now, as it hangs (tilted) in the hand."""
        index = self.world.object_index(self.held)
        size = np.asarray(CATALOG[self.world.layout.objects[index].cls].size)
        body = self.world.object_body_ids[index]
        low = self.world.object_pose(self.held)[0][2] - np.abs(self.world.data.xmat[body].reshape(3, 3)[2]) @ size / 2
        return float(self.world.data.site("robot/grip").xpos[2] - low)

    def hand_line(self, point: np.ndarray, quat: np.ndarray, base_cost: float, partial: bool = False,
                   seed: np.ndarray | None = None) -> list[np.ndarray] | None:
        """`line` from where the grip site is now (or at configuration `seed`, shape (13,)) to `point` (m) at
        orientation `quat`, turning the hand evenly on the way: CARRY_STEP m and at most TURN_STEP rad between IK
        waypoints (at least two), every one within WAYPOINT_TOL: a move between poses, not onto a grasp."""
        if seed is None:
            start, now = self.world.data.site("robot/grip").xpos.copy(), self.grip_quat()
        else:
            start, now = self.ik.grip_pose(seed)
        turn = 2.0 * math.acos(min(abs(float(np.dot(now, quat))), 1.0))
        steps = max(2, int(np.ceil(np.linalg.norm(point - start) / CARRY_STEP)), int(np.ceil(turn / TURN_STEP)))
        return self.line(start, point, quat, steps, base_cost=base_cost, loose_end=True, partial=partial,
                          seed=seed, from_quat=now)

    def grip_line(self, point: np.ndarray, quat: np.ndarray) -> bool:
        """Move the grip site in a straight line to `point` (m), orientation `quat` kept (see `hand_line`), the
        base free to follow; False (nothing moved) if the line leaves the arm's reach."""
        path = self.hand_line(point, quat, PULL_BASE_COST)
        if path is None:
            return False
        self.controller.move_through(path)
        return True

    # --- the held object ---------------------------------------------------------------------------------
    def held_offset(self, name: str) -> np.ndarray:
        """Where object `name` sits in the grip site's frame (m, shape (3,)): it stays put while the hand turns,
        so a change of it is slip."""
        grip = self.world.data.site("robot/grip")
        return grip.xmat.reshape(3, 3).T @ (self.world.object_pose(name)[0] - grip.xpos)

    def hand_empty(self) -> bool:
        """Whether the closed fingers hold nothing (they met each other)."""
        return float(np.mean(self.controller.q()[-2:])) < MIN_HELD_OPENING

    def held_object(self, name: str) -> Held:
        """Object `name` as it sits in the hand now, for clearance checks of moves that carry it."""
        model, index = self.world.model, self.world.object_index(name)
        body = self.world.object_body_ids[index]
        grip = self.world.data.site("robot/grip")
        rotation = grip.xmat.reshape(3, 3)
        return Held(frozenset(np.flatnonzero(model.geom_bodyid == body).tolist()),
                    int(model.jnt_qposadr[model.body_jntadr[body]]), self.held_offset(name),
                    rotation.T @ self.world.data.xmat[body].reshape(3, 3))

    def held_reach(self) -> float:
        """How far (m) the held object sticks out from the base centre, with CLEARANCE."""
        index = self.world.object_index(self.held)
        size = CATALOG[self.world.layout.objects[index].cls].size
        position = self.world.object_pose(self.held)[0]
        return float(np.linalg.norm(position[:2] - self.controller.q()[:2]) + np.linalg.norm(size[:2]) / 2
                     + CLEARANCE)

    def fallen_over(self, name: str) -> bool:
        """Whether object `name` no longer stands up (its up axis tilted past UPRIGHT)."""
        return bool(self.world.data.xmat[self.world.object_body_ids[self.world.object_index(name)]][8] < UPRIGHT)

    def grip_quat(self) -> np.ndarray:
        """The grip site's current orientation (wxyz), kept while carrying."""
        return matrix_to_quat(self.world.data.site("robot/grip").xmat.reshape(3, 3))


def _swing_steps(q_from: np.ndarray, q_to: np.ndarray) -> int:
    """How many SWING_STEP steps the largest torso or arm joint change of q_from -> q_to takes (at least one)."""
    return max(1, int(np.ceil(np.max(np.abs(q_to[3:11] - q_from[3:11])) / SWING_STEP)))
