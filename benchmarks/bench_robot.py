# Imports follow the sys.path set-up that lets the script run without installation.
# ruff: noqa: E402
"""Robot benchmarks: IK throughput on the robot-only model (one core), and the wall time of one relocation.

IK: `solve_ik_steps_per_s` counts single differential-IK steps (one QP each); `solves_per_s` counts complete
solves to 5 mm / 2 degrees for random reachable targets near the current grip pose (the controller's typical
request). Relocations, wall time in s: the bowl from the right kitchen counter to the dining-room sink (navigate,
pick, navigate, place), and the milk from the fridge to the dining table (navigate, open the fridge, pick,
navigate, place, navigate, close the fridge).
Usage: python benchmarks/bench_robot.py [--repeats N]
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT))

import numpy as np

from benchmarks._common import emit, machine_info, pin_to_one_core, positive_int, setup_logging, summary
from homer_sim.world import World
from planners.motion.ik import IKSolver
from planners.robot import add_robot
from planners.skills import Robot

log = logging.getLogger("benchmarks.robot")
TARGET_IK_SOLVES_PER_S = 2000
TARGET_RELOCATION_S = 20.0
DOWN = np.array([np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0])


def bench_ik(n: int, rng: np.random.Generator) -> dict[str, float]:
    """Full solves from a reached pose to targets 1-3 cm away, and raw IK steps per second."""
    solver = IKSolver()
    q = solver.solve(solver.model.key("home").qpos.copy(), np.array([0.7, 0.0, 0.9]), DOWN, base_cost=100.0).q
    targets = np.array([0.7, 0.0, 0.9]) + rng.uniform(-0.03, 0.03, size=(n, 3))
    steps = converged = 0
    start = time.perf_counter()
    for target in targets:
        result = solver.solve(q, target, DOWN, base_cost=100.0, seeds=False)
        steps += result.iterations
        converged += result.converged
    elapsed = time.perf_counter() - start
    return {"solves_per_s": n / elapsed, "solve_ik_steps_per_s": steps / elapsed, "converged": converged / n,
            "mean_iterations": steps / n}


def bench_relocation(with_door: bool) -> dict[str, float | bool]:
    world = World(extras=[add_robot])
    if not with_door:
        world.set_object_pose("bowl", (5.0, 0.45, 0.938))
    world.settle()
    robot = Robot(world, np.random.default_rng(5 if with_door else 0))
    robot.observer.observe_all()
    start, physics = time.perf_counter(), world.data.time
    if with_door:
        steps = (lambda: robot.open_articulation("fridge/door"), lambda: robot.pick("milk"),
                 lambda: robot.place("table_dining_room"), lambda: robot.close_articulation("fridge/door"))
    else:
        steps = (lambda: robot.pick("bowl"), lambda: robot.place("sink_dining_room"))
    ok = all(step().success for step in steps)
    return {"wall_s": time.perf_counter() - start, "physics_s": world.data.time - physics, "success": ok}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=positive_int, default=3)
    parser.add_argument("--solves", type=positive_int, default=500)
    args = parser.parse_args(argv)
    setup_logging()
    cpu = pin_to_one_core()
    rng = np.random.default_rng(0)
    ik_runs = [bench_ik(args.solves, rng) for _ in range(args.repeats)]
    log.info("IK done")
    relocations = [bench_relocation(False) for _ in range(args.repeats)]
    fetches = [bench_relocation(True) for _ in range(args.repeats)]
    emit({
        "machine": machine_info(cpu),
        "ik_solves_per_s": summary([r["solves_per_s"] for r in ik_runs], 1),
        "ik_steps_per_s": summary([r["solve_ik_steps_per_s"] for r in ik_runs], 1),
        "ik_converged_fraction": min(r["converged"] for r in ik_runs),
        "ik_mean_iterations": ik_runs[0]["mean_iterations"],
        "ik_target_solves_per_s": TARGET_IK_SOLVES_PER_S,
        "relocation": "bowl kitchen_counter_right -> sink_dining_room (navigate, pick, navigate, place); "
                      "no door to open",
        "relocation_wall_s": summary([r["wall_s"] for r in relocations], 3),
        "relocation_physics_s": relocations[0]["physics_s"],
        "relocation_success": all(r["success"] for r in relocations),
        "relocation_with_door": "milk fridge -> table_dining_room (open the fridge, pick, place, close it)",
        "relocation_with_door_wall_s": summary([r["wall_s"] for r in fetches], 3),
        "relocation_with_door_physics_s": fetches[0]["physics_s"],
        "relocation_with_door_success": all(r["success"] for r in fetches),
        "relocation_target_s": TARGET_RELOCATION_S,
    })


if __name__ == "__main__":
    main()
