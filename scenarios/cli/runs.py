"""`homer demo breakfast` and `homer run NAME`: the named headless runs.

The scenario code (mujoco, torch) is imported inside the command functions, so `homer --help` stays fast.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from model.names import METHODS
from scenarios.breakfast_data import DataSpec
from scenarios.cli.common import emit
from scenarios.registry import SCENARIOS


def add_commands(subparsers: argparse._SubParsersAction) -> None:
    """Add the `demo` and `run` subcommands to the `homer` parser's subparsers."""
    demo = subparsers.add_parser("demo", help="the breakfast demo: the robot sets and clears the table",
                                 description="On the first run: simulate a small breakfast-household dataset and "
                                 "train the predictor (cached in ~/.cache/homer-sim, or $HOMER_SIM_CACHE); then run "
                                 "a morning with the robot helping, scored against the same morning without it.")
    demo_commands = demo.add_subparsers(dest="demo_name", required=True, metavar="DEMO")
    breakfast = demo_commands.add_parser("breakfast", help="cereal, milk and bowl out before breakfast, away after")
    breakfast.add_argument("--rrd", type=Path, default=None, help="write a rerun recording of the morning here")
    breakfast.add_argument("--skip-breakfast", action="store_true",
                           help="the person skips breakfast that day (the robot puts its help back later)")
    breakfast.add_argument("--method", default=DataSpec.method, choices=METHODS, metavar="METHOD",
                           help=f"predictor, one of {', '.join(METHODS)} (default {DataSpec.method})")
    breakfast.add_argument("--json", action="store_true", help="print one JSON object")
    breakfast.set_defaults(func=cmd_demo_breakfast)

    run = subparsers.add_parser("run", help="run a named headless scenario, recorded with rerun",
                                description="Scenarios: " + "; ".join(f"{s.name}: {s.help}"
                                                                      for s in SCENARIOS.values()))
    run.add_argument("name", metavar="NAME", help=f"one of {', '.join(SCENARIOS)}")
    run.add_argument("--rrd", type=Path, required=True, help="write the rerun recording here")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    run.set_defaults(func=cmd_run)


def cmd_demo_breakfast(args: argparse.Namespace) -> int:
    from scenarios.breakfast import Morning, format_summary, run_breakfast

    result = run_breakfast(args.rrd, Morning(skip_breakfast=args.skip_breakfast), DataSpec(method=args.method))
    emit(result, args.json, format_summary(result))
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    from scenarios.registry import get

    scenario = get(args.name)
    result = scenario.run(args.rrd)
    emit(result, args.json, scenario.summary(result))
    return 0
