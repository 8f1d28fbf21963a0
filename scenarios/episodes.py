"""Named assisted-day environments for `scenarios.env.make`: the breakfast mornings, the whole days of the
project's households, and any test day of a dataset made by `homer generate`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from homer_sim.clock import DEFAULT_WINDOW_MIN
from homer_sim.errors import unknown_name
from scenarios.registry import FULL_DAY_HOUSEHOLDS
from scenarios.task import AssistEnv, AssistTask, DayPlan

TUNINGS = ("paper", "assist")  # tunings of the robot's predictor, in order; it acts on the last (assistance)


@dataclass(frozen=True)
class Setup:
    """An environment and the predictor fitted for its household (None where there is none)."""

    env: AssistEnv
    predictor: object | None


def dataset_day_plan(dataset, household: str, index: int, split: str = "test", end_min: int | None = None,
                     robot_seed: int | None = None) -> DayPlan:
    """Day `index` of `split` of `household` in a dataset made by `homer generate`, as an episode: its schedule
    and its key (the physics stream it was drawn with), and the robot's stream from (robot_seed, household, day)."""
    if household not in dataset.meta.households:
        raise unknown_name("household", household, dataset.meta.households)
    day = dataset.load(household, split)[index]
    key = day.replay_key()
    seed = None if robot_seed is None else (robot_seed, key.household, index)
    return DayPlan(household, key, tuple(tuple(e) for e in day.schedule), end_min, robot_seed=seed)


class Fitted(NamedTuple):
    """A household's tuned predictor, its checkpoint info (tunings) and whether it was fitted or tuned just now."""

    predictor: object
    info: dict
    fresh: bool


def predictor_for(dataset, household: str, method: str | None, window_min: int, checkpoints: Path,
                  progress: bool = False) -> Fitted:
    """The household's predictor fitted on its training days (all but the last tenth, which are its validation
    days) and tuned on the validation days at `window_min`, cached under `checkpoints` as `homer evaluate` caches
    it (fitted on the first call, loaded after), with its checkpoint info. method None: the best validated method
    of the validation table (`model.selection`). Tuned for the paper's objective (reported) and then for the
    assistance objective, whose threshold the predictor keeps: the robot's (see `thresholds`)."""
    from model.evaluate import FitSpec, fit_task, household_split, run_fit
    from model.selection import default_method

    fit, val, _, _ = household_split(dataset, household, None)
    spec = FitSpec(method or default_method(), tuple(fit), tuple(val))
    result = run_fit(None, fit_task(spec.method, spec, dataset.meta, window_min,
                                    spec.path(Path(checkpoints), household), TUNINGS, progress=progress))
    result.save()
    return Fitted(result.predictor, result.info, result.changed)


def method_source(method: str | None) -> str:
    """How the predictor's method was chosen: named by the caller, or the validation table's best."""
    from model.selection import TABLE

    return "as asked" if method else f"best on validation days in {TABLE.parent.name}/{TABLE.name}"


def thresholds(info: dict, window_min: int) -> dict[str, float]:
    """{target: the threshold tuned on validation days for it} of a checkpoint's info, for TUNINGS."""
    return {t: float(info["tunings"][f"{t}@{window_min}"]["params"]["threshold"]) for t in TUNINGS}


def _breakfast(skip_breakfast: bool = False, **options) -> Setup:
    from scenarios.breakfast import Morning, morning_setup
    from scenarios.breakfast_data import DataSpec

    morning_keys = {"split", "index", "end_min"}
    morning = Morning(skip_breakfast=skip_breakfast, **{k: v for k, v in options.items() if k in morning_keys})
    spec = DataSpec(**{k: v for k, v in options.items() if k not in morning_keys | {"recording"}})
    setup = morning_setup(morning, spec, options.get("recording"))
    return Setup(setup.env, setup.predictor)


def _full_day(household: str) -> Callable[..., Setup]:
    def build(**options) -> Setup:
        from scenarios.breakfast import FULL_DAY_TRAIN_DAYS

        return _breakfast(end_min=options.pop("end_min", None), household=household,
                          train_days=options.pop("train_days", FULL_DAY_TRAIN_DAYS), test_days=1, **options)

    return build


def _dataset_day(data: str, household: str, index: int = 0, split: str = "test", end_min: int | None = None,
                 method: str | None = None, seed: int = 0, window_min: int = DEFAULT_WINDOW_MIN,
                 checkpoints: str | None = None, recording=None) -> Setup:
    from homer_sim.data.dataset import Dataset
    from homer_sim.data.generate import Generator, Sources
    dataset = Dataset(data)
    generator = Generator(Sources())
    plan = dataset_day_plan(dataset, household, index, split, end_min, seed)
    env = AssistEnv(AssistTask([plan], window_min=window_min, reference=generator, recording=recording))
    folder = Path(checkpoints) if checkpoints else Path(data) / "checkpoints"
    return Setup(env, predictor_for(dataset, household, method, window_min, folder)[0] if method else None)


ENVIRONMENTS: dict[str, Callable[..., Setup]] = {
    "breakfast": _breakfast,
    "breakfast_skipped": lambda **options: _breakfast(skip_breakfast=True, **options),
    **{f"day_{h}": _full_day(h) for h in FULL_DAY_HOUSEHOLDS},
    "dataset_day": _dataset_day,
}


def make_setup(name: str, **options) -> Setup:
    """The named environment (ENVIRONMENTS) and its household's predictor."""
    if name not in ENVIRONMENTS:
        raise unknown_name("environment", name, ENVIRONMENTS, limit=len(ENVIRONMENTS))
    return ENVIRONMENTS[name](**options)
