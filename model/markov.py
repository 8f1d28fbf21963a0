"""The extra baseline: a per-object Markov chain over parents, conditioned on the time of day.

For each movable object i and parent l it has been seen on, the next parent l' is drawn with probability
    T_i(l -> l' | t) = (c_i(l, l', t) + a [l' = l]) / (sum_l'' c_i(l, l'', t) + a),
where c counts training transitions whose target minute is near t (a Gaussian kernel of width `sigma_min` over
the circular day) and `a` (`stay_prior`) is a pseudo-count for staying. Parents never seen for an object keep
it in place. Probabilities are propagated exactly: P'(l') = sum_l P(l) T(l -> l'). Objects are independent,
so the chain cannot use one object's move as a cue for another's (the graph network can).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from homer_sim.clock import MINUTES_PER_DAY
from homer_sim.data.dataset import GRID_MIN, DatasetMeta, Day
from model.predictor import THRESHOLDS, Predictor, transitions

SLOTS = MINUTES_PER_DAY // GRID_MIN  # 144 ten-minute slots per day


class TimedMarkov(Predictor):
    """Per-object, time-of-day Markov chain; tunables: kernel width, stay pseudo-count, confidence threshold."""

    method = "markov"
    cross_validated = True
    grid = {"threshold": THRESHOLDS, "sigma_min": (30.0, 10.0, 20.0, 60.0, 120.0),
            "stay_prior": (1.0, 0.25, 4.0)}

    def __init__(self, meta: DatasetMeta, **params: float) -> None:
        self.triples = np.zeros((0, 3), dtype=np.int64)  # (U, 3): object node index, from, to
        self.counts = np.zeros((0, SLOTS))  # (U, SLOTS) transitions per target slot
        self._table: np.ndarray | None = None
        super().__init__(meta, **params)

    def set_params(self, **params: float) -> None:
        super().set_params(**params)
        self._table = None

    def fit(self, fit_days: Sequence[Day], val_days: Sequence[Day]) -> None:
        """Count (object, from, to, target slot) transitions; add a zero-count stay triple for every (object, from)."""
        data = transitions(fit_days)
        rows = np.flatnonzero(self.movable)
        self.count(data.parent[:, rows], data.target[:, rows], data.minute_next)

    def count(self, parent: np.ndarray, target: np.ndarray, minute_next: np.ndarray) -> None:
        """Fit on transitions of the movable objects: parent and target Shape (S, M) (columns in node order of the
        movable objects), minute_next Shape (S,) the minute of each target."""
        rows = np.flatnonzero(self.movable)
        obj = np.broadcast_to(rows, parent.shape).ravel()
        src, dst = np.asarray(parent, dtype=np.int64).ravel(), np.asarray(target, dtype=np.int64).ravel()
        slot = np.repeat(self._slot(minute_next), len(rows))
        stay = np.unique(np.stack([obj, src], axis=1), axis=0)
        keys = np.concatenate([np.stack([obj, src, dst], axis=1), np.column_stack([stay, stay[:, 1]])])
        self.triples, inverse = np.unique(keys, axis=0, return_inverse=True)
        self.counts = np.zeros((len(self.triples), SLOTS))
        np.add.at(self.counts, (inverse[:len(obj)], slot), 1.0)
        self._table = None

    @staticmethod
    def _slot(minute: np.ndarray) -> np.ndarray:
        return np.round(np.asarray(minute, dtype=np.float64) / GRID_MIN).astype(np.int64) % SLOTS

    def table(self) -> np.ndarray:
        """Transition probability of each triple at each target slot: (SLOTS, U)."""
        if self._table is None:
            lag = np.minimum(np.arange(SLOTS), SLOTS - np.arange(SLOTS)) * GRID_MIN
            kernel = np.exp(-0.5 * (lag / self.params["sigma_min"]) ** 2)
            smooth = np.real(np.fft.ifft(np.fft.fft(self.counts, axis=1) * np.fft.fft(kernel)[None], axis=1))
            smooth = np.maximum(smooth, 0.0) + self.params["stay_prior"] * (self.triples[:, 1] == self.triples[:, 2])[
                :, None]
            _, group = np.unique(self.triples[:, :2], axis=0, return_inverse=True)
            totals = np.zeros((group.max() + 1 if len(group) else 0, SLOTS))
            np.add.at(totals, group, smooth)
            self._table = (smooth / totals[group]).T.astype(np.float32)
        return self._table

    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        n = self.n_nodes
        flat_in = np.asarray(probs, dtype=np.float32).reshape(len(probs), n * n)
        out = flat_in.copy()
        source = self.triples[:, 0] * n + self.triples[:, 1]
        target = self.triples[:, 0] * n + self.triples[:, 2]
        moved = flat_in[:, source] * self.table()[self._slot(minute)]  # (B, U)
        seen = np.unique(source)
        out[:, seen] -= flat_in[:, seen]
        np.add.at(out, (np.arange(len(probs))[:, None], target[None]), moved)
        return out.reshape(probs.shape)

    def state(self) -> dict[str, np.ndarray]:
        return {"triples": self.triples, "counts": self.counts}

    def load_state(self, arrays: dict[str, np.ndarray]) -> None:
        self.triples = np.asarray(arrays["triples"], dtype=np.int64)
        self.counts = np.asarray(arrays["counts"], dtype=np.float64)
        self._table = None
