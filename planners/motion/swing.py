"""A joint-space way for the torso and arm between two configurations, the base held, where the straight swing
between them touches something: RRT-Connect (Kuffner and LaValle, 2000) over the joints' ranges, then shortened
by shortcuts. Every leg is checked by the caller's `clear(q_from, q_to)` (see `Arm.swing_clear`)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

SWING_SAMPLES = 400  # random configurations drawn at most before a way counts as not found
SWING_REACH = 0.3  # largest joint change (rad, m for the torso) of one step towards a drawn configuration
SHORTCUTS = 40  # pairs of a found way's waypoints tried for a straight swing between them


def plan_swing(q_from: np.ndarray, q_to: np.ndarray, clear: Callable[[np.ndarray, np.ndarray], bool],
               lower: np.ndarray, upper: np.ndarray, joints: slice, seed: int = 0) -> list[np.ndarray] | None:
    """The waypoints (configurations, each shape like q_from) strictly between q_from and q_to of a way whose
    every leg `clear` accepts, drawn in the joints `joints` of q within [`lower`, `upper`] (their ranges, shape
    of those joints), the other entries at q_to's; None where SWING_SAMPLES draws found none. Deterministic for
    a `seed`."""
    rng = np.random.default_rng(seed)
    start, goal = q_to.copy(), q_to.copy()
    start[joints] = q_from[joints]
    trees = ([start], [0]), ([goal], [0])  # (nodes, parent indices) grown from each end
    for _ in range(SWING_SAMPLES):
        drawn = q_to.copy()
        drawn[joints] = rng.uniform(lower, upper)
        grown = _extend(trees[0], drawn, clear, joints)
        if grown is not None:
            met = _connect(trees[1], trees[0][0][grown], clear, joints)
            if met is not None:
                way = _way(trees[0], grown)[::-1] + _way(trees[1], met)[1:]
                if trees[0][0][0] is goal:
                    way = way[::-1]
                return _shortcut(way, clear, rng)[1:-1]
        trees = trees[1], trees[0]
    return None


def _extend(tree, towards: np.ndarray, clear, joints: slice) -> int | None:
    """Grow `tree` one step of at most SWING_REACH from its node nearest `towards`; the new node's index, or
    None where that step is not clear."""
    nodes, parents = tree
    nearest = int(np.argmin([np.max(np.abs(n[joints] - towards[joints])) for n in nodes]))
    step = towards - nodes[nearest]
    span = float(np.max(np.abs(step[joints])))
    new = nodes[nearest] + step * min(1.0, SWING_REACH / span) if span > 0 else towards.copy()
    if not clear(nodes[nearest], new):
        return None
    nodes.append(new)
    parents.append(nearest)
    return len(nodes) - 1


def _connect(tree, towards: np.ndarray, clear, joints: slice) -> int | None:
    """Grow `tree` step after step towards `towards` until it reaches it (its index then) or a step is not
    clear (None)."""
    while True:
        index = _extend(tree, towards, clear, joints)
        if index is None:
            return None
        if np.max(np.abs(tree[0][index][joints] - towards[joints])) < 1e-9:
            return index


def _way(tree, index: int) -> list[np.ndarray]:
    """The nodes from `tree`'s node `index` back to its root."""
    nodes, parents = tree
    way = [nodes[index]]
    while index:
        index = parents[index]
        way.append(nodes[index])
    return way


def _shortcut(way: list[np.ndarray], clear, rng: np.random.Generator) -> list[np.ndarray]:
    """`way` with the waypoints between pairs drawn SHORTCUTS times dropped where the straight swing between the
    pair is clear."""
    for _ in range(SHORTCUTS):
        if len(way) < 3:
            break
        i, j = sorted(rng.choice(len(way), size=2, replace=False))
        if j - i > 1 and clear(way[i], way[j]):
            way = way[:i + 1] + way[j:]
    return way
