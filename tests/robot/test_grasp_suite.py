"""The grasp regression suite: the quick subset in the default pass, the full suite behind the `slow` marker."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from homer_sim.errors import HomerError
from homer_sim.home.apartment import default_layout
from homer_sim.home.catalog import CATALOG
from homer_sim.home.placement import SPOT_GAP
from homer_sim.recording import read_recording
from homer_sim.world import World
from planners.grasps.candidate import ungraspable_reason
from planners.motion.control import robot_geom_ids
from planners.robot import add_robot
from planners.suites.grasp_suite import (
    MAX_PENETRATION,
    MAX_SLIP,
    MIN_LIFT,
    TARGET_CLASS,
    TARGET_OVERALL,
    TrialResult,
    _jitter_pose,
    chosen_classes,
    quick_subset,
    run_suite,
    suite_classes,
    summarise,
)


def test_suite_lists_every_apartment_class_once_with_reasons_for_exclusions() -> None:
    included, excluded = suite_classes()
    assert not set(included) & set(excluded)
    assert len(included) + len(excluded) == len({o.cls for o in default_layout().objects})  # every class
    for cls, reason in excluded.items():
        assert reason == ungraspable_reason(CATALOG[cls]) and reason
    quick = quick_subset(included)
    families = {CATALOG[c].family for c in included}
    assert len(quick) == len(families) + 1
    assert {CATALOG[c].family for c in quick} == families  # one class per family, and one with a handle
    assert len([c for c in quick if CATALOG[c].handle is not None]) == 1


def test_chosen_classes_name_their_instances_and_refuse_unknown_or_excluded_ones() -> None:
    included, _ = suite_classes()
    assert chosen_classes(["mug", "bowl"]) == {"mug": included["mug"], "bowl": included["bowl"]}
    with pytest.raises(HomerError, match="'mugg' is unknown; included: bowl"):
        chosen_classes(["mugg"])
    with pytest.raises(HomerError, match="'plate' is excluded"):
        chosen_classes(["plate"])


def test_summary_counts_trials_and_rates() -> None:
    results = [TrialResult("bowl", True, "", 0.15, 0.001, 1.0), TrialResult("bowl", False, "missed", 0.0,
                                                                             np.nan, 1.0),
               TrialResult("mug", True, "", 0.14, 0.0, 1.0),
               TrialResult("mug", False, "collateral: moved cup 3.0 cm", 0.14, 0.0, 1.0, collateral=True)]
    summary = summarise(results, {"plate": "wide"}, 3, 3.0, {})
    assert summary["trials"] == 4 and summary["overall"] == pytest.approx(2 / 4) and summary["collateral"] == 1
    assert summary["per_class"]["bowl"] == {"trials": 2, "successes": 1, "failures": ["missed"], "family": "bowl",
                                            "min_lift_m": 0.15, "max_slip_m": 0.001}
    assert summary["worst_class_rate"] == 0.5 and not summary["meets_targets"]


QUICK_MIN_OVERALL = 0.9  # regression floor: 12 of 12 measured; one failure allowed for float differences between
# machines (the slow full-suite test asserts the targets)


def test_quick_subset_lifts_and_holds(tmp_path: Path) -> None:
    result = run_suite(quick=True, seed=0, progress=False, rrd=tmp_path / "grasps.rrd")
    assert result["trials"] == len(result["per_class"]) >= 8
    assert 0.0 <= result["overall"] <= 1.0
    assert result["overall"] >= QUICK_MIN_OVERALL, result["per_class"]
    for cls, entry in result["per_class"].items():
        assert len(entry["failures"]) == entry["trials"] - entry["successes"]
        assert all(entry["failures"]), cls  # every failure says why
        if entry["successes"]:
            assert entry["min_lift_m"] >= MIN_LIFT and entry["max_slip_m"] < MAX_SLIP, (cls, entry)
    assert result["per_class"]["trashcan"]["successes"] == 1  # a rim pinch of a bin on the floor
    entities = read_recording(tmp_path / "grasps.rrd")  # every trial recorded, one after the other
    events = [text for row in entities["events"].column("TextLog:text").to_pylist() if row for text in row]
    assert {e.split(" trial ")[0] for e in events if " trial " in e} == set(result["per_class"]), events
    times = entities["world/bodies/robot\\/base"].column("physics_s").drop_null().to_pylist()
    assert times == sorted(times) and len(times) > 10 * result["trials"]


class _Draws:
    """A stand-in for the suite's random generator: `uniform` hands out the given draws in turn."""

    def __init__(self, *draws) -> None:
        self.draws = list(draws)

    def uniform(self, low, high, size=None):
        return self.draws.pop(0)


def _nearest_beside(world: World, name: str) -> tuple[float, np.ndarray]:
    """The gap (m) from object `name` to the nearest collision geom beside it (not under it, not the robot's)
    within 6 cm, and the unit horizontal direction towards it."""
    model, data = world.model, world.data
    body = int(world.object_body_ids[world.object_index(name)])
    robot = set(robot_geom_ids(model).tolist())
    best, towards, fromto = np.inf, np.zeros(2), np.zeros(6)
    for other in range(model.ngeom):
        if model.geom_bodyid[other] == body or other in robot or not model.geom_contype[other]:
            continue
        for g in np.flatnonzero(model.geom_bodyid == body):
            gap = mujoco.mj_geomDistance(model, data, int(g), other, 0.06, fromto)
            step = fromto[3:5] - fromto[:2]
            if gap < best and np.linalg.norm(step) > 0.9 * gap > 0.005:  # beside it: the way there is level
                best, towards = gap, step / np.linalg.norm(step)
    return float(best), towards


@pytest.mark.parametrize("name", ["cd", "charger"])  # in a drawer: beside the charger; before the drawer's front
def test_a_jittered_start_keeps_the_gap_the_layout_keeps_to_neighbours_and_walls(name: str) -> None:
    """A start pose 3 mm from a neighbour or a wall presses into nothing, but leaves no finger room where the
    layout keeps SPOT_GAP: it is drawn again (here: no jitter), not taken."""
    world = World(extras=[add_robot])
    gap, towards = _nearest_beside(world, name)
    assert SPOT_GAP - 1e-3 <= gap < 0.06
    home, quat = world.object_pose(name)
    _jitter_pose(world, name, _Draws((gap - 0.003) * towards, 0.0, np.zeros(2), 0.0))
    pos, _ = world.object_pose(name)
    assert np.allclose(pos, home, atol=1e-6), pos - home  # the second draw: the home pose
    assert _nearest_beside(world, name)[0] >= SPOT_GAP - MAX_PENETRATION


def test_the_way_down_into_a_side_grasp_keeps_to_its_line() -> None:
    """Seed 1's first two start poses of the milk in the fridge: the descent's waypoints, solved loosely and each
    seeding the next, drifted up to 14 mm aside, a pad struck the carton, and it turned out of the hand in the hold
    (lifted -51.5 cm); a descent that strays is solved exactly, and the carton is held."""
    included, _ = suite_classes()
    result = run_suite(trials=2, seed=1, progress=False, classes={"milk": included["milk"]})
    assert result["per_class"]["milk"]["successes"] == 2, result["per_class"]["milk"]["failures"]


def test_fingers_opening_on_the_way_down_from_the_raised_arm_sweep_nothing() -> None:
    """Seed 12345's first start pose of the charger in the desk drawer: the leg from the raised arm to the
    approach pose touched the desk only with the fingers open to the grasp's width, and they opened on the way: the
    pads swept the keyboard 77 cm across the desk top. They now open once the arm is there."""
    included, _ = suite_classes()
    result = run_suite(trials=1, seed=12345, progress=False, classes={"charger": included["charger"]})
    assert result["per_class"]["charger"]["successes"] == 1, result["per_class"]["charger"]["failures"]
    assert result["collateral"] == 0


def test_a_hand_that_pushes_a_neighbour_on_its_way_in_stops_and_backs_off() -> None:
    """Seed 12345's first start pose of the shampoo on the shower's shelf: the arm trailing its planned descent, a
    finger pushed the conditioner beside it 1 cm in 0.07 s, and on to 18 cm as the fingers closed. The pick watches
    the other objects while the hand goes in, stops where one moves WATCH_PUSH, backs off without opening wider, and
    takes the next grasp."""
    included, _ = suite_classes()
    result = run_suite(trials=1, seed=12345, progress=False, classes={"shampoo": included["shampoo"]})
    assert result["per_class"]["shampoo"]["successes"] == 1, result["per_class"]["shampoo"]["failures"]
    assert result["collateral"] == 0


def test_grasps_from_above_are_planned_again_where_a_failed_one_moved_the_object() -> None:
    """Seed 777's first start pose of the pencil in the filing cabinet's drawer, beside a note pad: the first grasp
    pushed the note pad and stopped, but the pad dragged the drawer, and the pencil in it, 1.5 cm out. Every grasp
    after it was still planned for where the pencil had stood, and the fingers came down on it. They are planned
    again for where it stands now."""
    included, _ = suite_classes()
    result = run_suite(trials=1, seed=777, progress=False, classes={"pencil": included["pencil"]})
    assert result["per_class"]["pencil"]["successes"] == 1, result["per_class"]["pencil"]["failures"]
    assert result["collateral"] == 0


def test_a_razor_on_a_shelf_is_picked_between_its_neighbours() -> None:
    """Seed 2024's first start pose of the razor, lying front to back on the bathroom cabinet's middle shelf: its
    neighbours stood 17.5 cm apart, the palm of every grasp that reaches a razor (pitched down over it, the fingers
    closing across) is 18 cm wide, and no grasp was left. The layout keeps the palm's room beside the objects of a
    shelf holding one so low (`homer_sim.home.placement.PALM_ROOM`)."""
    included, _ = suite_classes()
    result = run_suite(trials=1, seed=2024, progress=False, classes={"razor": included["razor"]})
    assert result["per_class"]["razor"]["successes"] == 1, result["per_class"]["razor"]["failures"]
    assert result["collateral"] == 0


def test_closing_fingers_neither_sweep_a_neighbour_nor_slide_the_object_into_one() -> None:
    """Seed 2024's second start pose of the rice in the cupboard, the oil beside it: the pitched grasp moved aside
    opened fully, and closing, its far finger swept past the oil's front and the rice slid 4.5 cm to the grasp's
    centre, into the oil; the oil came out of the cupboard with the rice, 31 cm. Such grasps are not tried."""
    included, _ = suite_classes()
    result = run_suite(trials=2, seed=2024, progress=False, classes={"food_rice": included["food_rice"]})
    assert result["per_class"]["food_rice"]["successes"] == 2, result["per_class"]["food_rice"]["failures"]
    assert result["collateral"] == 0


def test_a_hand_stopped_on_its_way_in_lets_go_of_what_it_pushed_before_it_backs_off() -> None:
    """Seed 2024's third start pose of the perfume in the bathroom cabinet: the far finger of a grasp moved aside
    pushed the toilet roll beside it 0.6 cm and the hand stopped; backing off, the finger still pressed on the roll
    and dragged it 2.2 cm further. The fingers now close until they let go of it first."""
    included, _ = suite_classes()
    result = run_suite(trials=3, seed=2024, progress=False, classes={"perfume": included["perfume"]})
    assert result["per_class"]["perfume"]["successes"] == 3, result["per_class"]["perfume"]["failures"]
    assert result["collateral"] == 0


@pytest.mark.slow
def test_full_grasp_suite_meets_its_targets() -> None:
    result = run_suite(seed=0, progress=False)
    rates = {c: e["successes"] / e["trials"] for c, e in result["per_class"].items()}
    assert result["overall"] >= TARGET_OVERALL, rates
    assert min(rates.values()) >= TARGET_CLASS, rates
    assert len(result["excluded"]) <= result["classes"] / 5, result["excluded"]
