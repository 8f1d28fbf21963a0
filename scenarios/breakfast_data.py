"""The breakfast household, its small dataset and its trained predictor, made deterministically and cached.

A household whose only activity is breakfast (BREAKFAST_SCRIPT), every day at 07:00: a regular routine like the
paper's robot demo, where the length of breakfast (and so the time of clearing up) varies from day to day.
`ensure_dataset` simulates its days with the project's generator (the same per-day random streams as
`homer generate`, so the bytes depend only on the seed) into a user cache folder; `ensure_predictor`
fits and tunes a predictor on it and caches the checkpoint next to it. Both reuse what is cached.

Cache root: $HOMER_SIM_CACHE, else $XDG_CACHE_HOME/homer-sim, else ~/.cache/homer-sim. Folder names carry a
digest of everything the data depends on (node list, habits, script text, package version, day counts, seed), so a
changed apartment or script never reuses stale data.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

from homer_sim import __version__
from homer_sim.clock import DEFAULT_WINDOW_MIN, HOURS_PER_DAY
from homer_sim.data.dataset import Dataset, DatasetMeta, day_path, write_day, write_meta
from homer_sim.data.generate import Generator, Sources
from homer_sim.days import DayKey
from homer_sim.errors import HomerError
from homer_sim.person.aliases import Resolver
from homer_sim.person.households import ACTIVITIES, OPTIONAL, Household
from homer_sim.person.scripts import parse_script

log = logging.getLogger(__name__)

HOUSEHOLD = "breakfast_only"
BREAKFAST_HABIT = (0.0, 1.0) + (0.0,) * (HOURS_PER_DAY - 2)  # starts at 07:00; its length (16-28 min) varies
CACHE_ENV = "HOMER_SIM_CACHE"


@dataclass(frozen=True)
class DataSpec:
    """What the demo's dataset and predictor are: days per split, seed, method (None: the best validated one),
    window (min), household."""

    train_days: int = 16
    test_days: int = 2
    seed: int = 0
    method: str | None = None  # None: the best validated method of the validation table (model.selection)
    window_min: int = DEFAULT_WINDOW_MIN
    household: str = HOUSEHOLD  # or one of the project's households (a full assisted day)


BREAKFAST_SCRIPT = """\
# The paper's robot demo: cereal, milk and bowl at the table; after eating the person sits on the sofa for a
# while, then returns cereal and milk and leaves bowl and spoon in the sink.
## 2-3
[Walk] <cupboard>
[Open] <cupboard>
[Grab] <bowl>
[Grab] <food_cereal>
[Walk] <table_dining_room>
[PutBack] <bowl> <table_dining_room>
[PutBack] <food_cereal> <table_dining_room>
## 1-2
[Walk] <cupboard>
[Grab] <spoon>
[Close] <cupboard>
[Walk] <fridge>
[Open] <fridge>
[Grab] <milk>
[Close] <fridge>
[Walk] <table_dining_room>
[PutBack] <spoon> <table_dining_room>
[PutBack] <milk> <table_dining_room>
## 10-16
[Pour] <food_cereal> <bowl>
[Pour] <milk> <bowl>
[Eat] <bowl>
[Eat] <bowl>
## 12-20
[Walk] <sofa_home_office>
[Sit] <sofa_home_office>
## 2-4
[Walk] <table_dining_room>
[Grab] <milk>
[Walk] <fridge>
[Open] <fridge>
[PutIn] <milk> <fridge>
[Close] <fridge>
[Walk] <table_dining_room>
[Grab] <food_cereal>
[Walk] <cupboard>
[Open] <cupboard>
[PutIn] <food_cereal> <cupboard>
[Close] <cupboard>
[Walk] <table_dining_room>
[Grab] <bowl>
[Grab] <spoon>
[Walk] <sink_dining_room>
[PutIn] <bowl> <sink_dining_room>
[PutIn] <spoon> <sink_dining_room>
"""
"""The demo household's breakfast: the person leaves the table for a while after eating, so there is time to
clear it that is not mid-meal (with the packaged scripts the person clears up the moment they finish)."""


def breakfast_household(variant: int = 0) -> Household:
    """Breakfast (script `variant` of the library; `make_generator` adds BREAKFAST_SCRIPT) and nothing else."""
    habits = {a: (0.0,) * HOURS_PER_DAY for a in ACTIVITIES}
    habits["breakfast"] = BREAKFAST_HABIT
    variants = {a: 0 for a in ACTIVITIES} | {"breakfast": variant}
    return Household(HOUSEHOLD, "Only breakfast, at 07:00.", habits, variants, OPTIONAL)


def cache_root() -> Path:
    """The user cache folder of homer-sim (see the module docstring)."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "homer-sim"


def make_generator(recording=None):
    """The project's day generator with the breakfast household added to its households."""

    generator = Generator(Sources(), recording=recording)
    script = parse_script(BREAKFAST_SCRIPT, "scenarios/breakfast_data.py", "breakfast", "demo",
                          Resolver(generator.world.layout.node_names()))
    generator.library["breakfast"] = [*generator.library["breakfast"], script]
    generator.households[HOUSEHOLD] = breakfast_household(len(generator.library["breakfast"]) - 1)
    return generator


def data_folder(generator, spec: DataSpec) -> Path:
    """The cache folder for `spec`, named by a digest of what the days depend on."""
    household = generator.households[spec.household]
    raw = json.dumps([generator.world.layout.node_names(), household.habits, household.variants,
                      repr(generator.scripts_for(spec.household)), __version__, spec.train_days, spec.test_days,
                      spec.seed], default=str, sort_keys=True)
    digest = hashlib.sha1(raw.encode()).hexdigest()[:10]
    return cache_root() / f"{spec.household}_{spec.train_days}+{spec.test_days}d_seed{spec.seed}_{digest}"


def ensure_dataset(generator, spec: DataSpec) -> tuple[Dataset, float]:
    """The dataset of `spec.household` (generated where missing, day by day, resumable); returns it and the wall
    seconds spent generating (0 when everything was cached)."""
    folder = data_folder(generator, spec)
    started = time.perf_counter()
    house = spec.household
    meta = generator.meta([house], {"generator": {"seed": spec.seed, "household": house, "homer_sim": __version__}})
    h_index = 0 if house == HOUSEHOLD else list(generator.households).index(house)  # as `homer generate` numbers
    if not (folder / "meta.json").is_file():
        write_meta(folder, meta)
    made = 0
    for split, count in (("train", spec.train_days), ("test", spec.test_days)):
        for index in range(count):
            if day_path(folder, house, split, index).exists():
                continue
            day, info = generator.simulate(house, DayKey(spec.seed, h_index, split, index))
            write_day(folder, day)
            made += 1
            log.info("%s dataset: %s day %d in %.1f s", house, split, index, info["wall_s"])
    return Dataset(folder), (time.perf_counter() - started) if made else 0.0


def ensure_predictor(dataset: Dataset, spec: DataSpec, progress: bool = False):
    """The predictor fitted and tuned on the training days (cached checkpoint, `scenarios.predictors.predictor_for`:
    the best validated method unless spec.method names one, the robot's threshold tuned for the assistance
    objective); returns it, its checkpoint info and the wall seconds spent fitting or tuning (0 when cached)."""
    from scenarios.predictors import predictor_for  # torch: imported when a predictor is needed

    started = time.perf_counter()
    fitted = predictor_for(dataset, spec.household, spec.method, spec.window_min, dataset.root / "checkpoints",
                           progress)
    log.info("predictor %s: %s", fitted.predictor.method, fitted.info)
    return fitted.predictor, fitted.info, time.perf_counter() - started if fitted.fresh else 0.0


def check_meta(meta: DatasetMeta, nodes: tuple[str, ...]) -> None:
    """The dataset's nodes must be the apartment's (the predictor indexes nodes by position)."""

    if tuple(meta.nodes) != tuple(nodes):
        raise HomerError(f"the cached dataset has {len(meta.nodes)} nodes, the apartment {len(nodes)}; "
                         f"delete {cache_root()} and run again")
