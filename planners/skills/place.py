"""The `place` skill of `planners.skills.Robot`: put the held object down on or inside furniture, checked in physics.

On an open top: lowered onto a free spot from above (spots the hand reaches from in front first, a few in turn;
along a way checked clear of the apartment where one is found from where the carry stopped), let go, the hand
drawn back; a lowering that stops on something backs up, still holding the object, and the next spot is tried.
On a cabinet's shelf, or a level of an open shelf under another: carried in from a base pose where the object and
the arm clear the furniture, eased in slowly, let go and drawn straight out. Success is read back from the
observed scene graph. Movement comes from `planners.motion.arm`.
"""

from __future__ import annotations

import copy
import math
from itertools import islice

import numpy as np

from homer_sim.errors import HomerError
from homer_sim.graph import INSIDE, RELATION_NAMES
from homer_sim.home.catalog import CATALOG
from homer_sim.home.spots import Spots
from homer_sim.observe import SceneGraphObserver
from planners.grasps.geometry import axis_rotation, matrix_to_quat, yaw_matrix
from planners.grasps.neighbours import rise_to_pass, tallest_beside
from planners.motion.arm import (
    ENTRY_OUT,
    GRASP_BASE_COST,
    LEVEL_HAND,
    PASS_OVER,
    PITCHED_HAND,
    PULL_BASE_COST,
    SIDE_LIFT,
    WAYPOINT_TOL,
    Arm,
)
from planners.motion.clearance import ARC_BASE_COST, Held
from planners.motion.control import CARRY_MOTION
from planners.motion.navigation import CLEARANCE, NavigationError, base_candidates
from planners.skills.parts import covered_places, shelves_inside
from planners.skills.result import SkillResult

APPROACH = 0.12  # m above the grasp the gripper comes from and leaves to (top grasps; see Grasp.approach)
NO_UP_FAMILIES = ("cloth", "sphere")  # shapes that lie as well one way as another: put down, none falls over
CARRY_SLIP = 0.03  # m the held object may shift in the hand on the way into a shelf before it no longer goes in
# as planned (one that moved more while carried, the fingers met, fell out), and on the way above a spot before it is
# aimed again (`_lower_onto`)
WAY_MARGIN = 0.005  # m the arm keeps from the apartment on the way down a held object is lowered along, where there
# is such a way (else one that touches nothing; see `Place._lower`)
UPRIGHT_TURN = math.radians(3.0)  # rad a held object hangs tilted at least before a lowering turns it upright
TOP_SPOTS = 4  # free spots on an open top tried for a place (the first one no way down is blocked to),
TOP_SPOT_GAP = 0.08  # m apart at least,
SPOT_DRAWS = 40  # from this many free spots of each place drawn in turn
STOPPED_ABOVE = 0.02  # m above its spot a lowered object may stop before it counts as stopped on something
SPOT_MISS = 0.05  # m beside its spot a lowered object may come down and still be let go (a loaf let go 16 cm
# short of its spot, where the base met the counter, landed on a towel and fell over)
DROP_HEIGHT = 0.05  # m above its spot a lowered object touching nothing but the robot is let fall at most
DROP_INTO = 0.02  # m over a bin's rim a thing with no up (cloth) is let go to drop in: lowered to the basket's
# floor, a dress hanging from its fold met the walls, and the arm reaching down there pushed the basket 14 cm
SHELF_SPOTS = 6  # free spots tried for a place inside, nearest the front first, then half as many on each other
# shelf (rack),
SHELF_SPOT_GAP = 0.05  # m apart at least
EASE_SLOWDOWN = 3.0  # times the default duration of a joint-space move with a held object into furniture
RELEASE_OPENING = 0.015  # m per finger the fingers open past the held object to let go (inside a shelf)
TOP_RELEASE_OPENING = 0.05  # m per finger the fingers open at least to let go on an open top
PASS_NEAR = 0.5  # m from its spot within which what stands on the surface is carried over (a can of wipes held
# from the side at the carry point hung 5 cm above the stove and swept the 10 cm sauce pan 32 cm aside)
FLOOR_DRAWS = 8  # free floor spots drawn in turn for a put-down on a floor, until one leaves the way free
DRIVEN_TURNS = np.radians([0, 45, -45, 90, -90])  # rad off pointing at the spot a level hand is turned to, for
# a lowering from a base pose chosen for it


class Place:
    """The `place` skill: puts what the `arm` holds down, on or in furniture; `observer` reads where it ended,
    `spots` (with `rng`) chooses where it goes."""

    def __init__(self, arm: Arm, observer: SceneGraphObserver, spots: Spots, rng: np.random.Generator) -> None:
        self.arm = arm
        self.observer = observer
        self.spots = spots
        self.rng = rng
        self.world, self.controller, self.navigator = arm.world, arm.controller, arm.navigator
        self.ik, self.clearance = arm.ik, arm.clearance

    def place(self, node: str, relation: int | None = None) -> SkillResult:
        """Put the held object at a free spot ON or INSIDE furniture `node`, release it and retreat: on its open
        places, TOP_SPOTS spots in turn (those reached from the base pose in front of them first), then, where the
        open ones gave none, on the levels under another from the front (`covered_places`)."""
        name = self.arm.held
        if name is None:
            return SkillResult(False, "place: the robot holds nothing")
        if node in self.world.layout.room_names():
            return self._place_on_floor(name, node)
        if node in self.world.object_names:
            return self._place_on_object(name, node)
        shelves = shelves_inside(self.spots, self.navigator.furniture.get(node), node, relation)
        if shelves:
            return self._place_in_shelf(name, node, shelves)
        covered = covered_places(self.spots, node, relation)  # under a level above: from the front, as shelves
        spots = _spread([spot for k, _ in self.spots.places_of(node, relation) if k not in covered
                         for spot in islice(self._free_spots(name, node, k), SPOT_DRAWS)],
                        TOP_SPOT_GAP, 2 * TOP_SPOTS)
        spots = sorted(spots, key=lambda spot: not self._reachable(name, node, np.array(spot.pos)))[:TOP_SPOTS]
        failures = []
        for spot in spots:  # each lowered onto until one is let go on (or the object is lost)
            target = np.array(spot.pos)
            failure, short = self._carry_to(name, node, target)
            if failure is not None:
                return failure
            outcome = self._lower(name, node, target, short)
            if outcome.success or self.arm.held is None:
                return outcome
            failures.append(outcome.reason.removeprefix("place: "))
        if covered:
            outcome = self._place_in_shelf(name, node, covered)
            if outcome.success or self.arm.held is None or not failures:
                return outcome
            failures.append(outcome.reason.removeprefix("place: "))
        if not failures:
            return SkillResult(False, f"place: no free spot for {name} on {node}")
        return SkillResult(False, f"place: {'; '.join(failures)}")

    def _free_spots(self, name: str, node: str, place_index: int, rng: np.random.Generator | None = None):
        """The free spots for `name` on place `place_index` of `node` (see `Spots.free_spots`), drawn with `rng`
        (default: the skill's)."""
        return self.spots.free_spots(name, node, place_index, self.rng if rng is None else rng,
                                     {self.world.object_index(name)})

    def _place_on_floor(self, name: str, room: str) -> SkillResult:
        """Put the held `name` on a free spot of the floor of `room` that leaves the floor passable: near the robot
        when it is in that room, else near the room's centre; lowered from above."""
        here = self.controller.q()[:2]
        rect = next(r.rect for r in self.world.layout.rooms if r.name == room)
        near = here if self.world.layout.room_at(*here) == room else ((rect[0] + rect[2]) / 2, (rect[1] + rect[3]) / 2)
        size = self.world.object_class(name).size
        half = math.hypot(size[0], size[1]) / 2
        spot = None
        for _ in range(FLOOR_DRAWS):  # the first that leaves the floor passable (`Navigator.leaves_way`)
            try:
                spot = self.spots.floor_spot(name, room, tuple(near), self.rng, {self.world.object_index(name)})
            except HomerError as error:
                return SkillResult(False, f"place: {error}")
            x, y = spot.pos[:2]
            if self.navigator.leaves_way((x - half, y - half, x + half, y + half)):
                break
        else:
            return SkillResult(False, f"place: no spot on the floor of {room} near {np.round(near, 2).tolist()} "
                                      f"leaves the way free ({FLOOR_DRAWS} drawn)")
        return self._down_at(name, room, room, np.array(spot.pos))

    def _place_on_object(self, name: str, node: str) -> SkillResult:
        """Put the held `name` on (into, for a bin) object `node`: centred over it, at the height it lands on what
        is there (its top, its floor or the pile in it); a thing with no up (cloth) into a bin is let go just over
        its rim and drops in. An object the catalogue does not count as a support (a cd player, a loaf) is tried
        too: whether the put-down object stays on it is for physics to say."""
        cls = self.world.object_class(node)
        position = self.world.object_pose(node)[0]
        held = self.world.object_class(name)
        size = held.size
        rim = position[2] + cls.size[2] / 2
        try:
            z = self.spots.landing_in(name, node, tuple(position[:2]), rim + size[2] + 0.05)
        except HomerError as error:
            return SkillResult(False, f"place: {error}")
        if cls.is_container and held.family in NO_UP_FAMILIES:  # dropped in from over the rim (see DROP_INTO)
            z = max(z, rim + size[2] / 2 + DROP_INTO)
        graph = self.observer.update()
        anchor = node
        while anchor in self.world.object_names and graph.parent_of(anchor):
            anchor = graph.parent_of(anchor)
        return self._down_at(name, node, anchor, np.array([position[0], position[1], z]))

    def _down_at(self, name: str, node: str, anchor: str, target: np.ndarray) -> SkillResult:
        """Carry `name` to stand at `anchor` (furniture: in front of it; a room: near `target` on the floor) and
        lower it onto `target` (m) on `node` along a checked way where one is found (`_lower`), as onto a spot of
        the furniture (`place`): lowered unchecked from where the carry stopped, a vegetable for the cutting board
        would have struck the knife block beside it, and the place gave up; a radio lowered to the floor straight
        down from where the robot stood met the robot's base on the way and came down on a shelf's plinth."""
        if anchor in self.navigator.furniture:
            failure, short = self._carry_to(name, anchor, target)
            if failure is not None:
                return failure
            return self._lower(name, node, target, short)
        held_at = self.arm.held_offset(name)
        try:
            self.navigator.drive_to(self.navigator.stand_near(tuple(target[:2])), self.arm.carry(),
                                    self.arm.held_reach(), **CARRY_MOTION, clear=self.arm.carry_clear())
        except HomerError as error:
            return SkillResult(False, f"place: {error}")
        return self._fell_out(name, held_at) or self._lower(name, node, target, short=False)

    def _carry_to(self, name: str, node: str, target: np.ndarray) -> tuple[SkillResult | None, bool]:
        """Carry `name` to a base pose in front of furniture `node` facing `target` (m, the spot it goes to; see
        `Arm.go_to`), held over what stands within PASS_NEAR of the spot: (a failure if it could not or the object
        fell out of the hand on the way; whether the robot stopped short with the object low)."""
        held_at = self.arm.held_offset(name)  # where the object hangs in the hand (grip frame)
        size = self.world.object_class(name).size
        surface = target[2] - size[2] / 2  # the held object passes over what stands near its spot, too
        try:
            short = self.arm.go_to(node, target[:2], surface_z=tallest_beside(self.world, name, target, surface,
                                                                              PASS_NEAR))
        except NavigationError as error:
            return SkillResult(False, f"place: {error}"), False
        return self._fell_out(name, held_at), short

    def _fell_out(self, name: str, held_at: np.ndarray) -> SkillResult | None:
        """The failure of a carry after which `name`, before it at `held_at` in the grip frame (m, shape (3,)),
        moved more than CARRY_SLIP in the hand and the fingers met (it fell out; fingers closed on a thin cloth
        meet too), else None: an object that slipped in the fingers but is still held is put down as it hangs now
        (the lowering reads where it hangs; a basket held by its rim or a bag slid 4-13 cm in the hand and the
        place gave up with them still held)."""
        if np.linalg.norm(self.arm.held_offset(name) - held_at) > CARRY_SLIP and self.arm.hand_empty():
            self.arm.held = None
            return SkillResult(False, f"place: {name} fell out of the hand while carried")
        return None

    def _lower_onto(self, name: str, node: str, target: np.ndarray, short: bool) -> SkillResult:
        """Lower the held `name` onto `target` (m) on furniture `node` from APPROACH m above, as it hangs in the
        hand (turned to stand it up, see `_lowering_rotations`), let go and retreat. Stopped `short` with the object
        low: first lift it over the surface and what stands within PASS_NEAR of the spot (driven in low, a can of
        wipes swept a sauce pan on the stove 17 cm aside), then drive in close (the object passes over the edge)
        and move it across to above the spot in a straight line. Where the object shifted more than CARRY_SLIP in
        the hand on the way above the spot, it is aimed again from where it hangs then, over its spot and straight
        down, if the arm reaches that (a laundry basket pinched at its rim pivoted 35 degrees on the way and stopped
        5.5 cm above the floor). Nothing is lowered where the arm or the object would come down on another object
        (`_struck`): the ways over the spot and down are checked before the hand moves over it, and a refusal
        drives the base back out to where the carry left it (`_withdrawn`)."""
        grip = self.world.data.site("robot/grip")
        now = grip.xmat.reshape(3, 3)
        offset = grip.xpos - self.world.object_pose(name)[0]  # where the object hangs from the hand now
        for rotation in self._lowering_rotations(name):  # the first the arm reaches above the spot at
            turned = rotation @ now.T @ offset  # the hand turned about the object
            quat = matrix_to_quat(rotation)
            release = target + turned + np.array([0.0, 0.0, 0.01])
            above = release + np.array([0.0, 0.0, APPROACH])
            if self.arm.solve(above, quat).converged:
                break
        came_from = self.controller.target.copy()  # withdrawn to on a failure (see the docstring)
        if short:
            surface = target[2] - self.world.object_class(name).size[2] / 2
            rise = tallest_beside(self.world, name, target, surface, PASS_NEAR) - surface + PASS_OVER
            if self.arm.grip_line(np.array([*grip.xpos[:2], max(grip.xpos[2], release[2] + rise)]), quat):
                try:
                    self.navigator.drive_to(self.navigator.stand_pose(node, tuple(target[:2])),
                                            self.controller.target.copy(), **CARRY_MOTION)
                except NavigationError:
                    pass  # reach from where it stands
        onto = node if node in self.world.object_names else None
        over = self._way_over(name, above, quat)
        if over is None:
            pre = self.arm.solve(above, quat)
            if not pre.converged:
                return self._withdrawn(came_from, f"place: {name} above {node} is {pre.reason}")
            over = [pre.q]
        down = self.arm.line(above, release, quat, seed=over[-1])
        if down is None:
            return self._withdrawn(came_from, f"place: lowering {name} onto {node} leaves the arm's reach")
        struck = self._struck(name, over) or self._struck(name, down, onto)
        if struck:
            return self._withdrawn(came_from, f"place: {name} on its way to {node} would strike {', '.join(struck)}")
        if len(over) > 1:
            self.controller.move_through(over)
        else:
            self.arm.reach(over[0])
        self.controller.settle(0.003)
        again = target + grip.xpos - self.world.object_pose(name)[0] + np.array([0.0, 0.0, 0.01])  # as it hangs now
        if np.linalg.norm(again - release) > CARRY_SLIP:  # turned in the fingers: over the spot again, then down
            lifted = again + np.array([0.0, 0.0, APPROACH])
            over_again = self.arm.line(grip.xpos.copy(), lifted, quat)
            straight = over_again and self.arm.line(lifted, again, quat, seed=over_again[-1])
            if straight:
                down, release = over_again + straight, again
            struck = self._struck(name, down, onto)  # checked again as the object hangs now
            if struck:
                return SkillResult(False, f"place: lowering {name} onto {node} would strike {', '.join(struck)}")
        self.controller.move_through(down)
        self.controller.settle(0.003)
        return self._release_on(name, node, target, release, quat)

    def _struck(self, name: str, path: list[np.ndarray], onto: str | None = None) -> list[str]:
        """The objects that the arm or the held `name` (as it hangs in the hand now) would touch along `path`
        (configurations, each shape (13,)), but `name`, what rides in or on it (`_riders`), the object `onto` it is
        lowered onto and the objects that one lies on: a lowering no clear way was found for is not tried onto
        them (a wrist came down on a sauce pan beside the spot and pushed it). The riders stay where they are in
        the check while the held object moves, so they would count as struck (a bin with a newspaper in it); a
        lowering onto an object ends touching it, and a bin wider than the mail it goes onto touches the
        newspaper under the mail too."""
        held = self.arm.held_object(name)
        bodies = {int(b): n for n, b in zip(self.world.object_names, self.world.object_body_ids, strict=True)}
        graph = self.observer.update()
        skip = {name, *self._riders(name, graph)}
        while onto in self.world.object_names:  # the object it goes onto and the pile that one lies on
            skip.add(onto)
            onto = graph.parent_of(onto)
        checked = frozenset(b for b, n in bodies.items() if n not in skip)
        struck = set().union(*(self.clearance.bodies_struck(q, held, checked) for q in path))
        return sorted(bodies[b] for b in struck)

    def _riders(self, name: str, graph) -> set[str]:
        """The objects that rest (through others) on or in `name` in the observed scene graph, or whose centre lies
        inside its box (a newspaper in a bin the graph puts the bin on); `graph`: the observed scene graph."""
        index = self.world.object_index(name)
        centre = self.world.object_pose(name)[0]
        rotation = self.world.data.xmat[self.world.object_body_ids[index]].reshape(3, 3)
        half = np.asarray(CATALOG[self.world.layout.objects[index].cls].size) / 2
        riders = set()
        for other in self.world.object_names:
            if other == name:
                continue
            parent = graph.parent_of(other)
            while parent and parent != name:
                parent = graph.parent_of(parent)
            local = rotation.T @ (self.world.object_pose(other)[0] - centre)
            if parent == name or bool(np.all(np.abs(local) <= half)):
                riders.add(other)
        return riders

    def _way_over(self, name: str, above: np.ndarray, quat: np.ndarray) -> list[np.ndarray] | None:
        """Configurations of a straight grip line taking the held `name` to `above` (m, at `quat`): the base free to
        follow where the arm and the object touch nothing on the way, else with the base held where that way is
        clear (following the hand, the base drove 15 cm into the laundry basket a dress was to go in and pushed it
        5 cm), else the base free, unchecked; None if the line leaves the arm's reach."""
        held = self.arm.held_object(name)
        for cost in (PULL_BASE_COST, GRASP_BASE_COST):
            path = self.arm.hand_line(above, quat, cost)
            if path is not None and all(self.clearance.clear(q, held=held) for q in path):
                return path
        return self.arm.hand_line(above, quat, PULL_BASE_COST)

    def _release_on(self, name: str, node: str, target: np.ndarray, release: np.ndarray, quat: np.ndarray
                    ) -> SkillResult:
        """With the held `name` lowered for `target` (m, its spot on `node`; the grip site at `release`, m, at
        `quat`): let go and retreat, unless its lowest point stopped more than STOPPED_ABOVE m above where its bottom
        goes (it came down on something) or, for a thing with an up put on furniture, its centre is more than
        SPOT_MISS m beside the spot (the arm fell short; cloth hangs off centre and lies as it lands, a floor has
        no edge to tip over: a vacuum cleaner held by its handle came down 5.1 cm beside its spot): then back up
        APPROACH m, still holding it. Where it stopped at most
        DROP_HEIGHT m above touching nothing but the robot (the arm reaches no lower: a vacuum cleaner held by its
        handle 2.6-4 cm above the floor), it is let go there. Where the fingers met on the way down, the object is
        no longer held (a laundry basket pinched by its rim slipped out as it touched the bed): nothing is backed up,
        the hand opens and draws back and where it ended is read."""
        if self.arm.hand_empty():
            return self._let_go(name, node, TOP_RELEASE_OPENING,
                                self._retreat(name, release, quat, TOP_RELEASE_OPENING))
        index = self.world.object_index(name)
        size = np.asarray(CATALOG[self.world.layout.objects[index].cls].size)
        tilt = np.abs(self.world.data.xmat[self.world.object_body_ids[index]].reshape(3, 3)[2])
        low = float(self.world.object_pose(name)[0][2] - tilt @ size / 2)  # its lowest point (it may hang tilted)
        stopped = low - float(target[2] - size[2] / 2) - 0.01
        family = CATALOG[self.world.layout.objects[index].cls].family
        lies_in = family in NO_UP_FAMILIES and self._rests_only_on(name, node)
        if stopped > STOPPED_ABOVE and not lies_in and (stopped > DROP_HEIGHT or self._touches_apartment(name)):
            self.arm.grip_line(release + np.array([0.0, 0.0, APPROACH]), quat)
            return SkillResult(False, f"place: {name} stopped {stopped * 100:.1f} cm above its spot on {node}")
        missed = float(np.linalg.norm(self.world.object_pose(name)[0][:2] - target[:2]))
        if missed > SPOT_MISS and node in self.navigator.furniture and family not in NO_UP_FAMILIES:
            self.arm.grip_line(release + np.array([0.0, 0.0, APPROACH]), quat)
            return SkillResult(False, f"place: {name} came down {missed * 100:.1f} cm beside its spot on {node}")
        opening = max(TOP_RELEASE_OPENING, self._held_opening() + RELEASE_OPENING)
        return self._let_go(name, node, opening, self._retreat(name, release, quat, opening))

    def _rests_only_on(self, name: str, node: str) -> bool:
        """Whether object `name` touches something besides the robot now, and all of it is `node` or what lies on
        or in `node` (a dress held by its fold hung down into the laundry basket and met its walls 10 cm above the
        basket's floor: it is where it goes, let go there it stays in)."""
        others = self._touching(name)
        if not len(others):
            return False
        graph = self.observer.update()
        touched = {self.observer.nodes[n] if n >= 0 else "" for n in self.observer.geom_node[others]}
        # "": a geom of no node (a wall), where the object does not go
        return all(t and (t == node or graph.parent_of(t) == node) for t in touched if t != name)

    def _touches_apartment(self, name: str) -> bool:
        """Whether object `name` touches anything but the robot now."""
        return bool(len(self._touching(name)))

    def _touching(self, name: str) -> np.ndarray:
        """The geoms, not the robot's, that object `name` touches now (one per contact)."""
        model, data, robot = self.world.model, self.world.data, self.clearance.robot
        body = self.world.object_body_ids[self.world.object_index(name)]
        g1, g2 = data.contact.geom1[:data.ncon], data.contact.geom2[:data.ncon]
        return np.concatenate([g2[(model.geom_bodyid[g1] == body) & ~robot[g2]],
                               g1[(model.geom_bodyid[g2] == body) & ~robot[g1]]])

    def _withdrawn(self, q: np.ndarray, reason: str) -> SkillResult:
        """The failure `reason`, after driving the base straight back to configuration q's (shape (13,)) with the
        arm and the held object as they are, where it drove in from there (a lowering given up next to a sauce pan
        left a can of wipes out over the stove, the base driven in close, and the drive to the next top swept the
        pan off it)."""
        if np.linalg.norm(self.controller.target[:2] - q[:2]) > WAYPOINT_TOL[0]:
            back = self.controller.target.copy()
            back[:3] = q[:3]
            self.controller.move_through([back], **CARRY_MOTION)
        return SkillResult(False, reason)

    def _lower(self, name: str, node: str, target: np.ndarray, short: bool) -> SkillResult:
        """Lower the held `name` onto `target` (m, a spot on `node`) after a carry that stopped `short` or not: along
        a checked way from where the robot stands (`_lower_checked`), else from a base pose chosen for it
        (`_lower_driven`), each first on a way whose arm keeps WAY_MARGIN from the apartment, then on one that only
        touches nothing (the arm trails its planned way: a palm planned 0.1 mm past a knife block beside a cutting
        board struck it, and letting go knocked the block off the counter); where there is none, or the carry
        stopped short, straight down from above the spot, unchecked (`_lower_onto`)."""
        if not short:
            for margin in (WAY_MARGIN, 0.0):
                outcome = self._lower_checked(name, node, target, margin)
                if outcome is None:
                    outcome = self._lower_driven(name, node, target, margin)
                if outcome is not None:
                    return outcome
        return self._lower_onto(name, node, target, short)

    def _lower_checked(self, name: str, node: str, target: np.ndarray, margin: float = 0.0) -> SkillResult | None:
        """Lower the held `name` onto `target` (m, a spot on furniture `node`) from where the robot stands, the
        base kept there, along a way (eased to APPROACH m above the spot, then straight down, the object as it
        hangs in the hand, stood up where it tilted: `_lowering_rotations`) that keeps the arm `margin` m from the
        apartment and the object clear of it; let go and retreat. None (nothing moved) where no such way is found."""
        held = self.arm.held_object(name)
        for rotation in self._lowering_rotations(name):
            quat = matrix_to_quat(rotation)
            release = target + np.array([0.0, 0.0, 0.01]) - rotation @ held.position
            above = release + np.array([0.0, 0.0, APPROACH])
            with self.clearance.keeping(margin):
                start = self.ik.solve(self.controller.target, above, quat, base_cost=ARC_BASE_COST)
                if not start.converged or not self.clearance.clear(start.q, held=held):
                    continue
                path = self.arm.checked_line(start.q, [above, release], quat, held)
                ease = None if path is None else self._ease_path(self.controller.target, start.q, held)
            if ease is None:
                continue
            self._ease_to(ease, start.q)
            self.controller.move_through(path)
            self.controller.settle(0.003)
            return self._release_on(name, node, target, release, quat)
        return None

    def _lower_driven(self, name: str, node: str, target: np.ndarray, margin: float = 0.0) -> SkillResult | None:
        """`_lower_checked` from a base pose chosen for the lowering (`_drive_for`: the object eases from the carry
        posture to APPROACH m above `target` and comes straight down, the arm and the object clear of the apartment
        all the way), for where the carry stopped too far off to reach the spot that way (moved over the spot
        unchecked, a toilet roll was knocked out of the fingers over the bathroom counter; there the bathroom
        cabinet's open door, which the full hand cannot close, leaves no free base pose either). A hand not
        pointing down is turned about the vertical (the object keeps its up) to point from where the robot stands
        towards the spot, then DRIVEN_TURNS off that: base poses are sought behind the hand, and
        straight behind it there may be no room. None (the robot may have driven, the object still held) where
        no base pose gives such a way."""
        held, posture = self.arm.held_object(name), self.arm.carry()
        here = self.controller.q()[:2]
        toward = math.atan2(target[1] - here[1], target[0] - here[0])
        for rotation in self._lowering_rotations(name):
            pointing = rotation[:2, 0]
            turns = [0.0] if np.linalg.norm(pointing) <= PITCHED_HAND else [
                toward - math.atan2(pointing[1], pointing[0]) + float(t) for t in DRIVEN_TURNS]
            for turn in turns:
                turned = yaw_matrix(turn) @ rotation
                release = target + np.array([0.0, 0.0, 0.01]) - turned @ held.position
                planned = self._drive_for([release + np.array([0.0, 0.0, APPROACH]), release], turned, posture, held,
                                          margin)
                if planned is None:
                    continue
                ease, path = planned
                self._ease_to(ease, path[0])
                self.controller.move_through(path[1:])
                self.controller.settle(0.003)
                return self._release_on(name, node, target, release, matrix_to_quat(turned))
        return None

    def _lowering_rotations(self, name: str) -> list[np.ndarray]:
        """The grip rotations (each shape (3, 3)) to lower the held `name` at, in the order tried: where it hangs
        tilted more than UPRIGHT_TURN in the hand and has an up (not NO_UP_FAMILIES), first the hand turned about
        the horizontal so that the object stands upright (a wine glass and a loaf that turned in the fingers were
        set down tilted and fell over); then the hand as it is."""
        now = self.world.data.site("robot/grip").xmat.reshape(3, 3).copy()
        index = self.world.object_index(name)
        up = self.world.data.xmat[self.world.object_body_ids[index]].reshape(3, 3)[:, 2]
        angle = math.acos(min(max(float(up[2]), -1.0), 1.0))
        axis = np.cross(up, [0.0, 0.0, 1.0])
        if CATALOG[self.world.layout.objects[index].cls].family in NO_UP_FAMILIES or angle < UPRIGHT_TURN:
            return [now]
        return [axis_rotation(axis / np.linalg.norm(axis), angle) @ now, now]

    def _reachable(self, name: str, node: str, target: np.ndarray) -> bool:
        """Whether the hand, holding `name` as it does now (turned as `_lowering_rotations` first turns it), reaches
        over `target` (m, a spot on furniture `node`) from the base pose in front of `node` facing it, the base kept
        there (the IK pushes the base into the furniture to reach a spot far back, and the furniture stops it)."""
        held = self.arm.held_object(name)
        rotation = self._lowering_rotations(name)[0]
        above = target + np.array([0.0, 0.0, 0.01 + APPROACH]) - rotation @ held.position
        try:
            base = self.navigator.stand_pose(node, tuple(target[:2]))
        except NavigationError:
            return False
        q = self.controller.target.copy()
        q[:3] = base
        return self.ik.solve(q, above, matrix_to_quat(rotation), base_cost=ARC_BASE_COST).converged

    def _held_opening(self) -> float:
        """The fingers' opening now (m per finger): round the held object, whose width a release must open past
        (a cd held across 12.5 cm stays wedged between fingers opened to 5 cm each)."""
        return float(np.mean(self.controller.q()[-2:]))

    def _retreat(self, name: str, release: np.ndarray, quat: np.ndarray, opening: float
                 ) -> list[np.ndarray] | None:
        """Configurations that take the open hand away from `name`, let go of at `release` (m), the fingers open
        to `opening` m: back along the grip x axis APPROACH m (straight up for a hand pointing down), then, for a
        hand held level, up as much (it held the object's side: lifted at once, or swung back into the tuck, the
        fingers knock it over). The base stays where it can, else it backs away with the hand (a cup let go 75 cm
        out over the dining table at 0.8 m was out of the arm's reach drawn back with the base held; the retract
        then lifted the open fingers round it and swung them across it, and it fell over). Where that way, the
        fingers open, touches anything but `name`, a level hand goes up first, then back, if that way touches
        nothing (the open pads drawn back from a vegetable let go on a cutting board caught the knife block
        beside it and dragged it 1 m)."""
        x = self.world.data.site("robot/grip").xmat.reshape(3, 3)[:, 0].copy()
        back, up = release - APPROACH * x, np.array([0.0, 0.0, APPROACH])
        away = self.arm.line(release, back, quat) or self.arm.line(release, back, quat, base_cost=PULL_BASE_COST)
        if away is None or np.linalg.norm(x[:2]) <= LEVEL_HAND:
            return away
        away += self.arm.line(back, back + up, quat, seed=away[-1]) or []
        if self._open_hand_clear(name, away, opening):
            return away
        lift = self.arm.line(release, release + up, quat)
        over = lift and self.arm.line(release + up, back + up, quat, seed=lift[-1])
        return lift + over if over and self._open_hand_clear(name, lift + over, opening) else away

    def _open_hand_clear(self, name: str, path: list[np.ndarray], opening: float) -> bool:
        """Whether the robot, the fingers open to `opening` m, touches nothing but object `name` along `path`."""
        body = self.world.object_body_ids[self.world.object_index(name)]
        for q in path:
            opened = q.copy()
            opened[self.controller.n_body:] = opening
            if any(self.world.model.geom_bodyid[g] != body for g in self.clearance.finger_contacts(opened, whole=True)):
                return False
        return True

    def _let_go(self, name: str, node: str, opening: float, away: list[np.ndarray] | None,
                inside: bool = False) -> SkillResult:
        """Open the fingers to `opening` m per finger, move the hand along `away` (configurations, if any), tuck,
        let the world settle, and read where `name` ended: on or in `node` (inside it, with `inside`)."""
        self.controller.set_grip(opening, seconds=0.4)
        self.arm.held = None
        if away is not None:
            self.controller.move_through(away)
        self.arm.retract()
        self.world.settle(max_seconds=2.0)
        graph = self.observer.update()
        parent, relation = graph.parent_of(name), graph.relation_of(name)
        if parent != node or (inside and relation != RELATION_NAMES[INSIDE]):
            return SkillResult(False, f"place: {name} ended {relation} {parent}, not {'inside' if inside else 'on'} "
                                      f"{node}")
        family = self.world.object_class(name).family
        if family not in NO_UP_FAMILIES and self.arm.fallen_over(name):
            return SkillResult(False, f"place: {name} fell over on {node}")
        return SkillResult(True)

    def _place_in_shelf(self, name: str, node: str, places: list[int]) -> SkillResult:
        """Put the held object on a shelf inside cabinet `node` (`places`: its shelf indices), the reverse of
        `_pick_from_shelf`: from a base pose where the object and the arm clear the cabinet and its contents, in
        SIDE_LIFT m (or over what stands in front of it, `rise_to_pass`) above a free spot (`_shelf_ways`), down,
        release, and out the way it went in."""
        posture, held = self.arm.carry(), self.arm.held_object(name)
        ways = self._shelf_ways(name, node, places, self.world.data.site("robot/grip").xmat.reshape(3, 3), held)
        if not ways:
            return SkillResult(False, f"place: no free spot for {name} inside {node}")
        for spot, rotation, release, outside, over in ways:
            up = np.array([0.0, 0.0, over])
            planned = self._drive_for([outside + up, release + up, release], rotation, posture, held)
            if planned is not None:
                return self._go_in(name, node, spot, rotation, held, planned, release, outside, over)
        return SkillResult(False, f"place: no free base pose puts {name} into {node} without it or the arm "
                                  f"touching {node} or its contents ({len(ways)} spots tried)")

    def takes(self, name: str, node: str, grip: np.ndarray, held: Held) -> bool:
        """Whether a shelf inside `node` takes `name` held as `held` at grip rotation `grip` (shape (3, 3)), as a
        grasp being chosen for it would hold it: put in as `_place_in_shelf` puts it (at the spots it would draw
        now, the skill's random draws left as they were), from a free base pose at one of them (the way from the
        carry posture, which that grasp has not reached yet, is not checked; checked at only the first 3 spots, a
        glass's grasp that went in at a later one was passed over for one that pushed a cup in the dishwasher).
        True where `node` has no shelf behind a door: the levels of an open shelf under another are tried after its
        top, which takes anything (a remote control's grasp was passed over for one that pushed a radio 4.6 cm
        on a tv stand). A pot held pitched 60 degrees from the front, picked off the stove for a kitchen cabinet,
        met the shelf above with its wrist at every spot; pitched 45, it goes in."""
        places = shelves_inside(self.spots, self.navigator.furniture.get(node), node, None)
        if not places:  # an open top first (see `place`), which takes anything
            return True
        q, rng = self.controller.target, copy.deepcopy(self.rng)  # the spots the place will draw, the draws undone
        for _, rotation, release, outside, over in self._shelf_ways(name, node, places, grip, held, rng):
            up = np.array([0.0, 0.0, over])
            if next(self._plan_for([outside + up, release + up, release], rotation, q, held, ease=False), None):
                return True
        return False

    def _shelf_ways(self, name: str, node: str, places: list[int], grip: np.ndarray, held: Held,
                    rng: np.random.Generator | None = None) -> list[tuple]:
        """The ways into the shelves `places` of cabinet `node` for `name`, held as `held` at grip rotation `grip`
        (shape (3, 3)): (spot, m; the grip rotation it goes in at, `_into_shelf`; the grip site at the release,
        m; out of the front at that height, m; the height above the release it goes in at, m), a free spot each
        (drawn with `rng`, default the skill's), nearest the front first, then those of each shelf none of those
        is on."""
        size = np.asarray(self.world.object_class(name).size)
        furniture = self.navigator.furniture[node]
        out = self.navigator.front_normal(node)
        front = np.array(furniture.pos) + out * furniture.size[1] / 2
        drawn = sorted(((spot, k) for k in places for spot in self._free_spots(name, node, k, rng)),
                       key=lambda pair: float(np.dot(front - pair[0].pos[:2], out)))
        spots = _spread([spot for spot, _ in drawn], SHELF_SPOT_GAP, SHELF_SPOTS)
        on = {id(spot): k for spot, k in drawn}
        missed = [k for k in places if all(on[id(spot)] != k for spot in spots)]  # shelves (racks) under the others'
        spots += [spot for k in missed for spot in _spread([s for s, at in drawn if at == k], SHELF_SPOT_GAP,
                                                           SHELF_SPOTS // 2)]
        rotation = self._into_shelf(out, grip)
        pull = np.array([out[0], out[1], 0.0])
        clear_out = np.linalg.norm(size) / 2 + ENTRY_OUT  # the object's centre this far out of the front: all out
        ways = []
        for spot in spots:
            release = np.array(spot.pos) + np.array([0.0, 0.0, 0.01]) - rotation @ held.position
            outside = release + (float(np.dot(front - release[:2], out)) + clear_out) * pull
            over = max(SIDE_LIFT, rise_to_pass(self.world, name, np.array(spot.pos), out,
                                               float(np.dot(front - np.array(spot.pos[:2]), out))))
            ways.append((np.array(spot.pos), rotation, release, outside, over))
        return ways

    def _go_in(self, name: str, node: str, spot: np.ndarray, rotation: np.ndarray, held: Held,
               planned: tuple[tuple, list[np.ndarray]], release: np.ndarray, outside: np.ndarray,
               over: float = SIDE_LIFT) -> SkillResult:
        """Carry `held` (`name`) into cabinet `node` along `planned` (from `_drive_for`) and let it go on the
        shelf at `spot` (m): eased in `over` m above the shelf, aimed again where it turned in the fingers on the
        way (the grip site at `release`, m, as planned, at `rotation`), down, released and drawn out to `outside`
        (m), straight, or, where it went in higher than SIDE_LIFT (over what stands in front), up that high
        first."""
        quat, up = matrix_to_quat(rotation), np.array([0.0, 0.0, 1.0])
        ease, path_in = planned
        self._ease_to(ease, path_in[0])
        if self.arm.hand_empty():
            self.arm.held = None
            self.arm.retract()
            return SkillResult(False, f"place: {name} fell out of the hand on the way into {node}")
        now = self.arm.held_object(name)  # the object may have turned in the fingers on the way: aim it again
        again = spot + np.array([0.0, 0.0, 0.01]) - rotation @ now.position
        entry = outside + over * up
        replanned = self.arm.checked_line(self.controller.target, [entry, again + over * up, again], quat, now)
        slip = float(np.linalg.norm(now.position - held.position))
        if replanned is not None:
            path_in, release = [self.controller.target.copy(), *replanned], again
        elif slip > CARRY_SLIP:  # still held, but no longer as planned: the caller puts it down elsewhere
            return SkillResult(False, f"place: {name} slipped {slip * 100:.1f} cm in the hand on the way into "
                                      f"{node} and no longer goes in clear")
        self.controller.move_through(path_in[1:])
        self.controller.settle(0.003)
        away = self._out_of_shelf(release, outside, quat, over)
        return self._let_go(name, node, self._held_opening() + RELEASE_OPENING, away, inside=True)

    def _out_of_shelf(self, release: np.ndarray, outside: np.ndarray, quat: np.ndarray, over: float = SIDE_LIFT
                      ) -> list[np.ndarray] | None:
        """Configurations that draw the open hand from `release` (m) straight out to `outside` (m) at `quat`: first
        up `over` m where it went in higher than SIDE_LIFT (over what stands in front; None if it cannot rise), else
        a hand pointing down first rises SIDE_LIFT m, as it came in, and goes out at that height (drawn out level at
        once, its fingertips, still beside the object, dragged a pair of socks back out of the washing machine's
        drum). Each line keeps the base where it stands if the arm alone reaches it, else the base backs away
        with the hand (a hand that let a wine glass go on a cupboard's upper shelf was too close to the base to be
        drawn back by the arm alone; the tuck from in there swept the glass out onto the floor)."""
        def line(start: np.ndarray, end: np.ndarray, seed: np.ndarray | None = None) -> list[np.ndarray] | None:
            return (self.arm.line(start, end, quat, loose_end=True, seed=seed)
                    or self.arm.line(start, end, quat, base_cost=PULL_BASE_COST, loose_end=True, seed=seed))

        x = self.world.data.site("robot/grip").xmat.reshape(3, 3)[:, 0]
        if over <= SIDE_LIFT and np.linalg.norm(x[:2]) > PITCHED_HAND:
            return line(release, outside)
        lift = np.array([0.0, 0.0, max(over, SIDE_LIFT)])
        up = line(release, release + lift)
        if up is None:
            return None if over > SIDE_LIFT else line(release, outside)
        out = line(release + lift, outside + lift, seed=up[-1])
        return up + out if out is not None else up

    def _into_shelf(self, out: np.ndarray, grip: np.ndarray) -> np.ndarray:
        """The grip rotation (shape (3, 3)) that carries the held object into a shelf whose front faces `out`
        (shape (2,)): `grip` (the hand's, shape (3, 3)) turned about the vertical; a hand held level or pitched
        then points into the shelf (a pitched hand leaning aside meets the shelf's side wall), one pointing down
        keeps its turn relative to the base, the base facing the shelf."""
        pitched = np.linalg.norm(grip[:2, 0]) > PITCHED_HAND
        turn = math.atan2(-out[1], -out[0]) - (math.atan2(grip[1, 0], grip[0, 0]) if pitched else
                                               self.controller.target[2])
        return yaw_matrix(turn) @ grip

    def _ease_path(self, q_from: np.ndarray, q_to: np.ndarray, held: Held
                   ) -> tuple[list[np.ndarray], list[np.ndarray]] | None:
        """The way of a held object from configuration q_from to q_to (shape (13,)): (along a straight grip line as
        far as it is reachable; the configurations between there and q_to of a clear joint-space way,
        `Arm.swing_way`), each configuration shape (13,); None if the line touches anything or no clear swing is
        found."""
        lead = self.arm.hand_line(*self.ik.grip_pose(q_to), ARC_BASE_COST, partial=True, seed=q_from) or []
        if not all(self.clearance.clear(q, held=held) for q in lead):
            return None
        via = self.arm.swing_way(lead[-1] if lead else q_from, q_to, held)
        return None if via is None else (lead, via)

    def _ease_to(self, ease: tuple[list[np.ndarray], list[np.ndarray]], q: np.ndarray) -> None:
        """Move a held object along `ease` (from `_ease_path`): its line, then through its swing to configuration
        q (shape (13,)) in joint space, slowly (a quick swing turns a long object held by one end in the
        fingers)."""
        lead, via = ease
        if lead:
            self.controller.move_through(lead)
        legs = zip([self.controller.target, *via], [*via, q], strict=True)
        self.controller.move_through([*via, q], duration=EASE_SLOWDOWN * sum(self.controller.duration(a, b)
                                                                             for a, b in legs))
        self.controller.settle(0.003)

    def _drive_for(self, points: list[np.ndarray], rotation: np.ndarray, posture: np.ndarray, held: Held,
                   margin: float = 0.0) -> tuple[tuple, list[np.ndarray]] | None:
        """Drive, holding `held` in `posture` (shape (13,)), to a free base pose from which the held object eases
        from `posture` onto the first of `points` (m, each shape (3,)) and the grip site follows them at `rotation`
        (shape (3, 3)), the object clear of the apartment all the way and the arm `margin` m off it (`_plan_for`);
        returns (the ease, see `_ease_path`; the configurations along `points`), each configuration shape (13,),
        or None (the robot stays)."""
        for base, ease, path in self._plan_for(points, rotation, posture, held, margin):
            try:
                self.navigator.drive_to(base, posture, self.arm.held_reach(), **CARRY_MOTION,
                                        clear=self.arm.carry_clear())
            except NavigationError:
                continue
            for q_in in [*ease[0], *ease[1], *path]:
                q_in[:3] = self.controller.target[:3]  # where the base really stopped
            return ease, path
        return None

    def _plan_for(self, points: list[np.ndarray], rotation: np.ndarray, posture: np.ndarray, held: Held,
                  margin: float = 0.0, ease: bool = True):
        """The plans of `_drive_for`, one per free base pose that gives one, lazily: (the base pose; the ease from
        `posture`, `_ease_path`, or none without `ease`; the configurations along `points`, each shape (13,))."""
        quat = matrix_to_quat(rotation)
        obstacles = self.navigator.obstacles()
        free = self.navigator.radius + CLEARANCE
        for base in base_candidates(points[-1], rotation, self.controller.q()[:2]):
            if not self.navigator.plan.disk_is_free(base[0], base[1], free, obstacles):
                continue
            q = posture.copy()
            q[:3] = base
            with self.clearance.keeping(margin):
                start = self.ik.solve(q, points[0], quat, base_cost=ARC_BASE_COST)
                if not start.converged or not self.clearance.clear(start.q, held=held):
                    continue
                path = self.arm.checked_line(start.q, points, quat, held)
                if path is None:
                    continue
                lead = self._ease_path(q, start.q, held) if ease else ([], [])
            if lead is not None:
                yield base, lead, [start.q, *path]


def _spread(spots: list, gap: float, limit: int) -> list:
    """Up to `limit` of `spots` (in their order), each at least `gap` m from the ones kept before it."""
    kept = []
    for spot in spots:
        if all(math.dist(spot.pos[:2], other.pos[:2]) >= gap for other in kept):
            kept.append(spot)
            if len(kept) == limit:
                break
    return kept
