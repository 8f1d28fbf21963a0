"""Cost of the analogs predictor on one household: fitting (storing the days) plus cross-validated tuning, and the
time of one rollout step (one observed graph, one 10-minute step) at the tuned parameters. One JSON object.

    .venv/bin/python benchmarks/bench_analogs.py --data DIR [--household NAME] [--queries 200] [--threads 1]

Rollout: `--queries` observed graphs of the household's test days, each rolled out 6 steps (60 minutes), B = 1;
the per-step time is the median over queries of (rollout time / 6). Targets: training (fit + tuning) <= 600 s,
a rollout step <= 5 ms.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402
import torch  # noqa: E402

from homer_sim.data.dataset import Dataset  # noqa: E402
from model.evaluate import HEADLINE_WINDOW_MIN, FitSpec, fit_tuned, household_split  # noqa: E402

TARGET_TRAIN_S = 600.0
TARGET_STEP_MS = 5.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="dataset folder")
    parser.add_argument("--household", default=None, help="household (default the dataset's first)")
    parser.add_argument("--queries", type=int, default=200, help="observed graphs timed (200)")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (1); analogs itself is numpy")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    dataset = Dataset(args.data)
    house = args.household or dataset.meta.households[0]
    fit, val, test, _ = household_split(dataset, house, None)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        spec = FitSpec("analogs", tuple(fit), tuple(val))
        predictor, info = fit_tuned(spec, dataset.meta, HEADLINE_WINDOW_MIN, spec.path(Path(folder), house),
                                 progress=False, target="f1")
    train_s = time.perf_counter() - started
    rng = np.random.default_rng(0)
    picks = [(d, int(rng.integers(d.steps - 1))) for d in (test[i % len(test)] for i in range(args.queries))]
    per_step = []
    for day, t in picks:
        begin = time.perf_counter()
        predictor.rollout(day.parent[t:t + 1], day.minutes[t:t + 1], 6)
        per_step.append((time.perf_counter() - begin) / 6 * 1000.0)
    step_ms = statistics.median(per_step)
    print(json.dumps({"household": house, "nodes": len(dataset.meta.nodes), "movable": int(sum(dataset.meta.movable)),
                      "fit_days": info["fit_days"],
                      "cross_validation_days": info.get("cross_validation_days", 0), "params": predictor.params,
                      "train_and_tune_s": round(train_s, 1), "rollout_step_ms_median": round(step_ms, 3),
                      "rollout_step_ms_p90": round(float(np.percentile(per_step, 90)), 3),
                      "targets": {"train_s": TARGET_TRAIN_S, "rollout_step_ms": TARGET_STEP_MS},
                      "met": train_s <= TARGET_TRAIN_S and step_ms <= TARGET_STEP_MS}))


if __name__ == "__main__":
    main()
