"""The navigator's obstacles beyond the floor plan: objects standing on the floor and what moves by itself."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from homer_sim.world import World
from planners.motion.navigation import IN_THE_WAY, NavigationError, _carry_poses
from planners.robot import add_robot
from planners.skills import Robot


@pytest.fixture(scope="module")
def robot() -> Robot:
    world = World(extras=[add_robot])
    world.reset_settled()
    return Robot(world, np.random.default_rng(0))


def _distance(xy, rect) -> float:
    return float(np.hypot(max(rect[0] - xy[0], 0.0, xy[0] - rect[2]), max(rect[1] - xy[1], 0.0, xy[1] - rect[3])))


def test_objects_standing_on_the_floor_are_kept_out_of_the_base_path(robot: Robot) -> None:
    navigator, world = robot.navigator, robot.world
    rects = navigator.floor_object_rects()
    low = [n for n in world.object_names if world.object_pose(n)[0][2] < 0.3 and
           navigator.furniture.get(robot.observer.update().parent_of(n)) is None]
    assert low and len(rects) == len(low)  # the bin, the vacuum cleaner... and nothing on furniture
    for name in low:
        xy = world.object_pose(name)[0][:2]
        rect = next(r for r in rects if r[0] < xy[0] < r[2] and r[1] < xy[1] < r[3])
        pose = navigator.stand_near(tuple(xy))  # beside it, the base clear of it
        assert _distance(pose[:2], rect) >= navigator.radius
        far = xy + 1.2 * (np.asarray(pose[:2]) - xy) / np.linalg.norm(np.asarray(pose[:2]) - xy)
        for other in (xy + (xy - far), far):  # a path past it, from one side to the other, keeps clear of it
            if not navigator.plan.disk_is_free(*other, navigator.radius + 0.05, navigator.obstacles()):
                continue
            path = np.array(navigator.path_to((*other, 0.0)))
            assert min(_distance(p, rect) for p in path[1:-1]) >= navigator.radius


def test_a_way_only_someone_blocks_fails_saying_so(robot: Robot) -> None:
    navigator = robot.navigator
    goal = navigator.stand_pose("table_dining_room", navigator.furniture["table_dining_room"].pos[:2])
    x, y = goal[:2]
    try:
        navigator.others = lambda: [(x - 4.0, y - 4.0, x + 4.0, y + 4.0)]  # someone all round it
        with pytest.raises(NavigationError, match=IN_THE_WAY):
            navigator.stand_pose("table_dining_room", navigator.furniture["table_dining_room"].pos[:2])
        with pytest.raises(NavigationError, match=IN_THE_WAY):
            navigator.path_to(goal)
        navigator.others = lambda: [(50.0, 50.0, 51.0, 51.0)]  # far away: nothing in the way
        assert navigator.path_to(goal)
    finally:
        navigator.others = list
    with pytest.raises(NavigationError) as error:  # a way blocked by the apartment says nothing of anyone
        navigator.path_to((-40.0, -40.0, 0.0))
    assert IN_THE_WAY not in str(error.value)


def test_a_base_in_someones_way_finds_the_nearest_spot_clear_of_it(robot: Robot) -> None:
    """`Navigator.clear_of`: where the robot waits while the person walks a path through where it stands (a robot
    left in a doorway had ended the person's day): reachable from it, at least the distance from every point."""
    navigator = robot.navigator
    here = robot.controller.q()[:2]
    points = np.array([here + (dx, 0.0) for dx in np.arange(-1.0, 1.01, 0.05)])  # a walk straight through it
    pose = navigator.clear_of(points, 0.6)
    assert pose is not None
    assert np.min(np.hypot(*(points - np.asarray(pose[:2])).T)) >= 0.6 - 1e-9
    assert np.hypot(*(np.asarray(pose[:2]) - here)) < 1.5  # near, not anywhere
    assert navigator.path_to(pose)  # and the base gets there
    assert navigator.clear_of(points + (20.0, 20.0), 0.6)[:2] == tuple(here)  # out of the way already: it stays


def test_an_object_set_down_in_a_doorway_would_shut_the_way(robot: Robot) -> None:
    """`Navigator.leaves_way`: a laundry basket set down just inside the bathroom's doorway (where one fell) cuts
    the floor the base reaches in two; one in the open dining room does not."""
    navigator = robot.navigator
    assert not navigator.leaves_way((1.96, 3.95, 2.51, 4.47))
    assert navigator.leaves_way((3.6, 3.0, 4.0, 3.4))


@pytest.mark.parametrize("length", [0.3, 0.45, 0.9, 2.0])
def test_a_carry_ends_at_the_goal_heading_however_short_the_way(length: float) -> None:
    """`_carry_poses` blends the heading from the start's over the first CARRY_TURN m and into the goal's over the
    last: on a way shorter than CARRY_TURN the start's blend came last and the base stopped short of the goal's
    heading (6 degrees off the pose a lowering was planned at, which then pushed a loaf)."""
    points = [(0.0, 0.0), *((x, 0.0) for x in np.linspace(0.15, length, 4))]
    goal = (length, 0.0, -1.0)
    for first in (None, ((0.0, 0.0), False)):
        poses = _carry_poses(points, 0.5, goal, first, None)
        assert poses[-1][:2] == pytest.approx(goal[:2]) and poses[-1][2] == pytest.approx(goal[2])
        assert all(abs(b[2] - a[2]) < np.pi for a, b in itertools.pairwise(poses))  # no turn the long way
