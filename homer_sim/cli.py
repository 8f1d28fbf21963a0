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
