"""The robot model, its place in the apartment, IK convergence and joint-space control."""

from __future__ import annotations

import math

import mink
import mujoco
import numpy as np
import pytest

from homer_sim.robot_spec import ROBOT
from homer_sim.world import World
from planners.motion.control import Controller, cruise
from planners.motion.ik import IKError, IKSolver
from planners.robot import DEFAULT_POSE, PAD_GEOMS, ROBOT_XML, add_robot, robot_at

DOWN = np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0])  # wxyz: grip x axis pointing down
FORWARD = np.array([1.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def solver() -> IKSolver:
    return IKSolver()


@pytest.fixture(scope="module")
def world() -> World:
    return World(extras=[add_robot])


def test_robot_file_has_classes_keyframe_coupled_force_limited_fingers() -> None:
    model = mujoco.MjModel.from_xml_path(str(ROBOT_XML))
    visual = [g for g in range(model.ngeom) if model.geom_group[g] == 2]
    assert visual and all(model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0 for g in visual)
    for pad in PAD_GEOMS:
        geom = model.geom(pad)
        assert geom.condim[0] >= 4 and geom.friction[0] >= 1.5
    assert model.key("home").id == 0
    assert model.eq("finger_coupling").type[0] == mujoco.mjtEq.mjEQ_JOINT
    gripper = model.actuator("gripper")
    assert model.actuator_forcelimited[gripper.id] and 0 < gripper.forcerange[1] <= 100.0
    torso = model.joint("torso_lift")
    assert torso.range[1] == pytest.approx(0.386)
    assert 90.0 < model.body_subtreemass[model.body("base").id] < 130.0  # Fetch: 113 kg


def test_robot_starts_clear_of_the_apartment_and_holds_still(world: World) -> None:
    model, data = world.model, world.data
    world.reset()
    robot = {g for g in range(model.ngeom) if model.body(model.geom_bodyid[g]).name.startswith("robot/")}
    touching = [(model.geom(c.geom1).name, model.geom(c.geom2).name) for c in data.contact[: data.ncon]
                if c.geom1 in robot or c.geom2 in robot]
    assert touching == []
    objects = world.object_positions()
    world.step(2500)  # 5 s
    assert world.warnings() == 0 and not world.has_nan()
    base = data.body("robot/base").xpos
    assert np.allclose(base[:2], DEFAULT_POSE[:2], atol=1e-3)
    assert np.abs(world.object_positions() - objects).max() < 0.01


def test_base_joints_read_world_coordinates() -> None:
    pose = (1.5, 1.5, math.pi / 2)
    world = World(extras=[robot_at(pose)])
    controller = Controller(world)
    assert np.allclose(controller.q()[:3], pose)
    assert np.allclose(world.data.body("robot/base").xpos[:2], pose[:2])
    controller.command(np.array([1.8, 1.6, math.pi / 2 + 0.3, *controller.q()[3:11]]))
    world.step(1500)
    assert np.allclose(controller.q()[:3], [1.8, 1.6, math.pi / 2 + 0.3], atol=2e-3)
    assert np.allclose(world.data.body("robot/base").xpos[:2], [1.8, 1.6], atol=2e-3)


@pytest.mark.parametrize(("target", "quat"), [((0.7, 0.0, 0.9), DOWN), ((0.8, 0.0, 1.1), FORWARD),
                                              ((0.6, -0.2, 0.5), FORWARD), ((0.7, 0.1, 0.2), DOWN)])
def test_ik_converges_to_reachable_targets(solver: IKSolver, target, quat) -> None:
    q0 = solver.model.key("home").qpos.copy()
    result = solver.solve(q0, np.array(target), quat, base_cost=100.0)
    assert result.converged, result.reason
    assert result.position_error < 0.005 and result.orientation_error < np.deg2rad(2.0)
    assert result.iterations < 150
    assert result.errors[-1] < 0.1 * result.errors[0] or result.errors[0] < 0.01
    position, _ = solver.grip_pose(result.q)
    assert np.linalg.norm(position - target) < 0.005
    lo, hi = solver.model.jnt_range[3:11].T
    assert np.all(result.q[3:11] >= lo - 1e-6) and np.all(result.q[3:11] <= hi + 1e-6)


def test_ik_error_falls_from_a_nearby_start(solver: IKSolver) -> None:
    q0 = solver.model.key("home").qpos.copy()
    start = solver.solve(q0, np.array([0.7, 0.0, 0.9]), DOWN, base_cost=100.0).q
    result = solver.solve(start, np.array([0.75, 0.05, 0.85]), DOWN, base_cost=100.0, seeds=False)
    assert result.converged and result.iterations < 20
    assert np.all(np.diff(result.errors) <= 1e-4)  # falls at every step


def test_ik_reports_unreachable_targets(solver: IKSolver) -> None:
    q0 = solver.model.key("home").qpos.copy()
    result = solver.solve(q0, np.array([2.5, 0.0, 0.9]), DOWN, base_cost=1e4)
    assert not result.converged
    assert "unreachable" in result.reason and "2.5" in result.reason
    assert result.position_error > 0.5
    assert np.all(np.abs(result.q[:2]) < 0.1)  # the base stays put while grasping
    with pytest.raises(IKError, match="unit wxyz"):
        solver.solve(q0, np.array([0.5, 0.0, 0.9]), np.array([1.0, 1.0, 0.0, 0.0]))


def test_controller_tracks_ik_targets_in_physics(world: World, solver: IKSolver) -> None:
    world.reset()
    controller = Controller(world)
    home = solver.model.key("home").qpos.copy()
    home[:3] = controller.q()[:3]
    controller.move_through([home])
    target = np.array([DEFAULT_POSE[0] + 0.7, DEFAULT_POSE[1], 0.9])
    result = solver.solve(controller.q(), target, DOWN, base_cost=100.0)
    assert result.converged, result.reason
    controller.move_through([result.q])
    controller.settle(0.002)
    assert np.linalg.norm(world.data.site("robot/grip").xpos - target) < 0.005
    assert world.warnings() == 0


def test_cruise_scaling_reaches_its_peak_speed_smoothly_and_ends_at_rest() -> None:
    duration, ramp = 5.0, 1.0
    t = np.linspace(0.0, duration, 5001)
    s = np.array([cruise(x, duration, ramp) for x in t])
    speed = np.diff(s) / np.diff(t)
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0) and np.all(np.diff(s) > 0.0)
    assert speed.max() == pytest.approx(1.0 / (duration - ramp), rel=1e-3)  # the cruise: 1 over duration - ramp
    assert speed[0] < 1e-3 and speed[-1] < 1e-3  # at rest at both ends
    assert np.abs(np.diff(speed)).max() < 1e-3  # no jump in speed: the ramps are smooth
    middle = (t > ramp) & (t < duration - ramp)
    assert np.allclose(speed[middle[1:]], 1.0 / (duration - ramp))


def test_ik_step_is_mink_solve_ik_bit_for_bit(solver: IKSolver) -> None:
    """The direct DAQP call and the cached velocity limit give exactly mink.solve_ik's velocity."""
    rng = np.random.default_rng(0)
    home = solver.model.key("home").qpos.copy()
    solver.frame_task.set_target(mink.SE3.from_rotation_and_translation(mink.SO3(DOWN), np.array([0.7, 0.1, 0.8])))
    limits = [solver.limits[0], mink.VelocityLimit(solver.model, dict(ROBOT.joint_speeds)), solver.limits[2]]
    for _ in range(20):
        q = np.clip(home + rng.uniform(-0.3, 0.3, size=home.shape), limits[0].lower + 1e-3, limits[0].upper - 1e-3)
        solver.configuration.update(q)
        solver.posture_task.set_target(home)
        tasks = [solver.frame_task, solver.posture_task, solver._damping_task(10.0)]
        expected = mink.solve_ik(solver.configuration, tasks, solver.dt, "daqp", damping=1e-3, limits=limits)
        assert np.array_equal(solver._velocity(tasks), expected)
