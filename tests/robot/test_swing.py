"""`plan_swing`: a joint-space way round what a straight swing would touch, every leg checked."""

from __future__ import annotations

import numpy as np

from planners.motion.swing import plan_swing

JOINTS = slice(1, 3)  # two planned joints; entry 0 (a base coordinate) stays at the goal's


def _wall_clear(a: np.ndarray, b: np.ndarray, step: float = 0.01) -> bool:
    """A leg is clear where none of its points (every `step`) lies in the wall 0.4 < x < 0.6, |y| < 0.8 of the
    planned joints (x, y), which blocks the straight way from (0, 0) to (1, 0) but leaves room round its ends."""
    n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
    for s in np.linspace(0.0, 1.0, n + 1):
        x, y = (a + s * (b - a))[JOINTS]
        if 0.4 < x < 0.6 and abs(y) < 0.8:
            return False
    return True


def test_a_way_round_a_wall_is_found_with_every_leg_clear() -> None:
    q_from, q_to = np.array([5.0, 0.0, 0.0]), np.array([7.0, 1.0, 0.0])
    assert not _wall_clear(q_from, q_to)
    lower, upper = np.array([-1.0, -1.0]), np.array([2.0, 1.0])
    via = plan_swing(q_from, q_to, _wall_clear, lower, upper, JOINTS)
    assert via, "no way found round the wall"
    start = q_to.copy()
    start[JOINTS] = q_from[JOINTS]  # the base entries are the goal's all the way
    way = [start, *via, q_to]
    assert all(_wall_clear(a, b) for a, b in zip(way[:-1], way[1:], strict=True))
    assert all(q[0] == 7.0 for q in via)
    assert all(np.all(lower <= q[JOINTS]) and np.all(q[JOINTS] <= upper) for q in via)
    assert plan_swing(q_from, q_to, _wall_clear, lower, upper, JOINTS) is not None  # deterministic for a seed
    assert all(np.array_equal(a, b) for a, b in zip(via, plan_swing(q_from, q_to, _wall_clear, lower, upper,
                                                                    JOINTS), strict=True))


def test_no_way_is_made_up_where_the_wall_closes_the_ranges() -> None:
    q_from, q_to = np.array([0.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    closed = np.array([-1.0, -0.7]), np.array([2.0, 0.7])  # the wall spans every y the ranges allow
    assert plan_swing(q_from, q_to, _wall_clear, *closed, JOINTS) is None
