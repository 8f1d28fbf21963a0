"""The breakfast household, its small dataset and its trained predictor, made deterministically and cached.

A household whose only activity is breakfast (the cereal script), every day at 07:00: a regular routine like the
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
from homer_sim.dataset import Dataset, DatasetMeta, day_path, write_day, write_meta
from homer_sim.households import ACTIVITIES, HOURS, OPTIONAL, Household

log = logging.getLogger(__name__)

HOUSEHOLD = "breakfast_only"
BREAKFAST_HABIT = (0.0, 1.0) + (0.0,) * (HOURS - 2)  # starts at 07:00; its length (16-28 min) varies
CACHE_ENV = "HOMER_SIM_CACHE"


@dataclass(frozen=True)
class DataSpec:
    """What the demo's dataset and predictor are: days per split, seed, method, window (min)."""

    train_days: int = 16
    test_days: int = 2
    seed: int = 0
    method: str = "markov"  # the graph network trains at ~50 s per epoch on 2 shared cores: too slow for a demo
    window_min: int = 30


def breakfast_household() -> Household:
    """Breakfast (script variant 0: cereal, milk and bowl at the table) and nothing else."""
    habits = {a: (0.0,) * HOURS for a in ACTIVITIES}
    habits["breakfast"] = BREAKFAST_HABIT
    return Household(HOUSEHOLD, "Only breakfast, at 07:00.", habits, {a: 0 for a in ACTIVITIES},
                     OPTIONAL)


def cache_root() -> Path:
    """The user cache folder of homer-sim (see the module docstring)."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "homer-sim"


def make_generator(recording=None):
    """The project's day generator with the breakfast household added to its households."""
    from homer_sim.generate import Generator, Sources

    generator = Generator(Sources(), recording=recording)
    generator.households[HOUSEHOLD] = breakfast_household()
    return generator


def data_folder(generator, spec: DataSpec) -> Path:
    """The cache folder for `spec`, named by a digest of what the days depend on."""
    script = generator.scripts_for(HOUSEHOLD)["breakfast"]
    raw = json.dumps([generator.world.layout.node_names(), BREAKFAST_HABIT, repr(script), __version__,
                      spec.train_days, spec.test_days, spec.seed], default=str)
    digest = hashlib.sha1(raw.encode()).hexdigest()[:10]
    return cache_root() / f"breakfast_{spec.train_days}+{spec.test_days}d_seed{spec.seed}_{digest}"


def ensure_dataset(generator, spec: DataSpec) -> tuple[Dataset, float]:
    """The breakfast dataset (generated where missing, day by day, resumable); returns it and the wall seconds
    spent generating (0 when everything was cached)."""
    folder = data_folder(generator, spec)
    started = time.perf_counter()
    meta = generator.meta([HOUSEHOLD], {"generator": {"seed": spec.seed, "household": HOUSEHOLD,
                                                      "homer_sim": __version__}})
    if not (folder / "meta.json").is_file():
        write_meta(folder, meta)
    made = 0
    for split, count in (("train", spec.train_days), ("test", spec.test_days)):
        for index in range(count):
            if day_path(folder, HOUSEHOLD, split, index).exists():
                continue
            day, info = generator.simulate(HOUSEHOLD, 0, split, index, spec.seed)
            write_day(folder, day)
            made += 1
            log.info("breakfast dataset: %s day %d in %.1f s", split, index, info["wall_s"])
    return Dataset(folder), (time.perf_counter() - started) if made else 0.0


def ensure_predictor(dataset: Dataset, spec: DataSpec, progress: bool = False):
    """The predictor fitted and tuned on the training days (cached checkpoint); returns it and wall seconds
    spent fitting (0 when cached)."""
    from model.evaluate import FitSpec, fit_tuned, split_days

    fit, val = split_days(dataset.load(HOUSEHOLD, "train"))
    fit_spec = FitSpec(spec.method, tuple(fit), tuple(val))
    path = fit_spec.path(dataset.root / "checkpoints", HOUSEHOLD)
    cached = path.is_file()
    started = time.perf_counter()
    predictor, info = fit_tuned(fit_spec, dataset.meta, spec.window_min, path, progress=progress)
    log.info("predictor %s: %s", spec.method, info)
    return predictor, 0.0 if cached else time.perf_counter() - started


def check_meta(meta: DatasetMeta, nodes: tuple[str, ...]) -> None:
    """The dataset's nodes must be the apartment's (the predictor indexes nodes by position)."""
    from homer_sim.errors import HomerError

    if tuple(meta.nodes) != tuple(nodes):
        raise HomerError(f"the cached dataset has {len(meta.nodes)} nodes, the apartment {len(nodes)}; "
                         f"delete {cache_root()} and run again")
