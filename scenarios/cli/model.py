"""`homer train` and `homer evaluate`: the predictors.

Imports of torch and the model code happen inside the command functions, so `homer --help` stays fast.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from homer_sim.clock import DEFAULT_WINDOW_MIN as HEADLINE_WINDOW_MIN
from model.names import DEFAULT_METHODS, METHODS
from model.report import format_f1_table, format_table
from scenarios.cli.common import add_backend_arguments, backend_from_args


def _methods(text: str) -> list[str]:
    """argparse type: a comma-separated list of known method names."""
    names = [m.strip() for m in text.split(",") if m.strip()]
    unknown = [m for m in names if m not in METHODS]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"unknown method(s) {unknown or text!r}; known: {', '.join(METHODS)}")
    return names


def add_commands(subparsers: argparse._SubParsersAction) -> None:
    """Add the `train` and `evaluate` subcommands to the `homer` parser's subparsers."""
    train = subparsers.add_parser("train", help="fit one method on one household and write a checkpoint",
                                  description="Fit on the household's training days (the last 10%% held out for "
                                  "early stopping and tuning) and write a checkpoint that rebuilds the predictor.")
    train.add_argument("--data", type=Path, required=True, help="dataset folder (with meta.json)")
    train.add_argument("--household", required=True, help="household name, as in the dataset's meta.json")
    train.add_argument("--method", default="gnn", choices=METHODS, metavar="METHOD",
                       help=f"one of {', '.join(METHODS)} (default gnn)")
    train.add_argument("--out", type=Path, required=True, help="checkpoint file to write (.pt)")
    train.add_argument("--train-days", type=int, default=None, help="use only the first N training days")
    train.add_argument("--window", type=int, default=HEADLINE_WINDOW_MIN,
                       help="proactivity window in minutes that the tunables are chosen for (default 30)")
    train.add_argument("--overwrite", action="store_true", help="replace an existing checkpoint")
    train.add_argument("--quiet", action="store_true", help="no progress bars on stderr")
    train.add_argument("--json", action="store_true", help="print one JSON object")
    train.set_defaults(func=cmd_train)
    evaluate = subparsers.add_parser("evaluate", help="score methods on the test days (the paper's metrics)",
                                     description="Fit what is missing (cached as checkpoints), tune on validation "
                                     "days, and report used/unused object percentages averaged over households.")
    evaluate.add_argument("--data", type=Path, required=True, help="dataset folder (with meta.json)")
    evaluate.add_argument("--methods", type=_methods, default=list(DEFAULT_METHODS),
                          help=f"comma-separated, from {', '.join(METHODS)} (default {','.join(DEFAULT_METHODS)})")
    evaluate.add_argument("--window", type=int, default=HEADLINE_WINDOW_MIN,
                          help="proactivity window in minutes, a multiple of 10 (default 30)")
    evaluate.add_argument("--checkpoints", type=Path, default=None,
                          help="checkpoint cache folder (default DATA/checkpoints); reused on the next run")
    evaluate.add_argument("--households", default=None, help="comma-separated subset of households (default all)")
    evaluate.add_argument("--train-days", type=int, default=None, help="use only the first N training days")
    evaluate.add_argument("--metric", choices=("paper", "f1", "both"), default="paper",
                          help="paper: used/unused object percentages at --window; f1: SLaTe-PRO's relocation F1 "
                          "per lookahead step 10..60 min; both (default paper; each tuned for its own metric)")
    add_backend_arguments(evaluate, "fits (one per household and method)")
    evaluate.add_argument("--quiet", action="store_true", help="no progress bars on stderr")
    evaluate.add_argument("--json", action="store_true", help="print one JSON object")
    evaluate.set_defaults(func=cmd_evaluate)


def cmd_train(args: argparse.Namespace) -> int:
    from homer_sim.data.dataset import Dataset
    from model.evaluate import FitSpec, fit_tuned, household_split
    from model.predictor import ModelError

    if args.out.exists() and not args.overwrite:
        raise ModelError(f"{args.out} exists; pass --overwrite to replace it")
    args.out.unlink(missing_ok=True)
    dataset = Dataset(args.data)
    fit, val, _, _ = household_split(dataset, args.household, args.train_days)
    predictor, info = fit_tuned(FitSpec(args.method, tuple(fit), tuple(val)), dataset.meta, args.window, args.out,
                                progress=not args.quiet)
    result = {"checkpoint": str(args.out), "method": args.method, "household": args.household,
              "params": predictor.params, **info}
    if args.json:
        print(json.dumps(result))
    else:
        print("\n".join(f"{k}: {v}" for k, v in result.items()))
    return 0


def cmd_evaluate(args: argparse.Namespace) -> int:
    from model.evaluate import evaluate

    households = [h.strip() for h in args.households.split(",")] if args.households else None
    result = evaluate(args.data, args.methods, args.window, args.checkpoints, households, args.train_days,
                      progress=not args.quiet, metric=args.metric,
                      backend=backend_from_args(args))
    tables = [t for t, on in ((format_table, args.metric != "f1"), (format_f1_table, args.metric != "paper")) if on]
    print(json.dumps(result) if args.json else "\n\n".join(table(result) for table in tables))
    return 0
