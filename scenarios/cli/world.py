"""`homer world info|check|export`: the apartment."""

from __future__ import annotations

import argparse
from pathlib import Path

from homer_sim.check import CHECK_SECONDS, MAX_DRIFT_M
from scenarios.cli.common import emit


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
    emit(result, args.json, lines)
    return 0

def cmd_world_check(args: argparse.Namespace) -> int:
    from homer_sim.check import run_world_check

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
    emit(result, args.json, lines)
    return 0 if ok else 1

def cmd_world_export(args: argparse.Namespace) -> int:
    from homer_sim.home.export import export_mjcf

    path = export_mjcf(args.out, overwrite=args.overwrite)
    result = {"mjcf": str(path)}
    emit(result, args.json, [f"wrote {path}", f"view it with: python -m mujoco.viewer --mjcf {path}"])
    return 0


def add_commands(subparsers: argparse._SubParsersAction) -> None:
    """Add `world info|check|export` to the `homer` parser."""
    world = subparsers.add_parser("world", help="the apartment: info, check, export")
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
