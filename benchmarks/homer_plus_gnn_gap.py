"""Why a method's HOMER+ relocation F1 here differs from the published one (issue 21, item 3): the same fitted and
tuned predictor as `homer_plus_results.py` (same checkpoint cache and key; fitted here if missing), scored on the
test days under each difference between this project's protocol and the SLaTe-PRO code's, one at a time:

- decision rule: the threshold tuned for F1 on validation days (`tuned`), or the per-node argmax of each step
  (`argmax`, threshold 0, what the SLaTe-PRO code takes);
- what a step compares: the object's parent at t + s (`state`, the definition HOMER+ publishes with its data
  and model/metrics.py), or its first change within (t, t + s] (`first_change`: what the SLaTe-PRO code's
  `evaluate_prediction` keeps in `dest_pred` / `dest_gt`, sticky once an object is predicted or seen to move);
- queries: every step but each day's last (`ours`, lookahead cut at the day's end), or steps 1 .. T - 7 only
  (`upstream`: the SLaTe-PRO code drops the first step and every query whose 6 lookahead steps leave the day).

Writes one JSON (per household and method: the training report, and F1 per step, mean, tp, fp, fn per variant).
`--config` refits the gnn with other training settings (e.g. longer) under a checkpoint of its own.

    .venv/bin/python benchmarks/homer_plus_gnn_gap.py --data DATA --checkpoints CKPT --out gap.json
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from homer_sim.data.dataset import Dataset, Day  # noqa: E402
from model.evaluate import FitSpec, fit_task, household_split, rollout_queries, run_fit  # noqa: E402
from model.metrics import (  # noqa: E402
    F1_STEPS,
    Queries,
    RelocationCounts,
    day_queries,
    first_change,
    gate,
    relocation_counts,
)
from model.predictor import Predictor  # noqa: E402

log = logging.getLogger("homer_plus_gnn_gap")


def upstream_rows(days: list[Day]) -> np.ndarray:
    """(Q,) bool over day_queries(days, ...): the queries the SLaTe-PRO code scores, steps 1 .. T - 7 of each day."""
    return np.concatenate([(t >= 1) & (t <= day.steps - 1 - F1_STEPS) for day in days
                           for t in [np.arange(day.steps - 1)]])


def subset(queries: Queries, rows: np.ndarray) -> Queries:
    return Queries(queries.observed[rows], queries.minute[rows], queries.future[rows], queries.valid[rows])


def first_change_counts(queries: Queries, predicted: np.ndarray, movable: np.ndarray) -> RelocationCounts:
    """The SLaTe-PRO code's counts per lookahead step s: each object's first change within (t, t + s], predicted
    and true (its parent at t where there is none), tp if both changed to the same parent, fp if the predicted
    destination is wrong and it was predicted to change, fn if it is wrong and the object truly changed."""
    tp, fp, fn = (np.zeros(F1_STEPS, dtype=np.int64) for _ in range(3))
    counted_obj = np.asarray(movable, bool)[None]
    for s in range(1, F1_STEPS + 1):
        steps = np.minimum(queries.valid, s)
        counted = counted_obj & (queries.valid >= s)[:, None]
        moved_gt, dest_gt = first_change(queries.observed, queries.future, steps)
        moved_pred, dest_pred = first_change(queries.observed, predicted, steps)
        dest_gt = np.where(moved_gt, dest_gt, queries.observed)
        dest_pred = np.where(moved_pred, dest_pred, queries.observed)
        wrong = dest_pred != dest_gt
        tp[s - 1] = (~wrong & moved_gt & moved_pred & counted).sum()
        fp[s - 1] = (wrong & moved_pred & counted).sum()
        fn[s - 1] = (wrong & moved_gt & counted).sum()
    return RelocationCounts(tp, fp, fn)


def variants(predictor: Predictor, days: list[Day]) -> dict:
    """F1 summaries of every (decision rule, comparison, query set) on `days`."""
    queries = day_queries(days, F1_STEPS)
    rollout = rollout_queries(predictor, queries, F1_STEPS)
    rows = upstream_rows(days)
    out = {}
    for rule, threshold in (("tuned", predictor.params["threshold"]), ("argmax", 0.0)):
        predicted = gate(rollout, queries.observed, threshold)
        for query_set, keep in (("ours", np.ones(len(queries), bool)), ("upstream", rows)):
            q, p = subset(queries, keep), predicted[keep]
            out[f"{rule}/state/{query_set}"] = relocation_counts(q, p, predictor.movable).summary()
            out[f"{rule}/first_change/{query_set}"] = first_change_counts(q, p, predictor.movable).summary()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="dataset folder of imported HOMER+ households")
    parser.add_argument("--checkpoints", type=Path, required=True, help="checkpoint cache of homer_plus_results.py")
    parser.add_argument("--households", default=None, help="comma-separated subset (default all)")
    parser.add_argument("--methods", default="gnn,markov", help="comma-separated methods")
    parser.add_argument("--config", default="", help="network overrides for the gnn, e.g. max_epochs=300,patience=40 "
                        "(a checkpoint of its own)")
    parser.add_argument("--out", type=Path, required=True, help="JSON file to write")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(asctime)s %(name)s: %(message)s")
    dataset = Dataset(args.data)
    config = tuple((k, int(v)) for k, v in (item.split("=") for item in args.config.split(",") if item))
    result: dict = {}
    for house in args.households.split(",") if args.households else dataset.meta.households:
        fit, val, test, _ = household_split(dataset, house, None)
        for method in args.methods.split(","):
            spec = FitSpec(method, tuple(fit), tuple(val), config if method == "gnn" else ())
            done = run_fit(None, fit_task(f"{house}/{method}", spec, dataset.meta, 30,
                                          spec.path(args.checkpoints, house), ("f1",)))
            done.save()
            info = {k: done.info.get(k) for k in ("epochs", "best_epoch", "train_s")} | dict(spec.config)
            result.setdefault(house, {})[method] = {"params": dict(done.predictor.params), "training": info,
                                                   "f1": variants(done.predictor, test)}
            log.info("%s/%s: %s", house, method, {k: v["mean"] for k, v in result[house][method]["f1"].items()})
    args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
