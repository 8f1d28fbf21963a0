"""Graph-network cost on a full-size synthetic household: training time to early stopping, rollout time per
10-minute step for the whole apartment graph, peak memory. Prints one JSON object on stdout.

    .venv/bin/python benchmarks/bench_model.py [--train-days 50] [--rollout-steps 200] [--data DIR]

Uses `--threads` torch threads (2). Training: 50 synthetic days (45 fit + 5 validation) of the 123-node apartment
(87 movable objects), default GNNConfig (hidden 20, Adam 1e-3, batch 32, patience 4). Rollout: B = 1 graph,
`--rollout-steps` steps fed back after 5 warm-up steps; also the per-graph cost in the batches that
evaluation rollouts use (model.train.ROLLOUT_CHUNK graphs).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402
import torch  # noqa: E402

from homer_sim.data.dataset import Dataset  # noqa: E402
from model.evaluate import split_days  # noqa: E402
from model.gnn import GNNConfig  # noqa: E402
from model.synthetic import write_synthetic_dataset  # noqa: E402
from model.train import ROLLOUT_CHUNK, GNNPredictor, adjacency  # noqa: E402

TARGET_TRAIN_S = 600.0
TARGET_ROLLOUT_MS = 5.0


def machine() -> dict:
    return {"cpu_count": os.cpu_count(), "affinity": len(os.sched_getaffinity(0)), "torch_threads":
            torch.get_num_threads(), "platform": platform.platform(), "python": platform.python_version(),
            "torch": torch.__version__, "numpy": np.__version__, "load_average_1min": os.getloadavg()[0]}


def bench_training(dataset: Dataset, household: str, train_days: int, max_epochs: int | None) -> tuple[dict,
                                                                                                        GNNPredictor]:
    fit, val = split_days(dataset.load(household, "train")[:train_days])
    config = GNNConfig(movable=tuple(dataset.meta.movable))
    if max_epochs is not None:
        config = GNNConfig(movable=config.movable, max_epochs=max_epochs)
    predictor = GNNPredictor(dataset.meta, config, progress=True)
    started = time.perf_counter()
    predictor.fit(fit, val)
    wall = time.perf_counter() - started
    report = predictor.report
    assert report is not None
    return {"fit_days": len(fit), "val_days": len(val), "transitions": sum(d.steps - 1 for d in fit),
            "wall_s": round(wall, 1), "epochs": report.epochs, "best_epoch": report.best_epoch,
            "s_per_epoch": round(wall / report.epochs, 2), "best_val_loss": round(report.best_val_loss, 5),
            "stopped_early": report.epochs < config.max_epochs, "target_s": TARGET_TRAIN_S,
            "meets_target": wall < TARGET_TRAIN_S}, predictor


def bench_rollout(predictor: GNNPredictor, dataset: Dataset, household: str, steps: int) -> dict:
    day = dataset.load(household, "train")[0]
    model = predictor.model
    with torch.no_grad():
        probs = adjacency(torch.as_tensor(day.parent[:1].astype(np.int64)), predictor.n_nodes)
        minute = torch.tensor([float(day.minutes[0])])
        for _ in range(5):
            probs = model.step(probs, minute)
        times = []
        for s in range(steps):
            started = time.perf_counter()
            probs = model.step(probs, minute + 10.0 * (s + 1))
            times.append((time.perf_counter() - started) * 1000)
        batch = adjacency(torch.as_tensor(day.parent[:ROLLOUT_CHUNK].astype(np.int64)), predictor.n_nodes)
        started = time.perf_counter()
        for s in range(steps):
            minute = torch.as_tensor(day.minutes[:ROLLOUT_CHUNK], dtype=torch.float32) + 10.0 * (s + 1)
            batch = model.step(batch, minute)
        batched = (time.perf_counter() - started) * 1000 / (steps * ROLLOUT_CHUNK)
    return {"ms_per_step": {"median": round(statistics.median(times), 3), "min": round(min(times), 3),
                            "max": round(max(times), 3)}, "steps": steps,
            "batched_ms_per_graph_step": round(batched, 3),
            "target_ms": TARGET_ROLLOUT_MS, "meets_target": statistics.median(times) < TARGET_ROLLOUT_MS}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=None, help="dataset folder (default: a fresh synthetic one)")
    parser.add_argument("--household", default=None, help="household to train on (default: the first)")
    parser.add_argument("--train-days", type=int, default=50)
    parser.add_argument("--rollout-steps", type=int, default=200)
    parser.add_argument("--max-epochs", type=int, default=None, help="cap epochs (default: GNNConfig's)")
    parser.add_argument("--threads", type=int, default=2, help="torch threads (2; 1 is faster for B = 1 rollouts "
                        "on a busy machine)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(asctime)s %(name)s: %(message)s")
    torch.set_num_threads(args.threads)
    with tempfile.TemporaryDirectory() as tmp:
        root = args.data or Path(tmp)
        if args.data is None:
            write_synthetic_dataset(root, np.random.default_rng(0), households=1, train_days=args.train_days,
                                    test_days=1)
        dataset = Dataset(root)
        household = args.household or dataset.meta.households[0]
        training, predictor = bench_training(dataset, household, args.train_days, args.max_epochs)
        rollout = bench_rollout(predictor, dataset, household, args.rollout_steps)
    result = {"machine": machine(), "nodes": len(dataset.meta.nodes), "movable": int(dataset.meta.movable_mask.sum()),
              "training": training, "rollout": rollout,
              "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)}
    json.dump(result, sys.stdout, indent=2)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
