"""Named assisted-day environments for `scenarios.env.make`: the breakfast mornings, the whole days of the
project's households, and any test day of a dataset made by `homer generate`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from homer_sim.clock import DEFAULT_WINDOW_MIN
from homer_sim.errors import unknown_name
from scenarios.predictors import predictor_for
from scenarios.registry import FULL_DAY_HOUSEHOLDS
from scenarios.task import AssistEnv, AssistTask, DayPlan


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
    from homer_sim.home.apartment import default_layout
    dataset = Dataset(data)
    dataset.require_nodes(default_layout().node_names())
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
