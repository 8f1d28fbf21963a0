"""The project's activity library: complete, parseable, physically sensible for the default apartment, and
timed so that the 10-minute snapshots see the moves."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from homer_sim.home.apartment import default_layout
from homer_sim.home.furniture import furniture_geometry
from homer_sim.person.activities import ACTIVITY_DIR, load_library, script_files
from homer_sim.person.aliases import default_resolver
from homer_sim.person.households import ACTIVITIES
from homer_sim.person.scripts import Script, SymbolicResult, symbolic_run

pytestmark = pytest.mark.physics  # steps a whole apartment for seconds or more

TWO_VARIANTS = {"breakfast", "lunch", "dinner", "brushing_teeth", "showering", "getting_dressed", "computer_work",
                "watching_tv", "reading", "wash_dishes", "leave_home", "come_home"}
DURATION_BOUNDS = {  # activity -> (lowest allowed min, highest allowed max), routine minutes
    "breakfast": (15, 35), "lunch": (12, 40), "dinner": (30, 90), "brushing_teeth": (2, 8), "showering": (10, 25),
    "computer_work": (30, 180), "leave_home": (2, 6), "come_home": (2, 10), "take_out_trash": (1, 6),
    "taking_medication": (2, 10), "going_to_the_bathroom": (2, 15), "getting_dressed": (3, 15),
    "watching_tv": (30, 180), "reading": (15, 90), "socializing": (30, 180), "laundry": (30, 90),
    "wash_dishes": (5, 70), "cleaning": (10, 45), "kitchen_cleaning": (10, 40), "vaccuum_cleaning": (10, 40),
    "playing_music": (15, 60), "listening_to_music": (15, 75),
}


@cache
def library() -> dict[str, list[Script]]:
    return load_library(default_resolver())


@cache
def start() -> dict:
    """The symbolic start state of the default apartment (its declared layout)."""
    layout = default_layout()
    return {
        "parents": {o.name: o.parent for o in layout.objects},
        "relations": {o.name: o.relation for o in layout.objects},
        "containers": frozenset(f.name for f in layout.furniture if furniture_geometry(f).parts),
        "node_rooms": {r: r for r in layout.room_names()} | {f.name: f.room for f in layout.furniture},
    }


def run(script: Script, after: SymbolicResult | None = None) -> SymbolicResult:
    """Symbolic run from the start layout, or from where `after` left things (all containers closed)."""
    s = start()
    parents = after.parents if after else s["parents"]
    carried = dict(held=after.held, worn=after.worn) if after else {}
    return symbolic_run(script, parents, s["containers"], s["containers"], relations=s["relations"],
                        node_rooms=s["node_rooms"], **carried)


def run_from_start(script: Script) -> SymbolicResult:
    if script.activity == "come_home":
        return run(script, after=run(library()["leave_home"][int(script.variant)]))  # come home as one left
    return run(script)


def all_scripts() -> list[Script]:
    return [script for scripts in library().values() for script in scripts]


def test_every_activity_has_its_variants() -> None:
    assert set(library()) == set(ACTIVITIES) and len(ACTIVITIES) == 22
    for activity, scripts in library().items():
        expected = ["0", "1"] if activity in TWO_VARIANTS else ["0"]
        assert [s.variant for s in scripts] == expected, activity
    assert len(script_files(ACTIVITY_DIR)) == 22 + len(TWO_VARIANTS)


def test_durations_are_sane() -> None:
    for script in all_scripts():
        low, high = script.duration_range
        lowest, highest = DURATION_BOUNDS[script.activity]
        assert lowest <= low < high <= highest, (script.activity, script.variant, low, high)


@pytest.mark.parametrize("script", all_scripts(), ids=lambda s: f"{s.activity}/{s.variant}")
def test_symbolic_run_from_the_start_layout_has_no_problems(script: Script) -> None:
    result = run_from_start(script)
    assert result.problems == (), result.problems
    assert all("closed" in reason for _, reason in result.warnings), result.warnings
    assert result.held == () or script.activity == "leave_home"


def test_a_day_of_every_activity_in_turn_has_no_problems() -> None:
    order = ["getting_dressed", "brushing_teeth", "showering", "breakfast", "taking_medication", "computer_work",
             "going_to_the_bathroom", "lunch", "wash_dishes", "cleaning", "vaccuum_cleaning", "laundry",
             "leave_home", "come_home", "playing_music", "listening_to_music", "reading", "socializing", "dinner",
             "kitchen_cleaning", "take_out_trash", "watching_tv", "wash_dishes"]
    for variant in (0, 1):
        state = None
        for activity in order:
            scripts = library()[activity]
            state = run(scripts[min(variant, len(scripts) - 1)], after=state)
            assert state.problems == (), (activity, state.problems)
            assert all("closed" in reason for _, reason in state.warnings), (activity, state.warnings)
        assert state.held == ()


def test_breakfast_takes_bowl_cereal_milk_and_spoon_to_the_table_and_away() -> None:
    result = run(library()["breakfast"][0])
    assert result.moved == {"bowl", "food_cereal", "milk", "spoon"}
    for obj in result.moved:
        assert "table_dining_room" in [c.parent for c in result.changes if c.obj == obj]
    assert result.parents["food_cereal"] == "cupboard" and result.parents["milk"] == "fridge"
    assert result.parents["bowl"] in ("sink_dining_room", "cupboard")
    assert result.parents["spoon"] in ("sink_dining_room", "cupboard")
    eating = max(library()["breakfast"][0].blocks, key=lambda b: b.min_min)
    assert eating.min_min >= 8 and all(a.verb not in ("grab", "putback", "putin") for a in eating.actions)


def test_leave_home_and_come_home_carry_the_outdoor_things() -> None:
    leave = run(library()["leave_home"][0])
    outdoor = {"shoes", "clothes_jacket", "keys", "wallet", "bag"}
    assert outdoor <= {obj for obj, parent in leave.parents.items() if parent == "outside"}
    assert set(leave.held) | set(leave.worn) == outdoor
    back = run(library()["come_home"][0], after=leave)
    assert (back.held, back.worn) == ((), ())
    assert {obj: back.parents[obj] for obj in outdoor} == {
        "keys": "bench", "wallet": "bench", "bag": "shoe_rack", "shoes": "shoe_rack", "clothes_jacket": "dresser"}


def test_household_chores_move_what_they_should() -> None:
    trash = run(library()["take_out_trash"][0])
    assert trash.parents["trashbag"] == "outside" and trash.parents["shoes"] == "shoe_rack"
    laundry = run(library()["laundry"][0])
    path = [c.parent for c in laundry.changes if c.obj == "clothes_dress"]
    assert path == ["basket_for_clothes", "washing_machine", "dresser"]
    shower = run(library()["showering"][0])
    assert [c.parent for c in shower.changes if c.obj == "towel"] == ["shower", "bathroom_counter"]
    dinner = run(library()["dinner"][0])
    assert "stove" in [c.parent for c in dinner.changes if c.obj == "cookingpot"]
    assert "table_dining_room" in [c.parent for c in dinner.changes if c.obj == "plate"]
    assert dinner.parents["plate"] == dinner.parents["fork"] == "sink_dining_room"
    for variant in library()["wash_dishes"]:
        dishes = run(variant, after=dinner)
        assert dishes.parents["plate"] == dishes.parents["fork"] == "cupboard"
        assert dishes.parents["cookingpot"] == "kitchen_cabinet"


def test_the_library_moves_between_30_and_60_distinct_objects() -> None:
    moved = set().union(*(run_from_start(script).moved for script in all_scripts()))
    assert 30 <= len(moved) <= 60, sorted(moved)
    assert moved <= set(start()["parents"])


def visible_moves(script: Script, rng: np.random.Generator, samples: int = 200) -> float:
    """Mean number of parent changes between 10-minute snapshots during one run of `script`, its blocks timed
    as the executor times them (block lengths uniform in their ranges, actions at random inside a block)."""
    result = run_from_start(script)
    before = run(library()["leave_home"][0]).parents if script.activity == "come_home" else start()["parents"]
    total = 0
    for _ in range(samples):
        minute, at = rng.uniform(0.0, 10.0), {}
        for block in script.blocks:
            length = rng.uniform(block.min_min, block.max_min)
            for action, offset in zip(block.actions, np.sort(rng.uniform(0, length, len(block.actions))), strict=True):
                at[action.line] = minute + offset
            minute += length
        parents, changes = dict(before), sorted((at[c.line], c.obj, c.parent) for c in result.changes)
        snapshot = dict(parents)
        for grid in np.arange(10.0, minute + 10.0, 10.0):
            while changes and changes[0][0] < grid:
                _, obj, parent = changes.pop(0)
                parents[obj] = parent
            total += sum(parents[obj] != snapshot[obj] for obj in result.moved)
            snapshot = dict(parents)
    return total / samples


def test_moves_are_timed_to_be_seen_but_not_too_many() -> None:
    rng = np.random.default_rng(0)
    seen = {f"{s.activity}/{s.variant}": visible_moves(s, rng) for s in all_scripts()}
    assert seen["breakfast/0"] == pytest.approx(8.0)  # four things to the table and away, each seen twice
    assert seen["leave_home/0"] == pytest.approx(5.0) and seen["come_home/0"] == pytest.approx(5.0)
    assert all(value <= 10.0 for value in seen.values()), seen
    # A day of 12-20 activities should show 20-45 moves: about 1.5-3.5 per activity.
    assert 1.5 <= np.mean(list(seen.values())) <= 3.5, seen
