"""The robot described once: the compiled robot agrees with its `RobotSpec`, and a spec it disagrees with is
refused where the model is built."""

from __future__ import annotations

from dataclasses import replace

import pytest

from homer_sim.errors import HomerError
from homer_sim.home.apartment import default_layout
from homer_sim.home.validate import validate_layout
from homer_sim.robot_spec import ROBOT, RobotSpec
from homer_sim.world import World
from planners.grasps.candidate import GRIPPER_OPEN, MAX_WIDTH, PAD_HALF, ungraspable_reason
from planners.motion.ik import IKError, IKSolver, robot_model
from planners.robot import PREFIX, add_robot, spec_mismatches


def test_the_compiled_robot_agrees_with_its_spec() -> None:
    assert spec_mismatches(robot_model()) == []
    assert spec_mismatches(World(extras=[add_robot]).model, prefix=PREFIX) == []


def test_a_spec_the_robot_file_disagrees_with_is_named_and_refused() -> None:
    wide = replace(ROBOT, finger_stroke=0.1, pad_friction=1.0)
    wrong = spec_mismatches(IKSolver().model, wide)
    assert [w.split(":")[0] for w in wrong] == ["finger_stroke", "pad_friction"]
    assert "the model has 0.08, the spec 0.1" in wrong[0]
    with pytest.raises(IKError, match="finger_stroke"):
        IKSolver(robot=wide)


def test_grasp_generation_and_the_validator_take_the_spec() -> None:
    assert (MAX_WIDTH, GRIPPER_OPEN, PAD_HALF) == (ROBOT.max_grasp_width, ROBOT.finger_stroke, ROBOT.pad_half_length)
    from homer_sim.home.catalog import CATALOG

    assert ungraspable_reason(CATALOG["food_cereal"]) is None
    narrow = replace(ROBOT, max_grasp_width=0.05)
    assert "wider than the 5 cm grasp" in ungraspable_reason(CATALOG["food_cereal"], narrow)
    validate_layout(default_layout())
    with pytest.raises(HomerError, match="out of the robot's reach"):
        validate_layout(default_layout(), replace(ROBOT, place_heights=(0.3, 1.2)))
    with pytest.raises(HomerError, match="narrower than the robot's 1.5 m"):
        validate_layout(default_layout(), replace(ROBOT, min_doorway=1.5))


def test_a_spec_out_of_its_own_bounds_is_refused() -> None:
    with pytest.raises(HomerError, match="max_grasp_width 0.2 m"):
        RobotSpec(max_grasp_width=0.2)
    with pytest.raises(HomerError, match="'elbow' is not a body joint"):
        ROBOT.joint_speed("elbow")
