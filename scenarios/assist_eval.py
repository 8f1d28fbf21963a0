"""`homer assist-eval`: the assisted day on every test day of every household of a dataset, measured end to end.

Per household, the predictor (by default the best validated method of `model.selection`'s table) is fitted on the
dataset's training days and tuned on their last tenth, its threshold for the assistance objective (the paper's
reported beside it), cached as `homer evaluate` caches it (`scenarios.predictors.predictor_for`); method `oracle`
instead predicts from the unassisted
replay of the same day (perfect prediction: what is left is manipulation). Each test day is one episode of the
assisted-day environment (`scenarios.env`) run by Psi, a task of `homer_sim.execution` (local or Ray); a day's
robot draws its random stream from (seed, household, day), so the figures do not depend on the number of workers.
Each day's result is kept in the output folder as it finishes, so an interrupted run resumes where it stopped.
"""

from __future__ import annotations

import hashlib
import json
import logging
import statistics
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from homer_sim import __version__
from homer_sim.clock import DEFAULT_WINDOW_MIN
from homer_sim.data.dataset import Dataset
from homer_sim.data.generate import Generator, Sources
from homer_sim.errors import HomerError, unknown_name
from homer_sim.execution import IN_PROCESS, Backend
from homer_sim.home.apartment import default_layout
from model.selection import default_method
from scenarios.episodes import dataset_day_plan
from scenarios.policies import OraclePredictor, PsiPolicy
from scenarios.predictors import TUNINGS, predictor_for, thresholds
from scenarios.scoring import day_result
from scenarios.task import AssistEnv, AssistTask, play

log = logging.getLogger(__name__)

ORACLE = "oracle"
COUNTS = ("relocations_planned", "relocations_done", "relocations_correct", "relocations_wrong", "fetches",
          "fetches_done_by_robot", "collateral")


@dataclass(frozen=True)
class EvalSpec:
    """One evaluation: the dataset folder, the method (a predictor name or `oracle`), the robot's seed, the
    prediction window (min), the folder of cached predictors, and the routine minute each day stops after (None:
    the whole day)."""

    data: str
    method: str = field(default_factory=default_method)
    seed: int = 0
    window_min: int = DEFAULT_WINDOW_MIN
    checkpoints: str | None = None
    end_min: int | None = None

    def checkpoint_folder(self) -> Path:
        return Path(self.checkpoints) if self.checkpoints else Path(self.data) / "checkpoints"

    def key(self) -> str:
        """A digest of the spec (day results are reused only under the same key)."""
        return hashlib.sha1(json.dumps(asdict(self), sort_keys=True).encode()).hexdigest()[:10]


class DayRunner:
    """One worker's simulators: the assisted-day environment and the unassisted replay it is judged against."""

    def __init__(self, spec: EvalSpec) -> None:
        self.spec = spec
        self.dataset = Dataset(spec.data)
        self.dataset.require_nodes(default_layout().node_names())
        self.generator = Generator(Sources())
        self.env: AssistEnv | None = None
        self.predictors: dict[str, object] = {}

    def run(self, household: str, index: int) -> dict:
        """The result of test day `index` of `household` (`scenarios.scoring.day_result` plus wall seconds)."""
        started = time.perf_counter()
        plan = dataset_day_plan(self.dataset, household, index, end_min=self.spec.end_min,
                                robot_seed=self.spec.seed)
        if self.env is None:
            self.env = AssistEnv(AssistTask([plan], window_min=self.spec.window_min,
                                            reference=self.generator))
        self.env.task.days = (plan,)
        timestep = self.env.reset()
        task = self.env.task
        policy = PsiPolicy(task.scene, self.predictor(household, task), self.spec.window_min)
        episode_return = play(self.env, timestep, policy)
        result = day_result(task.log, task.reference, task.scene.nodes, task.scene.categories, policy.plans,
                            self.spec.window_min, until=task.day.end_min)
        result.update({"household": household, "day": index, "return": episode_return,
                       "wall_s": round(time.perf_counter() - started, 2)})
        return result

    def predictor(self, household: str, task: AssistTask):
        """The household's fitted predictor, or for `oracle` the replay of the task's current day."""
        if self.spec.method == ORACLE:
            return OraclePredictor(task.reference, task.scene.movable)
        if household not in self.predictors:
            self.predictors[household] = predictor_for(self.dataset, household, self.spec.method,
                                                      self.spec.window_min, self.spec.checkpoint_folder())[0]
        return self.predictors[household]


def assist_day(runner: DayRunner, task: tuple[str, int]) -> dict:
    """Day `task` = (household, test day index) on a worker's DayRunner: the task function of the execution
    backend (the worker reads the dataset and the checkpoints at the spec's paths)."""
    return runner.run(*task)


# --- the evaluation ---------------------------------------------------------------------------------------------
def assist_eval(spec: EvalSpec, households: Sequence[str] | None = None, days: int | None = None,
                backend: Backend = IN_PROCESS, out: Path | None = None, progress: bool = True) -> dict:
    """Run (or resume) the evaluation, each day a task on `backend` (this process, local processes or Ray: on a
    cluster every node must see the dataset and checkpoints at their paths); returns the `homer assist-eval` JSON
    (`summarise`) and writes it, the markdown table and the figure into `out` (default: the checkpoint folder's
    `assist_eval_<method>_<key>`), here only."""
    from tqdm import tqdm

    dataset = Dataset(spec.data)
    dataset.require_nodes(default_layout().node_names())
    names = list(households or dataset.meta.households)
    for name in names:
        if name not in dataset.meta.households:
            raise unknown_name("household", name, dataset.meta.households)
    tuned: dict[str, dict[str, float]] = {}
    if spec.method != ORACLE:
        from model.methods import check_method

        check_method(spec.method)
        for name in names:  # fit once here, not in every worker
            info = predictor_for(dataset, name, spec.method, spec.window_min, spec.checkpoint_folder(), progress)[1]
            act = info["tunings"][f"{TUNINGS[-1]}@{spec.window_min}"]["params"].get("act_steps", 0.0)
            tuned[name] = {**thresholds(info, spec.window_min), "act_steps": act}
    out = Path(out) if out else spec.checkpoint_folder() / f"assist_eval_{spec.method}_{spec.key()}"
    cached = _cached_days(out, spec)
    tasks = [(name, i) for name in names for i in range(_test_days(dataset, name, days))]
    todo = [t for t in tasks if t not in cached]
    bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), desc="assisted days", unit="day",
               disable=not progress, dynamic_ncols=True)
    from model.names import GNN_METHODS
    from model.train import TORCH_THREADS

    threads = TORCH_THREADS if spec.method in GNN_METHODS else 1  # a Ray task then runs torch as this process does
    with backend.run(assist_day, todo, DayRunner, (spec,), cpus_per_task=threads) as run:
        for result in run:
            cached[(result["household"], result["day"])] = result
            _write_json(out / "days" / f"{result['household']}_{result['day']:03d}.json", result)
            bar.set_postfix(household=result["household"], share=result["fetch_share"])
            bar.update()
    bar.close()
    summary = summarise(spec.method, [cached[t] for t in tasks], names)
    summary["thresholds"] = tuned
    _write_json(out / "assist_eval.json", summary)
    (out / "assist_eval.md").write_text(markdown_table(summary))
    plot(summary, out / "assist_eval.png")
    summary["out"], summary["execution"] = str(out), run.usage()
    return summary


def _test_days(dataset: Dataset, household: str, days: int | None) -> int:
    available = len(dataset.load(household, "test"))
    if available == 0:
        raise HomerError(f"household {household} has no test days in {dataset.root}")
    return available if days is None else min(days, available)


def _cached_days(out: Path, spec: EvalSpec) -> dict[tuple[str, int], dict]:
    """Day results of an earlier run of the same spec and package version in `out` (a folder of another one is
    refused: its days were lived by other code or settings)."""
    setting = {"spec": asdict(spec), "homer_sim": __version__, "robot_threshold": f"tuned for {TUNINGS[-1]}"}
    spec_path = out / "spec.json"
    if spec_path.is_file() and json.loads(spec_path.read_text()) != setting:
        raise HomerError(f"{out} holds an assist-eval of another setting ({spec_path.read_text()}); use another --out")
    _write_json(spec_path, setting)
    found = {}
    for path in sorted((out / "days").glob("*.json")):
        result = json.loads(path.read_text())
        found[(result["household"], result["day"])] = result
    return found


def _write_json(path: Path, value: dict) -> None:
    """Write atomically (temp file + rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(value, indent=1, default=str))
    tmp.replace(path)


def totals(results: Sequence[dict]) -> dict:
    """The counts of `COUNTS` summed over day results, the fetch share, days, robot minutes and the median wall
    seconds per day."""
    out = {k: int(sum(r[k] for r in results)) for k in COUNTS}
    out["fetch_share"] = round(out["fetches_done_by_robot"] / out["fetches"], 4) if out["fetches"] else None
    out["days"] = len(results)
    out["robot_minutes"] = round(float(sum(r["robot_minutes"] for r in results)), 1)
    out["wall_s_per_day"] = round(statistics.median(r["wall_s"] for r in results), 1) if results else None
    out["person_stopped"] = sum(bool(r["error"]) for r in results)
    return out


def summarise(method: str, results: Sequence[dict], households: Sequence[str]) -> dict:
    """The `homer assist-eval` JSON: totals, per household, failures counted by cause, and the person's fetches
    counted by whether the robot made them ahead or why not (`scenarios.scoring.why_not_ahead`)."""
    failures: Counter = Counter()
    outcomes: Counter = Counter()
    for r in results:
        failures.update(r["failures"])
        outcomes.update(r.get("fetch_outcomes", {}))
    per_household = {h: totals([r for r in results if r["household"] == h]) for h in households}
    return {"method": method, "total": totals(results), "per_household": per_household,
            "failures": dict(failures.most_common()), "fetch_outcomes": dict(outcomes.most_common())}


def markdown_table(summary: dict) -> str:
    """The per-household table and the failure causes, in markdown."""
    columns = ("days", *COUNTS, "fetch_share", "robot_minutes", "wall_s_per_day")
    lines = [f"method: {summary['method']}", *threshold_lines(summary.get("thresholds", {})), "",
             "| household | " + " | ".join(columns) + " |",
             "|---" * (len(columns) + 1) + "|"]
    rows = [*summary["per_household"].items(), ("total", summary["total"])]
    lines += [f"| {name} | " + " | ".join(str(row[c]) for c in columns) + " |" for name, row in rows]
    lines += ["", "| failure cause | relocations |", "|---|---|"]
    lines += [f"| {cause} | {n} |" for cause, n in summary["failures"].items()] or ["| (none) | 0 |"]
    lines += ["", "| the person's fetches: made ahead, or why not | fetches |", "|---|---|"]
    lines += [f"| {kind} | {n} |" for kind, n in summary.get("fetch_outcomes", {}).items()] or ["| (none) | 0 |"]
    return "\n".join(lines) + "\n"


def threshold_lines(tuned: dict[str, dict[str, float]]) -> list[str]:
    """The thresholds per household: the robot's (tuned for the assistance objective, with its act steps) and the
    paper's."""
    if not tuned:
        return []
    return ["", "thresholds tuned on validation days (the robot acts on the assistance one, on moves predicted at most",
            "act steps of 10 min ahead):", "",
            "| household | assistance | act steps | paper |", "|---|---|---|---|",
            *(f"| {h} | {t['assist']:.2f} | {t.get('act_steps', 0):.0f} | {t['paper']:.2f} |"
              for h, t in tuned.items())]


def plot(summary: dict, path: Path) -> None:
    """Per household: the fetch share (left) and the relocations done correct, done wrong and not done (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(summary["per_household"])
    rows = [summary["per_household"][n] for n in names]
    x = np.arange(len(names))
    fig, (share, outcomes) = plt.subplots(1, 2, figsize=(10, 3.6))
    share.bar(x, [100 * (r["fetch_share"] or 0.0) for r in rows], color="tab:blue")
    share.set(xticks=x, xticklabels=names, ylabel="fetches made ahead by the robot (%)",
              title=f"fetch share ({summary['method']})")
    correct = np.array([r["relocations_correct"] for r in rows])
    wrong = np.array([r["relocations_wrong"] for r in rows])
    failed = np.array([r["relocations_planned"] - r["relocations_done"] for r in rows])
    outcomes.bar(x, correct, label="done, correct", color="tab:green")
    outcomes.bar(x, wrong, bottom=correct, label="done, wrong", color="tab:orange")
    outcomes.bar(x, failed, bottom=correct + wrong, label="not done", color="tab:red")
    outcomes.set(xticks=x, xticklabels=names, ylabel="relocations", title="relocation outcomes")
    outcomes.legend(fontsize=8)
    for axis in (share, outcomes):
        axis.tick_params(axis="x", labelrotation=20)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".tmp.png")
    fig.savefig(tmp, dpi=100)
    plt.close(fig)
    tmp.replace(path)
