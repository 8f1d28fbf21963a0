# Imports follow the sys.path set-up that lets the script run without installation.
# ruff: noqa: E402
"""Grasp-suite benchmark: the full suite (or the quick subset), its success rates and its wall time.

Prints the `grasp-suite` JSON object (trials, overall, per_class, excluded) with the machine description and
the targets (overall at least 0.95, no class under 0.8, at most a fifth of the classes excluded).
Usage: python benchmarks/bench_grasp_suite.py [--quick] [--trials N] [--seed S]
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT))

from benchmarks._common import emit, machine_info, pin_to_one_core, positive_int, setup_logging
from planners.suites.grasp_suite import TARGET_CLASS, TARGET_OVERALL, run_suite

log = logging.getLogger("benchmarks.grasp_suite")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="one class of each shape family")
    parser.add_argument("--trials", type=positive_int, default=None, help="trials per class (3; 1 with --quick)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    setup_logging()
    logging.getLogger("planners").setLevel(logging.WARNING)
    cpu = pin_to_one_core()
    result = run_suite(quick=args.quick, trials=args.trials, seed=args.seed, progress=True)
    log.info("overall %.3f over %d trials", result["overall"], result["trials"])
    emit({"machine": machine_info(cpu), "target_overall": TARGET_OVERALL, "target_class": TARGET_CLASS,
          **result})


if __name__ == "__main__":
    main()
