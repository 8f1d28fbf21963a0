"""The paper's results on a dataset, as files. Resumable: every finished run is recorded in OUT/runs.json and
skipped next time; fitted predictors are cached under OUT/checkpoints.

Experiments (--experiments, default all):
  main      the default methods on all training days of each household; outcome counts for windows 10..120 min
            (every method tuned on its validation days at 30 min)
  ablation  gnn_no_attention and gnn_linear_time, same protocol
  days      gnn, fremen, fremen_prior, static_semantic, markov and analogs on the first 5, 10, 20, 30, 40 training days
            (50 comes from `main`)
  pretrain  gnn pre-trained on the other four households' training days, fine-tuned on 5..50 days of each
Files in OUT: main_table.md / main_table.json (30 and 40 min: mean and spread over households), windows.png,
days.png, pretrain.png, ablation.md, validation_table.md; and the validation table the robot's default predictor is
chosen from (`model/validation_table.json`, see model/selection.py: each main run's tuning objective on its
validation days). One JSON object (the main table at 30 min and the file list) on stdout.

    .venv/bin/python benchmarks/paper_results.py --data DIR --out DIR [--experiments main,ablation]
    .venv/bin/python benchmarks/paper_results.py --data DIR --out DIR --report   # files from the runs so far
    .venv/bin/python benchmarks/paper_results.py --data DIR --out DIR --ray auto   # runs as tasks on a cluster
"""

from __future__ import annotations

import argparse
import fcntl
import json
import logging
import os
import sys
from dataclasses import asdict
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from homer_sim.data.dataset import Dataset, Day  # noqa: E402
from homer_sim.execution import IN_PROCESS, Backend  # noqa: E402
from model.evaluate import (  # noqa: E402
    CURVE_WINDOWS_MIN,
    HEADLINE_WINDOW_MIN,
    FitResult,
    FitSpec,
    FitTask,
    days_fingerprint,
    fit_task,
    household_result,
    household_split,
    run_fit,
    score_windows,
    split_days,
    summarise,
)
from model.metrics import Counts, Queries, day_queries  # noqa: E402
from model.names import DEFAULT_METHODS  # noqa: E402
from model.plots import days_curve, window_bars  # noqa: E402
from model.predictor import Predictor  # noqa: E402
from model.report import format_table  # noqa: E402
from model.selection import TABLE, format_validation, validation_table  # noqa: E402
from model.train import TORCH_THREADS  # noqa: E402
from scenarios.cli.common import add_backend_arguments, backend_from_args  # noqa: E402

log = logging.getLogger("paper_results")
EXPERIMENTS = ("main", "ablation", "days", "pretrain")
ABLATIONS = ("gnn", "gnn_no_attention", "gnn_linear_time")
DAYS_METHODS = ("gnn", "fremen", "fremen_prior", "static_semantic", "markov", "analogs")
DAY_COUNTS = (5, 10, 20, 30, 40)
TABLE_WINDOWS = (HEADLINE_WINDOW_MIN, 40)


class Runs:
    """runs.json: the dataset's fingerprint and run key -> record, rewritten atomically after every run.

    Results of one dataset only: resuming onto another (regenerated with other code or seed) is refused. Several
    processes may share the file (give each its own --households): a record is merged into what is on disk, under
    a lock, never written over it.
    """

    def __init__(self, path: Path, dataset: str) -> None:
        self.path, self.dataset = path, dataset
        self.records: dict[str, dict] = self._read()

    def _read(self) -> dict[str, dict]:
        saved = json.loads(self.path.read_text()) if self.path.is_file() else {"dataset": self.dataset, "runs": {}}
        if saved.get("dataset") != self.dataset:
            raise SystemExit(f"{self.path} holds runs on dataset {saved.get('dataset')}, not on this one "
                             f"({self.dataset}); use another --out or move the file away")
        return saved["runs"]

    def done(self, key: str) -> bool:
        return key in self.records

    def add(self, key: str, record: dict) -> None:
        with open(self.path.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            self.records = {**self._read(), key: record}
            tmp = self.path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(json.dumps({"dataset": self.dataset, "runs": self.records}, indent=1, sort_keys=True))
            os.replace(tmp, self.path)


def dataset_fingerprint(dataset: Dataset) -> str:
    """Digest of every day of every household and split (what the results depend on)."""
    return days_fingerprint([day for house in dataset.meta.households for split in ("train", "test")
                             for day in dataset.load(house, split)])


def run_task(dataset: Dataset, key: str, house: str, method: str, days: int | None, folder: Path,
             init: Path | None = None) -> FitTask:
    """The fit (or the checkpoint), tuning at 30 min and outcome counts on the test days for every curve window."""
    fit, val, test, pool = household_split(dataset, house, days)
    spec = FitSpec(method, tuple(fit), tuple(val), init=init)
    queries = day_queries(test, max(CURVE_WINDOWS_MIN) // dataset.meta.grid_min)
    return fit_task(key, spec, dataset.meta, HEADLINE_WINDOW_MIN, spec.path(folder, house),
                    scorer=partial(curve_scores, queries, pool))


def curve_scores(queries: Queries, pool: np.ndarray, predictor: Predictor, target: str) -> dict:
    """Outcome counts of a tuned predictor on the test queries for every curve window (all movable nodes as the
    unused pool, and the household's used objects)."""
    scored = score_windows(predictor, queries, CURVE_WINDOWS_MIN, predictor.meta.grid_min, pool)
    return {"windows": {str(w): {"all": asdict(c), "used_pool": asdict(p)} for w, (c, p) in scored.items()},
            "queries": len(queries)}


def record(result: FitResult) -> dict:
    """The runs.json record of a finished run."""
    return {**result.scores, "params": result.predictor.params, "info": result.info,
            "wall_s": round(result.wall_s, 1)}


def pretrain_task(dataset: Dataset, house: str, folder: Path) -> FitTask:
    """The graph network trained on every other household's training days (fit and validation)."""
    fit: list[Day] = []
    val: list[Day] = []
    for other in dataset.meta.households:
        if other != house:
            f, v = split_days(dataset.load(other, "train"))
            fit, val = fit + f, val + v
    spec = FitSpec("gnn", tuple(fit), tuple(val))
    return fit_task(house, spec, dataset.meta, HEADLINE_WINDOW_MIN, spec.path(folder / "pretrain", f"without_{house}"))


def plan(dataset: Dataset, experiments: list[str], households: list[str], methods: list[str]) -> list[tuple]:
    """(key, household, method, days, pretrain?) of every run, in the order of `experiments`: one experiment for
    every household before the next, so that a partial run already gives whole tables."""
    runs = []
    n_train = {house: len(dataset.day_indices(house, "train")) for house in households}
    for experiment in experiments:
        for house in households:
            n = n_train[house]
            if experiment == "main":
                runs += [(f"main/{house}/{m}/{n}", house, m, None, False) for m in methods]
            elif experiment == "ablation":
                runs += [(f"main/{house}/{m}/{n}", house, m, None, False) for m in ABLATIONS]
            elif experiment == "days":
                runs += [(f"days/{house}/{m}/{d}", house, m, d, False) for d in DAY_COUNTS if d < n
                         for m in DAYS_METHODS]
            else:
                runs += [(f"pretrain/{house}/gnn/{d}", house, "gnn", d, True) for d in (*DAY_COUNTS, n) if d <= n]
    return list(dict.fromkeys(runs))


def execute(dataset: Dataset, runs: Runs, todo: list[tuple], folder: Path, backend: Backend = IN_PROCESS) -> None:
    """Every run of `todo` not yet in `runs`, as tasks on `backend`: first the pre-training each household's
    fine-tuning runs start from, then the runs; checkpoints and runs.json are written here as tasks finish."""
    todo = [run for run in todo if not runs.done(run[0])]
    pretraining = [pretrain_task(dataset, house, folder)
                   for house in dict.fromkeys(house for _, house, _, _, pretrain in todo if pretrain)]
    inits = {task.key: task.checkpoint for task in pretraining}
    with backend.run(run_fit, pretraining, type(None), cpus_per_task=TORCH_THREADS) as run:
        for result in run:
            log.info("pre-trained without %s (%d s)", result.key, round(result.wall_s))
            result.save()
    tasks = (run_task(dataset, key, house, method, days, folder, inits[house] if pretrain else None)
             for key, house, method, days, pretrain in todo)
    with backend.run(run_fit, tasks, type(None), cpus_per_task=TORCH_THREADS) as run:
        for k, result in enumerate(run):
            log.info("run %d/%d: %s (%d s)", k + 1, len(todo), result.key, round(result.wall_s))
            result.save()
            runs.add(result.key, record(result))


def _counts(record: dict, window: int, pool: str = "all") -> Counts:
    return Counts(**record["windows"][str(window)][pool])


def table(records: dict, prefix: str, window: int) -> dict:
    """{"window_min", "households", "methods": summarised percentages} from runs whose key starts with prefix."""
    per_method: dict[str, dict[str, dict]] = {}
    for key, record in records.items():
        if key.startswith(prefix):
            _, house, method, _ = key.split("/")
            result = household_result(_counts(record, window), _counts(record, window, "used_pool"), record["params"])
            per_method.setdefault(method, {})[house] = result
    houses = sorted({h for per in per_method.values() for h in per})
    return {"window_min": window, "households": houses, "methods": {m: summarise(v) for m, v in per_method.items()}}


def _complete(records: dict, prefix: str, methods: tuple[str, ...]) -> dict:
    """The runs under `prefix` of `methods`, for only the households that have a run of every one of them."""
    runs = {k: r for k, r in records.items() if k.startswith(prefix) and k.split("/")[2] in methods}
    done = {(k.split("/")[1], k.split("/")[2]) for k in runs}
    houses = {house for house, _ in done if all((house, m) in done for m in methods)}
    return {k: r for k, r in runs.items() if k.split("/")[1] in houses}


def per_query(records: dict, prefix: str) -> dict[str, dict[int, dict]]:
    """Objects per query in each outcome, averaged over households, per method and window."""
    out: dict[str, dict[int, dict]] = {}
    for key, record in records.items():
        if key.startswith(prefix):
            method = key.split("/")[2]
            for window in CURVE_WINDOWS_MIN:
                c, q = _counts(record, window), record["queries"]
                values = {"used": {"correct": c.used_correct / q, "wrong": c.used_wrong / q,
                                   "missed": c.used_missed / q},
                          "unused": {"correct": c.unused_correct / q, "wrong": c.unused_wrong / q}}
                out.setdefault(method, {}).setdefault(window, []).append(values)
    return {m: {w: _mean_nested(v) for w, v in per.items()} for m, per in out.items()}


def main_methods(records: dict) -> list[str]:
    """The methods that have a main run, in first-seen order."""
    return list(dict.fromkeys(k.split("/")[2] for k in records if k.startswith("main/")))


def _mean_nested(rows: list[dict]) -> dict:
    return {g: {k: float(np.mean([r[g][k] for r in rows])) for k in rows[0][g]} for g in rows[0]}


def days_summary(records: dict, experiment: str, methods: tuple[str, ...], label: str = "") -> dict:
    """summary[method label][days] of the 30-minute percentages, the full-data point taken from `main`."""
    out: dict[str, dict[int, dict]] = {}
    for key, record in records.items():
        kind, house, method, days = key.split("/")
        if method in methods and kind in (experiment, "main"):
            name = f"{method}{label}" if kind == experiment else method
            if kind == "main" and label:
                continue
            out.setdefault(name, {}).setdefault(int(days), {})[house] = household_result(
                _counts(record, HEADLINE_WINDOW_MIN), _counts(record, HEADLINE_WINDOW_MIN, "used_pool"), {})
    return {m: {d: summarise(h) for d, h in sorted(per.items())} for m, per in out.items()}


def write_outputs(records: dict, out: Path, dataset: str = "", table_path: Path | None = TABLE) -> dict:
    """Every file that the finished runs allow; returns the 30-minute main table and the files written. The
    validation table goes to `table_path` (None: not written) and, as markdown, to OUT."""
    files, main = [], {}
    methods_runs = {k: r for k, r in records.items() if k.split("/")[2] not in ABLATIONS[1:]}
    for window in TABLE_WINDOWS:
        result = table(methods_runs, "main/", window)
        if result["methods"]:
            main.setdefault("tables", {})[str(window)] = result
    if main:
        (out / "main_table.json").write_text(json.dumps(main["tables"], indent=1))
        (out / "main_table.md").write_text("\n\n".join(format_table(t) for t in main["tables"].values()) + "\n")
        files += ["main_table.json", "main_table.md"]
        curves = per_query(records, "main/")
        files.append(window_bars({m: curves[m] for m in curves if m not in ABLATIONS[1:]}, out / "windows.png").name)
        ablation = table(_complete(records, "main/", ABLATIONS), "main/", HEADLINE_WINDOW_MIN)
        if ablation["methods"]:
            rows = [f"| {m} | {v['used']['correct']:.2f} | {v['used']['wrong']:.2f} | {v['unused']['wrong']:.2f} |"
                    for m, v in ablation["methods"].items()]
            (out / "ablation.md").write_text(f"households: {', '.join(ablation['households'])}\n\n"
                                             "| method | % used correct | % used wrong | % unused wrong |\n"
                                             "|---|---|---|---|\n" + "\n".join(rows) + "\n")
            files.append("ablation.md")
        validation = validation_table(_complete(records, "main/", tuple(main_methods(records))), dataset,
                                      HEADLINE_WINDOW_MIN)
        (out / "validation_table.md").write_text(format_validation(validation))
        files.append("validation_table.md")
        if table_path is not None:
            table_path.write_text(json.dumps(validation, indent=1) + "\n")
            files.append(str(table_path))
    if any(k.startswith("days/") for k in records):
        files.append(days_curve(days_summary(records, "days", DAYS_METHODS), out / "days.png",
                                "30-minute window, by training days").name)
    houses = sorted({k.split("/")[1] for k in records if k.startswith("pretrain/")})
    if houses:  # from scratch on the same households as the pre-trained runs so far
        same = {k: r for k, r in records.items() if k.split("/")[1] in houses}
        curves = {**days_summary(same, "days", ("gnn",)), **days_summary(same, "pretrain", ("gnn",), " (pre-trained)")}
        files.append(days_curve(curves, out / "pretrain.png", "graph network: from scratch vs pre-trained "
                                f"({', '.join(houses)})").name)
    headline = main.get("tables", {}).get(str(HEADLINE_WINDOW_MIN), {})
    return {"main_30min": {m: {"used": v["used"], "unused": v["unused"], "spread": v["spread"]}
                           for m, v in headline.get("methods", {}).items()}, "files": files}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="dataset folder")
    parser.add_argument("--out", type=Path, required=True, help="output folder (runs.json, checkpoints, files)")
    parser.add_argument("--experiments", default=",".join(EXPERIMENTS),
                        help=f"from {', '.join(EXPERIMENTS)}, run in the order given")
    parser.add_argument("--households", default=None, help="comma-separated subset (default all)")
    parser.add_argument("--methods", default=",".join(DEFAULT_METHODS), help="methods of the main experiment")
    add_backend_arguments(parser, "training runs")
    parser.add_argument("--report", action="store_true",
                        help="only write the files from the runs already in OUT/runs.json (another process may still "
                             "be adding runs)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(asctime)s %(name)s: %(message)s")
    experiments = [e for e in args.experiments.split(",") if e]
    unknown = sorted(set(experiments) - set(EXPERIMENTS))
    if unknown:
        parser.error(f"unknown experiments {unknown}; known: {', '.join(EXPERIMENTS)}")
    dataset = Dataset(args.data)
    households = args.households.split(",") if args.households else list(dataset.meta.households)
    args.out.mkdir(parents=True, exist_ok=True)
    runs = Runs(args.out / "runs.json", dataset_fingerprint(dataset))
    if not args.report:
        execute(dataset, runs, plan(dataset, experiments, households, args.methods.split(",")),
                args.out / "checkpoints", backend_from_args(args))
    json.dump(write_outputs(runs.records, args.out, runs.dataset), sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
