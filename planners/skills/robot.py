"""Robot skills in physics: pick and place, checked on the observed scene graph.

Objects move only because the fingers hold them (no weld, no teleport). Each skill returns a `SkillResult`
with success or a clear failure reason; a failed grasp is retried from the next grasp candidate.

`Robot` owns the state (world, IK, control, navigation, scene-graph observer) and mixes in the skills, one
module each: movement in `planners.motion.arm`, `pick` in `planners.skills.pick`, `place` in
`planners.skills.place`; doors and drawers are run by `planners.skills.doors`.
"""

from __future__ import annotations

import numpy as np

from homer_sim.home.spots import Spots
from homer_sim.observe import SceneGraphObserver
from homer_sim.robot_spec import ROBOT, RobotSpec
from planners.motion.arm import Motion, SkillResult
from planners.motion.clearance import ClearanceCheck
from planners.motion.control import Controller
from planners.motion.ik import IKSolver
from planners.motion.navigation import Navigator
from planners.skills.doors import PartMover
from planners.skills.pick import Pick
from planners.skills.place import Place


class Robot(Motion, Pick, Place):
    """The robot in a World: IK, control, navigation, scene-graph checks, and the skills built on them."""

    def __init__(self, world, rng: np.random.Generator | None = None, robot: RobotSpec = ROBOT) -> None:
        self.world = world
        self.ik = IKSolver(robot=robot)
        self.controller = Controller(world, robot=robot)
        self.navigator = Navigator(world, self.controller, robot)
        self.spots = Spots(world)
        self.observer = SceneGraphObserver(world)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.tuck = self.ik.model.key("home").qpos.copy()
        self.held: str | None = None
        self.folded = True  # the arm is in (or moving from) the tuck posture
        self.shoulder_lift = self.ik.model.joint("shoulder_lift").qposadr[0]
        self.clearance = ClearanceCheck(world, self.controller)

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


__all__ = ["Robot", "SkillResult"]
