# Imports follow the sys.path set-up that lets the script run without installation.
# ruff: noqa: E402
"""Scene-graph observation cost: one full observation, and incremental updates with nothing or one object moved.

Usage (from anywhere): python benchmarks/bench_scene_graph.py [--repeats N] [--full-repeats N]
Prints one JSON object on stdout (times in ms); progress and diagnostics go to stderr.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path
from typing import Any

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT))

from benchmarks._common import emit, machine_info, pin_to_one_core, positive_int, setup_logging, summary
from homer_sim.home.catalog import CATALOG
from homer_sim.observe import SceneGraphObserver
from homer_sim.world import World

log = logging.getLogger("benchmarks.scene_graph")

TARGET_INCREMENTAL_MS = 1.0
SETTLE_PHYSICS_S = 10.0  # s of physics run before any timing
MOVED_OBJECT = "mug"
# (surface node, world x m, world y m, top z m): the moved object alternates between these two spots
SURFACES = (
    ("table_dining_room", 2.8, 2.3, 0.75),
    ("kitchen_counter_right", 5.0, 0.2, 0.9),
)
DROP_CLEARANCE = 0.01  # m between the surface and the released object's lowest point
MOVE_SETTLE_MAX_S = 5.0  # s of physics allowed for the moved object to come to rest


def settled_world() -> World:
    world = World()
    world.step(int(round(SETTLE_PHYSICS_S / world.model.opt.timestep)))
    log.info("%d/%d trees asleep at t=%.1f s", (world.data.tree_asleep >= 0).sum(), world.model.ntree,
             world.data.time)
    return world


def time_full(observer: SceneGraphObserver, repeats: int) -> list[float]:
    """ms per `observe_all()`."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        observer.observe_all()
        times.append((time.perf_counter() - start) * 1e3)
    return times


def time_unchanged(observer: SceneGraphObserver, repeats: int) -> list[float]:
    """ms per `update()` when no body moved since the last observation."""
    observer.update()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        graph = observer.update()
        times.append((time.perf_counter() - start) * 1e3)
        assert graph is observer.graph
    return times


def time_moved(world: World, observer: SceneGraphObserver, repeats: int) -> tuple[list[float], int]:
    """ms per `update()` right after MOVED_OBJECT was put on another surface and settled.

    Returns the times and how many updates gave the object the surface it was put on as its parent."""
    half_height = CATALOG[MOVED_OBJECT].size[2] / 2
    times, correct = [], 0
    for r in range(repeats):
        surface, x, y, top_z = SURFACES[r % len(SURFACES)]
        world.set_object_pose(MOVED_OBJECT, (x, y, top_z + half_height + DROP_CLEARANCE))
        world.settle(max_seconds=MOVE_SETTLE_MAX_S)
        start = time.perf_counter()
        graph = observer.update()
        times.append((time.perf_counter() - start) * 1e3)
        parent = graph.parent_of(MOVED_OBJECT)
        correct += parent == surface
        if parent != surface:
            log.warning("repeat %d: %s put on %s, observed on %s", r, MOVED_OBJECT, surface, parent)
    return times, correct


def run(repeats: int, full_repeats: int) -> dict[str, Any]:
    pinned = pin_to_one_core()
    world = settled_world()
    observer = SceneGraphObserver(world)
    observer.observe_all()  # warm-up: first-call costs stay out of the numbers
    full = time_full(observer, full_repeats)
    log.info("observe_all: median %.3f ms over %d", summary(full)["median"], full_repeats)
    unchanged = time_unchanged(observer, repeats)
    log.info("update, nothing moved: median %.4f ms over %d", summary(unchanged)["median"], repeats)
    moved, correct = time_moved(world, observer, repeats)
    log.info("update, one moved: median %.3f ms over %d (%d correct parents)", summary(moved)["median"],
             repeats, correct)
    unchanged_ms, moved_ms = summary(unchanged)["median"], summary(moved)["median"]
    return {
        "benchmark": "scene_graph",
        "machine": machine_info(pinned),
        "nodes": len(observer.nodes),
        "movable": len(world.object_names),
        "full_ms": {"repeats": full_repeats, **summary(full)},
        "incremental_unchanged_ms": {"repeats": repeats, **summary(unchanged)},
        "incremental_one_moved_ms": {"repeats": repeats, "object": MOVED_OBJECT,
                                     "surfaces": [s[0] for s in SURFACES], **summary(moved)},
        "moved_parent_correct": f"{correct}/{repeats}",
        "warnings": world.warnings(),
        "has_nan": world.has_nan(),
        "target_incremental_ms": TARGET_INCREMENTAL_MS,
        "meets_target": bool(unchanged_ms < TARGET_INCREMENTAL_MS and moved_ms < TARGET_INCREMENTAL_MS),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=positive_int, default=200,
                        help="timed incremental updates per situation (default 200)")
    parser.add_argument("--full-repeats", type=positive_int, default=50,
                        help="timed full observations (default 50)")
    args = parser.parse_args(argv)
    setup_logging()
    emit(run(args.repeats, args.full_repeats))


if __name__ == "__main__":
    main()
