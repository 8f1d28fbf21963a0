"""A simulated day's identity (`DayKey`) and the random streams derived from it alone.

Every day of every household gets two independent `numpy.random.Generator`s, one for the schedule (which
activities, when, how long) and one for physics details (placements, durations of the actions inside an
activity). Both come from one `SeedSequence([seed, household, split, day, attempt])`, so the bytes of a day
depend on nothing else: not on the process, the worker count or the order in which days are generated, and the
same day can be replayed with and without the robot (the robot never draws from the schedule stream). The key
is stored with every day file, so a replay needs nothing but the day.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from homer_sim.errors import HomerError, unknown_name

SPLIT_INDEX: dict[str, int] = {"train": 0, "test": 1}
"""Integer code of each dataset split inside the seed sequence (never renumber: it changes every day)."""


@dataclass(frozen=True)
class DayKey:
    """Where one simulated day comes from.

    seed: the run's seed; household: the household's index (0-based) in the habits it was generated from;
    split: "train" or "test"; index: the day's index inside the split; attempt: 0 for the first try, +1 each
    time the day had to be drawn again (it ended outside, or its physics failed). Integers are non-negative.
    """

    seed: int
    household: int
    split: str
    index: int
    attempt: int = 0

    def __post_init__(self) -> None:
        if self.split not in SPLIT_INDEX:
            raise unknown_name("split", self.split, SPLIT_INDEX)
        for name in ("seed", "household", "index", "attempt"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
                raise HomerError(f"DayKey: {name} must be a non-negative integer, got {value!r}")

    def streams(self) -> tuple[np.random.Generator, np.random.Generator]:
        """The (schedule, physics) generators of this day, fresh on every call."""
        sequence = np.random.SeedSequence([self.seed, self.household, SPLIT_INDEX[self.split], self.index,
                                           self.attempt])
        schedule_seed, physics_seed = sequence.spawn(2)
        return np.random.default_rng(schedule_seed), np.random.default_rng(physics_seed)

    def next_attempt(self) -> DayKey:
        """The same day drawn again."""
        return replace(self, attempt=self.attempt + 1)

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, raw: dict) -> DayKey:
        return cls(int(raw["seed"]), int(raw["household"]), str(raw["split"]), int(raw["index"]),
                   int(raw["attempt"]))
