"""Dataset generation: households live sampled days in physics; each day becomes one file.

A day is simulated from the start layout with two random streams seeded from its `DayKey` (seed, household,
split, day, attempt); a day that fails (it ends outside, an object falls out, a placement cannot be found) is retried
with the next attempt and logged. Day files are written atomically, so an interrupted run resumes where it
stopped and the bytes never depend on the number of workers. Timings go to `generation.log` only.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from homer_sim import __version__
from homer_sim.data.dataset import DatasetMeta, Day, day_path, write_day, write_meta
from homer_sim.data.stats import LOG_NAME
from homer_sim.days import DayKey
from homer_sim.errors import HomerError
from homer_sim.execution import IN_PROCESS, Backend
from homer_sim.person.activities import load_library
from homer_sim.person.aliases import Resolver
from homer_sim.person.avatar import add_avatar
from homer_sim.person.executor import DayLog, Executor
from homer_sim.person.households import load_homer_habits, load_households
from homer_sim.person.sampler import sample_schedule
from homer_sim.world import World

log = logging.getLogger(__name__)

MAX_ATTEMPTS = 12


@dataclass(frozen=True)
class Sources:
    """Where habits and scripts come from: None means the packaged ones."""

    habits: str | None = None
    scripts: str | None = None

    def absolute(self) -> Sources:
        """The same sources with absolute paths, for workers that run elsewhere (on a cluster, every node must
        see the folders at these paths)."""
        return Sources(*(str(Path(p).resolve()) if p else None for p in (self.habits, self.scripts)))


class Generator:
    """One worker's simulator: a World with an avatar, an executor, households and scripts."""

    def __init__(self, sources: Sources, recording=None) -> None:

        self.world = World(extras=[add_avatar])
        self.executor = Executor(self.world, recording=recording)
        self.households = load_homer_habits(sources.habits) if sources.habits else load_households()
        resolver = Resolver(self.world.layout.node_names())
        self.library = load_library(resolver, Path(sources.scripts) if sources.scripts else None)

    def scripts_for(self, household: str) -> dict:
        """The script variant this household uses for each activity."""
        chosen = {}
        variants = self.households[household].variants
        missing = [a for a in self.households[household].order if a not in self.library]
        if missing:
            raise HomerError(f"no script for activities {', '.join(missing)}")
        for activity in self.households[household].order:
            options = self.library[activity]
            chosen[activity] = options[variants.get(activity, 0) % len(options)]
        return chosen

    def schedule(self, household: str, key: DayKey) -> list[tuple[str, float, float]]:
        """The (activity, start_min, end_min) entries of `household`'s day `key`, drawn from its schedule stream."""

        durations = {a: s.duration_range for a, s in self.scripts_for(household).items()}
        schedule = sample_schedule(self.households[household], durations, key.streams()[0])
        return [(e.activity, e.start_min, e.end_min) for e in schedule.entries]

    def replay(self, household: str, key: DayKey, entries: Sequence[tuple[str, float, float]], executor=None,
               **run_options) -> DayLog:
        """Live `entries` of `household` with the physics stream of `key`, in this generator's world or in
        `executor`'s (a world with a robot, say): the same day by construction whenever the key and entries
        are a dataset day's. run_options go to `Executor.run_day` (after_tick, end_min)."""
        executor = executor or self.executor
        return executor.run_day(entries, self.scripts_for(household), key.streams()[1], **run_options)

    def simulate(self, household: str, key: DayKey) -> tuple[Day, dict]:
        """Simulate day `key` of `household`, drawing it again (the key's next attempt) while an attempt fails;
        returns the day and its log record."""
        started, failures = time.perf_counter(), []
        for _ in range(MAX_ATTEMPTS):
            try:
                record = self.replay(household, key, self.schedule(household, key))
            except HomerError as error:  # a failed attempt: log it and sample again
                failures.append(f"{type(error).__name__}: {error}")
                log.info("%s %s: failed: %s", household, key, error)
                key = key.next_attempt()
                continue
            day = Day(household, key.split, key.index, np.array(record.minutes, dtype=np.int32),
                      np.array(record.parents, dtype=np.int16), np.array(record.relations, dtype=np.int8),
                      tuple(record.schedule), tuple(record.moves), key)
            info = {"household": household, "split": key.split, "day": key.index, "attempts": key.attempt + 1,
                    "failures": failures, "wall_s": round(time.perf_counter() - started, 3),
                    "physics_s": round(float(self.world.data.time), 2)}  # the day starts at time 0
            return day, info
        raise HomerError(f"{household}/{key.split}/day {key.index}: all {MAX_ATTEMPTS} attempts failed; "
                         f"last: {failures[-1]}")

    def meta(self, households: list[str], extra: dict) -> DatasetMeta:
        return world_meta(self.world, households, extra)


def world_meta(world: World, households: list[str], extra: dict) -> DatasetMeta:
    """The dataset meta of days lived in `world`: its declared nodes, their categories and which are movable."""
    graph = world.declared_graph()
    movable = set(world.object_names)
    return DatasetMeta(graph.nodes, graph.categories, tuple(n in movable for n in graph.nodes),
                       tuple(households), extra=extra)


def simulate_task(generator: Generator, task: tuple) -> tuple[Day, dict]:
    """One day of `day_tasks` on a worker's Generator: the task function of the execution backend."""
    return generator.simulate(*task)


def day_tasks(households: list[str], train_days: int, test_days: int, seed: int) -> list[tuple[str, DayKey]]:
    """(household, first key) for every day of the dataset; households are numbered in the habits' order."""
    return [(name, DayKey(seed, h, split, d)) for h, name in enumerate(households)
            for split, count in (("train", train_days), ("test", test_days)) for d in range(count)]


def generate(out: Path, n_households: int, train_days: int, test_days: int, seed: int,
             backend: Backend = IN_PROCESS, sources: Sources = Sources(), progress: bool = True) -> dict:
    """Generate (or resume) a dataset folder with the days run on `backend` (local processes or Ray tasks) and
    written here; returns a summary with where the days ran (`execution`)."""
    out = Path(out)
    probe = Generator(sources)
    names = list(probe.households)[:n_households]
    if len(names) < n_households:
        raise HomerError(f"asked for {n_households} households; the habits define {len(names)}: {', '.join(names)}")
    extra = {"generator": {"seed": seed, "train_days": train_days, "test_days": test_days,
                           "habits": sources.habits or "packaged", "scripts": sources.scripts or "packaged",
                           "homer_sim": __version__}}
    meta = probe.meta(names, extra)
    _check_existing(out, meta)
    write_meta(out, meta)
    tasks = [(house, key) for house, key in day_tasks(names, train_days, test_days, seed)
             if not day_path(out, house, key.split, key.index).exists()]
    started = time.perf_counter()
    with (open(out / LOG_NAME, "a") as log_file,
          backend.run(simulate_task, tasks, Generator, (sources.absolute(),), probe) as run):
        for day, info in _progress(run, len(tasks), progress):
            write_day(out, day)
            log_file.write(json.dumps(info, sort_keys=True) + "\n")
            log_file.flush()
    usage = run.usage()
    log.info("%d days on %d %s workers (%d nodes)", len(tasks), usage["workers"], usage["mode"], usage["nodes"])
    return {"out": str(out), "days_written": len(tasks), "households": names,
            "wall_s": round(time.perf_counter() - started, 2), "execution": usage}


def _progress(results, total: int, enabled: bool):

    return tqdm(results, total=total, desc="days", unit="day", disable=not enabled, dynamic_ncols=True)


def _check_existing(out: Path, meta: DatasetMeta) -> None:
    """Refuse to mix a new dataset into a folder that holds a different one."""
    path = out / "meta.json"
    if not path.exists():
        if out.exists() and any(out.iterdir()):
            raise HomerError(f"{out} exists and is not a homer-sim dataset; choose an empty or new folder")
        return
    existing = json.loads(path.read_text())
    if existing.get("version") != meta.version:
        raise HomerError(f"{out} holds a dataset of format version {existing.get('version')}; this homer-sim writes "
                         f"version {meta.version}: generate into a new folder")
    if existing.get("generator") != meta.extra["generator"] or existing.get("nodes") != list(meta.nodes):
        raise HomerError(f"{out} holds a dataset generated with other settings ({existing.get('generator')}); "
                         "use another folder")
