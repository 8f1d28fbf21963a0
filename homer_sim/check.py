"""`homer world check`: compile the apartment, simulate it at rest and compare what is observed with the layout."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from homer_sim.observe import SceneGraphObserver
from homer_sim.recording import Recording
from homer_sim.world import World

MAX_DRIFT_M = 0.005  # a settled object may move this far from its spawn pose
CHECK_SECONDS = 10.0  # physics seconds `world check` simulates


def run_world_check(rrd: Path | None = None, seconds: float = CHECK_SECONDS) -> dict:
    """Compile, simulate `seconds` of physics, and compare the observed scene graph with the declared layout."""
    started = time.perf_counter()
    world = World()
    recording = None
    if rrd is not None:

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
