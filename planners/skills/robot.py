"""Robot skills in physics: pick and place, doors and drawers, checked on the observed scene graph.

Objects move only because the fingers hold them (no weld, no teleport). Each skill returns a `SkillResult`
with success or a clear failure reason; a failed grasp is retried from the next grasp candidate.

`Robot` builds the parts and hands each skill only what it uses: the IK, the controller, the navigator and the
clearance check make the `Arm` (`planners.motion.arm`, the movement primitives and what the hand holds); `Pick`
(`planners.skills.pick`) and `Place` (`planners.skills.place`) take the arm, the scene-graph observer and the
furniture's places; doors and drawers are run by a `PartMover` (`planners.skills.doors`) on the arm.
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from homer_sim.graph import INSIDE, ON
from homer_sim.home.spots import Spots
from homer_sim.observe import SceneGraphObserver
from homer_sim.robot_spec import ROBOT, RobotSpec
from planners.motion.arm import PITCHED_HAND, Arm
from planners.motion.clearance import ClearanceCheck
from planners.motion.control import Controller
from planners.motion.ik import IKSolver
from planners.motion.navigation import Navigator
from planners.skills.doors import PartMover
from planners.skills.parts import covered_places, rim_above, shelves_inside
from planners.skills.pick import Pick
from planners.skills.place import Place
from planners.skills.result import SkillResult

BASIN_RIM = 0.08  # m a rim in front may rise above a place before it is a basin, entered only from above (a
# shower's 6 cm curb is not one, a sink's 14 cm rim is)
CROWDED = 0.5  # m farther an open top counts, for a set-down, per thing on or in it (the crowded counter by the
# coffee maker was nearest, and a pill bottle stood up there knocked the knife block and the loaf)


class Robot:
    """The robot in a World: IK, control, navigation, scene-graph checks, and the skills built on them."""

    def __init__(self, world, rng: np.random.Generator | None = None, robot: RobotSpec = ROBOT) -> None:
        self.world = world
        self.spec = robot
        self.ik = IKSolver(robot=robot)
        self.controller = Controller(world, robot=robot)
        self.navigator = Navigator(world, self.controller, robot)
        self.spots = Spots(world)
        self.observer = SceneGraphObserver(world)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.clearance = ClearanceCheck(world, self.controller)
        self.arm = Arm(world, self.ik, self.controller, self.navigator, self.clearance)
        self._place = Place(self.arm, self.observer, self.spots, self.rng)
        self._pick = Pick(self.arm, self.observer, self.spots, self._place.takes)

    @property
    def held(self) -> str | None:
        """The name of the object in the hand, or None."""
        return self.arm.held

    @property
    def tuck(self) -> np.ndarray:
        """The tuck posture (shape (13,)) of the robot-only model, at its base pose."""
        return self.arm.tuck

    def pick(self, name: str, node: str | None = None, into: str | None = None) -> SkillResult:
        """Grasp object `name` and lift it (see `planners.skills.pick.Pick.pick`). One that has fallen over (or
        that a grasp knocks over) is taken from above as it lies; where it goes next (`into`) onto a shelf, which
        takes it upright and held from the side, it is first stood up on the nearest open top without a door
        (`set_down` stands it up as it lowers it) and picked again; so is one held from the side that goes into a
        basin (`_into_basin`), picked again from above."""
        fallen = self.arm.fallen_over(name)
        result = self._pick.pick(name, node, into)
        if not result.success and not fallen and self.held is None and self.arm.fallen_over(name):
            fallen = True  # knocked over by a grasp: picked again as it lies now
            at = self.observer.update().anchor_of(name, self.world.object_names)
            again = self._pick.pick(name, at if at in self.navigator.furniture else None, into)
            result = again if again.success else SkillResult(False, f"{result.reason}; then {again.reason}")
        if not result.success or into is None:
            return result
        if fallen and shelves_inside(self.spots, self.navigator.furniture.get(into), into, None):
            how = "picked as it lay"
        elif self._into_basin(into) and np.linalg.norm(self.world.data.site("robot/grip").xmat[[0, 3]]) > \
                PITCHED_HAND:  # the grip x axis's horizontal part: not from above
            how = "held from the side"
        else:
            return result
        stood = self.set_down({a.furniture for a in self.world.articulations.values()})
        if not stood.success:
            return SkillResult(False, f"{name}: {how}, then {stood.reason}")
        at = self.observer.update().anchor_of(name, self.world.object_names)
        return self._pick.pick(name, at if at in self.navigator.furniture else None, into)

    def _into_basin(self, node: str) -> bool:
        """Whether `node` is used inside a place sunk more than BASIN_RIM m below a rim in front of it, open
        above (a sink's basin): a hand held level lowering something in there meets the rim with its wrist (a
        can of wipes from a cabinet's shelf stopped 15-17 cm above the basin), one from above does not."""
        furniture = self.spots.furniture.get(node)
        if furniture is None or shelves_inside(self.spots, self.navigator.furniture.get(node), node, None):
            return False
        return any(place.relation == INSIDE and place.part is None and rim_above(furniture, place) > BASIN_RIM
                   for _, place in self.spots.places_of(node, None))

    def place(self, node: str, relation: int | None = None) -> SkillResult:
        """Put the held object at a free spot ON or INSIDE furniture `node`, release it and retreat (see
        `planners.skills.place.Place.place`). Where a shelf inside `node` (or a level under another,
        `covered_places`) took nothing from a hand pointing down (the wrist meets the shelf above: a pill bottle
        picked from above off a crowded counter, a spoon off the table), the object is set down on the nearest
        open top without a door, picked again as a shelf takes it (`pick` with `into`: from the side or pitched,
        where a grasp fits there) and placed once more."""
        result = self._place.place(node, relation)
        name = self.held
        if (result.success or name is None or np.linalg.norm(self.world.data.site("robot/grip").xmat[[0, 3]])
                > PITCHED_HAND or not (shelves_inside(self.spots, self.navigator.furniture.get(node), node, relation)
                                       or covered_places(self.spots, node, relation))):
            return result
        stood = self.set_down({a.furniture for a in self.world.articulations.values()})
        if not stood.success:
            return SkillResult(False, f"{result.reason}; then {stood.reason}")
        at = self.observer.update().anchor_of(name, self.world.object_names)
        again = self._pick.pick(name, at if at in self.navigator.furniture else None, node)
        if not again.success:
            return SkillResult(False, f"{result.reason}; set down, then pick: {again.reason}")
        return self._place.place(node, relation)

    def set_down(self, avoid: Collection[str] = (), tries: int = 3) -> SkillResult:
        """Put the held object down for a while on the open top nearest the robot (furniture with a place ON it,
        not in `avoid`, say furniture with doors; each thing on or in one counts CROWDED m farther), the `tries`
        nearest in turn: done when it stands on the top or on what lies there, the hand empty."""
        name = self.held
        if name is None:
            return SkillResult(False, "set-down: the robot holds nothing")
        x, y = self.controller.q()[:2]
        graph = self.observer.update()
        things = [graph.anchor_of(n, self.world.object_names) for n in self.world.object_names if n != name]
        tops = sorted((float(np.hypot(f.pos[0] - x, f.pos[1] - y)) + CROWDED * things.count(f.name), f.name)
                      for f in self.world.layout.furniture
                      if f.name not in avoid and f.name in self.navigator.furniture
                      and self.spots.places_of(f.name, ON))
        result = SkillResult(False, f"set-down: no open top for {name}")
        for _, top in tops[:tries]:
            result = self.place(top, ON)
            if result.success or self.held is None:
                break
        on = self.observer.update().parent_of(name)
        while on in self.world.object_names:  # on what lies on the top
            on = self.observer.update().parent_of(on)
        if self.held is None and on in self.navigator.furniture and on not in avoid and not self.arm.fallen_over(name):
            return SkillResult(True)
        return SkillResult(False, f"set-down: {result.reason.removeprefix('place: ').removeprefix('set-down: ')}")

    def retract(self) -> None:
        """Tuck the arm in place (see `planners.motion.arm.Arm.retract`)."""
        self.arm.retract()

    def tucked(self) -> np.ndarray:
        """The tuck posture at the current base pose and torso height (see `planners.motion.arm.Arm.tucked`)."""
        return self.arm.tucked()

    def raised(self, torso: float) -> np.ndarray:
        """The tuck posture with the upper arm raised and the torso at `torso` m (see `Arm.raised`)."""
        return self.arm.raised(torso)

    # --- doors and drawers ---------------------------------------------------------------------------------
    def open_articulation(self, name: str) -> SkillResult:
        """Open door or drawer `name` (`<furniture>/<part>`, or a furniture with one part) above openness 0.9,
        by holding its handle (and a door's free edge past the handle's reach); the arm ends tucked."""
        if self.held is not None:
            return SkillResult(False, f"open {name}: the hand holds {self.held}")
        return SkillResult(*PartMover(self.arm).move_to(name, opening=True))

    def close_articulation(self, name: str) -> SkillResult:
        """Close door or drawer `name` below openness 0.05 (see `open_articulation`)."""
        if self.held is not None:
            return SkillResult(False, f"close {name}: the hand holds {self.held}")
        return SkillResult(*PartMover(self.arm).move_to(name, opening=False))


__all__ = ["Robot", "SkillResult"]
