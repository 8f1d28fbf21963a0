"""Robot skills in physics: pick and place, checked on the observed scene graph.

Objects move only because the fingers hold them (no weld, no teleport). Each skill returns a `SkillResult`
with success or a clear failure reason; a failed grasp is retried from the next grasp candidate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from homer_sim.catalog import CATALOG
from homer_sim.graph import INSIDE, ON, RELATION_NAMES
from homer_sim.observe import SceneGraphObserver
from homer_sim.placement import place_world
from homer_sim.spots import Spots
from homer_sim.validate import ROBOT_RADIUS
from planners.articulate import base_candidates, drawer_rim
from planners.container_grasps import hang_rotation
from planners.control import CARRY_MOTION, FREE_MOTION, Controller
from planners.door_skills import ARC_BASE_COST, ClearanceCheck, Held, PartMover
from planners.grasps import Grasp, disturbed, matrix_to_quat, slerp, ungraspable_reason
from planners.ik import IKSolver
from planners.navigation import CLEARANCE, NavigationError, Navigator
from planners.neighbours import neighbour_footprints
from planners.shelf_grasps import shelf_grasps
from planners.top_grasps import offset_grasps, rim_approach, top_grasps

APPROACH = 0.12  # m above the grasp the gripper comes from and leaves to (top grasps; see Grasp.approach)
LIFT = 0.15  # m
DRAWER_CLEARANCE = 0.03  # m an object lifted out of a drawer rises past the top of its front
HOLD_SECONDS = 0.5
MIN_HELD_OPENING = 0.001  # m per finger: closed further means the fingers missed
GRASP_BASE_COST = 100.0  # IK damping on the base while grasping
RAISED_TORSO = 0.3  # m
CARRY_REACH = 0.35  # m from the base centre
CARRY_HEIGHT = 1.05  # m
CARRY_SLIP = 0.03  # m the held object may shift in the hand while carried before a place gives up
CARRY_STEP = 0.05  # m between IK waypoints on the way to the carry point
TURN_STEP = 0.15  # rad the hand turns at most between IK waypoints of a move between poses
RAISED_SHOULDER = -1.0  # rad: upper arm raised above the tuck
SIDE_LIFT = 0.03  # m: a side grasp first lifts the object this much off its shelf,
SIDE_PULL = 0.35  # m: then draws it this far out of the furniture,
SIDE_RAISE = 0.13  # m: then raises it this much more
ENTRY_OUT = 0.12  # m: a grasp inside furniture is entered from this far in front of its front plane
ENTRY_STEP = 0.05  # m between checked configurations on the way in
PASS_OVER = 0.03  # m between a carried object and a surface it is carried over before it is put down
PULL_BASE_COST = 0.1  # IK damping on the base while drawing an object out: the base backs away
LEAD_HEIGHTS = (0.15, 0.3)  # m above a grasp's entry point the arm may first swing to, then come down
SWING_STEP = 0.02  # rad between checked configurations of a joint-space swing (a fingertip 0.9 m out moves
# under 2 cm: it cannot pass through a drawer front unseen)
UPRIGHT = 0.7  # z component of an object's up axis below which a put-down object has fallen over
PITCHED_HAND = 0.25  # horizontal part of the grip x axis above which the hand does not count as pointing down
LEVEL_HAND = 0.7  # horizontal part of the grip x axis above which the hand counts as held level
OPEN_ABOVE = 0.5  # m of free height above a place below which a grasp from above does not fit
SHELF_SPOTS = 6  # free spots on a shelf tried for a place, nearest the front first,
SHELF_SPOT_GAP = 0.05  # m apart at least
EASE_SLOWDOWN = 3.0  # times the default duration of a joint-space move with a held object into furniture
RELEASE_OPENING = 0.015  # m per finger the fingers open past the held object to let go (inside a shelf)
WAYPOINT_TOL = (0.015, np.deg2rad(5.0))  # m, rad: IK tolerance of a straight line's intermediate points (the end
# point is exact); tight ones stall near joint limits on the way


@dataclass(frozen=True)
class SkillResult:
    """success, and when not, why (names the object, the place and the measured values)."""

    success: bool
    reason: str = ""


class Robot:
    """The robot in a World: IK, control, navigation, scene-graph checks, and the skills built on them."""

    def __init__(self, world, rng: np.random.Generator | None = None) -> None:
        self.world = world
        self.ik = IKSolver()
        self.controller = Controller(world)
        self.navigator = Navigator(world, self.controller)
        self.spots = Spots(world)
        self.observer = SceneGraphObserver(world)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.tuck = self.ik.model.key("home").qpos.copy()
        self.held: str | None = None
        self.folded = True  # the arm is in (or moving from) the tuck posture
        self.shoulder_lift = self.ik.model.joint("shoulder_lift").qposadr[0]
        self.clearance = ClearanceCheck(world, self.controller)

    # --- motion helpers ---------------------------------------------------------------------------------
    def _ik(self, position: np.ndarray, rotation_quat: np.ndarray, seeds: bool = True):
        return self.ik.solve(self.controller.target, position, rotation_quat, base_cost=GRASP_BASE_COST,
                             seeds=seeds)

    def _line(self, start: np.ndarray, end: np.ndarray, quat: np.ndarray, steps: int = 4,
              base_cost: float = GRASP_BASE_COST, loose_end: bool = False,
              partial: bool = False, seed: np.ndarray | None = None,
              from_quat: np.ndarray | None = None) -> list[np.ndarray] | None:
        """IK configurations along the straight grip-site line start -> end (m), or None if any is unreachable
        (with `partial`, those up to the last reachable point instead); base_cost: IK damping on the base (low
        lets the base back away, e.g. drawing an object off a shelf). Points before the end are solved within
        WAYPOINT_TOL, the end exactly unless `loose_end`. seed: the configuration at `start` (default: the
        controller's target). from_quat: the orientation at `start`, turned evenly into `quat` on the way (default:
        `quat` all along)."""
        q = (self.controller.target if seed is None else seed).copy()
        path = []
        for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
            loose = {} if s == 1.0 and not loose_end else {"position_tol": WAYPOINT_TOL[0],
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

    def reach(self, q_goal: np.ndarray, grip: float | None = None) -> None:
        """Move to configuration q_goal (shape (13,)); from the tuck posture straight there if that swing touches
        nothing, else through `raised`, quicker (the hand is empty)."""
        if self.folded:
            via = [] if self._swing_clear(self.controller.target, q_goal) else [self.raised(q_goal[3])]
            self.controller.move_through([*via, q_goal], grip=grip, **FREE_MOTION)
        else:
            self.controller.move_through([q_goal], grip=grip)
        self.folded = False

    def retract(self) -> None:
        """Tuck the arm in place (the base and the torso stay): with an empty hand straight there if that swing
        touches nothing, quicker; else through `raised`."""
        if not self.folded:
            tucked = self.tucked()
            if self.held is None and self._swing_clear(self.controller.target, tucked):
                self.controller.move_through([tucked], **FREE_MOTION)
            else:
                self.controller.move_through([self.raised(self.controller.target[3]), tucked])
        self.folded = True

    def tucked(self) -> np.ndarray:
        """The tuck posture at the current base pose and torso height (at least the tuck's): the torso is the
        slowest joint (0.1 m/s), so it stays up between skills instead of going down and up again."""
        q = self.tuck.copy()
        q[:3] = self.controller.target[:3]
        q[3] = max(float(self.controller.target[3]), float(self.tuck[3]))
        return q

    def go_to(self, node: str, target_xy: np.ndarray, surface_z: float | None = None) -> bool:
        """Drive to a free base pose in front of furniture `node`, facing `target_xy`: with the arm tucked, or
        while holding an object with the grip site CARRY_REACH m in front of the base at CARRY_HEIGHT m. A held
        object keeps clear of open doors, and, if it hangs lower than PASS_OVER above `surface_z` (m, the surface
        it is for), of the furniture itself: then the robot stops short and returns True."""
        if self.folded:
            posture = self.tucked()
        else:
            path = self._carry_path()
            self.controller.move_through(path)
            posture = path[-1]
        reach, short = 0.0, False
        if self.held is not None:  # the held object sticks out past the base
            size = CATALOG[self.world.layout.objects[self.world.object_index(self.held)].cls].size
            body = self.world.object_body_ids[self.world.object_index(self.held)]
            position = self.world.object_pose(self.held)[0]
            half_height = float(np.abs(self.world.data.xmat[body].reshape(3, 3)[2]) @ np.asarray(size) / 2)
            reach = self._held_reach()
            short = surface_z is not None and position[2] - half_height < surface_z + PASS_OVER
            if short:  # the straight carry line stalled low: one IK solution lifts it clear, if there is one
                grip = self.world.data.site("robot/grip").xpos
                lift = surface_z + PASS_OVER + half_height - position[2]
                higher = self._ik(grip + np.array([0.0, 0.0, lift + 0.02]), self._held_quat())
                if higher.converged:
                    self.controller.move_through([higher.q])
                    posture = higher.q
                    position = self.world.object_pose(self.held)[0]
                    short = position[2] - half_height < surface_z + PASS_OVER
        self.navigator.drive_to(self.navigator.stand_pose(node, tuple(target_xy), reach if short else 0.0), posture,
                                reach, **(FREE_MOTION if self.held is None else CARRY_MOTION))
        return short

    def _go_to_grasp(self, grasp: Grasp, pull: np.ndarray, entry: float, here_first: bool = False,
                     direct: bool = False) -> list[np.ndarray] | None:
        """Drive (arm tucked) to a free base pose from which the way into `grasp` is reachable with the arm
        clear of the apartment: the grip `entry` m out along `pull` (a horizontal unit vector out of the
        furniture, shape (3,)) from the approach point, in along a straight line, the approach, and SIDE_LIFT m
        above the grasp. Returns the configurations (each shape (13,)) from the entry to the approach point, or
        None (the robot stays) if no base pose works. With `here_first`, where the robot stands is tried first;
        with `direct`, the arm may also swing straight from the tuck (see `_way_in`)."""
        quat = grasp.quat()
        above = grasp.position - grasp.approach * grasp.rotation[:, 0]
        obstacles = self.navigator.open_part_rects()
        here = [tuple(self.controller.target[:3])] if here_first else []
        for base in [*here, *base_candidates(grasp.position, grasp.rotation, self.controller.q()[:2])]:
            if base not in here and not self.navigator.plan.disk_is_free(base[0], base[1], ROBOT_RADIUS + CLEARANCE,
                                                                         obstacles):
                continue
            q = self.tuck.copy()
            q[:3] = base
            start = self.ik.solve(q, above + entry * pull, quat, base_cost=ARC_BASE_COST)
            if not start.converged or not self.clearance.clear(start.q):
                continue
            path = self._checked_line(start.q, [above + entry * pull, above], quat)
            if path is None or self._checked_line(path[-1], [above, grasp.position, grasp.position + np.array(
                    [0.0, 0.0, SIDE_LIFT])], quat) is None:
                continue
            lead = self._way_in(base, start.q, above + entry * pull, quat, direct)
            if lead is None:
                continue
            self.retract()
            self.navigator.drive_to(base, self.tucked(), **FREE_MOTION)
            path_in = [*lead, *path]
            for q_in in path_in:
                q_in[:3] = self.controller.target[:3]  # where the base really stopped
            return path_in
        return None

    def _way_in(self, base: np.ndarray, q: np.ndarray, point: np.ndarray, quat: np.ndarray, direct: bool = False
                ) -> list[np.ndarray] | None:
        """The way from the tuck at base pose `base` (x m, y m, yaw rad) to configuration q (shape (13,), the grip
        site at `point`, m, orientation `quat`): unfolded, then `_lead_in`; else, with `direct` (where unfolding
        touches: close to a tall cupboard or its open door), straight from the tuck to q if that swing is clear
        (`reach` takes it); None if neither."""
        if self._unfold_clear(base, q[3]):
            lead = self._lead_in(q, point, quat)
            if lead is not None:
                return lead
        if not direct:
            return None
        tucked = self.tucked()
        tucked[:3] = base
        return [q] if self._swing_clear(tucked, q) else None

    def _unfold_clear(self, base: np.ndarray, torso: float) -> bool:
        """Whether the arm unfolds from the tuck to `raised(torso)` at base pose `base` (x m, y m, yaw rad)
        without touching anything: next to a table the folded elbow swings out over its top."""
        tucked, raised = self.tucked(), self.raised(torso)
        tucked[:3] = raised[:3] = base
        return self._swing_clear(tucked, raised)

    def _lead_in(self, q: np.ndarray, point: np.ndarray, quat: np.ndarray) -> list[np.ndarray] | None:
        """The way from the raised arm to configuration q (shape (13,), the grip site at `point`, m): q alone if
        the joint-space swing there touches nothing, else down onto `point` from a LEAD_HEIGHTS m higher one
        (the swing passes over what stands on a table); None if neither is clear."""
        if self._swing_clear(self.raised(q[3]), q):
            return [q]
        for height in LEAD_HEIGHTS:
            high = point + np.array([0.0, 0.0, height])
            via = self.ik.solve(q, high, quat, base_cost=ARC_BASE_COST, seeds=False)
            if not via.converged or not self._swing_clear(self.raised(q[3]), via.q):
                continue
            down = self._checked_line(via.q, [high, point], quat)
            if down is not None:
                return [via.q, *down]
        return None

    def _swing_clear(self, q_from: np.ndarray, q_to: np.ndarray, held: Held | None = None) -> bool:
        """Whether the joint-space move q_from -> q_to (each shape (13,), base at q_to's) keeps the arm, the
        fingers (they swing free) and `held`, an object in the hand, clear, checked every SWING_STEP rad of the
        largest joint change."""
        q_from = q_from.copy()
        q_from[:3] = q_to[:3]
        steps = max(1, int(np.ceil(np.max(np.abs(q_to[3:11] - q_from[3:11])) / SWING_STEP)))
        return all(self.clearance.clear(q_from + s * (q_to - q_from), held=held, fingers=True)
                   for s in np.linspace(0.0, 1.0, steps + 1)[1:])

    def _checked_line(self, q: np.ndarray, points: list[np.ndarray], quat: np.ndarray, held: Held | None = None
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

    def _carry_path(self) -> list[np.ndarray]:
        """Configurations (each shape (13,)) along a straight grip-site line from where the hand is to the carry
        point, CARRY_REACH m in front of the base at CARRY_HEIGHT m; a joint-space move there could swing the held
        object down through the furniture or out of the fingers. A hand pointing behind the base's front (and not
        down) turns on the way about the vertical to point ahead of it: a later move into a shelf the base faces
        would swing the object past the base and knock it out of the fingers. Otherwise the orientation is kept.
        Where the line leaves the arm's reach, the hand stays at the last reachable point."""
        x, y, yaw = self.controller.target[:3]
        point = np.array([x + CARRY_REACH * np.cos(yaw), y + CARRY_REACH * np.sin(yaw), CARRY_HEIGHT])
        rotation = self.world.data.site("robot/grip").xmat.reshape(3, 3)
        ahead = np.array([np.cos(yaw), np.sin(yaw)])
        if np.linalg.norm(rotation[:2, 0]) > PITCHED_HAND and rotation[:2, 0] @ ahead < 0.0:  # points back: turn it
            rotation = _yaw_matrix(yaw - math.atan2(rotation[1, 0], rotation[0, 0])) @ rotation
        return self._hand_line(point, matrix_to_quat(rotation), GRASP_BASE_COST, partial=True) or [
            self.controller.target.copy()]

    def _hand_line(self, point: np.ndarray, quat: np.ndarray, base_cost: float, partial: bool = False,
                   seed: np.ndarray | None = None) -> list[np.ndarray] | None:
        """`_line` from where the grip site is now (or at configuration `seed`, shape (13,)) to `point` (m) at
        orientation `quat`, turning the hand evenly on the way: CARRY_STEP m and at most TURN_STEP rad between IK
        waypoints (at least two), every one within WAYPOINT_TOL: a move between poses, not onto a grasp."""
        if seed is None:
            start, now = self.world.data.site("robot/grip").xpos.copy(), self._held_quat()
        else:
            start, now = self.ik.grip_pose(seed)
        turn = 2.0 * math.acos(min(abs(float(np.dot(now, quat))), 1.0))
        steps = max(2, int(np.ceil(np.linalg.norm(point - start) / CARRY_STEP)), int(np.ceil(turn / TURN_STEP)))
        return self._line(start, point, quat, steps, base_cost=base_cost, loose_end=True, partial=partial,
                          seed=seed, from_quat=now)

    # --- pick --------------------------------------------------------------------------------------------
    def pick(self, name: str, node: str | None = None, into: str | None = None) -> SkillResult:
        """Grasp object `name` and lift it LIFT m; `node` (the furniture it is on or in) is where to stand.
        `into`: where it goes next; a cabinet's shelf takes an object held from the side or pitched down from the
        front (a hand pointing straight down does not fit under the shelf above), so from a table it is then
        grasped that way first."""
        cls = CATALOG[self.world.layout.objects[self.world.object_index(name)].cls]
        reason = ungraspable_reason(cls)
        if reason is not None:
            return SkillResult(False, f"{name}: not graspable ({reason})")
        if self._fallen_over(name):  # every grasp here is for an object standing up
            return SkillResult(False, f"{name}: it has fallen over (lies on its side), and no grasp fits it so")
        graph = self.observer.update()
        node = node or graph.parent_of(name)
        position, quat = self.world.object_pose(name)
        furniture = self.navigator.furniture.get(node)
        inside = graph.relation_of(name) == RELATION_NAMES[INSIDE] and furniture is not None
        if (inside and furniture.kind == "cabinet") or self._under_a_shelf(node, position, cls.size[2]):
            return self._pick_from_shelf(name, node, cls, position, quat)  # from the front, the base placed per grasp
        side_failures: list[str] = []
        if into is not None and furniture is not None and self._shelves(into, None):
            try:  # from the side nearest where the robot would stand
                stand = np.array(self.navigator.stand_pose(node, tuple(position[:2]))[:2])
            except NavigationError as error:
                return SkillResult(False, f"{name}: {error}")
            toward = (stand - position[:2]) / max(float(np.linalg.norm(stand - position[:2])), 1e-9)
            yaw = 2.0 * math.atan2(quat[3], quat[0])
            axes = [np.array([math.cos(yaw + a), math.sin(yaw + a)]) for a in np.arange(4) * math.pi / 2]
            for out in sorted(axes, key=lambda a: -float(a @ toward)):  # the object's sides, nearest side first
                if out @ toward > -0.5:
                    outcome = self._pick_from_shelf(name, node, cls, position, quat, out)
                    if outcome.success:
                        return outcome
                    side_failures.append(outcome.reason.removeprefix(f"{name}: "))
        stand_failure = ""
        try:
            if furniture is None:  # on the floor of a room
                goal = self.navigator.stand_near(tuple(position[:2]))
                self.retract()
                self.navigator.drive_to(goal, self.tucked(), **FREE_MOTION)
            else:
                self.go_to(node, position[:2])
        except NavigationError as error:
            stand_failure = str(error)  # a base pose checked for the grasp itself may still reach it
        failures = side_failures
        rim = None if furniture is None else drawer_rim(self.world, node, position)
        lift = 0.0 if rim is None else rim + DRAWER_CLEARANCE - (position[2] - cls.size[2] / 2)  # out of the drawer
        grasps = [replace(g, lift=max(g.lift, lift), approach=g.approach if rim is None else rim_approach(
            g, rim, DRAWER_CLEARANCE)) for g in top_grasps(cls, position, quat, self.controller.q()[:2])]
        grasps.sort(key=lambda g: not self._fingers_fit(g))  # stable: the blocked ones last
        offsets = [o for g in grasps for o in offset_grasps(cls, quat, g) if self._fingers_fit(o)]
        unchecked = []
        for grasp in grasps + offsets:  # those with a way in clear of the apartment first
            outcome = self._grasp_from_above(name, grasp, stand_failure, checked_only=True)
            if outcome is None:
                unchecked += [] if "-offset" in grasp.kind else [grasp]
                continue
            if outcome.success:
                self.held = name
                return outcome
            failures.append(f"{grasp.kind}: {outcome.reason}")
        for grasp in unchecked:
            outcome = self._grasp_from_above(name, grasp, stand_failure)
            if outcome.success:
                self.held = name
                return outcome
            failures.append(f"{grasp.kind}: {outcome.reason}")
        return SkillResult(False, f"{name}: every grasp failed ({'; '.join(failures)})")

    def _grasp_from_above(self, name: str, grasp: Grasp, stand_failure: str, checked_only: bool = False
                          ) -> SkillResult | None:
        """Try `grasp` from a base pose checked for it (the arm clear of the apartment on the way in), else from
        where the robot stands, unless it found no place to stand (`stand_failure`, the reason). With
        `checked_only`, None (nothing moved) where no checked base pose reaches it."""
        try:
            path_in = self._go_to_grasp(grasp, np.zeros(3), 0.0, here_first=not stand_failure)
        except NavigationError as error:
            return SkillResult(False, str(error))
        if path_in is None and checked_only:
            return None
        if path_in is None and stand_failure:
            return SkillResult(False, f"{stand_failure}, and no checked base pose reaches the grasp")
        return self._try_grasp(name, grasp, path_in=path_in)

    def _fingers_fit(self, grasp: Grasp) -> bool:
        """Whether the fingers, open `grasp.pre_opening`, fit round the object at `grasp` without landing on
        anything else (a neighbour, a drawer's wall); True where the arm cannot tell from where it stands."""
        at_grasp = self._ik(grasp.position, grasp.quat())
        q = at_grasp.q.copy()
        q[self.controller.n_body:] = grasp.pre_opening
        return not at_grasp.converged or self.clearance.fingers_clear(q)

    def _pick_from_shelf(self, name: str, node: str, cls, position: np.ndarray, quat: np.ndarray,
                         out: np.ndarray | None = None, replan: bool = True) -> SkillResult:
        """Pick `name` from a shelf inside cabinet `node`: each grasp of `shelf_grasps` in turn, from a base
        pose where the arm clears the compartment; the object lifted SIDE_LIFT m, drawn out, then raised.
        With `out` (a horizontal unit vector, shape (2,)), from an open top instead, for a shelf next: the grasps a
        shelf takes (side grasps, the fingers as deep on the object as they reach, then pitched ones), approached
        against `out`. With `replan`, once a failed grasp has moved the object (see `disturbed`), the grasps are
        planned again for where it now stands (the others were for where it stood)."""
        furniture = self.navigator.furniture[node]
        if out is None:
            out = self.navigator.front_normal(node)
            front = float(np.dot(np.array(furniture.pos) + out * furniture.size[1] / 2 - position[:2], out))
            grasps = shelf_grasps(cls, position, quat, out, front, neighbour_footprints(self.world, name))
        else:  # side grasps, then pitched ones (a hand pointing straight down, or holding the object front to
            front = -np.inf  # back, "-along", does not put it down under a shelf)
            grasps = [g for g in shelf_grasps(cls, position, quat, out, front)
                      if not g.kind.endswith(("-90", "-along")) and "-rolled" not in g.kind]
        if not grasps:
            return SkillResult(False, f"{name}: no grasp fits its shape ({cls.size} m) on a shelf of {node}")
        unreachable, failures = [], []
        pull = np.array([out[0], out[1], 0.0])
        # every grasp unfolding the arm first (the tried way), then those no base pose reached, swinging straight in
        for grasp, direct in [*((g, False) for g in grasps), *((g, True) for g in grasps)]:
            if direct and grasp.kind not in unreachable:
                continue
            try:
                path_in = self._go_to_grasp(grasp, pull, max(front, 0.0) + ENTRY_OUT, direct=direct)
            except NavigationError as error:
                failures.append(f"{grasp.kind}: {error}")
                continue
            if path_in is None:
                if not direct:
                    unreachable.append(grasp.kind)
                continue
            if direct:
                unreachable.remove(grasp.kind)  # reached after all: its outcome is reported instead
            outcome = self._try_grasp(name, grasp, pull=pull, path_in=path_in)
            if outcome.success:
                self.held = name
                return outcome
            failures.append(f"{grasp.kind}: {outcome.reason}")
            now = self.world.object_pose(name)
            if replan and disturbed(position, quat, *now) and not self._fallen_over(name):
                again = self._pick_from_shelf(name, node, cls, *now, out, replan=False)
                return again if again.success else SkillResult(False, f"{again.reason} (moved by {failures})")
        if unreachable:
            failures.append(f"{', '.join(unreachable)}: no free base pose reaches the grasp without the arm "
                            f"touching {node} or its contents")
        return SkillResult(False, f"{name}: every grasp in {node} failed ({'; '.join(failures)})")

    def _try_grasp(self, name: str, grasp: Grasp, pull: np.ndarray | None = None,
                   path_in: list[np.ndarray] | None = None) -> SkillResult:
        """Approach along the grip x axis, close, lift: straight up LIFT m, or with `pull` (a horizontal unit
        vector out of the furniture, shape (3,)) up SIDE_LIFT m, out SIDE_PULL m and up SIDE_RAISE m.
        path_in: configurations (each shape (13,)) ending at the approach point, already checked; when None the
        approach configuration is solved here."""
        quat = grasp.quat()
        back = -grasp.rotation[:, 0]  # from the grasp towards where the gripper comes from
        above = grasp.position + grasp.approach * back
        if path_in is None:
            pre = self._ik(above, quat)
            if not pre.converged:
                return SkillResult(False, f"approach pose {pre.reason}")
            path_in = [pre.q]
        self.reach(path_in[0], grip=grasp.pre_opening)
        if len(path_in) > 1:
            self.controller.move_through(path_in[1:], grip=grasp.pre_opening)
        self.controller.settle(0.003)
        down = self._line(above, grasp.position, quat)
        if down is None:
            return SkillResult(False, "the descent leaves the arm's reach")
        start, _ = self.world.object_pose(name)
        self.controller.move_through(down)
        self.controller.settle(0.002)
        opening = self.controller.set_grip(0.0)
        if opening < MIN_HELD_OPENING:
            self._back_off(above, quat)
            return SkillResult(False, f"fingers closed on nothing (opening {opening * 1000:.1f} mm)")
        up = np.array([0.0, 0.0, 1.0])
        if pull is not None:
            legs = [SIDE_LIFT * up, SIDE_PULL * pull, SIDE_RAISE * up]
        else:
            legs = [LIFT * up]
        legs[-1] = legs[-1] + max(0.0, grasp.lift - sum(leg[2] for leg in legs)) * up  # raised further
        point = grasp.position
        for leg in legs:  # the base follows a horizontal leg; a vertical one only where the arm alone falls short
            path = self._line(point, point + leg, quat, base_cost=PULL_BASE_COST if leg[2] == 0 else GRASP_BASE_COST)
            if path is None and leg[2] != 0:
                path = self._line(point, point + leg, quat, base_cost=PULL_BASE_COST)
            if path is None:
                self._back_off(above, quat)
                return SkillResult(False, "the lift leaves the arm's reach")
            self.controller.move_through(path)
            point = point + leg
        if grasp.hang:  # turn the hand until the object hangs straight below the grip site
            com = self.world.data.xipos[self.world.object_body_ids[self.world.object_index(name)]]
            grip = self.world.data.site("robot/grip")
            turned = hang_rotation(grip.xmat.reshape(3, 3), grip.xpos, com)
            path = self._hand_line(point, matrix_to_quat(turned), GRASP_BASE_COST, partial=True)
            if path:  # as far as the arm turns it
                self.controller.move_through(path)
        self.world.step(int(HOLD_SECONDS / self.world.model.opt.timestep))
        lifted = self.world.object_pose(name)[0][2] - start[2]
        rise = float(sum(leg[2] for leg in legs))
        if lifted < 0.5 * rise:
            self._back_off(above, quat)
            return SkillResult(False, f"the object rose only {lifted * 100:.1f} cm of {rise * 100:.0f} cm")
        return SkillResult(True)

    def _back_off(self, above: np.ndarray, quat: np.ndarray) -> None:
        """Open the fingers and return above the grasp (then tuck)."""
        self.controller.set_grip(0.05, seconds=0.3)
        result = self._ik(above, quat, seeds=False)
        if result.converged:
            self.controller.move_through([result.q])
        self.retract()

    # --- place -------------------------------------------------------------------------------------------
    def place(self, node: str, relation: int | None = None) -> SkillResult:
        """Put the held object at a free spot ON or INSIDE furniture `node`, release it and retreat."""
        name = self.held
        if name is None:
            return SkillResult(False, "place: the robot holds nothing")
        exclude = {self.world.object_index(name)}
        shelves = self._shelves(node, relation)
        if shelves:
            return self._place_in_shelf(name, node, shelves)
        spot = None
        for k, _ in self.spots.places_of(node, relation):
            spot = self.spots.free_spot(name, node, k, self.rng, exclude)
            if spot is not None:
                break
        if spot is None:
            return SkillResult(False, f"place: no free spot for {name} on {node}")
        target = np.array(spot.pos)
        held_at = self._held_offset(name)  # where the object hangs in the hand (grip frame)
        size = CATALOG[self.world.layout.objects[self.world.object_index(name)].cls].size
        try:
            short = self.go_to(node, target[:2], surface_z=target[2] - size[2] / 2)
        except NavigationError as error:
            return SkillResult(False, f"place: {error}")
        slip = float(np.linalg.norm(self._held_offset(name) - held_at))
        if slip > CARRY_SLIP and self._hand_empty():
            self.held = None
            return SkillResult(False, f"place: {name} fell out of the hand while carried")
        if slip > CARRY_SLIP:  # still in the hand: the caller decides where it goes down
            return SkillResult(False, f"place: {name} slipped {slip * 100:.1f} cm in the hand while carried")
        grip = self.world.data.site("robot/grip")
        offset = grip.xpos - self.world.object_pose(name)[0]  # keep the object where it hangs now
        quat = self._held_quat()
        release = target + offset + np.array([0.0, 0.0, 0.01])
        above = release + np.array([0.0, 0.0, APPROACH])
        # Stopped short with the object low: lift it over the surface, then drive in close (the object passes
        # over the edge) and move it across to above the spot in a straight line.
        if short and self._grip_line(np.array([*grip.xpos[:2], max(grip.xpos[2], release[2] + PASS_OVER)]), quat):
            try:
                self.navigator.drive_to(self.navigator.stand_pose(node, tuple(target[:2])),
                                        self.controller.target.copy(), **CARRY_MOTION)
            except NavigationError:
                pass  # reach from where it stands
        if not self._grip_line(above, quat):
            pre = self._ik(above, quat)
            if not pre.converged:
                return SkillResult(False, f"place: {name} above {node} is {pre.reason}")
            self.reach(pre.q)
        down = self._line(above, release, quat)
        if down is None:
            return SkillResult(False, f"place: lowering {name} onto {node} leaves the arm's reach")
        self.controller.move_through(down)
        self.controller.settle(0.003)
        return self._let_go(name, node, 0.05, self._retreat(release, quat))

    def _retreat(self, release: np.ndarray, quat: np.ndarray) -> list[np.ndarray] | None:
        """Configurations that take the open hand away from an object it let go of at `release` (m): back along
        the grip x axis APPROACH m (straight up for a hand pointing down), then, for a hand held level, up as
        much (it held the object's side: lifted at once, or swung back into the tuck, the fingers knock it
        over)."""
        x = self.world.data.site("robot/grip").xmat.reshape(3, 3)[:, 0].copy()
        back = release - APPROACH * x
        away = self._line(release, back, quat)
        if away is None or np.linalg.norm(x[:2]) <= LEVEL_HAND:
            return away
        return away + (self._line(back, back + np.array([0.0, 0.0, APPROACH]), quat, seed=away[-1]) or [])

    def _let_go(self, name: str, node: str, opening: float, away: list[np.ndarray] | None,
                inside: bool = False) -> SkillResult:
        """Open the fingers to `opening` m per finger, move the hand along `away` (configurations, if any), tuck,
        let the world settle, and read where `name` ended: on or in `node` (inside it, with `inside`)."""
        self.controller.set_grip(opening, seconds=0.4)
        self.held = None
        if away is not None:
            self.controller.move_through(away)
        self.retract()
        self.world.settle(max_seconds=2.0)
        graph = self.observer.update()
        parent, relation = graph.parent_of(name), graph.relation_of(name)
        if parent != node or (inside and relation != RELATION_NAMES[INSIDE]):
            return SkillResult(False, f"place: {name} ended {relation} {parent}, not {'inside' if inside else 'on'} "
                                      f"{node}")
        if self._fallen_over(name):
            return SkillResult(False, f"place: {name} fell over on {node}")
        return SkillResult(True)

    def _under_a_shelf(self, node: str, position: np.ndarray, height: float) -> bool:
        """Whether an object of `height` m at `position` stands on a fixed shelf of furniture `node` with another
        shelf less than OPEN_ABOVE m above it (a bookshelf's lower levels): only a grasp from the front fits."""
        furniture = self.spots.furniture.get(node)
        if furniture is None:
            return False
        bottom = position[2] - height / 2
        below = [(place_world(self.world.layout, furniture, p)["z"], p) for _, p in
                 [*self.spots.places_of(node, ON), *self.spots.places_of(node, INSIDE)] if p.part is None]
        below = [(z, p) for z, p in below if z <= bottom + 0.02]
        return bool(below) and max(below, key=lambda zp: zp[0])[1].clearance < OPEN_ABOVE

    def _shelves(self, node: str, relation: int | None) -> list[int]:
        """Indices of the shelves inside cabinet `node` that a place with `relation` goes to (none elsewhere)."""
        furniture = self.navigator.furniture.get(node)
        if furniture is None or furniture.kind != "cabinet":
            return []
        return [k for k, p in self.spots.places_of(node, relation) if p.relation == INSIDE and p.part is None]

    def _place_in_shelf(self, name: str, node: str, places: list[int]) -> SkillResult:
        """Put the held object on a shelf inside cabinet `node` (`places`: its shelf indices), the reverse of
        `_pick_from_shelf`: from a base pose where the object and the arm clear the cabinet and its contents, in
        SIDE_LIFT m above a free spot (spots nearest the front first), down, release, and straight out."""
        index = self.world.object_index(name)
        size = np.asarray(CATALOG[self.world.layout.objects[index].cls].size)
        furniture = self.navigator.furniture[node]
        out = self.navigator.front_normal(node)
        front = np.array(furniture.pos) + out * furniture.size[1] / 2
        spots = [spot for k in places for spot in self.spots.free_spots(name, node, k, self.rng, {index})]
        spots = _spread(sorted(spots, key=lambda spot: float(np.dot(front - spot.pos[:2], out))), SHELF_SPOT_GAP,
                        SHELF_SPOTS)
        if not spots:
            return SkillResult(False, f"place: no free spot for {name} inside {node}")
        carry = self._carry_path()
        self.controller.move_through(carry)
        posture, held = carry[-1], self._held(name)
        grip = self.world.data.site("robot/grip")
        now = grip.xmat.reshape(3, 3)
        # turned about the vertical: a hand held level points into the shelf; one pointing down keeps its turn
        # relative to the base, the base facing the shelf
        level = np.linalg.norm(now[:2, 0]) > LEVEL_HAND
        turn = math.atan2(-out[1], -out[0]) - (math.atan2(now[1, 0], now[0, 0]) if level else
                                               self.controller.target[2])
        rotation = _yaw_matrix(turn) @ now
        quat = matrix_to_quat(rotation)
        up, pull = np.array([0.0, 0.0, 1.0]), np.array([out[0], out[1], 0.0])
        clear_out = np.linalg.norm(size) / 2 + ENTRY_OUT  # the object's centre this far out of the front: all out
        for spot in spots:
            release = np.array(spot.pos) + np.array([0.0, 0.0, 0.01]) - rotation @ held.position
            outside = release + (float(np.dot(front - release[:2], out)) + clear_out) * pull
            points = [outside + SIDE_LIFT * up, release + SIDE_LIFT * up, release]
            planned = self._drive_for(points, rotation, posture, held)
            if planned is None:
                continue
            ease, path_in = planned
            self._ease_to(ease, path_in[0])
            if self._hand_empty():
                self.held = None
                self.retract()
                return SkillResult(False, f"place: {name} fell out of the hand on the way into {node}")
            now = self._held(name)  # the object may have turned in the fingers on the way: aim it again
            again = np.array(spot.pos) + np.array([0.0, 0.0, 0.01]) - rotation @ now.position
            replanned = self._checked_line(self.controller.target, [points[0], again + SIDE_LIFT * up, again],
                                           quat, now)
            slip = float(np.linalg.norm(now.position - held.position))
            if replanned is not None:
                path_in, release = [self.controller.target.copy(), *replanned], again
            elif slip > CARRY_SLIP:  # still held, but no longer as planned: the caller puts it down elsewhere
                return SkillResult(False, f"place: {name} slipped {slip * 100:.1f} cm in the hand on the way into "
                                          f"{node} and no longer goes in clear")
            self.controller.move_through(path_in[1:])
            self.controller.settle(0.003)
            return self._let_go(name, node, float(np.mean(self.controller.q()[-2:])) + RELEASE_OPENING,
                                self._line(release, outside, quat, steps=4, loose_end=True), inside=True)
        return SkillResult(False, f"place: no free base pose puts {name} into {node} without it or the arm "
                                  f"touching {node} or its contents ({len(spots)} spots tried)")

    def _ease_path(self, q_from: np.ndarray, q_to: np.ndarray, held: Held) -> list[np.ndarray] | None:
        """The way (configurations, each shape (13,)) of a held object from configuration q_from to q_to: along a
        straight grip line as far as it is reachable, the rest in joint space; None if any of it touches anything.
        """
        lead = self._hand_line(*self.ik.grip_pose(q_to), ARC_BASE_COST, partial=True, seed=q_from) or []
        if not all(self.clearance.clear(q, held=held) for q in lead):
            return None
        return lead if self._swing_clear(lead[-1] if lead else q_from, q_to, held) else None

    def _ease_to(self, lead: list[np.ndarray], q: np.ndarray) -> None:
        """Move a held object through `lead` (from `_ease_path`), then to configuration q (shape (13,)) in joint
        space, slowly (a quick swing turns a long object held by one end in the fingers)."""
        if lead:
            self.controller.move_through(lead)
        self.controller.move_through([q], duration=EASE_SLOWDOWN * self.controller.duration(self.controller.target, q))
        self.controller.settle(0.003)

    def _drive_for(self, points: list[np.ndarray], rotation: np.ndarray, posture: np.ndarray, held: Held
                   ) -> tuple[list[np.ndarray], list[np.ndarray]] | None:
        """Drive, holding `held` in `posture` (shape (13,)), to a free base pose from which the held object eases
        from `posture` onto the first of `points` (m, each shape (3,)) and the grip site follows them at `rotation`
        (shape (3, 3)), the object and the arm clear of the apartment all the way; returns (the ease, see
        `_ease_path`; the configurations along `points`), each configuration shape (13,), or None (the robot
        stays)."""
        quat = matrix_to_quat(rotation)
        reach = self._held_reach()
        obstacles = self.navigator.open_part_rects()
        for base in base_candidates(points[-1], rotation, self.controller.q()[:2]):
            if not self.navigator.plan.disk_is_free(base[0], base[1], ROBOT_RADIUS + CLEARANCE, obstacles):
                continue
            q = posture.copy()
            q[:3] = base
            start = self.ik.solve(q, points[0], quat, base_cost=ARC_BASE_COST)
            if not start.converged or not self.clearance.clear(start.q, held=held):
                continue
            path = self._checked_line(start.q, points, quat, held)
            if path is None:
                continue
            carried = posture.copy()
            carried[:3] = base
            ease = self._ease_path(carried, start.q, held)
            if ease is None:
                continue
            try:
                self.navigator.drive_to(base, posture, reach, **CARRY_MOTION)
            except NavigationError:
                continue
            path = [start.q, *path]
            for q_in in [*ease, *path]:
                q_in[:3] = self.controller.target[:3]  # where the base really stopped
            return ease, path
        return None

    # --- doors and drawers ---------------------------------------------------------------------------------
    def open_articulation(self, name: str) -> SkillResult:
        """Open door or drawer `name` (`<furniture>/<part>`, or a furniture with one part) above openness 0.9,
        by holding its handle (and a door's free edge past the handle's reach); the arm ends tucked."""
        if self.held is not None:
            return SkillResult(False, f"open {name}: the hand holds {self.held}")
        return SkillResult(*PartMover(self).move_to(name, opening=True))

    def close_articulation(self, name: str) -> SkillResult:
        """Close door or drawer `name` below openness 0.05 (see `open_articulation`)."""
        if self.held is not None:
            return SkillResult(False, f"close {name}: the hand holds {self.held}")
        return SkillResult(*PartMover(self).move_to(name, opening=False))

    def _grip_line(self, point: np.ndarray, quat: np.ndarray) -> bool:
        """Move the grip site in a straight line to `point` (m), orientation `quat` kept (see `_hand_line`), the
        base free to follow; False (nothing moved) if the line leaves the arm's reach."""
        path = self._hand_line(point, quat, PULL_BASE_COST)
        if path is None:
            return False
        self.controller.move_through(path)
        return True

    def _held_offset(self, name: str) -> np.ndarray:
        """Where object `name` sits in the grip site's frame (m, shape (3,)): it stays put while the hand turns,
        so a change of it is slip."""
        grip = self.world.data.site("robot/grip")
        return grip.xmat.reshape(3, 3).T @ (self.world.object_pose(name)[0] - grip.xpos)

    def _hand_empty(self) -> bool:
        """Whether the closed fingers hold nothing (they met each other)."""
        return float(np.mean(self.controller.q()[-2:])) < MIN_HELD_OPENING

    def _held(self, name: str) -> Held:
        """Object `name` as it sits in the hand now, for clearance checks of moves that carry it."""
        model, index = self.world.model, self.world.object_index(name)
        body = self.world.object_body_ids[index]
        grip = self.world.data.site("robot/grip")
        rotation = grip.xmat.reshape(3, 3)
        return Held(frozenset(np.flatnonzero(model.geom_bodyid == body).tolist()),
                    int(model.jnt_qposadr[model.body_jntadr[body]]), self._held_offset(name),
                    rotation.T @ self.world.data.xmat[body].reshape(3, 3))

    def _held_reach(self) -> float:
        """How far (m) the held object sticks out from the base centre, with CLEARANCE."""
        index = self.world.object_index(self.held)
        size = CATALOG[self.world.layout.objects[index].cls].size
        position = self.world.object_pose(self.held)[0]
        return float(np.linalg.norm(position[:2] - self.controller.q()[:2]) + np.linalg.norm(size[:2]) / 2
                     + CLEARANCE)

    def _fallen_over(self, name: str) -> bool:
        """Whether object `name` no longer stands up (its up axis tilted past UPRIGHT)."""
        return bool(self.world.data.xmat[self.world.object_body_ids[self.world.object_index(name)]][8] < UPRIGHT)

    def _held_quat(self) -> np.ndarray:
        """The grip site's current orientation (wxyz), kept while carrying."""
        return matrix_to_quat(self.world.data.site("robot/grip").xmat.reshape(3, 3))


def _yaw_matrix(angle: float) -> np.ndarray:
    """The rotation (shape (3, 3)) by `angle` rad about the vertical."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _spread(spots: list, gap: float, limit: int) -> list:
    """Up to `limit` of `spots` (in their order), each at least `gap` m from the ones kept before it."""
    kept = []
    for spot in spots:
        if all(math.dist(spot.pos[:2], other.pos[:2]) >= gap for other in kept):
            kept.append(spot)
            if len(kept) == limit:
                break
    return kept


__all__ = ["Robot", "SkillResult", "ON", "INSIDE"]
