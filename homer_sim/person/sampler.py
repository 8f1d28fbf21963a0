"""The Monte Carlo routine sampler of the seed paper's appendix ("Sampling routines").

Times are routine minutes (minutes since midnight): the day starts at 06:00 = 360 and no activity starts at or
after 24:00 = 1440 (one that started before may run past midnight). Rules, at each decision time t:

1. Hour slot h = floor(t / 60) - 6, clipped to 0..17.
2. Away (after leave_home, before come_home): only come_home can start. It starts at t with the hazard
   p(t) / sum(p(t_k)) over the decision times t_k = t, t + 10, t + 20, ... < 1440 that remain if the person
   keeps waiting, p being come_home's hourly value at each time; otherwise the person waits 10 minutes. This is
   the hazard of the distribution that puts mass p(hour) on every remaining 10-minute step, so come_home's
   start follows its habit restricted to after the leave (an hourly-resolution hazard applied every 10 minutes
   would pull the return early). If that sum is 0, come_home starts at once.
3. At home: draw u uniformly in [0, R), R = the largest hourly sum of the household's 22 values (a constant of
   the household). Walk `household.order`, treating as 0 the value of every activity that may not start now;
   at each activity, if its value exceeds u it is chosen, else u -= value. Nothing chosen: wait 10 minutes.
   May not start: an activity whose last instance ended less than 180 minutes before t (blocked), except the
   activity that ended exactly at t while its length is still more than a second below its maximum duration,
   which is extended instead; and come_home (only through rule 2).
4. Chosen activity that ended at t (extension): its end becomes uniform in [t, start + max]; the entry is the
   same instance. Any other: a new instance [t, t + uniform(min, max)]. Either way t moves to its end.
5. The day ends when t >= 1440. If the person is still away, `DayEndedOutside` is raised and the caller draws
   the day again from the next attempt's stream (`sample_day` does this).

Because R is the largest hourly sum, cumulative values never exceed R, so each allowed activity is chosen with
probability value / R at every decision whatever the order. The order (compulsory five first, then the
household's fixed shuffle) still decides which activity a given u maps to: it is part of the reproducibility
contract (reordering changes every sampled day of a seed), and with a smaller R (a sampler drawing u in [0, 1)
while hourly sums exceed 1) it would decide which activities get cut off: the compulsory ones never are.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from homer_sim.clock import DAY_END_MIN, DAY_START_MIN, HOURS_PER_DAY
from homer_sim.days import DayKey
from homer_sim.errors import HomerError, unknown_name
from homer_sim.person.households import ACTIVITIES, FIRST_HOUR, Household

"""06:00, the first decision time."""
"""24:00: no activity starts at or after it."""
IDLE_MIN = 10.0
"""Minutes the person waits when no activity is chosen."""
BLOCK_MIN = 180.0
"""An activity may not start again within this many minutes of its last end (extensions excepted)."""
EXTEND_ROOM_MIN = 1.0 / 60.0
"""An instance within one second of its maximum duration counts as at its maximum (it cannot be extended);
without this, an activity chosen at every decision would be extended by ever smaller steps."""
LEAVE, COME = "leave_home", "come_home"


class ScheduleError(HomerError):
    """Durations or a stored schedule that the sampler cannot use."""


class DayEndedOutside(ScheduleError):
    """The sampled day ended with the person outside; draw it again with the next attempt's stream."""


@dataclass(frozen=True)
class ScheduledActivity:
    """One activity instance: routine minutes [start_min, end_min)."""

    activity: str
    start_min: float
    end_min: float


@dataclass(frozen=True)
class Schedule:
    """A day's activity instances, sorted by start, non-overlapping, the first starting at or after 06:00."""

    entries: tuple[ScheduledActivity, ...]

    def __post_init__(self) -> None:
        previous_end = DAY_START_MIN
        for entry in self.entries:
            if entry.activity not in ACTIVITIES:
                raise unknown_name("activity", entry.activity, ACTIVITIES)
            if not (entry.start_min >= previous_end and entry.end_min >= entry.start_min
                    and entry.start_min < DAY_END_MIN):
                raise ScheduleError(f"schedule entry {entry} overlaps the previous one (ended {previous_end}), "
                                    f"ends before it starts or starts outside 06:00-24:00")
            previous_end = entry.end_min

    def to_json(self) -> list[list]:
        """[[activity, start_min, end_min], ...], the form dataset day files store."""
        return [[entry.activity, entry.start_min, entry.end_min] for entry in self.entries]

    @classmethod
    def from_json(cls, raw: object) -> Schedule:
        if not isinstance(raw, list) or not all(isinstance(row, list | tuple) and len(row) == 3 for row in raw):
            raise ScheduleError(f"a schedule is a list of [activity, start_min, end_min], got {raw!r:.80}")
        return cls(tuple(ScheduledActivity(str(a), float(start), float(end)) for a, start, end in raw))

    def activities(self) -> tuple[str, ...]:
        return tuple(entry.activity for entry in self.entries)


def hour_slot(minute: float) -> int:
    """The habit slot (0..17) of a routine minute; times outside 06:00-24:00 clip to the first or last slot."""
    return min(max(int(minute // 60) - FIRST_HOUR, 0), HOURS_PER_DAY - 1)


def _check_durations(household: Household, durations: Mapping[str, tuple[float, float]]) -> None:
    leaves = max(household.habits[LEAVE]) > 0.0
    for activity in household.order:
        if max(household.habits[activity]) == 0.0 and not (activity == COME and leaves):
            continue  # never sampled
        if activity not in durations:
            raise ScheduleError(f"household {household.name!r}: no duration range for activity {activity!r}")
        low, high = durations[activity]
        if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low <= high and high > 0.0):
            raise ScheduleError(f"activity {activity!r}: duration range ({low}, {high}) min must satisfy "
                                f"0 <= min <= max, max > 0")


def _come_home_hazard(habit: tuple[float, ...], minute: float) -> float:
    """p(now) / sum of p over the remaining 10-minute decision times (now included); 1 if that sum is 0.

    The decision times left in the current hour are counted exactly; every later hour holds six of them.
    """
    hour = hour_slot(minute)
    steps_this_hour = math.ceil((60.0 * (FIRST_HOUR + hour + 1) - minute) / IDLE_MIN)
    remaining = habit[hour] * steps_this_hour + (60.0 / IDLE_MIN) * sum(habit[hour + 1:])
    return 1.0 if remaining <= 0.0 else habit[hour] / remaining


def _walk(order: tuple[str, ...], values: list[float], allowed: list[bool], u: float) -> int | None:
    """Index into `order` of the activity u falls on, blocked ones counting as 0; None if none."""
    for index, value in enumerate(values):
        if not allowed[index]:
            continue
        if value > u:
            return index
        u -= value
    return None


def sample_schedule(household: Household, durations: Mapping[str, tuple[float, float]],
                    rng: np.random.Generator) -> Schedule:
    """One day of `household` (module docstring, rules 1-5), drawing only from `rng` (the schedule stream).

    durations: activity -> (min, max) total duration in routine minutes (from its script variant's blocks),
    needed for every activity with a non-zero habit (and come_home if leave_home has one). Raises
    DayEndedOutside.
    """
    _check_durations(household, durations)
    order = household.order
    matrix = household.habit_matrix(order)  # (22, 18)
    total_by_hour = float(matrix.sum(axis=0).max())  # R
    columns = [matrix[:, hour].tolist() for hour in range(HOURS_PER_DAY)]
    come_habit = household.habits[COME]
    entries: list[list] = []  # [activity, start, end]
    last_end: dict[str, float] = {}
    minute, away = DAY_START_MIN, False
    while minute < DAY_END_MIN:
        if away:
            if rng.random() < _come_home_hazard(come_habit, minute):
                minute = _start(entries, last_end, COME, minute, durations, rng)
                away = False
            else:
                minute += IDLE_MIN
            continue
        previous = entries[-1] if entries and entries[-1][2] == minute else None
        extendable = previous is not None and previous[1] + durations[previous[0]][1] - minute > EXTEND_ROOM_MIN
        allowed = [activity != COME and (minute >= last_end.get(activity, -math.inf) + BLOCK_MIN
                                         or (extendable and activity == previous[0])) for activity in order]
        chosen = _walk(order, columns[hour_slot(minute)], allowed, rng.random() * total_by_hour)
        if chosen is None:
            minute += IDLE_MIN
        elif extendable and order[chosen] == previous[0]:
            previous[2] = float(rng.uniform(minute, previous[1] + durations[previous[0]][1]))
            last_end[previous[0]] = minute = previous[2]
        else:
            minute = _start(entries, last_end, order[chosen], minute, durations, rng)
            away = order[chosen] == LEAVE
    if away:
        raise DayEndedOutside(f"household {household.name!r}: the day ended outside (left at "
                              f"{entries[-1][1]:.0f} min, no come_home before 24:00)")
    return Schedule(tuple(ScheduledActivity(a, start, end) for a, start, end in entries))


def _start(entries: list[list], last_end: dict[str, float], activity: str, minute: float,
           durations: Mapping[str, tuple[float, float]], rng: np.random.Generator) -> float:
    """Append a new instance of `activity` at `minute`; return its end."""
    low, high = durations[activity]
    end = minute + float(rng.uniform(low, high))
    entries.append([activity, minute, end])
    last_end[activity] = end
    return end


def sample_day(household: Household, durations: Mapping[str, tuple[float, float]], key: DayKey,
               max_attempts: int = 100) -> tuple[Schedule, DayKey]:
    """The schedule of day `key` and the key of the attempt that produced it (days ending outside are drawn
    again with the next attempt's schedule stream); the caller takes the physics stream of that key."""
    for _ in range(max_attempts):
        try:
            return sample_schedule(household, durations, key.streams()[0]), key
        except DayEndedOutside:
            key = key.next_attempt()
    raise DayEndedOutside(f"household {household.name!r}: every one of {max_attempts} attempts of {key.split} day "
                          f"{key.index} ended outside")
