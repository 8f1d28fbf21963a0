"""Robot skills in the apartment, verified on the observed scene graph, by physics alone."""

from __future__ import annotations

import numpy as np
import pytest

from homer_sim.graph import INSIDE, ON, RELATION_NAMES
from homer_sim.home.catalog import CATALOG
from homer_sim.world import World
from planners.motion.arm import LEVEL_HAND, PASS_OVER
from planners.robot import add_robot
from planners.skills import Robot


def _others_moved(world: World, before: np.ndarray, moved: str) -> tuple[float, str]:
    drift = np.linalg.norm(world.object_positions() - before, axis=1)
    if moved:
        drift[world.object_index(moved)] = 0.0
    k = int(np.argmax(drift))
    return float(drift[k]), world.object_names[k]


def _scene(obj: str, position: tuple[float, float, float], on: str, seed: int,
           quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)) -> tuple[World, Robot]:
    """Scenario set-up: `obj` put down at `position` (m) turned by `quat` (wxyz), where it must settle on
    furniture `on`."""
    world = World(extras=[add_robot])
    world.set_object_pose(obj, position, quat)
    world.settle()
    robot = Robot(world, np.random.default_rng(seed))
    assert robot.observer.observe_all().parent_of(obj) == on
    return world, robot


@pytest.mark.xfail(strict=True, reason="since the coffee maker's bays and the start layout's row gaps, the pick of "
                   "the bowl 13 cm from the kitchen towel drags the towel 3.0 cm (more than the 2 cm collateral "
                   "bound); cause not traced")
def test_robot_picks_bowl_from_counter_and_places_it_in_the_sink() -> None:
    world, robot = _scene("bowl", (5.0, 0.45, 0.9 + 0.035 + 0.003), "kitchen_counter_right", seed=3)
    before = world.object_positions()
    start = world.object_pose("bowl")[0]

    picked = robot.pick("bowl")
    assert picked.success, picked.reason
    assert world.object_pose("bowl")[0][2] - start[2] > 0.10  # lifted by the fingers

    placed = robot.place("sink_dining_room")
    assert placed.success, placed.reason
    graph = robot.observer.update()
    assert graph.parent_of("bowl") == "sink_dining_room"
    assert graph.relation_of("bowl") == RELATION_NAMES[INSIDE]
    drift, name = _others_moved(world, before, "bowl")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm"
    assert world.warnings() == 0 and not world.has_nan()


def test_pick_reports_a_clear_reason_for_ungraspable_objects() -> None:
    world = World(extras=[add_robot])
    robot = Robot(world)
    result = robot.pick("mail")
    assert not result.success
    assert "mail" in result.reason and "thin" in result.reason


def test_pick_refuses_an_object_lying_on_its_side_without_touching_anything() -> None:
    side = (np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0)  # about x: the 0.07 m side down
    world, robot = _scene("food_cereal", (2.6, 2.0, 0.75 + 0.035 + 0.003), "table_dining_room", seed=0, quat=side)
    before, arm = world.object_positions(), robot.controller.q().copy()
    result = robot.pick("food_cereal", into="cupboard")
    assert not result.success and "fallen over" in result.reason, result.reason
    assert np.abs(world.object_positions() - before).max() == 0.0  # refused before any move
    assert np.abs(robot.controller.q() - arm).max() < 1e-6


def test_an_object_a_grasp_knocks_over_is_picked_again_as_it_lies(monkeypatch) -> None:
    """The grasps left after one knocked the object over were made for it standing (a juice carton knocked over on a
    bookshelf was reached for four more times where it had stood): the pick stops there and the robot takes it
    again as it lies. The knock is staged (the first grasp lays the bottle down instead of closing on it); the
    pick that follows is physics."""
    from planners.skills.pick import Pick
    from planners.skills.result import SkillResult

    world, robot = _scene("water_bottle", (2.6, 2.0, 0.75 + 0.12), "table_dining_room", seed=0)
    tried, real = [], Pick._try_grasp

    def knock(self, name, grasp, *args, **kwargs):
        if tried:
            return real(self, name, grasp, *args, **kwargs)
        tried.append(grasp.kind)
        position, _ = world.object_pose(name)
        world.set_object_pose(name, position - np.array([0.0, 0.0, 0.08]),
                              (np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0))  # on its side
        world.settle()
        return SkillResult(False, "staged: the fingers knocked it over")

    monkeypatch.setattr(Pick, "_try_grasp", knock)
    result = robot.pick("water_bottle")
    assert result.success, result.reason
    assert robot.held == "water_bottle" and len(tried) == 1
    assert world.object_pose("water_bottle")[0][2] > 0.75 + 0.1  # lifted off the table top by the fingers


def test_pick_for_a_room_floor_takes_the_object() -> None:
    """A pick whose next destination is a room (a free spot of its floor) plans as for any top: the side-first
    check for shelves asked the room for its fixed places, `Spots.places_of` raised KeyError for it, and that ended
    a whole assisted evaluation."""
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world, np.random.default_rng(0))
    assert robot.observer.observe_all().parent_of("food_bread") == "kitchen_counter_left"
    assert robot.spots.places_of("dining_room", None) == []  # a room has no fixed places (a place there asks too)
    result = robot.pick("food_bread", into="dining_room")
    assert result.success, result.reason
    assert robot.held == "food_bread"


def _basket_onto_the_floor(world: World, robot: Robot, room: str) -> None:
    """Pick the laundry basket for `room`, put it down on its floor; it must stand there."""
    result = robot.pick("basket_for_clothes", into=room)
    assert result.success, result.reason
    result = robot.place(room)
    assert result.success, result.reason
    world.settle(max_seconds=2.0)
    assert robot.observer.update().parent_of("basket_for_clothes") == room
    assert not robot.arm.fallen_over("basket_for_clothes")


def test_a_laundry_basket_pinched_at_its_rim_is_put_down_on_a_rooms_floor() -> None:
    """The basket turns in the fingers on the way above its spot (pinched at one point of its rim, it pivots): the
    place aims it again from where it hangs then. Aimed from where it hung after the carry, it stopped 5.1 cm above
    the bathroom floor, out of the arm's reach, and the place failed."""
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world, np.random.default_rng(0))
    robot.observer.observe_all()
    _basket_onto_the_floor(world, robot, "bathroom")


def test_a_laundry_basket_in_the_middle_of_the_bed_is_pinched_at_its_near_rim() -> None:
    """Its far rim, where a bin is pinched to hang clear of the robot, lies out of the arm's reach from every side
    of the bed (the pick failed there, "approach pose unreachable"); the near rim is pinched instead."""
    world, robot = _scene("basket_for_clothes", (8.57, 6.0, 0.72), "bed", seed=0)
    _basket_onto_the_floor(world, robot, "bedroom")


def test_unfold_check_sees_the_table_top_the_folded_elbow_swings_over() -> None:
    """Beside the dining table, arm side towards it, the unfold from the tuck sticks on the table top: the check
    says so before the robot goes there; turned the other way round the arm unfolds freely, and the check agrees."""
    for yaw, clear in ((0.684, False), (0.684 + np.pi, True)):
        world = World(extras=[add_robot])
        robot = Robot(world)
        base = np.array([2.256, 1.549, yaw])
        assert robot.arm.unfold_clear(base, 0.26) == clear
        robot.navigator.drive_to(tuple(base), robot.tucked())
        raised = robot.raised(0.26)
        robot.controller.move_through([raised])
        robot.controller.settle(0.01)
        stuck = float(np.abs(robot.controller.q()[:11] - raised[:11]).max())
        assert (stuck < 0.05) == clear, f"joint error {stuck:.3f} rad after the unfold"


def test_robot_fetches_milk_from_the_fridge_to_the_dining_table() -> None:
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world, np.random.default_rng(5))
    graph = robot.observer.observe_all()
    assert graph.parent_of("milk") == "fridge" and graph.relation_of("milk") == RELATION_NAMES[INSIDE]
    before = world.object_positions()
    start = world.object_pose("milk")[0]

    opened = robot.open_articulation("fridge/door")
    assert opened.success, opened.reason
    assert world.openness("fridge/door") > 0.9
    graph = robot.observer.update()
    assert graph.parent_of("milk") == "fridge"  # opening the door leaves the milk where it was
    drift, name = _others_moved(world, before, "")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm while the door opened"

    picked = robot.pick("milk")
    assert picked.success, picked.reason
    assert world.object_pose("milk")[0][2] - start[2] > 0.05  # held by the fingers, off its shelf

    placed = robot.place("table_dining_room")
    assert placed.success, placed.reason
    graph = robot.observer.update()
    assert graph.parent_of("milk") == "table_dining_room"
    assert graph.relation_of("milk") == RELATION_NAMES[ON]

    closed = robot.close_articulation("fridge/door")
    assert closed.success, closed.reason
    assert world.openness("fridge/door") < 0.05
    graph = robot.observer.update()
    assert graph.parent_of("milk") == "table_dining_room"
    drift, name = _others_moved(world, before, "milk")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm"
    assert world.warnings() == 0 and not world.has_nan()


def test_a_box_held_from_the_side_is_carried_above_the_dining_table() -> None:
    """The cereal, taken off its low cupboard shelf with the hand level (a side grasp), is carried with its bottom
    over the dining table's top: at the nearest carry point a hand held level reaches no higher than 0.9 m, and at
    breakfast the box, carried that low, struck the table's top on the way and fell."""
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world, np.random.default_rng(0))
    opened = robot.open_articulation("cupboard")
    assert opened.success, opened.reason
    picked = robot.pick("food_cereal")
    assert picked.success, picked.reason
    robot.arm.carry()
    hand = world.data.site("robot/grip").xmat.reshape(3, 3)[:, 0]
    assert np.linalg.norm(hand[:2]) > LEVEL_HAND, hand  # held level
    top = world.data.geom("table_dining_room/top")
    table = top.xpos[2] + world.model.geom_size[top.id][2]
    bottom = world.object_pose("food_cereal")[0][2] - CATALOG["food_cereal"].size[2] / 2
    assert bottom > table + PASS_OVER, f"box bottom {bottom:.3f} m, table top {table:.3f} m"


def test_robot_puts_cereal_from_the_table_back_on_its_cupboard_shelf() -> None:
    world, robot = _scene("food_cereal", (2.6, 2.0, 0.75 + 0.14 + 0.003), "table_dining_room", seed=0)
    opened = robot.open_articulation("cupboard")
    assert opened.success, opened.reason
    before = world.object_positions()

    picked = robot.pick("food_cereal", into="cupboard")  # from the side: the hand enters the shelf level
    assert picked.success, picked.reason
    placed = robot.place("cupboard", INSIDE)
    assert placed.success, placed.reason

    graph = robot.observer.update()
    assert graph.parent_of("food_cereal") == "cupboard"
    assert graph.relation_of("food_cereal") == RELATION_NAMES[INSIDE]
    body = world.object_body_ids[world.object_index("food_cereal")]
    assert world.data.xmat[body].reshape(3, 3)[2, 2] > 0.95  # standing, not dropped on its side
    drift, name = _others_moved(world, before, "food_cereal")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm"
    assert world.warnings() == 0 and not world.has_nan()


def test_open_shelves_lower_levels_are_covered_and_a_showers_floor_is_not(world: World) -> None:
    from homer_sim.home.spots import Spots
    from planners.skills.parts import covered_places

    spots = Spots(world)
    tvstand = [k for k, _ in spots.places_of("tvstand_home_office", None)]
    assert covered_places(spots, "tvstand_home_office", None) == tvstand[:-1]  # all but the top
    assert covered_places(spots, "shower", None) == []  # its small soap shelf covers little of the floor
    assert covered_places(spots, "table_dining_room", None) == []



def test_only_a_basin_has_a_rim_a_level_hand_meets() -> None:
    from homer_sim.home.apartment import default_layout
    from homer_sim.home.furniture import furniture_geometry
    from planners.skills.parts import rim_above
    from planners.skills.robot import BASIN_RIM

    furniture = default_layout().furniture_by_name()
    rims = {name: max(rim_above(furniture[name], p) for p in furniture_geometry(furniture[name]).places)
            for name in ("sink_bathroom", "sink_dining_room", "shower", "table_dining_room", "kitchen_counter_left")}
    assert rims["sink_bathroom"] > BASIN_RIM and rims["sink_dining_room"] > BASIN_RIM
    assert 0.0 < rims["shower"] < BASIN_RIM  # its curb
    assert rims["table_dining_room"] == 0.0 and rims["kitchen_counter_left"] == 0.0


def test_an_object_behind_another_on_a_shelf_must_rise_over_it_to_come_out() -> None:
    """`rise_to_pass`: a glass behind the dishwasher's front cup must rise over the cup's top to be drawn out;
    one beside the cup need not rise."""
    from planners.grasps.neighbours import PASS_ABOVE, rise_to_pass

    world = World(extras=[add_robot])
    cup = world.object_pose("cup")[0]
    cup_top = cup[2] + CATALOG["cup"].size[2] / 2
    rack = cup[2] - CATALOG["cup"].size[2] / 2
    glass = np.array([cup[0] + 0.02, cup[1] - 0.35, rack + CATALOG["drinking_glass"].size[2] / 2])
    world.set_object_pose("drinking_glass", tuple(glass), (1.0, 0.0, 0.0, 0.0))
    out = np.array([0.0, 1.0])  # the dishwasher's front faces north
    assert abs(rise_to_pass(world, "drinking_glass", glass, out, 0.4) - (cup_top + PASS_ABOVE - rack)) < 1e-6
    beside = glass + np.array([0.16, 0.0, 0.0])
    world.set_object_pose("drinking_glass", tuple(beside), (1.0, 0.0, 0.0, 0.0))
    assert rise_to_pass(world, "drinking_glass", beside, out, 0.4) == 0.0


@pytest.mark.physics
def test_a_canister_in_the_bathroom_basin_is_lifted_over_its_rim_before_it_is_drawn_out() -> None:
    """The wipes standing in the bathroom sink's basin (their top below its rim), picked for the kitchen
    cabinet's shelf: gripped from the front and lifted 3 cm, then drawn out, the canister struck the basin's front
    wall and fell over in the hand; lifted over the rim first (`Pick._rim_rise`), it comes out held."""
    world, robot = _scene("disinfectant_wipes", (1.742, 7.593, 0.71 + CATALOG["disinfectant_wipes"].size[2] / 2
                                                 + 0.003), "sink_bathroom", seed=0)
    before = world.object_pose("disinfectant_wipes")[0]
    assert robot._pick._rim_rise("sink_bathroom", before, CATALOG["disinfectant_wipes"].size[2]) > 0.15
    positions = world.object_positions()
    picked = robot.pick("disinfectant_wipes", "sink_bathroom", into="kitchen_cabinet")
    assert picked.success, picked.reason
    assert world.object_pose("disinfectant_wipes")[0][2] - before[2] > 0.15  # up over the rim, in the hand
    drift, name = _others_moved(world, positions, "disinfectant_wipes")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm"


@pytest.mark.physics
def test_a_wine_glass_behind_the_dishwashers_cup_comes_out_over_it_and_stays_in_the_hand() -> None:
    """Drawn out 3 cm off the rack, the wine glass at the back took the cup in front of it along; drawn out the
    fixed 0.35 m, it was still inside when raised, struck the top's edge and fell out of the hand."""
    world = World(extras=[add_robot])
    cup = world.object_pose("cup")[0]
    rack = cup[2] - CATALOG["cup"].size[2] / 2
    world.set_object_pose("wine_glass", (cup[0] + 0.03, 0.22, rack + CATALOG["wine_glass"].size[2] / 2 + 0.003),
                          (1.0, 0.0, 0.0, 0.0))
    world.settle()
    robot = Robot(world, np.random.default_rng(0))
    assert robot.observer.observe_all().parent_of("wine_glass") == "dishwasher"
    opened = robot.open_articulation("dishwasher")
    assert opened.success, opened.reason
    before = world.object_positions()
    picked = robot.pick("wine_glass", "dishwasher")
    assert picked.success, picked.reason
    robot.arm.carry()
    world.step(500)
    assert not robot.arm.hand_empty(), "the wine glass fell out of the hand"
    drift, name = _others_moved(world, before, "wine_glass")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm"


def test_what_stands_near_a_spot_on_a_top_is_what_a_carried_object_must_pass_over() -> None:
    """`tallest_beside`: near its spot on the stove the sauce pan's top, not the stove's surface, is the height a
    carried object must pass over (a can of wipes carried 5 cm over the stove swept the pan 32 cm aside); far
    from the pan, the surface."""
    from planners.grasps.neighbours import tallest_beside

    world = World(extras=[add_robot])
    pan = world.object_pose("sauce_pan")[0]
    surface = pan[2] - CATALOG["sauce_pan"].size[2] / 2
    near = pan + np.array([-0.25, -0.1, 0.0])
    assert abs(tallest_beside(world, "disinfectant_wipes", near, surface, 0.5) - (pan[2] + CATALOG["sauce_pan"].size[
        2] / 2)) < 1e-6
    assert tallest_beside(world, "disinfectant_wipes", pan + np.array([-0.8, 0.0, 0.0]), surface, 0.5) == surface


def test_what_stands_beside_a_cutting_board_on_its_counter_counts_for_a_place_onto_the_board() -> None:
    """`tallest_beside` onto an object: the knife block standing on the counter beside the cutting board rises
    over the board's top and counts, though it does not stand on the board (a vegetable carried onto the board was
    driven into it)."""
    from planners.grasps.neighbours import tallest_beside

    world = World(extras=[add_robot])
    board, block = world.object_pose("cutting_board")[0], world.object_pose("knifeblock")[0]
    top = board[2] + CATALOG["cutting_board"].size[2] / 2
    block_top = block[2] + CATALOG["knifeblock"].size[2] / 2
    assert np.linalg.norm(board[:2] - block[:2]) < 0.5 and block_top > top
    assert abs(tallest_beside(world, "food_vegetable", board, top, 0.5) - block_top) < 1e-6


def test_a_vegetable_put_on_the_cutting_board_leaves_the_knife_block_beside_it_standing() -> None:
    """The vegetable from the fridge onto the cutting board: the way down planned to touch nothing passed the knife
    block beside the board at 0.1 mm; the arm, trailing its planned way, struck it with the palm, and letting go
    knocked it off the counter (1 m). The way down now keeps the arm WAY_MARGIN off the apartment where it can."""
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world, np.random.default_rng(0))
    robot.observer.observe_all()
    before = world.object_positions()
    assert robot.open_articulation("fridge/door").success
    picked = robot.pick("food_vegetable")
    assert picked.success, picked.reason
    placed = robot.place("cutting_board")
    assert placed.success, placed.reason
    assert robot.observer.update().parent_of("food_vegetable") == "cutting_board"
    block = float(np.linalg.norm(world.object_pose("knifeblock")[0] - before[world.object_index("knifeblock")]))
    assert block < 0.005, f"the knife block moved {block * 100:.1f} cm"


def test_a_pot_from_the_stove_goes_into_the_kitchen_cabinet() -> None:
    """The pot off the stove for the kitchen cabinet: picked pitched 60 degrees from the front (as a shelf takes
    things as a rule), its wrist met the shelf above at every spot; the pick now takes the grasp the cabinet
    takes (`Place.takes`), and the way in from the carry point, which met the open door on every straight swing,
    is planned round it with the pot kept upright (pinched by its wall and turned over, it slipped out)."""
    world, robot = _scene("cookingpot", (4.1, 0.45, 0.9 + 0.07 + 0.003), "stove", seed=0)
    before = world.object_positions()
    assert robot.open_articulation("kitchen_cabinet/door").success
    picked = robot.pick("cookingpot", into="kitchen_cabinet")
    assert picked.success, picked.reason
    placed = robot.place("kitchen_cabinet")
    assert placed.success, placed.reason
    graph = robot.observer.update()
    assert (graph.parent_of("cookingpot"), graph.relation_of("cookingpot")) == ("kitchen_cabinet",
                                                                                 RELATION_NAMES[INSIDE])
    drift, name = _others_moved(world, before, "cookingpot")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm"


def test_a_dress_is_dropped_into_the_laundry_basket_from_over_its_rim() -> None:
    """Cloth into a bin on the floor is let go just over the rim and drops in: lowered to the basket's floor, a
    dress hanging from its fold met the basket's walls 10 cm up and was backed out, and the arm reaching down (the
    base following the hand) pushed the basket across the floor."""
    world, robot = _scene("clothes_dress", (6.15, 7.65, 0.9 + 0.02 + 0.003), "dresser", seed=0)  # clear of the comb
    before = world.object_positions()
    picked = robot.pick("clothes_dress")
    assert picked.success, picked.reason
    placed = robot.place("basket_for_clothes")
    assert placed.success, placed.reason
    graph = robot.observer.update()
    assert (graph.parent_of("clothes_dress"), graph.relation_of("clothes_dress")) == (
        "basket_for_clothes", RELATION_NAMES[INSIDE])
    drift, name = _others_moved(world, before, "clothes_dress")
    assert drift < 0.02, f"{name} moved {drift * 100:.1f} cm"
    assert world.warnings() == 0 and not world.has_nan()


def test_a_lowering_may_touch_what_it_goes_onto_and_what_rides_in_the_held_object() -> None:
    """`Place._struck` leaves out the object a held one is lowered onto and what rides in the held one (they stay
    put in the check while it moves): lowering a bin with the mail in it onto a newspaper was refused as striking
    both. Anything else the held object touches still counts."""
    world = World(extras=[add_robot])
    world.set_object_pose("newspaper", (5.3, 2.7, 0.006), (1.0, 0.0, 0.0, 0.0))
    world.set_object_pose("trashcan", (5.3, 2.7, 0.162), (1.0, 0.0, 0.0, 0.0))
    world.set_object_pose("mail", (5.3, 2.7, 0.028), (1.0, 0.0, 0.0, 0.0))
    world.settle()
    robot = Robot(world)
    assert robot.observer.update().parent_of("mail") == "trashcan"
    path = [robot.controller.target.copy()]  # the bin as it stands, "held" where it is
    place = robot._place
    assert "mail" in place._riders("trashcan", robot.observer.update())
    assert place._struck("trashcan", path) == ["newspaper"]  # it stands on it
    assert place._struck("trashcan", path, onto="newspaper") == []


def test_an_object_touching_a_wall_does_not_rest_only_on_where_it_goes(world: World) -> None:
    """A held object the hand lowered against a wall (a geom of no node) is not lying in its destination: the
    check says so instead of asking the scene graph for the parent of the wall's empty node name (an unknown-node
    error that ended an oracle evaluation)."""
    from homer_sim.observe import SceneGraphObserver
    from planners.skills.place import Place

    place = Place.__new__(Place)  # the check alone: it reads what the object touches and the observed graph
    place.observer = SceneGraphObserver(world)
    wall = next(g for g in range(world.model.ngeom) if world.model.geom(g).name.startswith("wall/"))
    basket = next(g for g in range(world.model.ngeom) if place.observer.geom_node[g] >= 0
                  and place.observer.nodes[place.observer.geom_node[g]] == "basket_for_clothes")
    place._touching = lambda name: np.array([basket])
    assert place._rests_only_on("clothes_dress", "basket_for_clothes")
    place._touching = lambda name: np.array([basket, wall])
    assert not place._rests_only_on("clothes_dress", "basket_for_clothes")


def test_a_lowering_that_would_strike_a_neighbour_is_given_up_where_the_carry_left_the_robot() -> None:
    """`Place._lower_onto` plans the way over the spot and the way down before it moves, and where either would
    strike another object it gives up with the base driven back out: moved over the stove first, then refused, a
    can of wipes was left out over the stove with the base driven in close, and the drive to the next top swept the
    sauce pan off it."""
    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world, np.random.default_rng(0))
    robot.observer.observe_all()
    name = "food_bread"
    assert robot.pick(name).success
    pan = world.object_pose("sauce_pan")[0]
    top = pan[2] - CATALOG["sauce_pan"].size[2] / 2
    target = np.array([pan[0] - 0.13, pan[1], top + CATALOG[name].size[2] / 2])  # the bread's spot beside the pan
    failure, _ = robot._place._carry_to(name, "stove", target)
    assert failure is None
    back = robot.controller.target.copy()  # stopped 0.3 m short: the lowering drives in first
    back[:2] -= 0.3 * np.array([np.cos(back[2]), np.sin(back[2])])
    robot.controller.move_through([back])
    before, held_at = world.object_positions(), world.object_pose(name)[0].copy()
    outcome = robot._place._lower_onto(name, "stove", target, short=True)
    assert not outcome.success and "sauce_pan" in outcome.reason, outcome.reason
    assert robot.held == name
    assert np.linalg.norm(robot.controller.q()[:2] - back[:2]) < 0.05
    assert np.linalg.norm(world.object_pose(name)[0][:2] - held_at[:2]) < 0.05  # not moved over the stove
    assert _others_moved(world, before, name)[0] < 0.005


def test_a_grasp_whose_descent_leaves_the_arms_reach_moves_nothing(monkeypatch) -> None:
    """`Pick._try_grasp` plans the descent onto the grasp before the arm moves: where it leaves the arm's reach, the
    arm stays tucked (it went out over a laundry basket on the floor and gave up above the dress in it)."""
    from planners.skills.pick import Pick

    world = World(extras=[add_robot])
    world.settle()
    robot = Robot(world, np.random.default_rng(0))
    name = "food_bread"
    node = robot.observer.observe_all().parent_of(name)
    position, quat = world.object_pose(name)
    robot.arm.go_to(node, position[:2])  # in front of it, the arm tucked
    grasp = robot._pick._above_candidates(node, world.object_class(name), position, quat)[0]
    monkeypatch.setattr(Pick, "_descent", lambda *args, **kwargs: None)
    before = robot.controller.q().copy()
    outcome = robot._pick._try_grasp(name, grasp)
    assert not outcome.success and "descent" in outcome.reason, outcome.reason
    assert np.abs(robot.controller.q() - before).max() < 1e-3
