"""Our predictor: analog forecasting over whole arrangements (`analogs`).

Why: the per-object time-of-day Markov chain wins on our data because routines are per-object and tied to the
clock; it loses what SLaTe-PRO exploits, that the whole arrangement tells which activity is under way (bowl and
cereal on the table: milk comes next), and a chain fed its own output compounds its errors over 60 minutes.
So, with no network to train, each query looks up its *analogs*: the training steps at a similar time of day whose
arrangement of movable objects resembles the observed one, and predicts every lookahead step directly from what
followed them (no feedback). For a query (arrangement A, minute t) and a training step j (arrangement A_j, minute
t_j, parents F_j(s) s steps later):

    w_j = exp(-dt_j^2 / (2 sigma^2)) * exp(-lambda * hamming(A, A_j)),   |dt_j| <= 2.5 sigma (circular day)
    P_o(s)[d] ~ sum_j w_j [A_j[o] == A[o]] [F_j(s)[o] == d] + a [d == A[o]] + b M_o(s)[d]

Only analogs where object o sat where it sits now count for o; `a` (stay_prior) keeps an object in place when its
situation was never seen. lambda = 0 is a direct multi-step, per-object, time-of-day transition table. M_o(s) is
the backoff: the per-object time-of-day Markov chain (model.markov, default tunables) counted on the same stored
steps and propagated s steps from the observed parent, weighted by b (`backoff`). With few days the analogs of an
arrangement are scarce and their multi-step futures scarcer, while one-step transitions chained still generalise;
with many days the analogs outweigh it. Tunables (sigma_min, lambda, stay_prior, backoff, threshold) are chosen
by the rule every method's are (model.evaluate), on up to CV_DAYS training days each left out of the fit it is
scored with (fitting is only storing days), and the predictor is then fitted on all training days. Training stores
the days' movable parents (int16); nothing is learned by gradient.

For the paper's objective and the robot, the decision threshold applies to the margin of the most likely
destination over all the others (`_margin`), not to its probability: a move split between several places is
predicted as no move.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from homer_sim.data.dataset import GRID_MIN, DatasetMeta, Day
from model.baselines import MINUTES_PER_DAY
from model.markov import TimedMarkov
from model.predictor import THRESHOLDS, ModelError, Predictor, Rollout, one_hot_parents, summarise_step

SLOTS = MINUTES_PER_DAY // GRID_MIN
REACH_SIGMAS = 2.5  # analogs further apart in time than this many kernel widths are not looked at
MEMO_SIZE = 8192  # queries whose analog mass is kept (see Analogs._analog_mass)


class Analogs(Predictor):
    """Kernel-weighted analogs of (time of day, arrangement); direct multi-step prediction per object."""

    method = "analogs"
    cross_validated = True
    grid = {"threshold": THRESHOLDS, "sigma_min": (10.0, 20.0, 40.0), "similarity": (0.5, 0.0, 1.0, 2.0),
            "stay_prior": (0.1, 0.02, 0.5), "backoff": (0.0, 1.0, 4.0)}

    def __init__(self, meta: DatasetMeta, **params: float) -> None:
        self.rows = np.flatnonzero(meta.movable_mask)  # (M,) node index of each movable object
        self.states = np.zeros((0, len(self.rows)), dtype=np.int16)  # (J, M) parents of movable objects
        self.minutes = np.zeros(0, dtype=np.int32)  # (J,) routine minute of each stored step
        self.last = np.zeros(0, dtype=np.int64)  # (J,) flat index of the last step of j's day
        self._buckets: dict[int, list[np.ndarray]] = {}
        self._memo: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self.chain = TimedMarkov(meta)  # the backoff: per-object time-of-day chain on the same stored steps
        super().__init__(meta, **params)

    def fit(self, fit_days: Sequence[Day], val_days: Sequence[Day]) -> None:
        """Store the fit days' arrangements (`val_days` unused)."""
        if not fit_days:
            raise ModelError("no days to learn from; give at least one training day")
        self.load_state({"states": np.concatenate([d.parent[:, self.rows] for d in fit_days]),
                         "minutes": np.concatenate([d.minutes for d in fit_days]),
                         "lengths": np.array([d.steps for d in fit_days])})

    def state(self) -> dict[str, np.ndarray]:
        starts = np.flatnonzero(np.r_[True, self.last[1:] != self.last[:-1]]) if len(self.last) else np.zeros(0, int)
        return {"states": self.states, "minutes": self.minutes, "lengths": np.diff(np.r_[starts, len(self.last)])}

    def load_state(self, arrays: dict[str, np.ndarray]) -> None:
        self.states = np.asarray(arrays["states"], dtype=np.int16)
        self.minutes = np.asarray(arrays["minutes"], dtype=np.int32)
        lengths = np.asarray(arrays["lengths"], dtype=np.int64)
        self.last = np.repeat(np.cumsum(lengths) - 1, lengths)
        self._buckets = {}
        self._memo = {}
        within = np.flatnonzero(self.last != np.arange(len(self.last)))  # steps followed by one of the same day
        self.chain.count(self.states[within], self.states[within + 1], self.minutes[within + 1])

    def _candidates(self, minute: float) -> np.ndarray:
        """Indices of stored steps within REACH_SIGMAS kernel widths of `minute` (circular)."""
        reach = max(1, int(np.ceil(REACH_SIGMAS * self.params["sigma_min"] / GRID_MIN)))
        if reach not in self._buckets:
            slot = np.round(self.minutes / GRID_MIN).astype(np.int64) % SLOTS
            by_slot = [np.flatnonzero(slot == s) for s in range(SLOTS)]
            self._buckets[reach] = [np.concatenate([by_slot[(s + k) % SLOTS] for k in range(-reach, reach + 1)])
                                    for s in range(SLOTS)]
        return self._buckets[reach][int(round(minute / GRID_MIN)) % SLOTS]

    def forecast(self, parent: np.ndarray, minute: float, steps: int, backoff: np.ndarray | None = None) -> np.ndarray:
        """Parent probabilities of the movable objects at 1 .. `steps` steps after one observed graph.

        parent: Shape (N,) observed parents. minute: the observed routine minute. backoff: the chain's forecast from
        the same graph, Shape (steps, M, N) (`_backoff`), weighted by the `backoff` tunable. Returns Shape
        (steps, M, N).
        """
        m = len(self.rows)
        observed = np.asarray(parent, dtype=np.int64)[self.rows]
        out = self._analog_mass(observed, minute, steps)
        out[:, np.arange(m), observed] += self.params["stay_prior"]
        if backoff is not None:
            out += self.params["backoff"] * backoff
        return out / np.maximum(out.sum(axis=-1, keepdims=True), 1e-12)

    def _analog_mass(self, observed: np.ndarray, minute: float, steps: int) -> np.ndarray:
        """sum_j w_j [A_j[o] == A[o]] [F_j(s)[o] == d] for observed movable parents (M,): Shape (steps, M, N).

        It depends on sigma_min and lambda only, so it is kept (sparse, up to MEMO_SIZE queries) for the grid
        search, which tries every stay_prior and backoff for each of them."""
        key = (self.params["sigma_min"], self.params["similarity"], float(minute), steps, observed.tobytes())
        n, m = self.n_nodes, len(self.rows)
        out = np.zeros((steps, m, n))
        if key in self._memo:
            index, value = self._memo[key]
            out.flat[index] = value
            return out
        cand = self._candidates(minute)
        if len(cand):
            lag = np.abs(self.minutes[cand] - minute) % MINUTES_PER_DAY
            lag = np.minimum(lag, MINUTES_PER_DAY - lag)
            same = self.states[cand] == observed[None]  # (C, M)
            weight = np.exp(-0.5 * (lag / self.params["sigma_min"]) ** 2
                            - self.params["similarity"] * (~same).sum(axis=1))  # (C,)
            mass = (weight[:, None] * same).ravel()
            offset = np.arange(m)[None] * n
            for s in range(steps):
                future = self.states[np.minimum(cand + s + 1, self.last[cand])].astype(np.int64)
                out[s] += np.bincount((offset + future).ravel(), weights=mass, minlength=m * n).reshape(m, n)
        if len(self._memo) >= MEMO_SIZE:
            self._memo.clear()
        index = np.flatnonzero(out)
        self._memo[key] = (index.astype(np.int32), out.flat[index])
        return out

    def rollout(self, parent: np.ndarray, minute: np.ndarray, steps: int) -> Rollout:
        """Direct prediction of every step from the observed graphs (no feedback). parent (B, N); minute (B,)."""
        parent = np.asarray(parent, dtype=np.int64)
        probs = np.empty((steps, len(parent), len(self.rows), self.n_nodes), dtype=np.float32)  # movable rows
        backoff = self._backoff(one_hot_parents(parent, self.n_nodes), minute, steps)
        for b in range(len(parent)):
            probs[:, b] = self.forecast(parent[b], float(minute[b]), steps, None if backoff is None else backoff[:, b])
        observed = parent[:, self.rows]
        blank = (parent, np.zeros(parent.shape, np.float32))  # static nodes: their parent, with confidence 0
        summaries = []
        for p in probs:
            full = [blank[0].copy(), blank[1].copy(), blank[0].copy(), blank[1].copy()]
            for whole, part in zip(full, summarise_step(p, observed), strict=True):
                whole[:, self.rows] = part
            summaries.append(full)
        rollout = self._finish(parent, summaries)
        margin = np.zeros(rollout.other_confidence.shape, dtype=np.float32)
        margin[..., self.rows] = _margin(probs, observed, rollout.other_confidence[..., self.rows], True)
        return replace(rollout, other_margin=margin)

    def _backoff(self, probs: np.ndarray, minute: np.ndarray, steps: int) -> np.ndarray | None:
        """The chain's forecast of the movable objects from probs (B, N, N) observed at `minute` (B,): Shape
        (steps, B, M, N); None when the `backoff` weight is 0."""
        if self.params["backoff"] <= 0:
            return None
        out = []
        for s in range(1, steps + 1):
            probs = self.chain.step(probs, np.asarray(minute, dtype=np.float32) + GRID_MIN * s)
            out.append(probs[:, self.rows])
        return np.stack(out)

    def step(self, probs: np.ndarray, minute: np.ndarray) -> np.ndarray:
        """One step from the most likely arrangement of `probs` (B, N, N) at minute - GRID_MIN."""
        out = np.array(probs, dtype=np.float32, copy=True)
        parent = np.asarray(probs).argmax(axis=-1)
        observed = np.asarray(minute, dtype=np.float32) - GRID_MIN
        backoff = self._backoff(one_hot_parents(parent, self.n_nodes), observed, 1)
        for b in range(len(out)):
            out[b, self.rows] = self.forecast(parent[b], float(observed[b]), 1,
                                              None if backoff is None else backoff[:, b])[0]
        return out


def _margin(probs: np.ndarray, observed: np.ndarray, other: np.ndarray, movable: np.ndarray) -> np.ndarray:
    """The best other parent's margin over every other destination, p_d - (1 - p_stay - p_d) clipped at 0, from
    probs (S, B, R, N) of R nodes' parents, their observed parents (B, R) and p_d (S, B, R): Shape (S, B, R), 0 for
    static nodes (`movable`: (R,) bool, or True where every node is movable).

    That margin is what acting on the move is worth in expectation where a wrong destination costs as much as a
    right one gains (the paper's objective, the robot's wrong moves): when an object's move is likely but split
    between places (dishes leaving the dishwasher for the cupboard or the table), p_d alone clears a low threshold
    while a wrong destination is about as likely as the right one; the margin stays low and the object is predicted
    to stay. Those rules gate on it (model.metrics.gate); F1, where a wrong destination only adds a false positive
    to a miss, gates on p_d."""
    index = np.broadcast_to(np.maximum(observed, 0)[None, ..., None], (*probs.shape[:-1], 1))
    stay = np.take_along_axis(probs, index, axis=-1)[..., 0]
    return np.where(movable, np.maximum(2.0 * other + stay - 1.0, 0.0), 0.0).astype(np.float32)
