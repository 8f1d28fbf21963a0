"""The paper's relocation metrics for a proactivity window (its "Metrics" section).

A query is a grid step t of a test day: the observed graph at t and what truly happens at t + 1 .. t + K.
For a window of w steps, an object is *used* when its true parent changes within (t, t + w]. Only the first
change counts, for truth and prediction alike, compared with the parent observed at t. Used objects are
*correct* (first predicted destination = first true destination, both inside the window), *wrong* (a predicted
move to another destination) or *missed* (no predicted move). Unused objects are *correct* (no predicted move)
or *wrong* (a predicted move). Near the end of a day the window is cut at the day's last step, for truth and
prediction alike; the last step of a day is no query. Percentages are per household.

SLaTe-PRO's relocation F1 (the metric published on HOMER+): for each query t, lookahead step s = 1 .. 6 (10 .. 60
minutes) that lies inside the day, and movable object o, with ref = o's parent at t, pred = the predicted parent at
t + s and gt = the true parent at t + s: a true positive if pred == gt != ref; a false positive if pred != gt and
pred != ref; a false negative if pred != gt and gt != ref (a wrong predicted move is both). Counts are pooled over
all queries of a household, per step; F1 = 2 TP / (2 TP + FP + FN), 0 when nothing moved or was predicted to.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

from homer_sim.data.dataset import Day
from model.predictor import ModelError, Rollout


@dataclass(frozen=True)
class Queries:
    """Every grid step of some days (but each day's last) as a query.

    observed: Shape (Q, N) int, parents at the query step t. minute: Shape (Q,) routine minute of t.
    future: Shape (Q, K, N) int, true parents at t + 1 .. t + K (the day's last step repeated past its end).
    valid: Shape (Q,) int, how many of the K future steps exist in the day (K, or fewer near its end).
    """

    observed: np.ndarray
    minute: np.ndarray
    future: np.ndarray
    valid: np.ndarray

    def __len__(self) -> int:
        return len(self.minute)


def day_queries(days: Sequence[Day], steps: int) -> Queries:
    """Queries at every step but the last of each day, with `steps` future steps each."""
    observed, minute, future, valid = [], [], [], []
    for day in days:
        t = np.arange(day.steps - 1)
        ahead = np.minimum(t[:, None] + 1 + np.arange(steps)[None], day.steps - 1)  # (T - 1, K)
        observed.append(day.parent[:-1])
        minute.append(day.minutes[:-1])
        future.append(day.parent[ahead])
        valid.append(np.minimum(steps, day.steps - 1 - t))
    if not observed:
        raise ModelError("no days to query; give at least one day with two or more grid steps")
    return Queries(np.concatenate(observed).astype(np.int64), np.concatenate(minute).astype(np.float32),
                   np.concatenate(future).astype(np.int64), np.concatenate(valid).astype(np.int64))


def gate(rollout: Rollout, observed: np.ndarray, threshold: float, margin: bool = False) -> np.ndarray:
    """The decision rule: predicted parents (Q, S, N) from a rollout of Shape (S, Q, N).

    threshold 0: the per-node argmax of each step (the paper). threshold t > 0: a node is predicted to move to the
    most likely parent other than the observed one once that parent's probability reaches t, else to stay; for
    t >= 0.5 this is the argmax, counted only when its probability reaches t. observed: Shape (Q, N). margin: where
    a wrong destination costs as much as a right one gains (the paper's objective and the robot's; not F1, where a
    wrong destination only adds a false positive to a miss), t applies to the rollout's `other_margin` instead, if
    it has one: the expected gain of acting on the move.
    """
    observed = np.asarray(observed)[None]
    if threshold <= 0.0:
        gated = rollout.parent
    else:
        confidence = rollout.other_margin if margin and rollout.other_margin is not None else rollout.other_confidence
        gated = np.where(confidence >= threshold, rollout.other, observed)
    return np.transpose(gated, (1, 0, 2))


def first_change(observed: np.ndarray, sequence: np.ndarray, steps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Whether and where each node first leaves its observed parent within its first `steps` steps.

    observed: (Q, N); sequence: (Q, K, N) parents at t + 1 .. t + K; steps: (Q,) steps that count.
    Returns changed (Q, N) bool and destination (Q, N) int (-1 where unchanged).
    """
    counted = np.arange(sequence.shape[1])[None, :] < np.asarray(steps)[:, None]  # (Q, K)
    differs = (sequence != observed[:, None, :]) & counted[:, :, None]
    changed = differs.any(axis=1)
    first = differs.argmax(axis=1)
    destination = np.take_along_axis(sequence, first[:, None, :], axis=1)[:, 0]
    return changed, np.where(changed, destination, -1)


@dataclass(frozen=True)
class Counts:
    """Object-queries in each outcome (integers), summed over queries."""

    used_correct: int = 0
    used_wrong: int = 0
    used_missed: int = 0
    unused_correct: int = 0
    unused_wrong: int = 0

    def __add__(self, other: Counts) -> Counts:
        return Counts(*(getattr(self, f.name) + getattr(other, f.name) for f in fields(self)))

    @property
    def used(self) -> int:
        return self.used_correct + self.used_wrong + self.used_missed

    @property
    def unused(self) -> int:
        return self.unused_correct + self.unused_wrong

    def objective(self) -> float:
        """The tuning objective, the same for every method: used correct % - used wrong % - unused wrong %.

        Each reported percentage weighs the same, so moving 1% of the unused objects costs as much as getting 1% of
        the used ones wrong (a count-based sum would let the far larger unused pool silence every baseline).
        """
        used = 100.0 * (self.used_correct - self.used_wrong) / self.used if self.used else 0.0
        return used - (100.0 * self.unused_wrong / self.unused if self.unused else 0.0)

    def percentages(self) -> dict[str, dict[str, float]]:
        """{"used": {"correct", "wrong", "missed"}, "unused": {"correct", "wrong"}} in 0..100 (NaN if no objects)."""
        def pct(part: int, whole: int) -> float:
            return 100.0 * part / whole if whole else float("nan")
        return {"used": {"correct": pct(self.used_correct, self.used), "wrong": pct(self.used_wrong, self.used),
                         "missed": pct(self.used_missed, self.used)},
                "unused": {"correct": pct(self.unused_correct, self.unused),
                           "wrong": pct(self.unused_wrong, self.unused)}}


def score(queries: Queries, predicted: np.ndarray, window_steps: int, movable: np.ndarray,
          pool: np.ndarray | None = None) -> Counts:
    """Count outcomes of predicted parents (Q, K', N), K' >= window_steps, against the truth.

    movable: (N,) bool, the objects scored. pool: (N,) bool, the objects counted among the unused ones
    (default: every movable node).
    """
    if window_steps < 1 or window_steps > min(predicted.shape[1], queries.future.shape[1]):
        raise ModelError(f"window of {window_steps} steps; predictions and truth cover 1..{predicted.shape[1]}")
    steps = np.minimum(queries.valid, window_steps)
    true_moved, true_dest = first_change(queries.observed, queries.future, steps)
    pred_moved, pred_dest = first_change(queries.observed, predicted, steps)
    movable = np.asarray(movable, dtype=bool)[None]
    pool = movable if pool is None else (np.asarray(pool, dtype=bool)[None] & movable)
    used, unused = true_moved & movable, ~true_moved & pool
    right = pred_moved & (pred_dest == true_dest)
    return Counts(int((used & right).sum()), int((used & pred_moved & ~right).sum()), int((used & ~pred_moved).sum()),
                  int((unused & ~pred_moved).sum()), int((unused & pred_moved).sum()))


F1_STEPS = 6  # SLaTe-PRO's lookahead steps, 10 .. 60 minutes


@dataclass(frozen=True)
class RelocationCounts:
    """SLaTe-PRO's pooled counts per lookahead step: tp, fp, fn Shape (S,) int."""

    tp: np.ndarray
    fp: np.ndarray
    fn: np.ndarray

    def __add__(self, other: RelocationCounts) -> RelocationCounts:
        return RelocationCounts(self.tp + other.tp, self.fp + other.fp, self.fn + other.fn)

    def f1(self) -> np.ndarray:
        """Shape (S,) float: F1 per step, 0 where a step has no true and no predicted relocation."""
        denominator = 2 * self.tp + self.fp + self.fn
        return np.where(denominator > 0, 2 * self.tp / np.maximum(denominator, 1), 0.0)

    def summary(self) -> dict:
        """{"per_step": F1 per step, "mean": their mean, "tp", "fp", "fn": summed over steps} (plain numbers)."""
        f1 = self.f1()
        return {"per_step": [round(float(v), 4) for v in f1], "mean": round(float(f1.mean()), 4),
                "tp": int(self.tp.sum()), "fp": int(self.fp.sum()), "fn": int(self.fn.sum())}


def relocation_counts(queries: Queries, predicted: np.ndarray, movable: np.ndarray,
                      steps: int = F1_STEPS) -> RelocationCounts:
    """SLaTe-PRO's TP/FP/FN of predicted parents (Q, K', N), K' >= steps, pooled per lookahead step.

    Steps past a day's last grid step (queries.valid) do not count. movable: (N,) bool, the objects scored.
    """
    if steps < 1 or steps > min(predicted.shape[1], queries.future.shape[1]):
        raise ModelError(f"{steps} lookahead steps; predictions and truth cover 1..{predicted.shape[1]}")
    ref = queries.observed[:, None, :]
    gt, pred = queries.future[:, :steps], np.asarray(predicted)[:, :steps]
    counted = (np.arange(steps)[None, :] < queries.valid[:, None])[:, :, None] & np.asarray(movable, bool)[None, None]
    wrong = pred != gt

    def pooled(mask: np.ndarray) -> np.ndarray:
        return (mask & counted).sum(axis=(0, 2)).astype(np.int64)

    return RelocationCounts(pooled(~wrong & (gt != ref)), pooled(wrong & (pred != ref)), pooled(wrong & (gt != ref)))


def window_steps(window_min: int, grid_min: int) -> int:
    """Minutes -> grid steps; the window must be a positive multiple of the grid."""
    if window_min <= 0 or window_min % grid_min:
        raise ModelError(f"window of {window_min} min; use a positive multiple of {grid_min} min (10, 20, ..., 120)")
    return window_min // grid_min


@dataclass(frozen=True)
class RobotCounts:
    """What a robot acting on gated predictions does over validation days (`robot_counts`): relocations it makes
    and of them the correct ones (the person's first move of the object within the window goes there: a fetch made
    ahead); `put_back`, the unused help it takes back (counted among the relocations, never correct)."""

    relocations: int = 0
    correct: int = 0
    put_back: int = 0

    @property
    def wrong(self) -> int:
        return self.relocations - self.correct

    def assistance(self) -> int:
        """Fetches made ahead minus wrong moves (put-backs of unused help included)."""
        return self.correct - self.wrong

    def __add__(self, other: RobotCounts) -> RobotCounts:
        return RobotCounts(self.relocations + other.relocations, self.correct + other.correct,
                           self.put_back + other.put_back)


def roots(parent: np.ndarray) -> np.ndarray:
    """The root (room, or `outside`) above each node of parent arrays of Shape (..., N) (roots have parent -1)."""
    parent = np.asarray(parent)
    root = np.broadcast_to(np.arange(parent.shape[-1]), parent.shape).copy()
    while True:
        up = np.take_along_axis(parent, root, axis=-1)
        if (up < 0).all():
            return root
        root = np.where(up >= 0, up, root)


def robot_counts(queries: Queries, predicted: np.ndarray, window_steps: int, movable: np.ndarray,
                 act_steps: int, outside: int = -1) -> RobotCounts:
    """Replay the assisted robot's decisions on queries of whole days in order (the grid steps of each day, a day
    starting where the minute does not increase), against the days themselves (the person's moves as they were).

    At each query the robot moves every movable object whose first predicted move (predicted: Shape (Q, K', N)
    parents) comes within `act_steps` steps, to that destination, unless it holds the object: what it moved stays
    `window_steps` steps for the person (a hold) and is released when the person moves it or the window has
    passed; then, unused, it goes back to where it came from (a relocation, and a wrong one) and is not moved
    again until the person moves it. The predictor is queried on the day's own arrangement, i.e. with held
    objects where they would be without the robot (as the robot queries it, `scenarios.policies.PsiPolicy`). A
    relocation is correct when the object's first true move within `window_steps` steps goes to its destination
    (`scenarios.scoring`). Nothing is taken to or from the root `outside` (its node index, -1 if none: the robot
    stays in the apartment), nor from or to where the person is: the days hold no positions, so the person is taken
    to be at the places (old and new parents) of their latest moves, for `window_steps` steps after them (eating
    at the table they laid, the robot may not clear it: `scenarios.psi.psi`'s in_use). Without this the replay
    credits the predictor's surest moves, the person clearing up where they sit, which the robot never makes."""
    return RobotReplay(queries, window_steps, movable, outside).counts(predicted, (act_steps,))[0]


def first_steps(observed: np.ndarray, sequence: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The step at which each node first leaves its observed parent, and where to: `first_change` for every count
    of steps at once (a node changed within its first c steps where first < c, and then to destination).

    observed: (Q, N); sequence: (Q, K, N). Returns first (Q, N) int (K where it never leaves) and destination
    (Q, N) int (its parent at that step; any value where it never leaves)."""
    differs = sequence != observed[:, None, :]
    first = differs.argmax(axis=1)
    destination = np.take_along_axis(sequence, first[:, None, :], axis=1)[:, 0]
    return np.where(differs.any(axis=1), first, sequence.shape[1]), destination


class RobotReplay:
    """`robot_counts` on fixed queries for many predictions and act_steps (a tuning grid): what depends only on the
    queries (the true first moves, the roots, the person's moves) is found once."""

    def __init__(self, queries: Queries, window_steps: int, movable: np.ndarray, outside: int = -1) -> None:
        self.observed, self.window_steps, self.outside = queries.observed, window_steps, outside
        self.rows = queries.observed.tolist()  # (Q, N) as lists, for `_replay`'s walk
        self.steps = np.minimum(queries.valid, window_steps)
        true_moved, true_dest = first_change(queries.observed, queries.future, self.steps)
        self.truth = np.where(true_moved, true_dest, -2).tolist()  # (Q, N): the first true move's place, else -2
        self.movable = np.asarray(movable, dtype=bool)
        self.root = roots(queries.observed) if outside >= 0 else None
        starts = np.r_[True, np.diff(queries.minute) <= 0]
        changed = np.zeros(queries.observed.shape, dtype=bool)  # (Q, N): moved since the previous query of the day
        changed[1:] = (queries.observed[1:] != queries.observed[:-1]) & self.movable[None] & ~starts[1:, None]
        self.starts = starts.tolist()
        self.person_at: list[set[int]] = []  # per query: where the person is taken to be (see `robot_counts`)
        near: set[int] = set()  # the places of the person's latest moves
        latest = -window_steps - 1  # the query those moves were seen at
        for i, moved in enumerate(changed):
            if starts[i]:
                near, latest = set(), i - window_steps - 1
            if moved.any():
                near = set(queries.observed[i - 1][moved].tolist()) | set(queries.observed[i][moved].tolist())
                latest = i
            self.person_at.append(near if i - latest < window_steps else set())

    def counts(self, predicted: np.ndarray, act_steps: Sequence[int]) -> list[RobotCounts]:
        """RobotCounts of `predicted` (Shape (Q, K', N) parents) for each of `act_steps`."""
        return [sum(days, RobotCounts()) for days in self.day_counts(predicted, act_steps)]

    def day_counts(self, predicted: np.ndarray, act_steps: Sequence[int]) -> list[list[RobotCounts]]:
        """RobotCounts of `predicted` (Shape (Q, K', N) parents) for each of `act_steps`, one per day of the
        queries, in order."""
        first, destination = first_steps(self.observed, predicted)
        allowed = np.broadcast_to(self.movable[None], first.shape)
        if self.root is not None:
            allowed = allowed & (self.root != self.outside) & (
                np.take_along_axis(self.root, np.clip(destination, 0, None), axis=1) != self.outside)
        results = []
        for k in act_steps:
            moved = first < np.minimum(self.steps, k)[:, None]
            results.append(self._replay(moved & allowed, destination))
        return results

    def _replay(self, pred_moved: np.ndarray, pred_dest: np.ndarray) -> list[RobotCounts]:
        """The robot's decisions over the queries in order (see `robot_counts`): it acts on the objects of
        pred_moved (Q, N) bool, each to its place in pred_dest (Q, N); the counts of each day."""
        window_steps, person_at = self.window_steps, self.person_at
        queried, objects = np.nonzero(pred_moved)  # row-major: by query, then object
        places = pred_dest[queried, objects].tolist()
        bounds = np.searchsorted(queried, np.arange(len(pred_moved) + 1)).tolist()
        objects = objects.tolist()
        days: list[RobotCounts] = []
        relocations = correct = put_back = 0
        held: dict[int, tuple[int, int]] = {}  # object -> (query it was moved at, where it came from)
        unwanted: dict[int, int] = {}  # object -> where its unused help went back to
        for i, observed in enumerate(self.rows):
            if self.starts[i]:
                if i:
                    days.append(RobotCounts(relocations, int(correct), put_back))
                relocations = correct = put_back = 0
                held, unwanted = {}, {}
            for o, (since, source) in list(held.items()):
                if observed[o] != source:  # the person moved it: the hold ends
                    del held[o]
                elif i - since > window_steps:  # unused: back to its source
                    del held[o]
                    relocations += 1  # never correct: the person's next move is away from where it lies
                    put_back += 1
                    unwanted[o] = source
            if unwanted:
                unwanted = {o: p for o, p in unwanted.items() if observed[o] == p}
            truth = self.truth[i]
            for j in range(bounds[i], bounds[i + 1]):
                o, place = objects[j], places[j]
                if o in held or o in unwanted or observed[o] in person_at[i] or place in person_at[i]:
                    continue
                relocations += 1
                correct += truth[o] == place
                held[o] = (i, observed[o])
        return days + [RobotCounts(relocations, int(correct), put_back)]
