"""One predictor interface: fit on training days; step the per-node parent distribution 10 minutes ahead.

Every predictor works on dense per-node parent probabilities `probs`, Shape (B, N, N): row i is node i's
distribution over parents j. Rows of movable nodes put their mass on candidate parents only (every other node);
rows of static nodes are the one-hot of their fixed parent; rows of rooms are zero. `step` maps the probabilities
at one grid step to those at the next; `rollout` starts from an observed graph and feeds the probabilities back.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from homer_sim.data.dataset import GRID_MIN, DatasetMeta, Day
from homer_sim.errors import HomerError

THRESHOLDS = (0.0, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)  # decision-rule grid, see gate


class ModelError(HomerError):
    """A bad method name, parameter, checkpoint or training input."""


def candidate_mask(movable: np.ndarray) -> np.ndarray:
    """Shape (N, N) bool: True where j is a candidate parent of movable node i (every other node)."""
    movable = np.asarray(movable, dtype=bool)
    return movable[:, None] & ~np.eye(len(movable), dtype=bool)


def one_hot_parents(parent: np.ndarray, n_nodes: int) -> np.ndarray:
    """Parent indices, Shape (..., N) int (-1 for rooms) -> adjacency Shape (..., N, N) float32, rooms' rows zero."""
    parent = np.asarray(parent, dtype=np.int64)
    out = np.zeros((*parent.shape, n_nodes), dtype=np.float32)
    np.put_along_axis(out, np.maximum(parent, 0)[..., None], 1.0, axis=-1)
    out[parent < 0] = 0.0
    return out


@dataclass(frozen=True)
class Transitions:
    """Consecutive grid steps of training days: the graph at t and the parents at t + 1.

    parent: Shape (S, N) int, parents at step t. minute_next: Shape (S,) routine minute of step t + 1.
    target: Shape (S, N) int, parents at step t + 1.
    """

    parent: np.ndarray
    minute_next: np.ndarray
    target: np.ndarray

    def __len__(self) -> int:
        return len(self.minute_next)


def transitions(days: Sequence[Day]) -> Transitions:
    """All (graph at t, time of t + 1, parents at t + 1) triples of the given days."""
    if not days:
        raise ModelError("no days to learn from; give at least one training day")
    return Transitions(np.concatenate([d.parent[:-1] for d in days]).astype(np.int64),
                       np.concatenate([d.minutes[1:] for d in days]).astype(np.float32),
                       np.concatenate([d.parent[1:] for d in days]).astype(np.int64))


@dataclass(frozen=True)
class Rollout:
    """Per predicted step: the most likely parent, and the most likely parent other than the observed one.

    parent: Shape (S, B, N) int64, argmax of step s + 1's probabilities (static nodes keep their parent).
    confidence: Shape (S, B, N) float32, the probability of that parent.
    other: Shape (S, B, N) int64, the most likely parent other than the one observed at the query step.
    other_confidence: Shape (S, B, N) float32, its probability (0 for static nodes).
    other_margin: Shape (S, B, N) float32 or None: its margin over every other destination, for the decision rules
    where a wrong destination costs as much as a right one gains (model.metrics.gate); None: they use its
    probability. `analogs` gives it (model.analogs).
    """

    parent: np.ndarray
    confidence: np.ndarray
    other: np.ndarray
    other_confidence: np.ndarray
    other_margin: np.ndarray | None = None


def summarise_step(probs: np.ndarray, observed: np.ndarray) -> tuple[np.ndarray, ...]:
    """(argmax, its probability, best parent other than `observed`, its probability) of probs (B, N, N)."""
    masked = np.array(probs, copy=True)
    np.put_along_axis(masked, np.maximum(observed, 0)[..., None], -1.0, axis=-1)
    return probs.argmax(axis=-1), probs.max(axis=-1), masked.argmax(axis=-1), np.maximum(masked.max(axis=-1), 0.0)


class Predictor(ABC):
    """Base of every method. Subclasses define `fit` and `step`, and list tunable parameters with their grids.

    params: current values of the tunable parameters; `threshold` is the decision rule (model.metrics.gate):
    0 predicts the per-node argmax (the paper); t > 0 predicts a move to the most likely other parent once its
    probability reaches t (for t >= 0.5 that is the argmax, gated by its confidence). `act_steps` is the robot's
    rule, not the metrics': it acts on a predicted move only when the move's first step is within that many grid
    steps (0: the whole window); tuned for the assistance objective (model.evaluate).
    """

    method = "predictor"
    grid: dict[str, tuple[float, ...]] = {}
    cross_validated = False  # cheap to fit: tuned by leaving training days out in turn (model.evaluate.cv_folds)

    def __init__(self, meta: DatasetMeta, **params: float) -> None:
        self.meta = meta
        self.movable = meta.movable_mask
        self.candidates = candidate_mask(self.movable)
        self.params: dict[str, float] = {"threshold": 0.0, "act_steps": 0.0, **{k: v[0] for k, v in self.grid.items()}}
        self.set_params(**params)

    @property
    def n_nodes(self) -> int:
        return len(self.meta.nodes)

    def set_params(self, **params: float) -> None:
        """Set tunable parameters by name; raises ModelError naming an unknown one."""
        for name, value in params.items():
            if name not in self.params:
                raise ModelError(f"{self.method} has no parameter {name!r}; known: {', '.join(sorted(self.params))}")
            self.params[name] = float(value)

    @abstractmethod
    def fit(self, fit_days: Sequence[Day], val_days: Sequence[Day]) -> None:
        """Learn from `fit_days`; `val_days` only for early stopping (tuning happens in model.evaluate)."""

    @abstractmethod
    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        """Parent probabilities at the next grid step.

        probs: Shape (B, N, N) float32, this step's probabilities (one-hot rows for an observed graph).
        minute: Shape (B,) routine minute of the step being predicted.
        Returns: Shape (B, N, N) float32, movable rows summing to 1 over candidates, other rows unchanged.
        """

    def rollout(self, parent: np.ndarray, minute: np.ndarray, steps: int) -> Rollout:
        """Predict `steps` grid steps ahead of the observed graphs, feeding the probabilities back.

        parent: Shape (B, N) int, observed parents (-1 for rooms). minute: Shape (B,) routine minute observed.
        """
        probs = one_hot_parents(parent, self.n_nodes)
        minute = np.asarray(minute, dtype=np.float32)
        steps_out = []
        for s in range(1, steps + 1):
            probs = self.step(probs, minute + GRID_MIN * s)
            steps_out.append(summarise_step(probs, parent))
        return self._finish(parent, steps_out)

    def _finish(self, parent: np.ndarray, steps_out: list[tuple[np.ndarray, ...]]) -> Rollout:
        """Stack per-step summaries (see summarise_step); static nodes keep their observed parent."""
        best, confidence, other, other_confidence = (np.stack(part) for part in zip(*steps_out, strict=True))
        observed = np.broadcast_to(np.asarray(parent, dtype=np.int64)[None], best.shape)
        static = np.broadcast_to(~self.movable, best.shape)
        return Rollout(np.where(static, observed, best).astype(np.int64), confidence.astype(np.float32),
                       np.where(static, observed, other).astype(np.int64),
                       np.where(static, 0.0, other_confidence).astype(np.float32))

    def state(self) -> dict[str, np.ndarray]:
        """Arrays that, with `params`, rebuild the fitted predictor (see model.methods.save_predictor)."""
        return {}

    def load_state(self, arrays: dict[str, np.ndarray]) -> None:  # noqa: B027 (optional hook, empty by default)
        """Restore what `state` returned."""
