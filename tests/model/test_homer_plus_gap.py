"""The SLaTe-PRO code's first-change counting in benchmarks/homer_plus_gnn_gap.py, on hand-worked sequences."""

from __future__ import annotations

import numpy as np

from benchmarks.homer_plus_gnn_gap import first_change_counts, upstream_rows
from homer_sim.data.dataset import Day
from model.metrics import Queries, relocation_counts

A, B, C = 1, 2, 3  # parents of node 0, the only movable node; nodes 1..3 are rooms (-1)
MOVABLE = np.array([True, False, False, False])


def one_query(future_parents: list[int]) -> Queries:
    """Node 0 observed on A at t; `future_parents` its true parents at t + 1 .. t + 6."""
    future = np.full((1, 6, 4), -1)
    future[0, :, 0] = future_parents
    return Queries(np.array([[A, -1, -1, -1]]), np.array([600.0], np.float32), future, np.array([6]))


def predicted(parents: list[int]) -> np.ndarray:
    out = np.full((1, 6, 4), -1)
    out[0, :, 0] = parents
    return out


def test_taken_out_and_put_back_counts_on_every_step_by_first_change_but_once_by_state() -> None:
    queries = one_query([B, A, A, A, A, A])  # moved to B, back on A ten minutes later
    stays = predicted([A] * 6)
    assert relocation_counts(queries, stays, MOVABLE).fn.tolist() == [1, 0, 0, 0, 0, 0]
    counts = first_change_counts(queries, stays, MOVABLE)
    assert counts.fn.tolist() == [1] * 6 and counts.tp.sum() == counts.fp.sum() == 0
    right = first_change_counts(queries, predicted([B, A, A, A, A, A]), MOVABLE)
    assert right.tp.tolist() == [1] * 6 and right.fp.sum() == right.fn.sum() == 0


def test_a_late_wrong_move_is_a_false_positive_from_its_step_and_the_first_true_move_stays_missed() -> None:
    queries = one_query([B, A, A, A, A, A])
    late = predicted([A, A, C, C, C, C])
    state = relocation_counts(queries, late, MOVABLE)
    assert state.fn.tolist() == [1, 0, 0, 0, 0, 0] and state.fp.tolist() == [0, 0, 1, 1, 1, 1]
    first = first_change_counts(queries, late, MOVABLE)
    assert first.fn.tolist() == [1] * 6 and first.fp.tolist() == [0, 0, 1, 1, 1, 1] and first.tp.sum() == 0


def test_steps_past_the_day_do_not_count_and_upstream_queries_skip_the_first_and_the_last_six_steps() -> None:
    queries = one_query([B] * 6)
    short = Queries(queries.observed, queries.minute, queries.future, np.array([2]))
    assert first_change_counts(short, predicted([A] * 6), MOVABLE).fn.tolist() == [1, 1, 0, 0, 0, 0]
    day = Day("h", "test", 0, np.arange(10, dtype=float) * 10 + 360, np.zeros((10, 4), dtype=np.int64),
              np.zeros((10, 4), dtype=np.int64))
    assert upstream_rows([day]).tolist() == [False, True, True, True] + [False] * 5
