# Imports follow the sys.path set-up that lets the script run without installation.
# ruff: noqa: E402
"""Wall seconds per assisted day on one core (median over test days): the person's day with the robot helping,
its unassisted reference replay and the scoring, as `homer assist-eval` runs them.

Usage: python benchmarks/bench_assist_day.py --data DIR [--days N] [--method NAME|oracle] [--checkpoints DIR]
Runs the first N test days of every household of DIR (a dataset made by `homer generate`, format 2) in one
process pinned to one core; predictors are fitted (and cached) first and not timed. Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT))

from benchmarks._common import emit, machine_info, pin_to_one_core, positive_int, setup_logging, summary
from model.selection import default_method
from scenarios.assist_eval import EvalSpec, assist_eval

log = logging.getLogger("benchmarks.assist_day")

TARGET_S_PER_DAY = 60.0  # issue 19: a whole assisted test day under a minute on one core


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True, help="dataset folder")
    parser.add_argument("--days", type=positive_int, default=2, help="test days per household (2)")
    parser.add_argument("--method", default=None,
                        help="predictor or oracle (default: the best validated, model/validation_table.json)")
    parser.add_argument("--checkpoints", type=Path, default=None, help="predictor cache (default DATA/checkpoints)")
    args = parser.parse_args()
    setup_logging()
    cpu = pin_to_one_core()
    spec = EvalSpec(str(args.data), args.method or default_method(),
                    checkpoints=str(args.checkpoints) if args.checkpoints else None)
    with tempfile.TemporaryDirectory() as out:
        result = assist_eval(spec, days=args.days, out=Path(out), progress=False)
        walls = [json.loads(path.read_text())["wall_s"] for path in sorted((Path(out) / "days").glob("*.json"))]
    emit({"benchmark": "assist_day", "machine": machine_info(cpu), "method": spec.method, "days": len(walls),
          "wall_s_per_day": summary(walls, 1), "target_s_per_day": TARGET_S_PER_DAY,
          "meets_target": summary(walls)["median"] <= TARGET_S_PER_DAY, "fetch_share": result["total"]["fetch_share"]})


if __name__ == "__main__":
    main()
