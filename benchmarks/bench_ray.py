# Imports follow the sys.path set-up that lets the script run without installation.
# ruff: noqa: E402
"""Ray against the local pool on this machine: days per minute of the same generation job, and task overhead.

The job (`--households` x `--days` training days, seed 0) is generated into a fresh folder `--repeats` times with
the local pool (`--workers`, all cores by default) and as Ray tasks on a Ray instance started here with as many
CPUs (started afresh for every job), alternating the two. Each timing is one `generate()` call, worker start-up
included in both (Ray's own start-up is not: it is `ray_start_s`, what joining a running cluster saves). Both
must write the same bytes. `task_overhead_ms` is the worker time an empty task costs: wall time x CPUs / tasks
over `--empty-tasks` tasks that return at once, through the same execution module (for both backends);
`cpu_s_per_day` the median CPU seconds a worker spends on one of `--cpu-days` days on each backend (what other
users cannot move). How busy the machine was: `machine.load_1min` before and after, and `machine.busy_before`,
the share of CPU time spent by anything in the 2 s before the bench started. Needs the cluster extra:
pip install -e ".[cluster]".

Usage: python benchmarks/bench_ray.py [--households 2] [--days 20] [--repeats 3] [--workers N]
"""

from __future__ import annotations

import argparse
import hashlib
import logging
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT))

from benchmarks._common import emit, machine_info, positive_int, setup_logging, summary
from homer_sim.data.generate import Generator, Sources, day_tasks, generate, simulate_task
from homer_sim.execution import Backend

log = logging.getLogger("benchmarks.ray")

TARGET_OVERHEAD = 0.10


def cpu_busy(seconds: float = 2.0) -> float:
    """Share (0..1) of all CPUs' time spent busy over `seconds`, from /proc/stat (Linux)."""
    def sample() -> tuple[int, int]:
        fields = [int(v) for v in Path("/proc/stat").read_text().split("\n")[0].split()[1:]]
        return sum(fields), fields[3] + fields[4]  # total, idle + iowait

    total_0, idle_0 = sample()
    time.sleep(seconds)
    total_1, idle_1 = sample()
    return round(1.0 - (idle_1 - idle_0) / max(total_1 - total_0, 1), 3)


def digest(folder: Path) -> str:
    files = sorted(p for p in folder.rglob("*") if p.is_file() and p.name != "generation.log")
    return hashlib.sha256(b"".join(p.read_bytes() for p in files)).hexdigest()


def timed_job(backend: Backend, households: int, days: int, scratch: Path) -> tuple[float, str, dict]:
    """Wall seconds of one generation job on `backend`, the digest of what it wrote, and where it ran."""
    out = Path(tempfile.mkdtemp(dir=scratch)) / "data"
    started = time.perf_counter()
    result = generate(out, households, days, 0, seed=0, backend=backend, progress=False)
    return time.perf_counter() - started, digest(out), result["execution"]


def start_ray(cpus: int) -> float:
    """Start a Ray instance here with `cpus` CPUs (fresh worker processes); returns the seconds it took."""
    import ray

    started = time.perf_counter()
    ray.init(address="local", num_cpus=cpus, include_dashboard=False, logging_level=logging.WARNING)
    return time.perf_counter() - started


def _empty(state: None, task: int) -> int:
    return task


def _cpu_timed(state: Generator, task: tuple) -> float:
    started = time.process_time()
    simulate_task(state, task)
    return time.process_time() - started


def cpu_s_per_day(backend: Backend, days: int) -> float:
    """Median CPU seconds a worker spends simulating one day on `backend` (the first `days` of household_a):
    unlike wall time, barely moved by other users of a shared machine."""
    with backend.run(_cpu_timed, day_tasks(["household_a"], days, 0, 0), Generator, (Sources(),)) as run:
        return round(statistics.median(run), 3)


def task_overhead_ms(backend: Backend, tasks: int, cpus: int) -> float:
    """Worker milliseconds an empty task costs on `backend` (wall x cpus / tasks, after a warm-up batch)."""
    for _ in range(2):  # the first batch starts the worker processes
        started = time.perf_counter()
        with backend.run(_empty, range(tasks), type(None)) as run:
            assert sorted(run) == list(range(tasks))
        wall = time.perf_counter() - started
    return round(wall * cpus / tasks * 1000, 3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--households", type=positive_int, default=2, help="households of the job (2)")
    parser.add_argument("--days", type=positive_int, default=20, help="training days per household (20)")
    parser.add_argument("--repeats", type=positive_int, default=3, help="jobs per backend (3)")
    parser.add_argument("--workers", type=positive_int, default=os.cpu_count() or 1,
                        help="local workers and Ray CPUs (all cores)")
    parser.add_argument("--empty-tasks", type=positive_int, default=400, help="tasks of the overhead batch (400)")
    parser.add_argument("--cpu-days", type=positive_int, default=16, help="days timed in CPU seconds (16)")
    args = parser.parse_args()
    setup_logging()
    import ray

    busy_before, load_before = cpu_busy(), os.getloadavg()[0]
    local, on_ray = Backend(workers=args.workers), Backend(ray="auto")  # the instance start_ray started here
    walls: dict[str, list[float]] = {"local": [], "ray": []}
    digests, usage, ray_start_s = set(), {}, []
    with tempfile.TemporaryDirectory() as scratch:
        for k in range(args.repeats):
            for name, backend in (("local", local), ("ray", on_ray))[:: 1 if k % 2 == 0 else -1]:
                if name == "ray":
                    ray_start_s.append(start_ray(args.workers))
                wall, written, usage[name] = timed_job(backend, args.households, args.days, Path(scratch))
                ray.shutdown()
                walls[name].append(wall)
                digests.add(written)
                log.info("repeat %d %s: %.2f s, %s", k, name, wall, usage[name])
    overhead = {"local": task_overhead_ms(local, args.empty_tasks, args.workers)}  # no fork beside Ray's threads
    cpu = {"local": cpu_s_per_day(local, args.cpu_days)}
    start_ray(args.workers)
    overhead["ray"] = task_overhead_ms(on_ray, args.empty_tasks, args.workers)
    cpu["ray"] = cpu_s_per_day(on_ray, args.cpu_days)
    ray.shutdown()
    days = args.households * args.days
    per_min = {name: round(days / statistics.median(w) * 60, 2) for name, w in walls.items()}
    emit({"benchmark": "ray", "machine": {**machine_info(None), "busy_before": busy_before,
                                          "load_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)]},
          "job": {"households": args.households, "days": days, "workers": args.workers, "repeats": args.repeats},
          "local_days_per_min": per_min["local"], "ray_days_per_min": per_min["ray"],
          "overhead": round(1.0 - per_min["ray"] / per_min["local"], 4),
          "overhead_fastest": round(1.0 - min(walls["local"]) / min(walls["ray"]), 4),
          "task_overhead_ms": overhead["ray"], "local_task_overhead_ms": overhead["local"], "cpu_s_per_day": cpu,
          "wall_s": {name: summary(w, 2) for name, w in walls.items()}, "ray_start_s": summary(ray_start_s, 2),
          "worker_s_per_day": round(statistics.median(walls["local"]) * args.workers / days, 3),
          "execution": usage, "same_bytes": len(digests) == 1, "target_overhead": TARGET_OVERHEAD,
          "meets_target": 1.0 - per_min["ray"] / per_min["local"] <= TARGET_OVERHEAD})


if __name__ == "__main__":
    main()
