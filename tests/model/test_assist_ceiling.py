"""The counting of benchmarks/assist_ceiling.py (the most fetches any decision rule could make ahead), hand-worked."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

from benchmarks.assist_ceiling import best_combination, grid_fetches
from homer_sim.data.dataset import Day

ROOM, SHELF, TABLE = 0, 1, 2  # node 3 is the one movable object; node 4 an object standing on the shelf, not movable
MOVABLE = np.array([False, False, False, True, False])
IS_ROOM = np.array([True, False, False, False, False])


def test_a_fetch_is_a_move_of_a_movable_object_onto_a_node_that_is_not_a_room() -> None:
    # the cup: shelf, table (a fetch), table, the room's floor (not one), shelf (a fetch); the other object moves too
    cup = [SHELF, TABLE, TABLE, ROOM, SHELF]
    other = [SHELF, TABLE, SHELF, SHELF, SHELF]
    parent = np.array([[-1, ROOM, ROOM, c, o] for c, o in zip(cup, other, strict=True)])
    day = Day("h", "test", 0, np.arange(5, dtype=float) * 10 + 600, parent, np.ones_like(parent, dtype=np.int8))
    assert grid_fetches([day, day], MOVABLE, IS_ROOM) == 4


def test_the_best_rule_per_household_keeps_all_wrong_relocations_within_the_limit() -> None:
    a = {(0.0, 1): (10, 9), (0.1, 1): (20, 15)}  # (relocations, correct) of each rule
    b = {(0.0, 1): (10, 10), (0.1, 1): (30, 29)}
    # a's 20 with b's 30: 44 correct but 6 of 50 wrong (12%); a's 10 with b's 30: 38 correct, 2 of 40 wrong (5%)
    assert best_combination([a, b], 10.0) == (40, 38)
    assert best_combination([a, b], 15.0) == (50, 44)
    assert best_combination([a], 0.0) == (0, 0)  # nothing without a wrong one, but doing nothing is allowed


def test_the_script_explains_itself_and_refuses_a_folder_that_is_no_dataset(tmp_path) -> None:
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "assist_ceiling.py"
    shown = subprocess.run([sys.executable, str(script), "--help"], capture_output=True, text=True, check=False)
    assert shown.returncode == 0 and "--full-grid" in shown.stdout
    refused = subprocess.run([sys.executable, str(script), "--data", str(tmp_path)], capture_output=True, text=True,
                             check=False)
    assert refused.returncode == 1 and "not a homer-sim dataset" in refused.stderr
    assert "Traceback" not in refused.stderr
