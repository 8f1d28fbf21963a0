"""Fit, tune on validation days, and score methods on test days; cache fitted predictors as checkpoints.

Protocol, per household: the last VAL_FRACTION of the training days (at least one) are validation days, the
rest are fit days. Each method is fitted on the fit days (the graph network early-stops on the validation
days), then every tunable parameter, the decision threshold included, is chosen on the validation days by grid
search: the highest used correct % - used wrong % - unused wrong % (model.metrics.Counts.objective) at the
tuning window among the settings that leave at least 99% of the unused objects in place (the paper's operating
point; if no setting does, the highest objective). "In place" is judged with a margin: the share moved on the
validation days, pooled, plus one standard error of the per-day shares, must stay within 1% (`keeps_unused`).
Without it, the setting picked among many is the one whose validation estimate came out low by chance, and on
new days it moves more than 1% about half the time. The same rule for every method. Test days are used only for
the reported numbers.

A method whose fit is cheap (`Predictor.cross_validated`: analogs, which only stores days, and markov, which only
counts) is validated on more days than the last 10%: up to CV_DAYS training days, spread over them, are held out
in turn, each scored by the method fitted on all the other training days, and the counts pooled (leave one day
out); it is then fitted on all training days. With one validation day (5 training days, a method that is not
cross-validated) there is no per-day spread and the margin is 0 (benchmarks/tuning_rules.py compares the rules).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, fields
from functools import partial
from pathlib import Path

import numpy as np
from tqdm import tqdm

from homer_sim.clock import DEFAULT_WINDOW_MIN
from homer_sim.data.dataset import Dataset, DatasetMeta, Day
from homer_sim.execution import IN_PROCESS, Backend
from homer_sim.graph import OUTSIDE
from model.methods import check_method, load_predictor, make_predictor, save_predictor
from model.metrics import (
    F1_STEPS,
    Counts,
    Queries,
    RobotCounts,
    RobotReplay,
    day_queries,
    gate,
    relocation_counts,
    score,
    window_steps,
)
from model.predictor import ModelError, Predictor, Rollout
from model.train import TORCH_THREADS

log = logging.getLogger(__name__)
VAL_FRACTION = 0.1
HEADLINE_WINDOW_MIN = DEFAULT_WINDOW_MIN
CURVE_WINDOWS_MIN = tuple(range(10, 130, 10))
MAX_UNUSED_WRONG_PCT = 1.0  # tuning keeps at least 99% of unused objects in place when any setting can
MAX_ROBOT_WRONG_PCT = 10.0  # the assistance tuning keeps the robot's wrong moves to a tenth when any setting can
MIN_ACT_STEPS = 2  # the robot's act_steps is at least this: a robot acting only on moves due within the next grid
# step acts at the very tick the person starts (its minutes of work make them wait, which the replay does not see:
# the table is set as breakfast starts, not before)
CV_DAYS = 10  # cross-validated methods: training days held out in turn (all of them when there are fewer)
TUNING_VERSION = 10  # bump when the tuning rule or a grid changes: cached tunings are then redone
TARGETS = ("paper", "f1", "assist")  # what tunables are chosen for: the paper's objective, relocation F1, or
# the assistance objective (fetches a robot acting on the predictions makes ahead, minus its wrong moves)
QUERY_CHUNK = 128  # queries per rollout call, bounds memory of the dense (B, N, N) probabilities


def split_days(days: Sequence[Day], val_fraction: float = VAL_FRACTION) -> tuple[list[Day], list[Day]]:
    """(fit days, validation days): the last `val_fraction` of the days, at least one, are for validation."""
    if len(days) < 2:
        raise ModelError(f"{len(days)} training day(s); need at least 2 (fit and validation)")
    n_val = min(len(days) - 1, max(1, int(round(len(days) * val_fraction))))
    return list(days[:-n_val]), list(days[-n_val:])


def _joined(parts: Sequence, axis: int = 0):
    """Rollouts (joined along the query axis, 1) or Queries (axis 0): each field of `parts` concatenated."""
    kind = type(parts[0])
    return kind(*(None if getattr(parts[0], f.name) is None else
                  np.concatenate([getattr(p, f.name) for p in parts], axis=axis) for f in fields(kind)))


def rollout_queries(predictor: Predictor, queries: Queries, steps: int) -> Rollout:
    """predictor.rollout over all queries, in chunks of QUERY_CHUNK."""
    return _joined([predictor.rollout(queries.observed[s:s + QUERY_CHUNK], queries.minute[s:s + QUERY_CHUNK], steps)
                    for s in range(0, len(queries), QUERY_CHUNK)], axis=1)


def tune(predictor: Predictor, queries: Queries | Sequence[tuple[Predictor, Queries]], steps: int,
         target: str = "paper") -> tuple[dict[str, float], float]:
    """Grid search of the predictor's tunables on validation queries; sets and returns the best (and its score).

    target "paper": the highest objective among settings that keep the unused objects in place (`keeps_unused`:
    at most MAX_UNUSED_WRONG_PCT moved, plus a margin of one standard error over the folds, each a validation day
    in `fit_and_tune`; none for a single Queries), or the highest objective overall if none does. target "f1": the
    highest mean relocation F1 over steps 1 .. `steps`. target "assist": the highest fetches made ahead minus
    wrong moves of the robot's own decision loop replayed on the validation days (`model.metrics.robot_counts`: it
    acts once on an object's first predicted move within act_steps, tuned beside the threshold, holds its help and
    puts unused help back) among the settings with at most MAX_ROBOT_WRONG_PCT of its relocations wrong (pooled,
    plus one standard error of the per-day shares: without it, tuned at 10% on validation days, the robot was
    wrong 16.5% of the time on the test days), or the highest overall if none has. See `tune_targets`.
    """
    return tune_targets(predictor, queries, steps, (target,))[target]


def tune_targets(predictor: Predictor, queries: Queries | Sequence[tuple[Predictor, Queries]], steps: int,
                 targets: Sequence[str]) -> dict[str, tuple[dict[str, float], float]]:
    """`tune` for each of `targets` on the same queries: {target: (best params, its score)}; the predictor keeps
    the last target's. The threshold only changes the decision rule applied to a rollout, so one rollout per
    combination of the other tunables scores every threshold, for every target. `queries` may instead be folds,
    (predictor fitted without these queries' days, queries), scored pooled (cross-validation, `cv_folds`)."""
    folds = [(predictor, queries)] if isinstance(queries, Queries) else list(queries)
    days = [q for _, q in folds]
    queries = _joined(days)
    names = [k for k in predictor.grid if k != "threshold"]
    thresholds = predictor.grid.get("threshold", (predictor.params["threshold"],))
    scored: dict[str, list[tuple[bool, float, int, dict[str, float]]]] = {t: [] for t in targets}
    nodes = list(predictor.meta.nodes)
    outside = nodes.index(OUTSIDE) if OUTSIDE in nodes else -1
    replay = RobotReplay(queries, steps, predictor.movable, outside) if "assist" in targets else None
    for values in itertools.product(*(predictor.grid[k] for k in names)):
        for fold, _ in folds:
            fold.set_params(**dict(zip(names, values, strict=True)))
        rollout = _joined([rollout_queries(fold, q, steps) for fold, q in folds], axis=1)
        for threshold in thresholds:
            predicted = {margin: gate(rollout, queries.observed, threshold, margin)
                         for margin in {uses_margin(t) for t in targets}}
            params = {**dict(zip(names, values, strict=True)), "threshold": float(threshold)}
            for target, rows in scored.items():
                for rule, (admissible, value) in _tuning_scores(target, queries, days, predicted[uses_margin(target)],
                                                                steps, predictor.movable, replay):
                    rows.append((admissible, value, -len(rows), params | rule))
    best = {}
    for target, rows in scored.items():
        _, objective, _, params = max(rows, key=lambda row: row[:3])  # earliest in grid order wins ties
        best[target] = (params, objective)
    predictor.set_params(**best[targets[-1]][0])
    return {t: (dict(predictor.params) | p, v) for t, (p, v) in best.items()}


def uses_margin(target: str) -> bool:
    """Whether `target`'s decisions gate on the rollout's margin (model.metrics.gate): all but F1."""
    return target != "f1"


def _tuning_scores(target: str, queries: Queries, days: Sequence[Queries], predicted: np.ndarray, steps: int,
                   movable: np.ndarray, replay: RobotReplay | None = None
                   ) -> list[tuple[dict[str, float], tuple[bool, float]]]:
    """[(decision-rule params beside the threshold, (admissible, score))] of one setting's predictions (Q, K, N) on
    `queries`, the queries of `days` joined in order; higher is better. "assist" scores each `act_steps`
    MIN_ACT_STEPS .. steps of the robot's own loop on the queries (`replay`, `model.metrics.robot_counts`): fetches
    made ahead minus wrong moves, admissible when at most MAX_ROBOT_WRONG_PCT of its relocations are wrong, with a
    margin of one standard error over the validation days (`within_margin`, as for the paper's unused share). "paper"
    is admissible when `keeps_unused` on the per-day counts. The other targets act on the whole window (act_steps
    0)."""
    if target == "assist":
        act = range(min(MIN_ACT_STEPS, steps), steps + 1)
        return [({"act_steps": float(k)}, (within_margin([(c.wrong, c.relocations) for c in per_day],
                                                         MAX_ROBOT_WRONG_PCT),
                                           float(sum(per_day, RobotCounts()).assistance())))
                for k, per_day in zip(act, replay.day_counts(predicted, act), strict=True)]
    if target == "f1":
        return [({"act_steps": 0.0}, (True, float(relocation_counts(queries, predicted, movable, steps).f1().mean())))]
    ends = np.cumsum([len(q) for q in days])
    per_day = [score(q, predicted[end - len(q):end], steps, movable) for q, end in zip(days, ends, strict=True)]
    return [({"act_steps": 0.0}, (keeps_unused(per_day), sum(per_day, Counts()).objective()))]


def keeps_unused(days: Sequence[Counts], limit_pct: float = MAX_UNUSED_WRONG_PCT) -> bool:
    """Whether a setting leaves the unused objects in place, judged on its counts of each validation day
    (`within_margin` of `limit_pct`)."""
    return within_margin([(c.unused_wrong, c.unused) for c in days], limit_pct)


def within_margin(days: Sequence[tuple[int, int]], limit_pct: float) -> bool:
    """Whether a share, given as (count, out of) on each validation day, is at most `limit_pct` % on new days:
    the pooled share plus one standard error of the per-day shares (days with nothing to share out left out;
    no margin with fewer than two such days). True when there is nothing to share out."""
    total = sum(n for _, n in days)
    if not total:
        return True
    rates = [100.0 * k / n for k, n in days if n]
    margin = float(np.std(rates, ddof=1) / np.sqrt(len(rates))) if len(rates) > 1 else 0.0
    return 100.0 * sum(k for k, _ in days) / total + margin <= limit_pct


def days_fingerprint(days: Sequence[Day]) -> str:
    """A short digest of the days' parent arrays (the cache key of a fitted predictor)."""
    digest = hashlib.sha1()
    for day in days:
        digest.update(f"{day.household}/{day.split}/{day.index}".encode())
        digest.update(np.ascontiguousarray(day.parent).tobytes())
    return digest.hexdigest()[:12]


@dataclass(frozen=True)
class FitSpec:
    """What a fitted predictor depends on: method, network overrides, the days, and pre-trained weights if any."""

    method: str
    fit_days: tuple[Day, ...]
    val_days: tuple[Day, ...]
    config: tuple[tuple[str, object], ...] = ()
    init: Path | None = None

    def key(self) -> str:
        raw = json.dumps([self.method, list(self.config), days_fingerprint(self.fit_days),
                          days_fingerprint(self.val_days), str(self.init) if self.init else None], default=str)
        return hashlib.sha1(raw.encode()).hexdigest()[:12]

    def path(self, folder: Path, household: str) -> Path:
        return folder / household / f"{self.method}_{len(self.fit_days)}+{len(self.val_days)}d_{self.key()}.pt"


def tuning_key(target: str, window_min: int) -> str:
    """Name of a tuning in a checkpoint's info: "paper@30" (paper objective at 30 min), "assist@30" (assistance
    objective at 30 min) or "f1" (steps 1 .. 6)."""
    if target not in TARGETS:
        raise ModelError(f"unknown metric {target!r}; known: {', '.join(TARGETS)}")
    return "f1" if target == "f1" else f"{target}@{window_min}"


def fit_and_tune(spec: FitSpec, meta: DatasetMeta, window_min: int, target: str | Sequence[str] = "paper",
                 cached: tuple[Predictor, dict] | None = None, init_state: dict[str, np.ndarray] | None = None,
                 progress: bool = True) -> tuple[Predictor, dict, bool]:
    """Fit `spec` (or take the `cached` predictor and its info) and tune it for `target` (or each of several)
    unless it already was; reads and writes no file. init_state: pre-trained weights to start from. Returns the
    predictor with the (last) target's params, its provenance (days, training report, tunings and their validation
    scores) and whether it is new or newly tuned.

    target "paper" and "assist" tune at `window_min` (together: one rollout per setting serves both), "f1" for
    SLaTe-PRO's F1 over 10 .. 60 minutes (window_min unused).
    """
    targets = (target,) if isinstance(target, str) else tuple(target)
    keys = {t: tuning_key(t, window_min) for t in targets}
    tunings: dict = {}
    if cached is not None and cached[0].cross_validated and "cross_validation_days" not in cached[1]:
        cached = None  # fitted before cross-validation, on the fit days only: refit on all training days
    if cached is not None:
        predictor, info = cached
        tunings = info.get("tunings", {}) if info.get("tuning_version") == TUNING_VERSION else {}
    else:
        predictor = make_predictor(spec.method, meta, progress=progress, **dict(spec.config))
        if init_state is not None:
            predictor.load_state(init_state)
        if predictor.cross_validated:
            predictor.fit(spec.fit_days + spec.val_days, ())
            info = {"fit_days": len(spec.fit_days) + len(spec.val_days), "val_days": 0,
                    "cross_validation_days": len(cv_days(spec)), "init": str(spec.init or "")}
        else:
            predictor.fit(spec.fit_days, spec.val_days)
            info = {"fit_days": len(spec.fit_days), "val_days": len(spec.val_days), "init": str(spec.init or "")}
        report = getattr(predictor, "report", None)
        if report is not None:
            info.update(epochs=report.epochs, best_epoch=report.best_epoch, train_s=round(report.wall_s, 2))
    missing = [t for t in targets if keys[t] not in tunings]
    folds = cv_folds(spec, meta) if missing and predictor.cross_validated else []
    for steps in dict.fromkeys(_tuning_steps(t, window_min, meta.grid_min) for t in missing):
        group = [t for t in missing if _tuning_steps(t, window_min, meta.grid_min) == steps]
        queries = [(fold, day_queries([day], steps))
                   for fold, day in (folds or [(predictor, day) for day in spec.val_days])]
        for t, (params, val_score) in tune_targets(predictor, queries, steps, group).items():
            log.info("%s tuned for %s: %s (validation score %.4f)", spec.method, keys[t], params, val_score)
            tunings = {**tunings, keys[t]: {"params": params, "val_score": round(val_score, 4)}}
    predictor.set_params(**tunings[keys[targets[-1]]]["params"])
    fresh = cached is None or bool(missing)
    return predictor, {**info, "tuning_version": TUNING_VERSION, "tunings": tunings} if fresh else info, fresh


def cv_days(spec: FitSpec) -> list[Day]:
    """The training days a cross-validated method is validated on: CV_DAYS of them spread evenly (all if fewer)."""
    train = spec.fit_days + spec.val_days
    return [train[i] for i in sorted(set(np.linspace(0, len(train) - 1, min(CV_DAYS, len(train))).round().astype(int)))]


def cv_folds(spec: FitSpec, meta: DatasetMeta) -> list[tuple[Predictor, Day]]:
    """Per held-out day of `cv_days`: the method fitted on all the other training days, and that day."""
    train = spec.fit_days + spec.val_days
    folds = []
    for day in cv_days(spec):
        fold = make_predictor(spec.method, meta, progress=False, **dict(spec.config))
        fold.fit([d for d in train if d is not day], ())
        folds.append((fold, day))
    return folds


def _tuning_steps(target: str, window_min: int, grid_min: int) -> int:
    return F1_STEPS if target == "f1" else window_steps(window_min, grid_min)


def fit_tuned(spec: FitSpec, meta: DatasetMeta, window_min: int, path: Path | None = None,
              progress: bool = True, target: str | Sequence[str] = "paper") -> tuple[Predictor, dict]:
    """Load the cached predictor at `path` or fit one; tune it for `target` (or each of several in turn; the
    predictor keeps the last one's params) unless the cache already was (see `fit_and_tune`), and write the
    checkpoint when it changed. Every tuning of one fit is kept in the checkpoint's info["tunings"]."""
    targets = (target,) if isinstance(target, str) else tuple(target)
    result = run_fit(None, fit_task(spec.method, spec, meta, window_min, path, targets, progress=progress))
    result.save()
    return result.predictor, result.info


@dataclass(frozen=True)
class FitTask:
    """A fit (unless cached) tuned for each of `targets` in turn, `scorer(predictor, target)` called after each:
    everything a worker needs, read from disk by the driver (`fit_task`); `run_fit` runs it. `key` names it and
    `checkpoint` is where the driver keeps the predictor."""

    key: str
    spec: FitSpec
    meta: DatasetMeta
    window_min: int
    targets: tuple[str, ...] = ("paper",)
    scorer: Callable[[Predictor, str], dict] | None = None
    checkpoint: Path | None = None
    cached: tuple[Predictor, dict] | None = None
    init_state: dict[str, np.ndarray] | None = None
    progress: bool = False


@dataclass(frozen=True)
class FitResult:
    """A FitTask done: the tuned predictor and its provenance, whether it differs from the checkpoint (then the
    driver writes it there), what the scorer returned (merged over targets) and the wall seconds."""

    key: str
    checkpoint: Path | None
    predictor: Predictor
    info: dict
    changed: bool
    scores: dict
    wall_s: float

    def save(self) -> None:
        """Write the checkpoint if the predictor is new or newly tuned (on the driver)."""
        if self.changed and self.checkpoint is not None:
            save_predictor(self.checkpoint, self.predictor, self.info)


def fit_task(key: str, spec: FitSpec, meta: DatasetMeta, window_min: int, path: Path | None = None,
             targets: tuple[str, ...] = ("paper",), scorer: Callable[[Predictor, str], dict] | None = None,
             progress: bool = False) -> FitTask:
    """The FitTask of `spec`, with the checkpoint at `path` and the pre-trained weights of spec.init read here,
    on the driver."""
    cached = load_predictor(path, meta, progress=progress) if path is not None and path.is_file() else None
    init_state = None
    if spec.init is not None and cached is None:
        init_state = load_predictor(spec.init, meta, progress=progress)[0].state()
    return FitTask(key, spec, meta, window_min, targets, scorer, path, cached, init_state, progress)


def run_fit(_: None, task: FitTask) -> FitResult:
    """Fit, tune and score a FitTask; writes nothing (the task function of `homer_sim.execution`, no state)."""
    started, scores = time.perf_counter(), {}
    predictor, info, changed = fit_and_tune(task.spec, task.meta, task.window_min, task.targets, task.cached,
                                            task.init_state, task.progress)
    for target in task.targets:
        predictor.set_params(**info["tunings"][tuning_key(target, task.window_min)]["params"])
        if task.scorer is not None:
            scores.update(task.scorer(predictor, target))
    return FitResult(task.key, task.checkpoint, predictor, info, changed, scores, time.perf_counter() - started)


def used_objects(days: Sequence[Day]) -> np.ndarray:
    """(N,) bool: nodes whose parent changes at least once between consecutive steps of `days`."""
    return np.any([np.any(d.parent[1:] != d.parent[:-1], axis=0) for d in days], axis=0)


def score_windows(predictor: Predictor, queries: Queries, windows_min: Sequence[int], grid_min: int,
                  pool: np.ndarray) -> dict[int, tuple[Counts, Counts]]:
    """Per window: (counts with every movable node as unused pool, counts with the household's used objects)."""
    steps = [window_steps(w, grid_min) for w in windows_min]
    rollout = rollout_queries(predictor, queries, max(steps))
    predicted = gate(rollout, queries.observed, predictor.params["threshold"], margin=uses_margin("paper"))
    return {w: (score(queries, predicted, s, predictor.movable), score(queries, predicted, s, predictor.movable, pool))
            for w, s in zip(windows_min, steps, strict=True)}


def evaluate(data: str | Path, methods: Sequence[str], window_min: int = HEADLINE_WINDOW_MIN,
             checkpoints: str | Path | None = None, households: Sequence[str] | None = None,
             train_days: int | None = None, progress: bool = True, metric: str = "paper",
             backend: Backend = IN_PROCESS) -> dict:
    """The `homer evaluate` result: per method, scores averaged over households.

    metric "paper" (the paper's table at `window_min`), "f1" (SLaTe-PRO's relocation F1, 10 .. 60 minutes) or
    "both"; each is scored with the tunables chosen on validation days for that metric. Keys: "methods"[name] (means
    over households; "f1" as in summarise_f1) and "per_household"[household][name]. Each household and method is
    one task on `backend` (this process, local processes or Ray); checkpoints are written here.
    """
    if metric not in (*TARGETS, "both"):
        raise ModelError(f"unknown metric {metric!r}; known: {', '.join(TARGETS)}, both")
    targets = TARGETS if metric == "both" else (metric,)
    dataset = Dataset(data)
    methods = [check_method(m) for m in methods]
    folder = Path(checkpoints) if checkpoints is not None else dataset.root / "checkpoints"
    names = list(households or dataset.meta.households)

    def tasks() -> Iterator[FitTask]:
        for house in names:
            fit, val, test, pool = household_split(dataset, house, train_days)
            for method in methods:
                spec = FitSpec(method, tuple(fit), tuple(val))
                yield fit_task(f"{house}/{method}", spec, dataset.meta, window_min, spec.path(folder, house),
                               targets, partial(score_household, (test, pool), window_min),
                               progress and backend == IN_PROCESS)

    done: dict[str, dict] = {}
    bar = tqdm(total=len(names) * len(methods), desc="evaluate", unit="fit", disable=not progress)
    with backend.run(run_fit, tasks(), type(None), cpus_per_task=TORCH_THREADS) as run:
        for result in run:
            result.save()
            done[result.key] = result.scores
            bar.set_postfix(fit=result.key)
            bar.update()
    bar.close()
    per_house = {m: {h: done[f"{h}/{m}"] for h in names} for m in methods}
    return {"window_min": window_min, "households": names, "train_days": train_days, "metric": metric,
            "methods": {m: summarise(per_house[m]) for m in methods},
            "per_household": {h: {m: per_house[m][h] for m in methods} for h in names}, "execution": run.usage()}


def household_scores(spec: FitSpec, meta: DatasetMeta, test: tuple[list[Day], np.ndarray], window_min: int,
                     path: Path | None, targets: Sequence[str], progress: bool = True) -> dict:
    """One method on one household's test days (and its used-object pool), for each target metric, in this
    process (the checkpoint at `path` read and written)."""
    task = fit_task(spec.method, spec, meta, window_min, path, tuple(targets), partial(score_household, test,
                                                                                         window_min), progress)
    result = run_fit(None, task)
    result.save()
    return result.scores


def score_household(test: tuple[list[Day], np.ndarray], window_min: int, predictor: Predictor, target: str) -> dict:
    """A predictor tuned for `target` on a household's test days and used-object pool: the paper's percentages at
    `window_min` (target "paper") or {"f1": SLaTe-PRO's relocation F1} (target "f1")."""
    days, pool = test
    if target == "f1":
        return {"f1": f1_result(predictor, days)}
    grid_min = predictor.meta.grid_min
    queries = day_queries(days, window_steps(window_min, grid_min))
    counts, pooled = score_windows(predictor, queries, [window_min], grid_min, pool)[window_min]
    return household_result(counts, pooled, predictor.params)


def f1_result(predictor: Predictor, days: Sequence[Day]) -> dict:
    """SLaTe-PRO's relocation F1 of a tuned predictor on `days` (RelocationCounts.summary, plus its params)."""
    queries = day_queries(days, F1_STEPS)
    predicted = gate(rollout_queries(predictor, queries, F1_STEPS), queries.observed, predictor.params["threshold"],
                     margin=uses_margin("f1"))
    return {**relocation_counts(queries, predicted, predictor.movable).summary(), "params": dict(predictor.params)}


def household_split(dataset: Dataset, house: str, train_days: int | None
                    ) -> tuple[list[Day], list[Day], list[Day], np.ndarray]:
    """Fit, validation and test days of a household and its used-object pool (from its training days)."""
    train = dataset.load(house, "train")
    if train_days is not None:
        if not 2 <= train_days <= len(train):
            raise ModelError(f"--train-days {train_days}; household {house} has {len(train)} training days (use 2..)")
        train = train[:train_days]
    test = dataset.load(house, "test")
    if not test:
        raise ModelError(f"household {house} has no test days in {dataset.root}")
    fit, val = split_days(train)
    return fit, val, test, used_objects(train)


def household_result(counts: Counts, pooled: Counts, params: dict[str, float]) -> dict:
    result = counts.percentages()
    result["unused_used_pool"] = pooled.percentages()["unused"]
    result["counts"] = {"used": counts.used, "unused": counts.unused, "unused_used_pool": pooled.unused}
    result["params"] = dict(params)
    return result


def summarise(per_house: dict[str, dict]) -> dict:
    """Mean and spread (population standard deviation) over households of each percentage, and of the F1s."""
    out: dict = {"per_household": per_house}
    first = next(iter(per_house.values()))
    for group in ("used", "unused", "unused_used_pool"):
        if group not in first:
            continue
        values = {k: np.array([h[group][k] for h in per_house.values()], dtype=float) for k in first[group]}
        out[group] = {k: _finite(np.nanmean(v)) for k, v in values.items()}
        out.setdefault("spread", {})[group] = {k: _finite(np.nanstd(v)) for k, v in values.items()}
    if "f1" in first:
        out["f1"] = summarise_f1([h["f1"] for h in per_house.values()])
    return out


def summarise_f1(rows: Sequence[dict]) -> dict:
    """Households' F1 results -> per_step and mean averaged over households (as the paper table is), tp, fp, fn
    summed, and "spread" (population standard deviation over households of the mean)."""
    means = np.array([r["mean"] for r in rows], dtype=float)
    return {"per_step": [round(float(v), 4) for v in np.mean([r["per_step"] for r in rows], axis=0)],
            "mean": round(float(means.mean()), 4), "spread": round(float(means.std()), 4),
            **{k: int(sum(r[k] for r in rows)) for k in ("tp", "fp", "fn")}}


def _finite(value: float) -> float | None:
    return round(float(value), 3) if np.isfinite(value) else None
