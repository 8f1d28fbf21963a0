"""The `homer` command line: the parser and `main`, one entry point above every package.

Each area's commands live beside this module (`world`, `data`, `model`, `robot`, `runs`), each adding its
subcommands with `add_commands(subparsers)`; command functions import heavy code (torch, mujoco) when they
run, so `homer --help` stays fast. Every command has --help; --json prints one JSON object on stdout. Exit
status 0 on success, 1 when a check fails, 2 on bad input (a HomerError), 130 when interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import logging
import sys

from homer_sim.errors import HomerError
from scenarios.cli import data, model, robot, runs, world

AREAS = (world, data, model, robot, runs)


def build_parser() -> argparse.ArgumentParser:
    """The `homer` parser with every area's subcommands."""
    parser = argparse.ArgumentParser(prog="homer", description="homer-sim: proactive robot assistance in physics")
    parser.add_argument("-v", "--verbose", action="store_true", help="log diagnostics to stderr")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for area in AREAS:
        area.add_commands(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one `homer` command; returns the exit status."""
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, stream=sys.stderr,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        return args.func(args)
    except HomerError as error:
        print(f"homer: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # every file is written atomically: what is there is complete
        print("homer: interrupted; files written so far are complete (generate, replay and assist-eval, run again, "
              "go on where they stopped)", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
