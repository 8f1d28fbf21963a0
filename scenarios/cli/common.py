"""Pieces every command module shares: printing a result, argparse types, and where independent tasks run."""

from __future__ import annotations

import argparse
import json

from homer_sim.execution import RAY_LOCAL, Backend


def emit(result: dict, as_json: bool, lines: list[str]) -> None:
    """Print `result` as one JSON object, or `lines` for people."""
    print(json.dumps(result) if as_json else "\n".join(lines))


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1, with a message naming the bad value."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


def add_backend_arguments(parser: argparse.ArgumentParser, units: str) -> None:
    """Add `--workers W` and `--ray [ADDRESS]` to a command that runs independent `units` (a plural noun)."""
    parser.add_argument("--workers", type=positive_int, default=1,
                        help=f"local worker processes running {units} (1: in this process); results do not depend "
                        "on it")
    parser.add_argument("--ray", nargs="?", const=RAY_LOCAL, default=None, metavar="ADDRESS",
                        help=f"run the {units} as Ray tasks (pip install -e '.[cluster]'): no ADDRESS starts Ray on "
                        "this machine, 'auto' joins the running cluster, 'ray://HOST:PORT' a remote one; outputs "
                        "are written by this process only")


def backend_from_args(args: argparse.Namespace) -> Backend:
    """The Backend that `--workers` and `--ray` (see `add_backend_arguments`) ask for."""
    return Backend(args.workers, args.ray)


def describe_usage(usage: dict) -> str:
    """One line for people from `TaskRun.usage()`: "2 local workers" or "4 Ray workers on 2 nodes (8 CPUs ...)"."""
    kind = "local" if usage["mode"] == "local" else "Ray"
    workers = f"{usage['workers']} {kind} worker" + "s" * (usage["workers"] != 1)
    if usage["mode"] == "local":
        return workers
    nodes = f"{usage['nodes']} node" + "s" * (usage["nodes"] != 1)
    return f"{workers} on {nodes} ({usage['cluster_cpus']:g} CPUs in the cluster)"
