# Imports follow the sys.path set-up that lets the script run without installation.
# ruff: noqa: E402
"""Physics throughput of the apartment: steps/s when everything sleeps, and while one object falls and settles.

Usage (from anywhere): python benchmarks/bench_physics.py [--repeats N] [--steps N]
Prints one JSON object on stdout; progress and diagnostics go to stderr.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path
from typing import Any, NamedTuple

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT))

import mujoco
import numpy as np

from benchmarks._common import emit, machine_info, pin_to_one_core, positive_int, setup_logging, summary
from homer_sim.world import SETTLE_SPEED, World

log = logging.getLogger("benchmarks.physics")

TARGET_STEPS_PER_S = 20_000
SETTLE_PHYSICS_S = 10.0  # s of physics run before any timing
FALL_OBJECT = "bowl"
TABLE = "table_dining_room"
TABLE_XY = (2.8, 2.3)  # m, world frame: centre of the dining table top
TABLE_TOP_Z = 0.75  # m
DROP_HEIGHT = 0.5  # m between the table top and the released object's centre
CHECK_EVERY = 10  # steps between at-rest checks while the object falls (checks are not timed)
MAX_FALL_STEPS = 20_000  # 40 s of physics: a fall that has not slept by then is reported as unsettled


class FallRun(NamedTuple):
    steps_per_s: float
    steps_to_rest: int | None  # first check after the fall began with speed below SETTLE_SPEED
    steps_to_sleep: int | None  # first check at which MuJoCo put the object's tree to sleep
    steps: int  # steps timed (up to sleep, or MAX_FALL_STEPS)
    final_pos: tuple[float, float, float]  # m, world


def settled_world() -> tuple[World, mujoco.MjData]:
    """The apartment after SETTLE_PHYSICS_S of physics, and a snapshot of its data to restore before each run."""
    world = World()
    at_rest_s = world.settle(max_seconds=SETTLE_PHYSICS_S)
    remaining = int(round((SETTLE_PHYSICS_S - world.data.time) / world.model.opt.timestep))
    world.step(max(remaining, 0))
    asleep = int((world.data.tree_asleep >= 0).sum())
    log.info("objects at rest after %.2f s of physics; %d/%d trees asleep at t=%.1f s",
             at_rest_s, asleep, world.model.ntree, world.data.time)
    snapshot = mujoco.MjData(world.model)
    mujoco.mj_copyData(snapshot, world.model, world.data)
    return world, snapshot


def time_settled(world: World, snapshot: mujoco.MjData, steps: int) -> float:
    """Steps/s of `steps` calls to mj_step from the settled snapshot."""
    model, data = world.model, world.data
    mujoco.mj_copyData(data, model, snapshot)
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    return steps / (time.perf_counter() - start)


def time_fall(world: World, snapshot: mujoco.MjData) -> FallRun:
    """Drop FALL_OBJECT from DROP_HEIGHT above the dining table and step until its tree sleeps."""
    model, data = world.model, world.data
    mujoco.mj_copyData(data, model, snapshot)
    body = int(world.object_body_ids[world.object_index(FALL_OBJECT)])
    tree = int(model.body_treeid[body])
    world.set_object_pose(FALL_OBJECT, (*TABLE_XY, TABLE_TOP_Z + DROP_HEIGHT))
    steps, elapsed, moving = 0, 0.0, False
    rest: int | None = None
    sleep: int | None = None
    while steps < MAX_FALL_STEPS and sleep is None:
        start = time.perf_counter()
        for _ in range(CHECK_EVERY):
            mujoco.mj_step(model, data)
        elapsed += time.perf_counter() - start
        steps += CHECK_EVERY
        speed = float(np.abs(data.cvel[body]).max())
        moving = moving or speed >= SETTLE_SPEED
        if rest is None and moving and speed < SETTLE_SPEED:
            rest = steps
        if data.tree_asleep[tree] >= 0:
            sleep = steps
    pos = data.xpos[body]
    return FallRun(steps / elapsed, rest, sleep, steps, (float(pos[0]), float(pos[1]), float(pos[2])))


def run(repeats: int, steps: int) -> dict[str, Any]:
    pinned = pin_to_one_core()
    world, snapshot = settled_world()
    settled, falls, warnings, nan = [], [], 0, False
    for r in range(repeats):
        settled.append(time_settled(world, snapshot, steps))
        warnings, nan = max(warnings, world.warnings()), nan or world.has_nan()
        falls.append(time_fall(world, snapshot))
        warnings, nan = max(warnings, world.warnings()), nan or world.has_nan()
        log.info("repeat %d/%d: settled %.0f steps/s, fall %.0f steps/s (%d steps)",
                 r + 1, repeats, settled[-1], falls[-1].steps_per_s, falls[-1].steps)
    median_settled = summary(settled, digits=0)["median"]
    last = falls[-1]
    return {
        "benchmark": "physics",
        "machine": machine_info(pinned),
        "model": {"nbody": world.model.nbody, "ngeom": world.model.ngeom, "ntree": world.model.ntree,
                  "free_objects": len(world.object_names), "timestep_s": world.model.opt.timestep,
                  "sleep_enabled": bool(world.model.opt.enableflags & mujoco.mjtEnableBit.mjENBL_SLEEP)},
        "repeats": repeats,
        "settled": {"steps": steps, "settle_physics_s": SETTLE_PHYSICS_S,
                    "steps_per_s": summary(settled, digits=0)},
        "fall": {"object": FALL_OBJECT, "onto": TABLE, "drop_height_m": DROP_HEIGHT,
                 "check_every_steps": CHECK_EVERY, "steps_per_s": summary([f.steps_per_s for f in falls], digits=0),
                 "steps_to_rest": last.steps_to_rest, "steps_to_sleep": last.steps_to_sleep,
                 "settled": last.steps_to_sleep is not None,
                 "same_steps_every_repeat": len({(f.steps_to_rest, f.steps_to_sleep) for f in falls}) == 1,
                 "final_pos_m": [round(v, 4) for v in last.final_pos]},
        "warnings": warnings,
        "has_nan": nan,
        "target_steps_per_s": TARGET_STEPS_PER_S,
        "meets_target": bool(median_settled >= TARGET_STEPS_PER_S),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=positive_int, default=5, help="timed runs of each case (default 5)")
    parser.add_argument("--steps", type=positive_int, default=20_000, help="steps per settled run (default 20000)")
    args = parser.parse_args(argv)
    setup_logging()
    emit(run(args.repeats, args.steps))


if __name__ == "__main__":
    main()
