"""The `homer` command line: one entry point, subcommands import what they need inside.

Every command has --help; --json prints one JSON object on stdout. Exit status 0 on success, 1 when a check
fails, 2 on bad input (a HomerError).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

from homer_sim.errors import HomerError

MAX_DRIFT_M = 0.005  # a settled object may move this far from its spawn pose
CHECK_SECONDS = 10.0  # physics seconds `world check` simulates


def _print(result: dict, as_json: bool, lines: list[str]) -> None:
    if as_json:
        print(json.dumps(result, indent=None))
    else:
        print("\n".join(lines))


def cmd_world_info(args: argparse.Namespace) -> int:
    from homer_sim.world import World

    world = World()
    graph = world.declared_graph()
    movable = set(world.object_names)
    nodes = [{"name": n, "category": c, "movable": n in movable} for n, c in zip(graph.nodes, graph.categories,
                                                                               strict=True)]
    articulations = [{"name": a.name, "joint_type": a.joint_type, "furniture": a.furniture}
                     for a in world.articulations.values()]
    counts = {c: sum(1 for n in nodes if n["category"] == c) for c in dict.fromkeys(graph.categories)}
    result = {"nodes": nodes, "articulations": articulations, "counts": counts,
              "bodies": world.model.nbody, "geoms": world.model.ngeom}
    lines = [f"{len(nodes)} nodes: " + ", ".join(f"{v} {k}" for k, v in counts.items()),
             f"{len(articulations)} articulations: " + ", ".join(a["name"] for a in articulations),
             f"MuJoCo model: {world.model.nbody} bodies, {world.model.ngeom} geoms"]
    _print(result, args.json, lines)
    return 0


def run_world_check(rrd: Path | None = None, seconds: float = CHECK_SECONDS) -> dict:
    """Compile, simulate `seconds` of physics, and compare the observed scene graph with the declared layout."""
    import numpy as np

    from homer_sim.observe import SceneGraphObserver
    from homer_sim.world import World

    started = time.perf_counter()
    world = World()
    recording = None
    if rrd is not None:
        from homer_sim.recording import Recording

        recording = Recording(rrd)
        recording.log_geometry(world.model, world.data)
    steps = int(round(seconds / world.model.opt.timestep))
    chunk = max(1, int(round(1 / 30 / world.model.opt.timestep)))
    for done in range(0, steps, chunk):
        world.step(min(chunk, steps - done))
        if recording is not None:
            recording.log_body_poses(world.data)
    drift = np.linalg.norm(world.object_positions() - world.start_positions(), axis=1)
    graph = SceneGraphObserver(world).observe_all()
    mismatches = world.declared_graph().mismatches(graph)
    if recording is not None:
        recording.log_scene_graph(graph, routine_minute=0.0)
        recording.log_event(f"world check: {len(mismatches)} scene-graph mismatches", routine_minute=0.0)
        recording.close()
    worst = int(np.argmax(drift))
    return {
        "warnings": world.warnings(),
        "nan": world.has_nan(),
        "max_drift_m": float(drift.max()),
        "max_drift_object": world.object_names[worst],
        "graph_matches_layout": not mismatches,
        "mismatches": mismatches,
        "physics_s": float(world.data.time),
        "objects": len(world.object_names),
        "nodes": len(graph.nodes),
        "wall_s": round(time.perf_counter() - started, 3),
        "rrd": str(rrd) if rrd is not None else None,
    }


def cmd_world_check(args: argparse.Namespace) -> int:
    result = run_world_check(args.rrd, args.seconds)
    ok = (result["warnings"] == 0 and not result["nan"] and result["max_drift_m"] <= MAX_DRIFT_M
          and result["graph_matches_layout"])
    result["ok"] = ok
    lines = [
        f"physics: {result['physics_s']:.1f} s simulated, {result['warnings']} MuJoCo warnings, NaN: {result['nan']}",
        f"drift: {result['max_drift_m'] * 1000:.2f} mm at most ({result['max_drift_object']}), "
        f"limit {MAX_DRIFT_M * 1000:.0f} mm",
        f"scene graph matches the declared layout: {result['graph_matches_layout']}"
        + "".join(f"\n  {m['node']}: expected {m['expected']}, observed {m['observed']}" for m in result["mismatches"]),
        f"recording: {result['rrd']}" if result["rrd"] else "recording: none (use --rrd PATH)",
        "OK" if ok else "FAILED",
    ]
    _print(result, args.json, lines)
    return 0 if ok else 1


def cmd_world_export(args: argparse.Namespace) -> int:
    from homer_sim.export import export_mjcf

    path = export_mjcf(args.out, overwrite=args.overwrite)
    result = {"mjcf": str(path)}
    _print(result, args.json, [f"wrote {path}", f"view it with: python -m mujoco.viewer --mjcf {path}"])
    return 0


def cmd_generate(args: argparse.Namespace) -> int:
    from homer_sim.generate import Sources, generate

    for name in ("households", "train_days", "test_days", "workers"):
        if getattr(args, name) < (1 if name in ("households", "workers") else 0):
            raise HomerError(f"--{name.replace('_', '-')} must be positive, not {getattr(args, name)}")
    sources = Sources(str(args.habits) if args.habits else None, str(args.scripts) if args.scripts else None)
    result = generate(args.out, args.households, args.train_days, args.test_days, args.seed, args.workers, sources,
                      progress=not args.json)
    _print(result, args.json, [f"wrote {result['days_written']} days for {', '.join(result['households'])} "
                               f"to {result['out']} in {result['wall_s']} s"])
    return 0


def cmd_dataset_stats(args: argparse.Namespace) -> int:
    from homer_sim.stats import dataset_stats

    result = dataset_stats(args.data)
    lines = [f"{'household':<14} {'days':>5} {'steps/day':>10} {'moves/day':>10} {'objects used':>13}"]
    for name, h in result["households"].items():
        lines.append(f"{name:<14} {h['days']:>5} {h['steps_per_day']:>10.1f} {h['moves_per_day']:>10.1f} "
                     f"{h['objects_used']:>13}")
    wall = result["wall_s_per_day"]
    lines.append(f"wall seconds per simulated day: {wall:.2f}" if wall is not None else "no generation log")
    _print(result, args.json, lines)
    return 0


def cmd_simulate_day(args: argparse.Namespace) -> int:
    from homer_sim.generate import Generator, Sources
    from homer_sim.recording import Recording

    recording = Recording(args.rrd) if args.rrd else None
    generator = Generator(Sources(), recording=recording)
    if recording is not None:
        recording.log_geometry(generator.world.model, generator.world.data)
    names = list(generator.households)
    if args.household not in names:
        from homer_sim.errors import unknown_name

        raise unknown_name("household", args.household, names)
    day, info = generator.simulate(args.household, names.index(args.household), args.split, args.day, args.seed)
    if recording is not None:
        recording.close()
    moves = int(((day.parent[1:] != day.parent[:-1])).sum())
    result = {"household": args.household, "steps": day.steps, "grid_moves": moves, "schedule": day.schedule,
              "events": len(day.moves), "attempts": info["attempts"], "wall_s": info["wall_s"],
              "rrd": str(args.rrd) if args.rrd else None}
    lines = [f"{a:<22} {int(s) // 60:02d}:{int(s) % 60:02d}-{int(e) // 60:02d}:{int(e) % 60:02d}"
             for a, s, e in day.schedule]
    lines.append(f"{day.steps} grid steps, {moves} object moves between steps, {info['wall_s']} s wall")
    _print(result, args.json, lines)
    return 0


def cmd_compat_check(args: argparse.Namespace) -> int:
    from homer_sim.compat import compat_check

    result = compat_check(args.scripts, progress=not args.json)
    share = result["executed"] / result["scripts"]
    lines = [f"{result['executed']} of {result['scripts']} scripts executed ({share:.0%})"]
    lines += [f"  {f['script']}:{f['line']}: {f['reason']}" for f in result["failures"]]
    _print(result, args.json, lines)
    return 0


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1, with a message naming the bad value."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


def cmd_import_homer_plus(args: argparse.Namespace) -> int:
    from homer_sim.data.homer_plus import import_household

    result = import_household(args.path, args.out, args.name)
    _print(result, args.json, [f"{k}: {v}" for k, v in result.items()])
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="homer", description="homer-sim: proactive robot assistance in physics")
    parser.add_argument("-v", "--verbose", action="store_true", help="log diagnostics to stderr")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    world = commands.add_parser("world", help="the apartment: info, check, export")
    world_commands = world.add_subparsers(dest="world_command", required=True, metavar="WORLD_COMMAND")
    info = world_commands.add_parser("info", help="nodes, categories and articulations of the apartment")
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.set_defaults(func=cmd_world_info)
    check = world_commands.add_parser(
        "check", help="compile, simulate and compare the observed scene graph with the layout")
    check.add_argument("--rrd", type=Path, default=None, help="write a rerun recording to this path")
    check.add_argument("--seconds", type=float, default=CHECK_SECONDS, help="physics seconds to simulate (10)")
    check.add_argument("--json", action="store_true", help="print one JSON object")
    check.set_defaults(func=cmd_world_check)
    export = world_commands.add_parser("export", help="write a standalone MJCF (with meshes) of the apartment")
    export.add_argument("--out", type=Path, required=True, help="output folder (apartment.xml and meshes/)")
    export.add_argument("--overwrite", action="store_true", help="replace an existing export")
    export.add_argument("--json", action="store_true", help="print one JSON object")
    export.set_defaults(func=cmd_world_export)

    gen = commands.add_parser("generate", help="simulate households' days into a HOMER-like dataset")
    gen.add_argument("--households", type=int, default=5, help="how many households (5)")
    gen.add_argument("--train-days", type=int, default=50, help="training days per household (50)")
    gen.add_argument("--test-days", type=int, default=10, help="test days per household (10)")
    gen.add_argument("--seed", type=int, default=0, help="dataset seed (0)")
    gen.add_argument("--out", type=Path, required=True, help="dataset folder (created; an interrupted run resumes)")
    gen.add_argument("--workers", type=int, default=1, help="worker processes (1); bytes do not depend on it")
    gen.add_argument("--habits", type=Path, default=None,
                     help="households from a HOMER personaBasedSchedules folder instead of ours")
    gen.add_argument("--scripts", type=Path, default=None,
                     help="activity scripts from a folder laid out <activity>/<name>.txt instead of ours")
    gen.add_argument("--json", action="store_true", help="print one JSON object (no progress bar)")
    gen.set_defaults(func=cmd_generate)

    dataset = commands.add_parser("dataset", help="inspect a dataset")
    dataset_commands = dataset.add_subparsers(dest="dataset_command", required=True, metavar="DATASET_COMMAND")
    stats = dataset_commands.add_parser("stats", help="steps, moves and objects used per household")
    stats.add_argument("data", type=Path, help="dataset folder")
    stats.add_argument("--json", action="store_true", help="print one JSON object")
    stats.set_defaults(func=cmd_dataset_stats)

    imports = commands.add_parser("import", help="convert external data into a homer-sim dataset")
    import_commands = imports.add_subparsers(dest="import_command", required=True, metavar="FORMAT")
    homer_plus = import_commands.add_parser(
        "homer-plus", help="one HOMER+ household (HouseholdX/processed_seqLM_coarse) -> dataset folder",
        description="Read common_data.json, train/*.pt and test/*.pt (weights only) of one household and write it "
        "into DIR, keeping the upstream train/test split; a DIR holding other HOMER+ households gains this one.")
    homer_plus.add_argument("path", type=Path, help="the unpacked HouseholdX folder (or its processed_seqLM_coarse)")
    homer_plus.add_argument("--out", type=Path, required=True, help="dataset folder to create or extend")
    homer_plus.add_argument("--name", default=None, help="household name in the dataset (default: the folder's)")
    homer_plus.add_argument("--json", action="store_true", help="print one JSON object")
    homer_plus.set_defaults(func=cmd_import_homer_plus)

    day = commands.add_parser("simulate-day", help="simulate one day of one household, recorded with rerun")
    day.add_argument("--household", default="household_a", help="household name (household_a)")
    day.add_argument("--seed", type=int, default=0, help="seed (0)")
    day.add_argument("--day", type=int, default=0, help="day index (0)")
    day.add_argument("--split", choices=("train", "test"), default="train")
    day.add_argument("--rrd", type=Path, default=None, help="write a rerun recording of the day here")
    day.add_argument("--json", action="store_true", help="print one JSON object")
    day.set_defaults(func=cmd_simulate_day)

    compat = commands.add_parser("compat-check", help="run every script of a HOMER-style folder in our apartment")
    compat.add_argument("--scripts", type=Path, required=True, help="folder laid out <activity>/<name>.txt")
    compat.add_argument("--json", action="store_true", help="print one JSON object")
    compat.set_defaults(func=cmd_compat_check)

    from model.cli import register as register_model  # train, evaluate (torch is imported only when they run)

    register_model(commands)
    from planners.grasp_suite import register as register_grasp_suite
    register_grasp_suite(commands)
    from scenarios.cli import register as register_scenarios  # demo, run (scenario code is imported when they run)
    register_scenarios(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, stream=sys.stderr,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        return args.func(args)
    except HomerError as error:
        print(f"homer: error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
