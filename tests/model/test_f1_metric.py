"""SLaTe-PRO's relocation F1 on hand-made sequences whose counts are worked out by hand.

Nodes: 0 kitchen (room), 1 table, 2 shelf, 3 cup, 4 book (cup and book movable). Lookahead: 3 steps here.
"""

from __future__ import annotations

import numpy as np
import pytest

from model.metrics import Queries, RelocationCounts, relocation_counts
from model.predictor import ModelError

MOVABLE = np.array([False, False, False, True, True])
ROOM, TABLE, SHELF, CUP, BOOK = range(5)
START = np.array([-1, ROOM, ROOM, SHELF, SHELF])  # both objects on the shelf at the query step


def _seq(cup: list[int], book: list[int]) -> np.ndarray:
    """Parents at t + 1 .. t + 3: Shape (1, 3, 5), furniture fixed."""
    return np.array([[-1, ROOM, ROOM, c, b] for c, b in zip(cup, book, strict=True)])[None]


def _counts(truth: tuple[list[int], list[int]], pred: tuple[list[int], list[int]], valid: int = 3) -> RelocationCounts:
    queries = Queries(START[None], np.array([600.0]), _seq(*truth), np.array([valid]))
    return relocation_counts(queries, _seq(*pred), MOVABLE, steps=3)


def _as_lists(counts: RelocationCounts) -> tuple[list[int], list[int], list[int]]:
    return counts.tp.tolist(), counts.fp.tolist(), counts.fn.tolist()


def test_each_step_compares_with_the_parent_at_query_time() -> None:
    # cup: truly to the table at t+2 and stays; predicted to the table from t+1.
    #   step 1: gt shelf = ref, pred table != gt, != ref -> FP.  steps 2, 3: pred = gt = table != ref -> TP.
    # book: stays, predicted to stay -> nothing.
    counts = _counts(([SHELF, TABLE, TABLE], [SHELF] * 3), ([TABLE] * 3, [SHELF] * 3))
    assert _as_lists(counts) == ([0, 1, 1], [1, 0, 0], [0, 0, 0])
    assert counts.f1().tolist() == [0.0, 1.0, 1.0]
    assert counts.summary() == {"per_step": [0.0, 1.0, 1.0], "mean": 0.6667, "tp": 2, "fp": 1, "fn": 0}


def test_a_move_to_the_wrong_place_is_a_false_positive_and_a_false_negative() -> None:
    # cup truly to the table at t+1; predicted to the kitchen floor: FP and FN at every step.
    # book truly stays; predicted to the table at t+3: one FP.  book missed nothing.
    counts = _counts(([TABLE] * 3, [SHELF] * 3), ([ROOM] * 3, [SHELF, SHELF, TABLE]))
    assert _as_lists(counts) == ([0, 0, 0], [1, 1, 2], [1, 1, 1])
    assert counts.f1().tolist() == [0.0, 0.0, 0.0]


def test_missed_moves_and_returns() -> None:
    # cup to the table at t+1, back on the shelf at t+3; predicted to stay: FN at steps 1, 2; at step 3 gt = ref.
    # book to the table at t+2, predicted at t+2: TP at steps 2, 3.
    counts = _counts(([TABLE, TABLE, SHELF], [SHELF, TABLE, TABLE]), ([SHELF] * 3, [SHELF, TABLE, TABLE]))
    assert _as_lists(counts) == ([0, 1, 1], [0, 0, 0], [1, 1, 0])
    # F1 = 2 TP / (2 TP + FP + FN): step 1 0/1, step 2 2/3, step 3 2/2.
    assert counts.f1() == pytest.approx([0.0, 2 / 3, 1.0])


def test_steps_past_the_end_of_the_day_do_not_count_and_counts_pool() -> None:
    # Only 1 valid future step: the wrong predictions at steps 2 and 3 are past the day's end.
    late = _counts(([TABLE] * 3, [SHELF] * 3), ([TABLE, ROOM, ROOM], [SHELF] * 3), valid=1)
    assert _as_lists(late) == ([1, 0, 0], [0, 0, 0], [0, 0, 0])
    pooled = late + _counts(([SHELF] * 3, [SHELF] * 3), ([SHELF] * 3, [TABLE] * 3))
    assert _as_lists(pooled) == ([1, 0, 0], [1, 1, 1], [0, 0, 0])
    assert pooled.f1() == pytest.approx([2 / 3, 0.0, 0.0])


def test_static_nodes_are_not_scored_and_steps_are_checked() -> None:
    queries = Queries(START[None], np.array([600.0]), _seq([SHELF] * 3, [SHELF] * 3), np.array([3]))
    moved_table = _seq([SHELF] * 3, [SHELF] * 3).copy()
    moved_table[..., TABLE] = SHELF  # a prediction that moves the (static) table is ignored
    assert _as_lists(relocation_counts(queries, moved_table, MOVABLE, steps=3)) == ([0, 0, 0],) * 3
    with pytest.raises(ModelError, match="lookahead steps"):
        relocation_counts(queries, moved_table, MOVABLE, steps=4)
