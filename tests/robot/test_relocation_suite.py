"""The relocation suite: triples read from a generated dataset, the quick subset in physics in the default pass,
the whole suite on the 5-household dataset behind the `slow` marker."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from homer_sim.data.dataset import DatasetError
from homer_sim.data.generate import generate
from homer_sim.world import World
from planners.suites.collateral import MAX_DISPLACEMENT, collateral_reason, displaced
from planners.suites.relocation_suite import (
    TARGET_CLASS,
    TARGET_OVERALL,
    Occurrence,
    exclusion_reason,
    occurrences,
    run_relocations,
)

FULL_DATA = Path(os.environ.get("HOMER_SIM_RELOCATION_DATA", Path.home() / ".cache/homer-sim/data_5x50_v2"))


@pytest.fixture(scope="module")
def one_day(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One household's one training day (household_a, seed 0)."""
    out = tmp_path_factory.mktemp("relocation_data")
    generate(out, n_households=1, train_days=1, test_days=0, seed=0, progress=False)
    return out


def test_occurrences_are_the_days_moves_each_triple_once(one_day: Path) -> None:
    found = occurrences(one_day)
    triples = [(o.obj, o.source, o.destination) for o in found]
    assert len(triples) == len(set(triples)) > 5
    assert all(o.household == "household_a" and o.index == 0 for o in found)
    assert [o.minute for o in found] == sorted(o.minute for o in found)


def test_a_dataset_of_another_apartment_is_refused(one_day: Path, tmp_path: Path) -> None:
    # A dataset generated before the apartment gained its HOMER+ bodies: the same nodes without the last ones.
    old = tmp_path / "old"
    shutil.copytree(one_day, old)
    meta = json.loads((old / "meta.json").read_text())
    for key in ("nodes", "categories", "movable"):
        meta[key] = meta[key][:-13]
    (old / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(DatasetError, match=rf"another apartment or object catalogue \({len(meta['nodes'])} nodes, this "
                                           rf"apartment has {len(meta['nodes']) + 13}.*generate the dataset again"):
        occurrences(old)
    occurrences(one_day)  # the dataset of this apartment reads


def test_exclusions_name_outside_and_ungraspable_objects() -> None:
    out = Occurrence("keys", "bench", "outside", "household_a", 0, 400.0)
    assert exclusion_reason(out, "keys") == "outside the apartment (the robot stays in)"
    assert exclusion_reason(Occurrence("plate", "cupboard", "sink_dining_room", "h", 0, 1.0), "plate").startswith(
        "not graspable: 26 cm across")
    assert exclusion_reason(Occurrence("bowl", "cupboard", "sink_dining_room", "h", 0, 1.0), "bowl") is None


def test_the_start_state_is_looked_for_over_the_whole_day_before_the_move() -> None:
    # Household b's headset: taken from the desk at 09:10, worn at every snapshot until it was put on the pen at
    # 11:42. It rested on its source last after the person's action before they took it, 2.5 h before the move;
    # the day is lived again up to there and the world let come to rest before the robot acts.
    from planners.suites.relocation_suite import Bench, _Stop

    events = [(540.0, "sit at the desk"), (550.0, "take the headset"), (640.0, "walk"), (702.29, "put it down")]

    class Lived:
        def __init__(self) -> None:
            self.index, self.stopped, self.settled = -1, [], []
            self.world = SimpleNamespace(settle=lambda max_seconds: self.settled.append(self.index))

        def _on_source(self, occurrence: Occurrence) -> bool:
            return self.index == 0  # on the desk only until it is taken

        def _live(self, occurrence: Occurrence, day, after_action) -> None:
            try:
                for self.index in range(len(events)):
                    after_action(self.index, events)
            except _Stop:
                self.stopped.append(self.index)

    lived = Lived()
    headset = Occurrence("headset", "desk_home_office", "pen", "household_b", 1, 702.29)
    assert Bench._before_the_move(lived, headset, day=None) is None
    assert lived.stopped == [2, 0] and lived.settled == [0]  # watched up to the move, then lived to the action

    lived = Lived()
    never = Occurrence("headset", "desk_home_office", "pen", "household_b", 1, 535.0)  # before any action
    assert "after no action of the day before the move" in Bench._before_the_move(lived, never, day=None)


def test_displaced_lists_what_moved_beyond_the_limit(world: World) -> None:
    before = world.object_positions()
    name, other = world.object_names[:2]
    pos, quat = world.object_pose(name)
    world.set_object_pose(name, pos + np.array([MAX_DISPLACEMENT * 2, 0.0, 0.0]), quat)
    pos, quat = world.object_pose(other)
    world.set_object_pose(other, pos + np.array([0.0, MAX_DISPLACEMENT / 2, 0.0]), quat)
    found = displaced(world, before)
    assert [n for n, _ in found] == [name] and found[0][1] == pytest.approx(MAX_DISPLACEMENT * 2)
    assert displaced(world, before, skip={name}) == []
    assert collateral_reason(found) == f"collateral: moved {name} 4.0 cm"


def test_only_the_parts_a_destination_is_used_behind_are_opened(world: World) -> None:
    from homer_sim.home.spots import Spots
    from planners.skills.parts import parts_to_place

    spots, parts = Spots(world), {}
    for a in world.articulations.values():
        parts.setdefault(a.furniture, []).append(a.name)
    assert parts_to_place(world, spots, parts["dresser"], "dresser") == []  # used on its top
    assert parts_to_place(world, spots, parts["cupboard"], "cupboard") == ["cupboard/door"]
    for node in ("dining_room", "cd_player"):  # a floor, an object: nothing to open, no places to look up
        assert parts_to_place(world, spots, parts.get(node, []), node) == []


QUICK_OUTCOMES = {  # measured: each passes. The toilet roll fell out of the hand on the cabinet's open door, which
    # stands across the counter; it is set down, the door closed and picked again (`blocked_when_open`). The spoon,
    # picked from above off the table, fit the cupboard from no base pose: it is set down and picked again as shelves
    # take it
    "bowl: cupboard -> table_dining_room": "",
    "milk: table_dining_room -> fridge": "",
    "spoon: table_dining_room -> cupboard": "",
    "toilet_paper: bathroom_cabinet -> bathroom_counter": "",
    "drinking_glass: cupboard -> dishwasher": "",
    "towel: bathroom_counter -> shower": "",
}


@pytest.mark.physics
def test_quick_relocations_add_up_and_keep_their_outcomes(one_day: Path) -> None:
    result = run_relocations(one_day, quick=True, progress=False)
    assert result["tried"] == len(result["results"]) == len(QUICK_OUTCOMES)
    assert result["successes"] + sum(result["causes"].values()) == result["tried"]
    assert sum(e["tried"] for e in result["per_class"].values()) == result["tried"]
    # what else a relocation moved is listed whether or not a skill failed first; a success moved nothing else
    assert result["with_collateral"] == sum(bool(r["collateral"]) for r in result["results"])
    assert not any(r["success"] and r["collateral"] for r in result["results"])
    outcomes = {f"{r['obj']}: {r['source']} -> {r['destination']}": r["cause"] for r in result["results"]}
    assert outcomes == QUICK_OUTCOMES, [r["reason"] for r in result["results"] if not r["success"]]


@pytest.mark.slow
def test_full_relocation_suite_meets_its_targets() -> None:
    if not (FULL_DATA / "meta.json").is_file():
        pytest.skip(f"no 5-household dataset at {FULL_DATA} (set HOMER_SIM_RELOCATION_DATA)")
    result = run_relocations(FULL_DATA, progress=False)
    assert result["triples"] == result["tried"] + result["n_excluded"]
    assert result["overall"] >= TARGET_OVERALL, result["causes"]
    assert result["worst_class_rate"] >= TARGET_CLASS, result["per_class"]
