"""The `pick` skill of `planners.skills.Robot`: grasp an object and lift it, checked in physics.

From above (top grasps, off-centre ones, out of a drawer past its front), or from a cabinet's shelf or under a
low shelf from the front (shelf grasps, the object lifted, drawn out, then raised; from a place with little
free height but nothing over it, a sink's basin, from the front first, then from above); a failed grasp is
retried from the next candidate. Movement comes from `planners.motion.arm`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import replace

import numpy as np

from homer_sim.graph import INSIDE, ON, RELATION_NAMES
from homer_sim.home.placement import place_world, yaw_quat
from homer_sim.home.spots import Spots
from homer_sim.observe import SceneGraphObserver
from planners.grasps.above import (
    lying_as,
    offset_grasps,
    raised_grasps,
    rim_approach,
    squared_grasps,
    top_grasps,
)
from planners.grasps.candidate import Grasp, disturbed, ungraspable_reason
from planners.grasps.features import hang_rotation
from planners.grasps.geometry import matrix_to_quat
from planners.grasps.neighbours import PASS_ABOVE, neighbour_footprints, rise_to_pass
from planners.grasps.ranking import rank_from_above
from planners.grasps.shelf import shelf_grasps
from planners.motion.arm import (
    ENTRY_OUT,
    GRASP_BASE_COST,
    MIN_HELD_OPENING,
    PULL_BASE_COST,
    SIDE_LIFT,
    Arm,
)
from planners.motion.clearance import Held
from planners.motion.control import FREE_MOTION
from planners.motion.navigation import NavigationError
from planners.skills.parts import behind_a_door, covered_places, drawer_rim, rim_above, shelves_inside
from planners.skills.result import SkillResult

LIFT = 0.15  # m
DRAWER_CLEARANCE = 0.03  # m an object lifted out of a drawer rises past the top of its front
HOLD_SECONDS = 0.5
# a side grasp lifts the object SIDE_LIFT m off its shelf (see planners.motion.arm),
SIDE_PULL = 0.35  # m: then draws it this far out of the furniture (at least until it is OUT_PAST out of its front),
OUT_PAST = 0.03  # m between the front plane and the object's outline once it is drawn out (a wine glass drawn
# 0.35 m off the back of a rack was still in it when raised, struck the top's edge and fell out of the hand)
SIDE_RAISE = 0.13  # m: then raises it this much more
OPEN_ABOVE = 0.5  # m of free height above a place below which a grasp from above may not fit
CLOSING_STEP = 0.005  # m per finger between the openings at which the fingers' way as they close is checked
NEIGHBOUR_PUSH = 0.005  # m an open finger coming down onto a grasp may press into a neighbour (it slides it a
# little aside; a side grasp of a glass grazed the wine glass beside it 3 mm, a roll's finger sank 12 mm into the
# perfume it came down on)
WATCH_PUSH = 0.005  # m another object may move while the hand goes in to a grasp before the hand stops and backs
# off (a descent onto shampoo pushed the conditioner beside it 1 cm in 0.07 s, then 18 cm; a tin of coffee stopped
# at 1 cm went on tipping to 2.9 cm; the collateral limit is 2 cm)
SLIDE_PUSH = 0.01  # m the object, slid to an off-centre grasp's centre as the fingers close, may press into a
# neighbour (it yields that far, half the 2 cm collateral limit; a charger closed on so pushed the cd beside it
# 0.3-1.5 cm, a rice box 4.5 cm towards the oil 3.5 cm from it dragged the oil out)
PUSH_NOISE = 0.002  # m an object may move while a grasp goes in without counting as pushed by it
DESCENT_DRIFT = 0.005  # m a loose waypoint of the descent onto a grasp may stray from the line (see `_descent`)


class Pick:
    """The `pick` skill: grasps an object with the `arm` and lifts it; `observer` reads where the object stands,
    `spots` the furniture's places, `takes` (`Place.takes`) whether a shelf takes it as a grasp would hold it."""

    def __init__(self, arm: Arm, observer: SceneGraphObserver, spots: Spots,
                 takes: Callable[[str, str, np.ndarray, Held], bool] | None = None) -> None:
        self.arm = arm
        self.takes = takes  # (object, furniture, grip rotation, held) -> whether a shelf of it takes it so held
        self.observer = observer
        self.spots = spots
        self.world, self.controller, self.navigator = arm.world, arm.controller, arm.navigator
        self.ik, self.clearance = arm.ik, arm.clearance

    def pick(self, name: str, node: str | None = None, into: str | None = None) -> SkillResult:
        """Grasp object `name` and lift it LIFT m; `node` (the furniture it is on or in) is where to stand.
        `into`: where it goes next; a cabinet's shelf (or an open shelf's level under another) takes an object held
        from the side or pitched down from the front (a hand pointing straight down does not fit under the shelf
        above), so from a table it is then grasped that way first. Standing on the floor, the object is no
        obstacle to the base poses that reach it (`Navigator.exempt`)."""
        self.navigator.exempt = frozenset({self.world.object_index(name)})
        try:
            return self._pick(name, node, into)
        finally:
            self.navigator.exempt = frozenset()

    def _pushed(self, since: np.ndarray | None = None) -> list[str]:
        """The objects, other than the one picked and those on or in it, now more than WATCH_PUSH m from where they
        stood when the pick began (the robot sees them move); with `since` (`world.object_positions()` when a grasp
        began), only those moved by that grasp too: one a grasp before pushed stands in another's way no more."""
        start, watched = self._watch
        now = self.world.object_positions()
        moved = np.linalg.norm(now - start, axis=1) > WATCH_PUSH
        if since is not None:
            moved &= np.linalg.norm(now - since, axis=1) > PUSH_NOISE
        return [self.world.object_names[i] for i in np.flatnonzero(moved & watched)]

    def _stopped(self, above: np.ndarray | None, quat: np.ndarray, since: np.ndarray) -> SkillResult:
        """Stop the hand on its way in to a grasp where it pushed something (`_pushed` since the grasp began at
        `since`), then back off: to `above` (the approach point, m) where it was coming down from there, else
        straight to the tuck posture."""
        pushed = self._pushed(since)
        self.controller.stop()
        self._let_go_of(pushed)
        if above is not None:  # the fingers open no wider: one pressing on what it pushed would push it further
            self._back_off(above, quat, release=False)
        else:
            self.arm.retract()
        return SkillResult(False, f"the hand pushed {', '.join(pushed)} on its way in, and stopped")

    def _let_go_of(self, pushed: list[str]) -> None:
        """Close the fingers, where they stopped, to the widest opening (in CLOSING_STEP m steps) at which they
        touch none of the objects `pushed` nor the one being picked, if there is one: a finger pressing on a
        neighbour from outside drags it along as the hand backs off (a perfume's far finger pushed a toilet roll
        0.6 cm on its way in, then 2.2 cm on its way back out)."""
        model, n_body = self.world.model, self.controller.n_body
        _, watched = self._watch
        bodies = {self.world.object_body_ids[self.world.object_index(n)] for n in pushed}
        bodies |= set(self.world.object_body_ids[~watched].tolist())
        q = self.controller.q()
        for value in np.arange(float(np.mean(q[n_body:])) - CLOSING_STEP, 0.0, -CLOSING_STEP):
            q[n_body:] = value
            touched = {int(model.geom_bodyid[g]) for g in self.clearance.finger_contacts(q, graze=0.0)}
            if not touched & bodies:
                self.controller.set_grip(value, seconds=0.3)
                return

    def _pick(self, name: str, node: str | None, into: str | None) -> SkillResult:
        cls = self.world.object_class(name)
        reason = ungraspable_reason(cls)
        if reason is not None:
            return SkillResult(False, f"{name}: not graspable ({reason})")
        graph = self.observer.update()
        watched = np.array([other != name and graph.parent_of(other) != name for other in self.world.object_names])
        self._watch = (self.world.object_positions(), watched)  # see `_pushed`
        node = node or graph.parent_of(name)
        position, quat = self.world.object_pose(name)
        if self.arm.fallen_over(name):  # from above, as an upright box of the extents it has as it lies
            body = self.world.object_body_ids[self.world.object_index(name)]
            lying = lying_as(cls, self.world.data.xmat[body].reshape(3, 3))
            quat = np.array(yaw_quat(lying[1])) if lying is not None else quat
            if (lying is None or self._standing_on(node, position, lying[0].size[2])[0]
                    or not top_grasps(lying[0], position, quat, self.controller.q()[:2])):
                return SkillResult(False, f"{name}: it has fallen over (lies on its side), and no grasp fits it so")
            return self._pick_from_above(name, node, lying[0], position, quat, [])
        furniture = self.navigator.furniture.get(node)
        inside = graph.relation_of(name) == RELATION_NAMES[INSIDE] and furniture is not None
        covered, low = self._standing_on(node, position, cls.size[2])
        if (inside and behind_a_door(furniture)) or covered:
            return self._pick_from_shelf(name, node, cls, position, quat)  # from the front, the base placed per grasp
        failures: list[str] = []
        if low:  # from the front first, then (where no front grasp moved it) from above
            outcome = self._pick_from_shelf(name, node, cls, position, quat)
            if outcome.success or disturbed(position, quat, *self.world.object_pose(name)):
                return outcome
            failures.append(outcome.reason.removeprefix(f"{name}: "))
        if into is not None and furniture is not None and (shelves_inside(
                self.spots, self.navigator.furniture.get(into), into, None) or covered_places(self.spots, into, None)
                ):  # from the side nearest where the robot would stand (an open shelf's lower levels, too)
            try:
                stand = np.array(self.navigator.stand_pose(node, tuple(position[:2]))[:2])
            except NavigationError as error:
                return SkillResult(False, f"{name}: {error}")
            outcome = self._pick_side_first(name, node, cls, position, quat, stand, failures, into)
            if outcome is not None:
                return outcome
        return self._pick_from_above(name, node, cls, position, quat, failures)

    def _pick_side_first(self, name: str, node: str, cls, position: np.ndarray, quat: np.ndarray,
                         stand: np.ndarray, failures: list[str], into: str) -> SkillResult | None:
        """Pick `name` (at `position`, m; body `quat`, wxyz) from furniture `node`'s open top as a shelf of
        `into` takes it (see `_pick_from_shelf` with `out`), from each of its sides that faces `stand` (the xy, m,
        where the robot would stand), nearest first; the successful outcome (or the failure that knocked it over),
        or None with each side's failure added to `failures`."""
        toward = (stand - position[:2]) / max(float(np.linalg.norm(stand - position[:2])), 1e-9)
        yaw = 2.0 * math.atan2(quat[3], quat[0])
        axes = [np.array([math.cos(yaw + a), math.sin(yaw + a)]) for a in np.arange(4) * math.pi / 2]
        for out in sorted(axes, key=lambda a: -float(a @ toward)):  # the object's sides, nearest side first
            if out @ toward > -0.5:
                outcome = self._pick_from_shelf(name, node, cls, position, quat, out, into=into)
                if outcome.success or self.arm.fallen_over(name):  # knocked over: the other sides' grasps and
                    return outcome  # those from above were made for it standing (see `_knocked_over`)
                failures.append(outcome.reason.removeprefix(f"{name}: "))
        return None

    def _pick_from_above(self, name: str, node: str, cls, position: np.ndarray, quat: np.ndarray,
                         failures: list[str], replan: bool = True) -> SkillResult:
        """Pick `name` from above: the robot goes to stand in front of furniture `node` (near it on the floor),
        then each grasp from above in the order `rank_from_above` gives, from a base pose checked for it; those
        no checked base pose reaches are tried last from where the robot stands. With `replan`, once a failed
        grasp has moved an upright object (see `disturbed`), the grasps are planned again for where it now stands
        (a pencil's first grasp pushed the note pad beside it, which dragged their drawer 1.5 cm out; the next
        grasp, planned for where the pencil stood, came down on it)."""
        furniture = self.navigator.furniture.get(node)
        stand_failure = ""
        try:
            if furniture is None:  # on the floor of a room
                goal = self.navigator.stand_near(tuple(position[:2]))
                self.arm.retract()
                self.navigator.drive_to(goal, self.arm.tucked(), **FREE_MOTION)
            else:
                self.arm.go_to(node, position[:2])
        except NavigationError as error:
            stand_failure = str(error)  # a base pose checked for the grasp itself may still reach it
        grasps = self._above_candidates(node, cls, position, quat)
        clear = [self._fingers_fit(g) for g in grasps]
        offsets = [(o, fits) for g, fits in zip(grasps, clear, strict=True) for o in offset_grasps(cls, quat, g)
                   if self._fingers_fit(o)]
        upright = not self.arm.fallen_over(name)
        slide = None if furniture is None or drawer_rim(self.world, node, position) is None else (
            self.navigator.front_normal(node))
        ranked = rank_from_above([*zip(grasps, clear, strict=True), *offsets], slide)  # a clear way in first
        queue = [(grasp, True) for grasp in ranked]
        for grasp, checked_only in queue:  # grows: a centred grasp no checked base pose reaches comes again, last
            outcome = self._grasp_from_above(name, grasp, stand_failure, checked_only=checked_only)
            if outcome is None:
                queue += [] if grasp.kind.offset else [(grasp, False)]
                continue
            if outcome.success:
                self.arm.held = name
                return outcome
            failures.append(f"{grasp.kind}: {outcome.reason}")
            if upright and (knocked := self._knocked_over(name, node, failures)):
                return knocked
            if upright and replan and disturbed(position, quat, *(now := self.world.object_pose(name))):
                return self._pick_from_above(name, node, cls, *now, failures, replan=False)
        return SkillResult(False, f"{name}: every grasp failed ({'; '.join(failures)})")

    def _above_candidates(self, node: str, cls, position: np.ndarray, quat: np.ndarray) -> list[Grasp]:
        """The centred grasps from above of an object of `cls` at `position` (m; body `quat`, wxyz) on or in
        furniture `node` (None: the floor), the robot where it stands now: top grasps (or a grip feature's, or
        rim pinches), in a drawer also those squared to its walls, and raised copies of low objects'; out of a
        drawer each rises past its front (see `rim_approach`)."""
        rim = None if self.navigator.furniture.get(node) is None else drawer_rim(self.world, node, position)
        lift = 0.0 if rim is None else rim + DRAWER_CLEARANCE - (position[2] - cls.size[2] / 2)  # out of the drawer
        candidates = top_grasps(cls, position, quat, self.controller.q()[:2])
        if rim is not None:  # in a drawer, last: the palm square to its walls
            out = self.navigator.front_normal(node)
            candidates += squared_grasps(cls, position, quat, math.atan2(out[1], out[0]))
        candidates += raised_grasps(cls, position, candidates)
        return [replace(g, lift=max(g.lift, lift), approach=g.approach if rim is None else rim_approach(
            g, rim, DRAWER_CLEARANCE)) for g in candidates]

    def _grasp_from_above(self, name: str, grasp: Grasp, stand_failure: str, checked_only: bool = False
                          ) -> SkillResult | None:
        """Try `grasp` from a base pose checked for it (the arm clear of the apartment on the way in), else from
        where the robot stands, unless it found no place to stand (`stand_failure`, the reason). With
        `checked_only`, None (nothing moved) where no checked base pose reaches it."""
        try:
            planned = self.arm.go_to_grasp(grasp, np.zeros(3), 0.0, here_first=not stand_failure)
        except NavigationError as error:
            return SkillResult(False, str(error))
        if planned is None and checked_only:
            return None
        if planned is None and stand_failure:
            return SkillResult(False, f"{stand_failure}, and no checked base pose reaches the grasp")
        return self._try_grasp(name, grasp, path_in=None if planned is None else planned[0])

    def _fingers_fit(self, grasp: Grasp) -> bool:
        """Whether the fingers, open `grasp.pre_opening`, fit round the object at `grasp` without landing on
        anything else (a neighbour, a drawer's wall); True where the arm cannot tell from where it stands."""
        at_grasp = self.arm.solve(grasp.position, grasp.quat())
        q = at_grasp.q.copy()
        q[self.controller.n_body:] = grasp.pre_opening
        return not at_grasp.converged or self.clearance.fingers_clear(q)

    def _closing_blocked(self, name: str, grasp: Grasp, q: np.ndarray) -> str | None:
        """Why the fingers at configuration q (shape (13,)), at `grasp` on `name`, may not close, else None.
        Closing from `grasp.pre_opening` m per finger (checked every CLOSING_STEP m), they must touch nothing
        they do not touch open already (the concern of `_fingers_fit`) but `name` and what is on or in it: where
        one strikes a wall's edge, the fingers stall there and the other pushes the object against the wall instead
        of against a pad; one sweeping past a neighbour drags it along (a rice box's far finger took the oil beside
        it out of the cupboard, 31 cm). Nor may the object, slid between the pads to the grasp's centre (an
        off-centre grasp's (`aside`, `offset`) near finger pushes it there), press into a neighbour deeper than
        SLIDE_PUSH m."""
        model = self.world.model
        _, watched = self._watch
        own = np.flatnonzero(np.isin(model.geom_bodyid, self.world.object_body_ids[~watched]))
        q = q.copy()
        q[self.controller.n_body:] = grasp.pre_opening
        touched = self.clearance.finger_contacts(q) | set(own.tolist())
        for value in np.arange(grasp.pre_opening - CLOSING_STEP, 0.0, -CLOSING_STEP):
            q[self.controller.n_body:] = value
            if struck := self.clearance.finger_contacts(q) - touched:
                return f"a closing finger would strike {', '.join(self._names({model.geom_bodyid[g] for g in struck}))}"
        if not (grasp.kind.aside or grasp.kind.offset):
            return None
        body = self.world.object_body_ids[self.world.object_index(name)]
        y = grasp.rotation[:, 1]
        shift = float((grasp.position - self.world.data.xpos[body]) @ y) * y
        shift[2] = 0.0  # along the shelf or the bottom it stands on
        if np.linalg.norm(shift) > PUSH_NOISE:
            neighbours = frozenset(self.world.object_body_ids[watched].tolist())
            if pressed := self.clearance.slide_strikes(body, shift, neighbours, SLIDE_PUSH):
                return f"closing, the fingers would slide it into {', '.join(self._names(pressed))}"
        return None

    def _names(self, bodies) -> list[str]:
        """Sorted names of `bodies` (body ids): objects by their object names, other bodies by theirs."""
        names = {int(b): n for n, b in zip(self.world.object_names, self.world.object_body_ids, strict=True)}
        return sorted({names.get(int(b), self.world.model.body(int(b)).name) for b in bodies})

    def _neighbours_struck(self, name: str, path: list[np.ndarray], opening: float) -> list[str]:
        """The objects other than `name` that the fingers, open `opening` m per finger, touch deeper than
        NEIGHBOUR_PUSH m along the descent `path` (configurations, each shape (13,)) onto a grasp: they would push
        them over or rest on them (a toilet roll's shelf grasp came down on the perfume beside it and the roll fell
        out)."""
        n_body = self.controller.n_body
        model = self.world.model
        ids = self.world.object_body_ids
        objects = set(ids.tolist()) - {int(ids[self.world.object_index(name)])}
        touched: set[int] = set()
        for q in path:
            q = q.copy()
            q[n_body:] = opening
            touched |= {int(model.geom_bodyid[g]) for g in self.clearance.finger_contacts(q, NEIGHBOUR_PUSH)}
        return self._names(touched & objects)

    def _pick_from_shelf(self, name: str, node: str, cls, position: np.ndarray, quat: np.ndarray,
                         out: np.ndarray | None = None, replan: bool = True, into: str | None = None
                         ) -> SkillResult:
        """Pick `name` from a shelf inside cabinet `node`: each grasp of `shelf_grasps` in turn, from a base
        pose where the arm clears the compartment; the object lifted SIDE_LIFT m (over what stands in front of it,
        `rise_to_pass`, and over a basin's rim, `_rim_rise`), drawn out, then raised.
        With `out` (a horizontal unit vector, shape (2,)), from an open top instead, for a shelf of `into` next: the
        grasps it takes, approached against `out` (see `_shelf_candidates`). With `replan`, once a failed grasp has
        moved the object (see `disturbed`), the grasps are planned again for where it now stands (the others were
        for where it stood)."""
        grasps, out, front = self._shelf_candidates(name, node, cls, position, quat, out, into)
        # over what stands in front of it on its shelf, or, on an open top, within the SIDE_PULL it is drawn out (a
        # cereal box drawn out low across the dining table took the bowl in front of it along, 80 cm); and over
        # the furniture's own rim in front of its place (a canister of wipes drawn out of the bathroom sink's basin
        # 3 cm up struck the basin's front wall and fell over in the hand)
        rise = max(rise_to_pass(self.world, name, position, out, front if np.isfinite(front) else SIDE_PULL),
                   self._rim_rise(node, position, cls.size[2]))
        unreachable, failures, tried = [], [], []
        pull = np.array([out[0], out[1], 0.0])

        def passes():  # every grasp unfolding the arm first (the tried way), then those no base pose reached,
            for g in grasps:  # swinging straight in; the grasps come as they are ordered, lazily
                tried.append(g)
                yield g, False
            yield from ((g, True) for g in tried)

        for grasp, direct in passes():
            if direct and grasp.kind not in unreachable:
                continue
            try:
                planned = self.arm.go_to_grasp(grasp, pull, max(front, 0.0) + ENTRY_OUT, direct=direct, rise=rise,
                                               held=self._held_by(name, grasp))
            except NavigationError as error:
                failures.append(f"{grasp.kind}: {error}")
                continue
            if planned is None:
                if not direct:
                    unreachable.append(grasp.kind)
                continue
            if direct:
                unreachable.remove(grasp.kind)  # reached after all: its outcome is reported instead
            outcome = self._try_grasp(name, grasp, pull=pull, path_in=planned[0], first_lift=planned[1],
                                      drawn=max(SIDE_PULL, front + max(cls.size[:2]) / 2 + OUT_PAST))
            if outcome.success:
                self.arm.held = name
                return outcome
            failures.append(f"{grasp.kind}: {outcome.reason}")
            if knocked := self._knocked_over(name, node, failures):
                return knocked
            now = self.world.object_pose(name)
            if replan and disturbed(position, quat, *now):
                again = self._pick_from_shelf(name, node, cls, *now, out, replan=False, into=into)
                return again if again.success else SkillResult(False, f"{again.reason} (moved by {failures})")
        if not tried:
            return SkillResult(False, f"{name}: no grasp fits its shape ({cls.size} m) on a shelf of {node}")
        if unreachable:
            failures.append(f"{', '.join(map(str, unreachable))}: no free base pose reaches the grasp without the arm "
                            f"touching {node} or its contents")
        return SkillResult(False, f"{name}: every grasp in {node} failed ({'; '.join(failures)})")

    def _knocked_over(self, name: str, node: str, failures: list[str]) -> SkillResult | None:
        """The failure of a pick whose last grasp (of those that `failures` lists) knocked the upright `name` over,
        else None: the grasps left were made for it standing (a juice carton knocked over on a bookshelf was reached
        for four more times where it had stood, the fingers closing on nothing)."""
        if not self.arm.fallen_over(name):
            return None
        return SkillResult(False, f"{name}: knocked over on {node} ({'; '.join(failures)})")

    def _held_by(self, name: str, grasp: Grasp) -> Held:
        """Object `name` as `grasp` would hold it (standing as it stands now), for clearance checks of its lift."""
        model, body = self.world.model, self.world.object_body_ids[self.world.object_index(name)]
        position, _ = self.world.object_pose(name)
        return Held(frozenset(np.flatnonzero(model.geom_bodyid == body).tolist()),
                    int(model.jnt_qposadr[model.body_jntadr[body]]), grasp.rotation.T @ (position - grasp.position),
                    grasp.rotation.T @ self.world.data.xmat[body].reshape(3, 3))

    def _shelf_candidates(self, name: str, node: str, cls, position: np.ndarray, quat: np.ndarray,
                          out: np.ndarray | None, into: str | None = None
                          ) -> tuple[Iterable[Grasp], np.ndarray, float]:
        """(grasps, out, front) for `_pick_from_shelf`: without `out`, the grasps of `name` inside cabinet `node`
        approached against its front normal (`out`, shape (2,)), the front plane `front` m out from the object,
        the palm clear of its neighbours; with `out`, approached against `out` from anywhere (`front` -inf), those a
        shelf takes as a rule (level, then pitched: a hand pointing straight down, holding the object front to back
        or leaning aside does not put it down under a shelf), those a shelf of `into` takes (`takes`) first (a pot
        picked off the stove pitched 60 degrees met the kitchen cabinet's shelf above with its wrist; pitched 45,
        it goes in), or, where it takes none of them, those of the other grasps it takes (a vegetable held from
        above, though the fridge takes it so, pushed an egg 4 cm in there)."""
        if out is None:
            furniture = self.navigator.furniture[node]
            out = self.navigator.front_normal(node)
            front = float(np.dot(np.array(furniture.pos) + out * furniture.size[1] / 2 - position[:2], out))
            return shelf_grasps(cls, position, quat, out, front, neighbour_footprints(self.world, name)), out, front
        grasps = shelf_grasps(cls, position, quat, out, -np.inf)
        usual = [g for g in grasps if g.kind.pitch != 90 and not g.kind.along and not g.kind.roll]
        if self.takes is None or into is None:
            return usual, out, -np.inf
        return self._taken_first(name, into, usual, [g for g in grasps if all(g is not u for u in usual)]), out, \
            -np.inf

    def _taken_first(self, name: str, into: str, usual: list[Grasp], others: list[Grasp]) -> Iterator[Grasp]:
        """The grasps of `name` in `usual` that a shelf of `into` takes (`takes`), in their order; where it takes
        none of them, those of `others` it takes; then the rest of `usual`: lazily (a check costs a search for a
        base pose at every spot, and the first grasp taken is mostly the one picked with)."""
        takes = lambda g: self.takes(name, into, g.rotation, self._held_by(name, g))  # noqa: E731
        rest = []
        for grasp in usual:
            if takes(grasp):
                yield grasp
            else:
                rest.append(grasp)
        if rest and len(rest) == len(usual):  # of none (not: where there are none; then the next side's)
            yield from (g for g in others if takes(g))
        yield from rest

    def _try_grasp(self, name: str, grasp: Grasp, pull: np.ndarray | None = None,
                   path_in: list[np.ndarray] | None = None, first_lift: float = SIDE_LIFT, drawn: float = SIDE_PULL
                   ) -> SkillResult:
        """Approach along the grip x axis, close, lift: straight up LIFT m, or with `pull` (a horizontal unit
        vector out of the furniture, shape (3,)) up `first_lift` m (SIDE_LIFT unless the way in was checked only
        with LOW_SIDE_LIFT, or more over what stands in front), out `drawn` m and up SIDE_RAISE m.
        path_in: configurations (each shape (13,)) ending at the approach point, already checked; when None the
        approach configuration is solved here. Nothing moves where the descent leaves the arm's reach or the
        fingers may not close there (see `_closing_blocked`)."""
        quat = grasp.quat()
        back = -grasp.rotation[:, 0]  # from the grasp towards where the gripper comes from
        above = grasp.position + grasp.approach * back
        if path_in is None:
            pre = self.arm.solve(above, quat)
            if not pre.converged:
                return SkillResult(False, f"approach pose {pre.reason}")
            path_in = [pre.q]
        planned = self._descent(above, grasp.position, quat, seed=path_in[-1])  # nothing moved yet
        if planned is None:
            return SkillResult(False, "the descent leaves the arm's reach")
        if blocked := self._closing_blocked(name, grasp, planned[-1]):
            return SkillResult(False, blocked)
        struck = self._neighbours_struck(name, planned, grasp.pre_opening)
        if struck:
            return SkillResult(False, f"an open finger would come down on {', '.join(struck)}")
        since = self.world.object_positions()
        pushing = lambda: bool(self._pushed(since))  # noqa: E731
        if not self.arm.reach(path_in[0], grip=grasp.pre_opening, abort=pushing) or (len(path_in) > 1 and not (
                self.controller.move_through(path_in[1:], grip=grasp.pre_opening, abort=pushing))):
            return self._stopped(None, quat, since)
        self.controller.settle(0.003)
        down = self._descent(above, grasp.position, quat)
        if down is None:
            return SkillResult(False, "the descent leaves the arm's reach")
        start, _ = self.world.object_pose(name)
        if not self.controller.move_through(down, abort=pushing):
            return self._stopped(above, quat, since)
        self.controller.settle(0.002)
        opening = self.controller.set_grip(0.0)
        if opening < MIN_HELD_OPENING:
            self._back_off(above, quat)
            return SkillResult(False, f"fingers closed on nothing (opening {opening * 1000:.1f} mm)")
        return self._lift_and_hold(name, grasp, above, start, pull, first_lift, drawn)

    def _lift_and_hold(self, name: str, grasp: Grasp, above: np.ndarray, start: np.ndarray,
                       pull: np.ndarray | None, first_lift: float, drawn: float = SIDE_PULL) -> SkillResult:
        """With the fingers closed on `name` (which stood at `start`, m) at `grasp`, lift it as `_try_grasp`
        says, turn the hand until it hangs where the grasp asks for that, hold HOLD_SECONDS and check that it rose
        at least half as far as the hand; on failure back off to `above` (the approach point, m)."""
        quat = grasp.quat()
        up = np.array([0.0, 0.0, 1.0])
        if pull is not None:
            legs = [first_lift * up, drawn * pull, SIDE_RAISE * up]
        else:
            legs = [LIFT * up]
        legs[-1] = legs[-1] + max(0.0, grasp.lift - sum(leg[2] for leg in legs)) * up  # raised further
        # every leg planned before the hand moves: a leg out of reach found once the object is up and drawn out
        # let go of it there (a conditioner raised off the shower's shelf fell 84 cm to the floor)
        point, seed, paths = grasp.position, self.controller.target, []
        for leg in legs:  # the base follows a horizontal leg; a vertical one only where the arm alone falls short
            path = self.arm.line(point, point + leg, quat, seed=seed,
                                 base_cost=PULL_BASE_COST if leg[2] == 0 else GRASP_BASE_COST)
            if path is None and leg[2] != 0:
                path = self.arm.line(point, point + leg, quat, seed=seed, base_cost=PULL_BASE_COST)
            if path is None:
                self._back_off(above, quat)
                return SkillResult(False, "the lift leaves the arm's reach")
            paths.append(path)
            point, seed = point + leg, path[-1]
        for path in paths:
            self.controller.move_through(path)
        if grasp.hang:  # turn the hand until the object hangs straight below the grip site
            com = self.world.data.xipos[self.world.object_body_ids[self.world.object_index(name)]]
            grip = self.world.data.site("robot/grip")
            turned = hang_rotation(grip.xmat.reshape(3, 3), grip.xpos, com)
            path = self.arm.hand_line(point, matrix_to_quat(turned), GRASP_BASE_COST, partial=True)
            if path:  # as far as the arm turns it
                self.controller.move_through(path)
        self.world.step(int(HOLD_SECONDS / self.world.model.opt.timestep))
        lifted = self.world.object_pose(name)[0][2] - start[2]
        rise = float(sum(leg[2] for leg in legs))
        if lifted < 0.5 * rise:
            self._back_off(above, quat)
            return SkillResult(False, f"the object rose only {lifted * 100:.1f} cm of {rise * 100:.0f} cm")
        return SkillResult(True)

    def _descent(self, above: np.ndarray, position: np.ndarray, quat: np.ndarray, seed: np.ndarray | None = None
                 ) -> list[np.ndarray] | None:
        """`line` from `above` down onto a grasp at `position` (m), from configuration `seed` (default: the
        controller's target): its waypoints within WAYPOINT_TOL, each seeding the next, unless one of them strays
        more than DESCENT_DRIFT m from the line (loose points drifted 6, 11, 14 mm aside on the way into a milk
        carton's side grasp, and a pad struck it: SIDE_MARGIN is 10 mm); then every waypoint exact, if the arm
        reaches them so (tight ones may stall near joint limits)."""
        path = self.arm.line(above, position, quat, seed=seed)
        if path is None:
            return None
        way = (position - above) / max(float(np.linalg.norm(position - above)), 1e-9)
        offsets = [self.ik.grip_pose(q)[0] - above for q in path]
        if max(float(np.linalg.norm(d - (d @ way) * way)) for d in offsets) <= DESCENT_DRIFT:
            return path
        return self.arm.line(above, position, quat, seed=seed, exact=True) or path

    def _back_off(self, above: np.ndarray, quat: np.ndarray, release: bool = True) -> None:
        """Open the fingers (with `release`) and return above the grasp (then tuck)."""
        if release:
            self.controller.set_grip(0.05, seconds=0.3)
        result = self.arm.solve(above, quat, seeds=False)
        if result.converged:
            self.controller.move_through([result.q])
        self.arm.retract()

    def _standing_on(self, node: str, position: np.ndarray, height: float) -> tuple[bool, bool]:
        """Of the fixed place of furniture `node` an object of `height` m at `position` stands on: (whether it lies
        under another of its places, `covered_places`: a bookshelf's lower levels, where only a grasp from the front
        fits; whether it has less than OPEN_ABOVE m of free height, though nothing of `node` is over it: a shower's
        corner shelf, a sink's basin, where one from the front may fit better than one from above)."""
        support = self._support(node, position, height)
        if support is None:
            return False, False
        _, relation, k, place = support
        return k in covered_places(self.spots, node, relation), place.clearance < OPEN_ABOVE

    def _support(self, node: str, position: np.ndarray, height: float) -> tuple | None:
        """(z m, relation, index, Place) of the fixed place of furniture `node` an object of `height` m at
        `position` stands on (the highest one at most 2 cm above its bottom), or None (none; not furniture)."""
        furniture = self.spots.furniture.get(node)
        if furniture is None:
            return None
        bottom = position[2] - height / 2
        below = [(place_world(self.world.layout, furniture, p)["z"], relation, k, p) for relation in (ON, INSIDE)
                 for k, p in self.spots.places_of(node, relation) if p.part is None]
        below = [(z, relation, k, p) for z, relation, k, p in below if z <= bottom + 0.02]
        return max(below, key=lambda b: b[0]) if below else None

    def _rim_rise(self, node: str, position: np.ndarray, height: float) -> float:
        """How far (m) an object of `height` m at `position` must rise so that its bottom passes PASS_ABOVE over
        the rim furniture `node` has in front of the place it stands on (`rim_above`: a basin's front wall, a
        shower's curb), drawn out through the front; 0 where there is none."""
        support = self._support(node, position, height)
        if support is None:
            return 0.0
        z, _, _, place = support
        rim = rim_above(self.spots.furniture[node], place)
        return 0.0 if rim <= 0.0 else max(0.0, z + rim + PASS_ABOVE - (position[2] - height / 2))
