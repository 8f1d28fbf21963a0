"""`homer grasp-suite`: the robot's regression suite."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from homer_sim.errors import HomerError
from planners.suites.grasp_suite import (
    DEFAULT_TRIALS,
    HOLD_SECONDS,
    MAX_SLIP,
    MIN_LIFT,
    QUICK_TRIALS,
    TARGET_CLASS,
    TARGET_OVERALL,
    chosen_classes,
    format_table,
    run_suite,
)
from planners.suites.relocation_suite import format_relocations, run_relocations
from scenarios.cli.common import add_backend_arguments, backend_from_args, emit, positive_int


def add_commands(subparsers: argparse._SubParsersAction) -> None:
    """Add the `grasp-suite` subcommand to the `homer` parser's subparsers."""
    suite = subparsers.add_parser(
        "grasp-suite", help="pick every graspable object class from randomised start poses",
        description=f"Pick each robot-graspable object class of the apartment from randomised start poses on "
        f"its home surface or shelf, each keeping the gaps the layout keeps to its neighbours and to furniture walls "
        f"(a narrower test than any pose: no object starts against a wall or touching another); success: lifted "
        f"{MIN_LIFT * 100:.0f} cm and held {HOLD_SECONDS:.0f} s with "
        f"slip under {MAX_SLIP * 1000:.0f} mm. Exit status 1 when the overall rate is below {TARGET_OVERALL} or a "
        f"class is below {TARGET_CLASS}. With --relocations: every (object, from, to) move of a dataset's training "
        "days, tried from the day's state before the move: opened, picked, carried, placed, closed; success: the "
        "object on or in the destination, standing, nothing else moved over 2 cm.")
    suite.add_argument("--quick", action="store_true", help="one class of each shape family (fast subset)")
    suite.add_argument("--trials", type=positive_int, default=None,
                       help=f"trials per class ({DEFAULT_TRIALS}; {QUICK_TRIALS} with --quick)")
    suite.add_argument("--seed", type=int, default=0, help="seed of the start-pose randomisation (0)")
    suite.add_argument("--classes", nargs="+", metavar="CLASS", help="only these object classes (default: all)")
    add_backend_arguments(suite, "trials")
    suite.add_argument("--relocations", action="store_true",
                       help="the relocation suite instead of picks (needs --data; --quick: a few triples)")
    suite.add_argument("--data", type=Path, help="dataset folder made by `homer generate` (with --relocations)")
    suite.add_argument("--households", nargs="+", metavar="NAME", help="only these households' days")
    suite.add_argument("--objects", nargs="+", metavar="NAME",
                       help="only these objects' moves (with --relocations)")
    suite.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    suite.add_argument("--json", action="store_true", help="print one JSON object")
    suite.set_defaults(func=cmd_grasp_suite)


def cmd_grasp_suite(args: argparse.Namespace) -> int:
    if args.relocations or args.data:
        return _relocations(args)
    result = run_suite(quick=args.quick, trials=args.trials, seed=args.seed, progress=not args.quiet,
                       classes=chosen_classes(args.classes) if args.classes else None, backend=backend_from_args(args))
    if args.json:
        print(json.dumps(result))
    else:
        print(format_table(result))
    return 0 if result["meets_targets"] else 1


def _relocations(args: argparse.Namespace) -> int:
    if not (args.relocations and args.data):
        raise HomerError("--relocations and --data DIR go together (the relocation suite reads a dataset's days)")
    result = run_relocations(args.data, quick=args.quick, seed=args.seed, progress=not args.quiet,
                             households=args.households, backend=backend_from_args(args), objects=args.objects)
    emit(result, args.json, [format_relocations(result)])
    return 0 if result["meets_targets"] else 1
