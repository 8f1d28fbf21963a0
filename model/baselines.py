"""The published baselines behind the predictor interface: last seen, static semantic and FreMEn.

Shapes: B graphs, N nodes, M movable nodes; probabilities are (B, N, N) as in model.predictor.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from homer_sim.clock import MINUTES_PER_DAY
from homer_sim.data.dataset import GRID_MIN, DatasetMeta, Day
from model.predictor import Predictor, Rollout, one_hot_parents, summarise_step

MAX_HARMONIC = 48  # FreMEn's candidate periods: one day divided by k = 1 .. 48 (down to 30 minutes)
PRIOR_FLOOR = 1e-6  # probability given to a candidate parent never observed, so no row is all zero


def _normalise(rows: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Restrict (..., M, N) non-negative rows to candidates (M, N) and make each sum to 1."""
    rows = np.where(candidates, np.maximum(rows, 0.0) + PRIOR_FLOOR, 0.0)
    return rows / rows.sum(axis=-1, keepdims=True)


def location_frequency(days: Sequence[Day], movable: np.ndarray) -> np.ndarray:
    """How often each movable node had each parent over all grid steps: (M, N) counts."""
    return pair_sums(days, movable, np.ones((sum(d.steps for d in days), 1)))[..., 0]


def pair_sums(days: Sequence[Day], movable: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Sum per (movable node, parent) of per-step values (S, K) over all grid steps S of `days`: (M, N, K)."""
    rows, n = np.flatnonzero(movable), len(movable)
    parents = np.concatenate([d.parent[:, rows] for d in days]).astype(np.int64)  # (S, M)
    flat = (np.arange(len(rows))[None] * n + parents).ravel()
    step = np.repeat(np.arange(len(parents)), len(rows))
    sums = [np.bincount(flat, weights=values[step, k], minlength=len(rows) * n) for k in range(values.shape[1])]
    return np.stack(sums, axis=-1).reshape(len(rows), n, values.shape[1])


class LastSeen(Predictor):
    """Every object stays where it was last seen."""

    method = "last_seen"

    def fit(self, fit_days: Sequence[Day], val_days: Sequence[Day]) -> None:
        """Nothing to learn."""

    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        return np.array(probs, dtype=np.float32, copy=True)


class StaticSemantic(Predictor):
    """Static prior from object-location frequencies (Zeng et al.), applied at every step with a noise model:
    P' = prior * ((1 - p) * P + p / C), normalised, with C the number of candidates and p the probability of change.
    """

    method = "static_semantic"
    grid = {"p_change": (0.4, 0.01, 0.03, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9)}

    def __init__(self, meta: DatasetMeta, **params: float) -> None:
        super().__init__(meta, **params)
        self.prior = np.zeros((int(self.movable.sum()), self.n_nodes))

    def fit(self, fit_days: Sequence[Day], val_days: Sequence[Day]) -> None:
        self.prior = _normalise(location_frequency(fit_days, self.movable), self.candidates[self.movable])

    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        p, candidates = self.params["p_change"], self.candidates[self.movable]
        noisy = (1.0 - p) * probs[:, self.movable] + p / candidates.sum(axis=-1, keepdims=True)
        out = np.array(probs, dtype=np.float32, copy=True)
        out[:, self.movable] = _normalise(self.prior * noisy, candidates)
        return out

    def state(self) -> dict[str, np.ndarray]:
        return {"prior": self.prior}

    def load_state(self, arrays: dict[str, np.ndarray]) -> None:
        self.prior = np.asarray(arrays["prior"], dtype=np.float64)


class FreMEnPrior(Predictor):
    """FreMEn's periodic prior alone (Krajnik et al.): per object-parent pair, the mean occupancy plus its `order`
    strongest Fourier components among periods of one day / k, k = 1 .. MAX_HARMONIC (chosen on the training
    days); the state is ignored. `order` is tuned on validation days.
    """

    method = "fremen_prior"
    grid = {"order": (2.0, 0.0, 1.0, 3.0, 4.0, 6.0, 8.0)}

    def __init__(self, meta: DatasetMeta, **params: float) -> None:
        m, n = int(meta.movable_mask.sum()), len(meta.nodes)
        self.mean = np.zeros((m, n))
        self.spectrum = np.zeros((m, n, MAX_HARMONIC), dtype=np.complex128)
        self._table: np.ndarray | None = None
        super().__init__(meta, **params)

    def set_params(self, **params: float) -> None:
        super().set_params(**params)
        self._table = None

    def fit(self, fit_days: Sequence[Day], val_days: Sequence[Day]) -> None:
        """Mean and spectrum gamma_k = mean((s(t) - mean) exp(-i w_k t)) of each pair's occupancy s(t) in {0, 1}."""
        minutes = np.concatenate([d.minutes for d in fit_days]).astype(np.float64)
        omega = 2 * np.pi * np.arange(1, MAX_HARMONIC + 1) / MINUTES_PER_DAY
        phasor = np.exp(-1j * np.outer(minutes, omega))  # (S, K)
        self.mean = location_frequency(fit_days, self.movable) / len(minutes)
        sums = (pair_sums(fit_days, self.movable, phasor.real) + 1j * pair_sums(fit_days, self.movable, phasor.imag))
        self.spectrum = (sums - self.mean[..., None] * phasor.sum(axis=0)) / len(minutes)
        self._table = None

    def prior_at(self, minute: np.ndarray) -> np.ndarray:
        """Prior parent distributions (B, M, N) at routine minutes (B,), from a table on the 10-minute grid."""
        if self._table is None:
            grid_minutes = np.arange(0, MINUTES_PER_DAY, GRID_MIN, dtype=np.float64)
            self._table = self._prior(grid_minutes).astype(np.float32)
        slot = np.round(np.asarray(minute) / GRID_MIN).astype(np.int64) % len(self._table)
        return self._table[slot]

    def _prior(self, minute: np.ndarray) -> np.ndarray:
        order = int(self.params["order"])
        amplitude = np.abs(self.spectrum)
        keep = np.zeros(amplitude.shape, dtype=bool)
        if order > 0:
            strongest = np.argsort(-amplitude, axis=-1)[..., :order]
            np.put_along_axis(keep, strongest, True, axis=-1)
        gamma = np.where(keep, self.spectrum, 0.0)
        omega = 2 * np.pi * np.arange(1, MAX_HARMONIC + 1) / MINUTES_PER_DAY
        phasor = np.exp(1j * np.outer(minute, omega))  # (B, K)
        wave = 2.0 * np.einsum("bk,mnk->bmn", phasor, gamma).real
        return _normalise(np.clip(self.mean[None] + wave, 0.0, 1.0), self.candidates[self.movable])

    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        out = np.array(probs, dtype=np.float32, copy=True)
        out[:, self.movable] = self.prior_at(minute)
        return out

    def state(self) -> dict[str, np.ndarray]:
        return {"mean": self.mean, "spectrum_real": self.spectrum.real, "spectrum_imag": self.spectrum.imag}

    def load_state(self, arrays: dict[str, np.ndarray]) -> None:
        self.mean = np.asarray(arrays["mean"], dtype=np.float64)
        self.spectrum = np.asarray(arrays["spectrum_real"]) + 1j * np.asarray(arrays["spectrum_imag"])
        self._table = None


class FreMEn(FreMEnPrior):
    """State-conditioned FreMEn, as used in the paper: prior(t + dt) + (observed - prior(t + dt)) * exp(-dt / tau).

    `step` (dt = one grid step) decays the given probabilities towards the prior; `rollout` uses the closed form
    from the observed graph, dt being the time since the observation. `order` and `tau_min` are tuned.
    """

    method = "fremen"
    grid = {"order": (2.0, 0.0, 1.0, 3.0, 4.0, 6.0), "tau_min": (60.0, 10.0, 20.0, 30.0, 120.0, 240.0, 480.0)}

    def _blend(self, probs: np.ndarray, minute: np.ndarray, dt_min: float) -> np.ndarray:
        weight = np.exp(-dt_min / self.params["tau_min"])
        prior = self.prior_at(minute)
        out = np.array(probs, dtype=np.float32, copy=True)
        out[:, self.movable] = prior + (probs[:, self.movable] - prior) * weight
        return out

    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        return self._blend(probs, minute, GRID_MIN)

    def rollout(self, parent: np.ndarray, minute: np.ndarray, steps: int) -> Rollout:
        observed = one_hot_parents(parent, self.n_nodes)
        steps_out = [summarise_step(self._blend(observed, np.asarray(minute) + GRID_MIN * s, GRID_MIN * s), parent)
                     for s in range(1, steps + 1)]
        return self._finish(parent, steps_out)
