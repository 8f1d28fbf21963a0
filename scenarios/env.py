"""The assisted day as a `dm_env.Environment`: `make(name, **options)` builds a named one.

The task, its specs and the environment are in `scenarios.task`; the named days (the breakfast mornings, the
households' whole days, any dataset day) in `scenarios.episodes`; policies in `scenarios.policies`.
"""

from __future__ import annotations

from scenarios.episodes import make_setup
from scenarios.task import (
    MAX_RELOCATIONS,
    NO_RELOCATION,
    OUTCOME_FIELDS,
    AssistEnv,
    AssistTask,
    DayPlan,
    SceneInfo,
    play,
    run_episode,
)

__all__ = ["MAX_RELOCATIONS", "NO_RELOCATION", "OUTCOME_FIELDS", "AssistEnv", "AssistTask", "DayPlan", "SceneInfo",
           "make", "play", "run_episode"]


def make(name: str, **options) -> AssistEnv:
    """The environment of a named assisted day (`scenarios.episodes.ENVIRONMENTS`; options as its builder takes
    them, for example `make("breakfast", skip_breakfast=True)` or `make("dataset_day", data="data/",
    household="household_b", index=3)`)."""
    return make_setup(name, **options).env
