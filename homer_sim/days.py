"""Random streams of one simulated day, derived from its coordinates only.

Every day of every household gets two independent `numpy.random.Generator`s, one for the schedule (which
activities, when, how long) and one for physics details (placements, durations of the actions inside an
activity). Both come from one `SeedSequence([seed, household, split, day, attempt])`, so the bytes of a day
depend on nothing else: not on the process, the worker count or the order in which days are generated, and the
same day can be replayed with and without the robot (the robot never draws from the schedule stream).
"""

from __future__ import annotations

import numpy as np

from homer_sim.errors import HomerError, unknown_name

SPLIT_INDEX: dict[str, int] = {"train": 0, "test": 1}
"""Integer code of each dataset split inside the seed sequence (never renumber: it changes every day)."""


def day_streams(seed: int, household: int, split: str, day: int,
                attempt: int = 0) -> tuple[np.random.Generator, np.random.Generator]:
    """The (schedule, physics) generators of one day.

    seed: the run's seed; household: the household's index (0-based); split: "train" or "test"; day: the day's
    index inside the split; attempt: 0 for the first try, +1 each time the day has to be resampled (for
    example when it ended outside). All integers must be non-negative.
    """
    if split not in SPLIT_INDEX:
        raise unknown_name("split", split, SPLIT_INDEX)
    coordinates = {"seed": seed, "household": household, "day": day, "attempt": attempt}
    for name, value in coordinates.items():
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
            raise HomerError(f"day_streams: {name} must be a non-negative integer, got {value!r}")
    sequence = np.random.SeedSequence([seed, household, SPLIT_INDEX[split], day, attempt])
    schedule_seed, physics_seed = sequence.spawn(2)
    return np.random.default_rng(schedule_seed), np.random.default_rng(physics_seed)
