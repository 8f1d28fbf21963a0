"""Every method on HOMER+ (the authors' own data), as files. Resumable: each finished (household, method) run is
recorded in OUT/runs.json and skipped next time; fitted predictors are cached under --checkpoints.

Per household and method: tunables chosen on the validation days (the last 10% of the upstream training days)
for SLaTe-PRO's relocation F1 over 10 .. 60 minutes, and separately for the paper's objective at 30 minutes;
each scored on the upstream test days with the metric it was tuned for.
Files in OUT: f1_table.md / f1_table.json (method x household x lookahead step, and mean), f1_lookahead.png,
paper_table.md (the paper's 30-minute table). Published F1 on HOMER+ (SLaTe-PRO paper): STOT 0.43, SLaTe-PRO 0.57.

    homer import homer-plus HouseholdA --out DATA; homer import homer-plus HouseholdB --out DATA
    .venv/bin/python benchmarks/homer_plus_results.py --data DATA --out benchmarks/results/homer_plus
    .venv/bin/python benchmarks/homer_plus_results.py --data DATA --out DIR --report   # files from the runs so far
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.paper_results import Runs, dataset_fingerprint  # noqa: E402
from homer_sim.data.dataset import Dataset  # noqa: E402
from model.evaluate import (  # noqa: E402
    HEADLINE_WINDOW_MIN,
    FitSpec,
    FitTask,
    fit_task,
    household_split,
    run_fit,
    score_household,
    summarise,
)
from model.names import DEFAULT_METHODS  # noqa: E402
from model.report import format_f1_table, format_table  # noqa: E402
from model.train import TORCH_THREADS  # noqa: E402
from scenarios.cli.common import add_backend_arguments, backend_from_args  # noqa: E402

log = logging.getLogger("homer_plus_results")
PUBLISHED_F1 = {"gnn (STOT, published)": 0.43, "SLaTe-PRO (published)": 0.57}


def run_task(dataset: Dataset, house: str, method: str, folder: Path) -> FitTask:
    """One method on one household, fitted (or loaded) and tuned for F1, then for the paper's table, and scored on
    the test days."""
    fit, val, test, pool = household_split(dataset, house, None)
    spec = FitSpec(method, tuple(fit), tuple(val))
    return fit_task(f"{house}/{method}", spec, dataset.meta, HEADLINE_WINDOW_MIN, spec.path(folder, house),
                    ("f1", "paper"), partial(score_household, (test, pool), HEADLINE_WINDOW_MIN))


def collect(records: dict) -> dict:
    """runs.json records -> an evaluate-shaped result (methods averaged over the households each has)."""
    per: dict[str, dict[str, dict]] = {}
    for key, record in sorted(records.items()):
        house, method = key.split("/")
        per.setdefault(method, {})[house] = record
    houses = sorted({k.split("/")[0] for k in records})
    return {"window_min": HEADLINE_WINDOW_MIN, "households": houses,
            "methods": {m: summarise(v) for m, v in per.items()}}


def write_outputs(records: dict, out: Path) -> dict:
    """f1_table.md/.json, f1_lookahead.png and paper_table.md from the finished runs; returns the F1 means."""
    result = collect(records)
    if not result["methods"]:
        return {"files": []}
    f1 = {m: {"mean_over_households": row["f1"], "per_household": {h: r["f1"] for h, r in
                                                                   row["per_household"].items()}}
          for m, row in result["methods"].items()}
    (out / "f1_table.json").write_text(json.dumps({"published": PUBLISHED_F1, "methods": f1}, indent=1) + "\n")
    lines = [format_f1_table(result), ""]
    for house in result["households"]:
        sub = {"households": [house], "methods": {m: {"f1": row["per_household"][house]["f1"]} for m, row in
                                                  result["methods"].items() if house in row["per_household"]}}
        lines += [format_f1_table(sub), ""]
    lines.append("published (SLaTe-PRO paper, three households, most likely F1 at 30 minutes: gnn_gap.md): " +
                 ", ".join(f"{k} {v:.2f}" for k, v in PUBLISHED_F1.items()))
    (out / "f1_table.md").write_text("\n".join(lines) + "\n")
    (out / "paper_table.md").write_text(format_table(result) + "\n")
    plot_f1(f1, out / "f1_lookahead.png")
    return {"f1_mean": {m: {h: r["mean"] for h, r in v["per_household"].items()} for m, v in f1.items()},
            "files": ["f1_table.md", "f1_table.json", "f1_lookahead.png", "paper_table.md"]}


def plot_f1(f1: dict, path: Path) -> None:
    """F1 against lookahead (10 .. 60 min), one panel per household, published means as dashed lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    houses = sorted({h for v in f1.values() for h in v["per_household"]})
    fig, axes = plt.subplots(1, len(houses), figsize=(5.5 * len(houses), 4.2), squeeze=False, sharey=True)
    for ax, house in zip(axes[0], houses, strict=True):
        for method, v in f1.items():
            if house in v["per_household"]:
                row = v["per_household"][house]
                ax.plot(range(10, 70, 10), row["per_step"], marker="o", label=f"{method} ({row['mean']:.2f})")
        for (name, value), style in zip(PUBLISHED_F1.items(), ("--", ":"), strict=True):
            ax.axhline(value, color="black", linestyle=style, linewidth=1, label=name)
        ax.set(title=f"HOMER+ {house}", xlabel="lookahead (min)", ylabel="relocation F1", ylim=(0, 1))
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="dataset folder of imported HOMER+ households")
    parser.add_argument("--out", type=Path, required=True, help="output folder (runs.json and the files)")
    parser.add_argument("--checkpoints", type=Path, default=None, help="checkpoint cache (default OUT/checkpoints)")
    parser.add_argument("--households", default=None, help="comma-separated subset (default all)")
    parser.add_argument("--methods", default=",".join(DEFAULT_METHODS), help="comma-separated methods")
    parser.add_argument("--report", action="store_true", help="only write the files from the runs so far")
    add_backend_arguments(parser, "runs (one per household and method)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(asctime)s %(name)s: %(message)s")
    dataset = Dataset(args.data)
    households = args.households.split(",") if args.households else list(dataset.meta.households)
    args.out.mkdir(parents=True, exist_ok=True)
    runs = Runs(args.out / "runs.json", dataset_fingerprint(dataset))
    todo = [(house, method) for house in households if not args.report for method in args.methods.split(",")
            if not runs.done(f"{house}/{method}")]
    tasks = (run_task(dataset, house, method, args.checkpoints or args.out / "checkpoints") for house, method in todo)
    with backend_from_args(args).run(run_fit, tasks, type(None), cpus_per_task=TORCH_THREADS) as run:
        for result in run:  # checkpoints and runs.json are written here, as each run finishes
            log.info("ran %s (%d s)", result.key, round(result.wall_s))
            result.save()
            runs.add(result.key, {**result.scores, "wall_s": round(result.wall_s, 1)})
    json.dump(write_outputs(runs.records, args.out), sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
