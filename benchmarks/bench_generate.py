# Imports follow the sys.path set-up that lets the script run without installation.
# ruff: noqa: E402
"""Wall seconds per simulated day on one core (median over days), and optionally a whole dataset.

Usage: python benchmarks/bench_generate.py [--days N] [--household NAME] [--dataset DIR --workers W]
With --dataset, also generates 5 households x 50 + 10 days into DIR (a new folder) with W workers and reports
the wall time of the whole run. Prints one JSON object on stdout; diagnostics go to stderr.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT))

from benchmarks._common import emit, machine_info, pin_to_one_core, positive_int, setup_logging, summary
from homer_sim.data.generate import Generator, Sources, generate
from homer_sim.days import DayKey  # noqa: E402
from homer_sim.execution import Backend

log = logging.getLogger("benchmarks.generate")

TARGET_S_PER_DAY = 3.0
TARGET_DATASET_S = 600.0


def per_day(days: int, households: list[str] | None) -> dict:
    generator = Generator(Sources())
    names = households or list(generator.households)
    generator.simulate(names[0], DayKey(0, 0, "train", 999))  # warm-up: compile caches, first paths
    walls, physics, attempts = [], [], []
    for k in range(days):
        name = names[k % len(names)]
        started = time.perf_counter()
        _, info = generator.simulate(name, DayKey(0, list(generator.households).index(name), "train", k))
        walls.append(time.perf_counter() - started)
        physics.append(info["physics_s"])
        attempts.append(info["attempts"])
        log.info("%s day %d: %.2f s wall, %.1f s physics, %d attempt(s)", name, k, walls[-1], physics[-1], attempts[-1])
    return {"days": days, "wall_s_per_day": summary(walls, 3), "physics_s_per_day": summary(physics, 1),
            "attempts_per_day": summary(attempts, 2), "target_s_per_day": TARGET_S_PER_DAY,
            "meets_target": summary(walls)["median"] <= TARGET_S_PER_DAY}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=positive_int, default=10, help="days to time on one core (10)")
    parser.add_argument("--household", action="append", default=None, help="household(s) to use (all)")
    parser.add_argument("--dataset", type=Path, default=None, help="also generate a full dataset here")
    parser.add_argument("--workers", type=positive_int, default=2, help="workers for --dataset (2)")
    args = parser.parse_args()
    setup_logging()
    cpu = pin_to_one_core()
    result = {"benchmark": "generate", "machine": machine_info(cpu), "one_core": per_day(args.days, args.household)}
    if args.dataset is not None:
        import os

        os.sched_setaffinity(0, range(os.cpu_count() or 1))  # the dataset run uses all its workers
        summary_ = generate(args.dataset, 5, 50, 10, seed=0, backend=Backend(args.workers), progress=False)
        result["dataset"] = {**summary_, "workers": args.workers, "target_s": TARGET_DATASET_S,
                             "meets_target": summary_["wall_s"] <= TARGET_DATASET_S}
    emit(result)


if __name__ == "__main__":
    main()
