"""`homer demo breakfast`, `homer run NAME` and `homer assist-eval`: the named headless runs and the assisted day
measured over a dataset.

The scenario code (mujoco, torch) is imported inside the command functions, so `homer --help` stays fast.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from model.names import METHODS
from model.selection import default_method
from scenarios.breakfast_data import DataSpec
from scenarios.cli.common import add_backend_arguments, backend_from_args, emit, positive_int
from scenarios.registry import SCENARIOS

DEFAULT_HELP = "the best on validation days in model/validation_table.json"


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
    breakfast.add_argument("--method", default=None, choices=METHODS, metavar="METHOD",
                           help=f"predictor, one of {', '.join(METHODS)} (default: {DEFAULT_HELP})")
    breakfast.add_argument("--json", action="store_true", help="print one JSON object")
    breakfast.set_defaults(func=cmd_demo_breakfast)

    run = subparsers.add_parser("run", help="run a named headless scenario, recorded with rerun",
                                description="Scenarios: " + "; ".join(f"{s.name}: {s.help}"
                                                                      for s in SCENARIOS.values()))
    run.add_argument("name", metavar="NAME", help=f"one of {', '.join(SCENARIOS)}")
    run.add_argument("--rrd", type=Path, required=True, help="write the rerun recording here")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    run.set_defaults(func=cmd_run)

    render = subparsers.add_parser(
        "render", help="a camera image of the apartment from a named assisted-day environment (PNG)",
        description="Run the named environment's episode (Psi on its predictor, or nothing asked of the robot) up "
        "to a routine minute and write an image of the apartment then. Headless: run with MUJOCO_GL=egl (or "
        "osmesa) in the environment.")
    render.add_argument("name", metavar="NAME", help="environment: breakfast, breakfast_skipped, day_household_a, ...")
    render.add_argument("--until", type=positive_int, default=None, metavar="MINUTE",
                        help="routine minute to stop the day after (default: the environment's own end)")
    render.add_argument("--policy", choices=("psi", "empty"), default="psi", help="who asks the robot (default psi)")
    render.add_argument("--size", type=positive_int, nargs=2, default=(480, 640), metavar=("HEIGHT", "WIDTH"),
                        help="image size in pixels (default 480 640)")
    render.add_argument("--out", type=Path, required=True, help="PNG file to write")
    render.add_argument("--json", action="store_true", help="print one JSON object")
    render.set_defaults(func=cmd_render)

    evaluate = subparsers.add_parser(
        "assist-eval", help="the assisted day on every test day of a dataset: relocations, fetch share, failures",
        description="For every test day of every household of a dataset made by `homer generate`: replay the day "
        "without the robot, then live it with the robot helping (Psi on the household's predictor, fitted on the "
        "training days and cached as `homer evaluate` caches it; `--method oracle` predicts from the replay). "
        "Writes the JSON, a markdown table and a PNG into --out; day results are kept as they finish, so an "
        "interrupted run resumes.")
    evaluate.add_argument("--data", type=Path, required=True, help="dataset folder (with meta.json)")
    evaluate.add_argument("--households", default=None, help="comma-separated subset of households (default all)")
    evaluate.add_argument("--days", type=positive_int, default=None, help="only the first N test days of each")
    evaluate.add_argument("--method", default=None, choices=(*METHODS, "oracle"), metavar="METHOD",
                          help=f"predictor ({', '.join(METHODS)}) or oracle (default: {DEFAULT_HELP})")
    add_backend_arguments(evaluate, "assisted days")
    evaluate.add_argument("--seed", type=int, default=0, help="seed of the robot's random streams (default 0)")
    evaluate.add_argument("--window", type=positive_int, default=DataSpec.window_min,
                          help=f"prediction window in minutes (default {DataSpec.window_min})")
    evaluate.add_argument("--until", type=positive_int, default=None, metavar="MINUTE",
                          help="stop each day after the snapshot at this routine minute (default: the whole day)")
    evaluate.add_argument("--checkpoints", type=Path, default=None,
                          help="predictor cache folder (default DATA/checkpoints), shared with `homer evaluate`")
    evaluate.add_argument("--out", type=Path, default=None,
                          help="results folder (default CHECKPOINTS/assist_eval_METHOD_KEY)")
    evaluate.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    evaluate.add_argument("--json", action="store_true", help="print one JSON object")
    evaluate.set_defaults(func=cmd_assist_eval)


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


def cmd_assist_eval(args: argparse.Namespace) -> int:
    from scenarios.assist_eval import EvalSpec, assist_eval, markdown_table

    spec = EvalSpec(str(args.data), args.method or default_method(), args.seed, args.window,
                    str(args.checkpoints) if args.checkpoints else None, args.until)
    households = [h.strip() for h in args.households.split(",") if h.strip()] if args.households else None
    result = assist_eval(spec, households, args.days, backend_from_args(args), args.out, progress=not args.quiet)
    emit(result, args.json, [markdown_table(result), f"written to {result['out']}"])
    return 0


def cmd_render(args: argparse.Namespace) -> int:
    import os

    from homer_sim.errors import HomerError

    if not os.environ.get("MUJOCO_GL"):
        raise HomerError("rendering needs an offscreen GL context: run with MUJOCO_GL=egl (or MUJOCO_GL=osmesa)")
    from matplotlib.image import imsave

    from scenarios.episodes import make_setup
    from scenarios.policies import EmptyPolicy, PsiPolicy
    from scenarios.task import run_episode

    setup = make_setup(args.name, **({} if args.until is None else {"end_min": args.until}))
    env = setup.env
    use_psi = args.policy == "psi" and setup.predictor is not None
    episode_return = run_episode(env, PsiPolicy(env.scene, setup.predictor) if use_psi else EmptyPolicy(env.scene))
    image = env.render(*args.size)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_name(args.out.stem + ".tmp.png")
    imsave(tmp, image)
    tmp.replace(args.out)
    result = {"out": str(args.out), "minute": float(env.task.minute), "return": episode_return,
              "shape": list(image.shape)}
    emit(result, args.json, [f"wrote {args.out} ({image.shape[1]}x{image.shape[0]}) at routine minute "
                             f"{result['minute']:.0f}, return {episode_return:g}"])
    return 0
