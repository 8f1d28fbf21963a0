"""Opening and closing doors and drawers by holding them, checked on the simulated joints."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from homer_sim.home.apartment import default_layout
from homer_sim.home.furniture import furniture_geometry
from homer_sim.world import World
from planners.grasps.geometry import matrix_to_quat
from planners.motion.clearance import ClearanceCheck, Held
from planners.motion.control import Controller
from planners.robot import add_robot
from planners.skills import Robot
from planners.skills.parts import PartMotion, drawer_rim, edge_grasp, handle_grasp


def _drift(world: World, before: np.ndarray, skip: tuple[str, ...] = ()) -> tuple[float, str]:
    drift = np.linalg.norm(world.object_positions() - before, axis=1)
    for name in skip:
        drift[world.object_index(name)] = 0.0
    k = int(np.argmax(drift))
    return float(drift[k]), world.object_names[k]


def test_matrix_to_quat_matches_mujoco_including_half_turns() -> None:
    rng = np.random.default_rng(0)
    for k in range(300):
        quat = rng.normal(size=4)
        if k % 2:
            quat[0] = 0.0  # half turns: the case a sign-from-trace formula gets wrong
        quat /= np.linalg.norm(quat)
        matrix = np.zeros(9)
        mujoco.mju_quat2Mat(matrix, quat)
        assert abs(np.dot(matrix_to_quat(matrix.reshape(3, 3)), quat)) == pytest.approx(1.0, abs=1e-9)


def test_door_grasps_follow_the_hinge_arc() -> None:
    world = World(extras=[add_robot])
    motion = PartMotion(world, "fridge/door")
    handle = handle_grasp(motion.handle_local, "hinge")
    site = world.data.site("fridge/door/handle").xpos
    pos0, _ = motion.grip_target(handle, 0.0)
    assert np.linalg.norm(pos0 - site) < 0.005  # the grip sits on the bar
    anchor, axis = motion.anchor, motion.axis
    for angle in (0.5, 1.0, 1.5):
        pos, _ = motion.grip_target(handle, angle)
        radial0, radial = pos0 - anchor, pos - anchor
        assert np.linalg.norm(radial) == pytest.approx(np.linalg.norm(radial0), abs=1e-9)  # on the arc
        assert np.dot(radial, axis) == pytest.approx(np.dot(radial0, axis), abs=1e-9)
        flat0, flat = radial0 - np.dot(radial0, axis) * axis, radial - np.dot(radial, axis) * axis
        turned = np.arctan2(np.dot(np.cross(flat0, flat), axis), np.dot(flat0, flat))
        assert turned == pytest.approx(angle, abs=1e-9)
    edge = edge_grasp(motion.handle_local, -0.7)
    assert edge.position[1] == pytest.approx(-0.7 + 0.025)


@pytest.mark.parametrize("name", ["fridge/door", "dresser/drawer_2"])
def test_robot_opens_and_closes_by_holding_the_part(name: str) -> None:
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world)
    robot.observer.observe_all()
    before = world.object_positions()
    # the drawer's contents ride along with it (dresser level k is drawer_k)
    riders = tuple(o.name for o in world.layout.objects if name == f"{o.parent}/drawer_{o.level}")

    opened = robot.open_articulation(name)
    assert opened.success, opened.reason
    assert world.openness(name) > 0.9
    drift, moved = _drift(world, before, riders)
    assert drift < 0.02, f"{moved} moved {drift * 100:.1f} cm"

    closed = robot.close_articulation(name)
    assert closed.success, closed.reason
    assert world.openness(name) < 0.05
    drift, moved = _drift(world, before)
    assert drift < 0.02, f"{moved} moved {drift * 100:.1f} cm"
    assert world.warnings() == 0 and not world.has_nan()


def test_clearance_check_on_the_filtered_model_agrees_with_a_full_collision() -> None:
    """Random robot configurations, some with a door moved or the bowl in the hand: the check on the robot-only
    collision filter answers as mj_collision over every geom of the apartment does."""
    world = World(extras=[add_robot])
    check = ClearanceCheck(world, Controller(world))
    model, full = world.model, mujoco.MjData(world.model)
    bowl = world.object_body_ids[world.object_index("bowl")]
    bowl_geoms = frozenset(np.flatnonzero(model.geom_bodyid == bowl).tolist())
    bowl_adr = int(world.object_qpos_adr[world.object_index("bowl")])
    door = world.articulation("fridge/door")
    rng = np.random.default_rng(3)
    q0, answers = world.data.qpos[check.qpos_adr].copy(), []
    for k in range(150):
        q = q0.copy()
        q[:3] = rng.uniform([0.5, 0.5, -3.0], [8.0, 6.0, 3.0])
        q[3:11] = rng.uniform(-1.5, 1.5, size=8)
        held = Held(bowl_geoms, bowl_adr, rng.uniform(-0.6, 0.6, size=3), np.eye(3))  # often in furniture or floor
        art, value, hand = (door, 1.0, None) if k % 3 == 0 else (None, 0.0, held if k % 2 else None)
        answer = check.clear(q, art, value, held=hand)
        full.qpos[:] = check.scratch.qpos  # the configuration the check just tested, held object included
        mujoco.mj_fwdPosition(model, full)
        own = np.isin(np.arange(model.ngeom), list(hand.geoms) if hand else [])
        robot = check.robot | own
        checked = robot if hand else check.checked
        touching = [c for c in full.contact[: full.ncon] if checked[c.geom1] != checked[c.geom2]
                    and not (robot[c.geom1] and robot[c.geom2])
                    or (own[c.geom1] and check.base[c.geom2]) or (own[c.geom2] and check.base[c.geom1])]
        assert answer == (not touching), f"configuration {k}: {q.round(3).tolist()}"
        answers.append(answer)
    assert 0.2 < np.mean(answers) < 0.8  # both answers were exercised


def test_a_held_object_against_the_robots_own_base_is_not_clear() -> None:
    """The object in the hand may touch the hand that holds it, never the robot's base: a radio lowered to the
    floor in front of the base met it on the way down, slid 4 cm in the fingers and came down on a shelf's plinth."""
    world = World(extras=[add_robot])
    check = ClearanceCheck(world, Controller(world))
    model, data = world.model, world.data
    mujoco.mj_forward(model, data)
    q = data.qpos[check.qpos_adr].copy()
    radio = world.object_body_ids[world.object_index("radio")]
    geoms = frozenset(np.flatnonzero(model.geom_bodyid == radio).tolist())
    adr = int(world.object_qpos_adr[world.object_index("radio")])
    grip = data.site("robot/grip")
    rotation = grip.xmat.reshape(3, 3)
    base = data.xpos[model.body("robot/base").id]
    assert check.clear(q, held=Held(geoms, adr, np.zeros(3), np.eye(3)))  # in the hand, over the base: clear
    in_base = Held(geoms, adr, rotation.T @ (base + np.array([0.0, 0.0, 0.15]) - grip.xpos), np.eye(3))
    assert not check.clear(q, held=in_base)


def test_drawer_rim_is_the_front_top_of_the_drawer_holding_a_point() -> None:
    world = World()
    shirt = world.object_pose("clothes_shirt")[0]  # in the dresser's bottom drawer
    front = world.model.geom("dresser/drawer_0/front").id
    top = world.data.geom_xpos[front][2] + world.model.geom_size[front][2]
    rim = drawer_rim(world, "dresser", shirt)
    assert rim == pytest.approx(top) and rim - (shirt[2] - 0.02) > 0.2  # a 15 cm lift would not clear it
    world.set_openness("dresser/drawer_0", 0.96)  # the drawer carries the point's drawer along: still found
    moved = shirt + 0.96 * 0.75 * 0.5 * world.data.xaxis[world.articulation("dresser/drawer_0").joint_id]
    assert drawer_rim(world, "dresser", moved) == pytest.approx(top)
    above = world.model.geom("dresser/drawer_1/front").id  # the next drawer up holds a point higher up
    assert drawer_rim(world, "dresser", shirt + np.array([0.0, 0.0, 0.3])) == pytest.approx(
        world.data.geom_xpos[above][2] + world.model.geom_size[above][2])
    assert drawer_rim(world, "dresser", shirt + np.array([0.0, 0.0, 1.0])) is None  # above the dresser
    assert drawer_rim(world, "table_dining_room", world.object_pose("bowl")[0]) is None  # no drawers


# Parts the robot does not open yet, each with why: strict, so one that opens fails the test until removed here.
OPEN_FAILS = {"oven/door": "its 4 kg door stops at 0.89 of its range, short of 0.9, touching nothing (cause not found)"}


def _every_part() -> list:
    layout = default_layout()
    names = [f"{f.name}/{part.name}" for f in layout.furniture for part in furniture_geometry(f).parts]
    return [pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=OPEN_FAILS[n])) if n in OPEN_FAILS else n
            for n in names]


@pytest.mark.physics
@pytest.mark.parametrize("name", _every_part())
def test_robot_opens_every_door_and_drawer_of_the_apartment(name: str) -> None:
    """From the apartment's start, each door and drawer opens: the layout leaves the floor free where the robot
    stands to hold it (a bathroom shelf by the doorway once left no way to the washing machine's door)."""
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world)
    robot.observer.observe_all()
    opened = robot.open_articulation(name)
    assert opened.success, opened.reason


def test_a_retract_below_a_drawers_handle_leaves_the_drawer_open() -> None:
    """The hand let go of a drawer it opened, drawn back and lower than its handle, its fingers open: tucking the
    arm away moves the drawer less than 2 cm (in an assisted day, a hand risen into such a handle swung on and
    pushed the drawer 10 cm shut; this start does not reproduce that rise, it guards the retract from there)."""
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world)
    robot.observer.observe_all()
    name = "dresser/drawer_2"
    assert robot.open_articulation(name).success
    motion = PartMotion(world, name)
    pos, quat = motion.grip_target(handle_grasp(motion.handle_local, "slide"), motion.value)
    rotation = np.empty(9)
    mujoco.mju_quat2Mat(rotation, quat)
    below = pos - 0.10 * rotation.reshape(3, 3)[:, 0] - np.array([0.0, 0.0, 0.09])
    result = robot.arm.ik.solve(robot.controller.target, below, quat)
    assert result.converged, result.reason
    robot.arm.reach(result.q, grip=0.03)
    robot.controller.settle(0.005)
    opened = world.openness(name)
    robot.arm.retract()
    world.settle(max_seconds=1.0)
    assert robot.arm.folded
    assert world.openness(name) == pytest.approx(opened, abs=0.02 / 0.375)  # moved less than 2 cm
