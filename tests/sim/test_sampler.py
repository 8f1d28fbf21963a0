"""The routine sampler and the day streams: determinism, well-formed days, blocking, outings and statistics."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from homer_sim.days import DayKey
from homer_sim.errors import HomerError, UnknownNameError
from homer_sim.person.households import ACTIVITIES, OPTIONAL, Household, load_households
from homer_sim.person.sampler import (
    DayEndedOutside,
    Schedule,
    ScheduleError,
    hour_slot,
    sample_day,
    sample_schedule,
)

# (min, max) minutes per activity, stand-ins for the script durations (close to HOMER's reference scripts).
TYPICAL_DURATIONS = {
    "brushing_teeth": (5, 10), "showering": (10, 25), "breakfast": (15, 35), "dinner": (25, 50), "lunch": (20, 40),
    "computer_work": (40, 150), "cleaning": (20, 45), "laundry": (20, 40), "leave_home": (3, 8), "come_home": (3, 8),
    "socializing": (45, 150), "taking_medication": (2, 5), "watching_tv": (30, 120), "vaccuum_cleaning": (15, 30),
    "reading": (20, 75), "going_to_the_bathroom": (3, 10), "getting_dressed": (5, 10), "kitchen_cleaning": (10, 20),
    "take_out_trash": (2, 5), "wash_dishes": (10, 20), "playing_music": (20, 60), "listening_to_music": (20, 60),
}
TEN_MINUTES = dict.fromkeys(ACTIVITIES, (10.0, 10.0))  # every decision lands on the 10-minute grid
DAYS = 2000
Z_MAX = 4.5  # per-check tolerance in standard deviations (about 1e-5 false alarms each; seeds are fixed anyway)


def _household(**habits: dict[int, float]) -> Household:
    """A test household: the given habits as {clock hour: value}, zeros elsewhere, variants 0."""
    full = {a: tuple(habits.get(a, {}).get(hour, 0.0) for hour in range(6, 24)) for a in ACTIVITIES}
    return Household("test", "inline test household", full, dict.fromkeys(ACTIVITIES, 0), OPTIONAL)


def _days(household: Household, durations: dict, days: int = DAYS, seed: int = 7) -> list[Schedule]:
    return [sample_schedule(household, durations, DayKey(seed, 0, "train", day).streams()[0]) for day in range(days)]


def _start_hours(schedules: list[Schedule], activity: str) -> np.ndarray:
    """Per day and hour slot, whether `activity` started then; shape (days, 18)."""
    started = np.zeros((len(schedules), 18), dtype=bool)
    for day, schedule in enumerate(schedules):
        for entry in schedule.entries:
            if entry.activity == activity:
                started[day, hour_slot(entry.start_min)] = True
    return started


@pytest.fixture(scope="module")
def sampled() -> dict[str, list[Schedule]]:
    """300 days of every packaged household with the typical durations."""
    households = load_households()
    return {name: [sample_day(household, TYPICAL_DURATIONS, DayKey(3, index, "train", day))[0] for day in range(300)]
            for index, (name, household) in enumerate(households.items())}


def test_day_streams_come_from_the_key_only() -> None:
    schedule, physics = DayKey(1, 2, "test", 3, 4).streams()
    expected = [np.random.default_rng(child).random(3) for child in np.random.SeedSequence([1, 2, 1, 3, 4]).spawn(2)]
    assert np.array_equal(schedule.random(3), expected[0]) and np.array_equal(physics.random(3), expected[1])
    first = {DayKey(*coords).streams()[0].random() for coords in
             [(1, 2, "test", 3, 4), (0, 2, "test", 3, 4), (1, 0, "test", 3, 4), (1, 2, "train", 3, 4),
              (1, 2, "test", 0, 4), (1, 2, "test", 3, 0)]}
    assert len(first) == 6
    code = "from homer_sim.days import DayKey; print(repr(DayKey(1, 2, 'test', 3, 4).streams()[1].random()))"
    other_process = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert float(other_process.stdout) == expected[1][0]
    with pytest.raises(UnknownNameError, match="unknown split 'tset'; closest known: test"):
        DayKey(1, 2, "tset", 3)
    with pytest.raises(HomerError, match="index must be a non-negative integer"):
        DayKey(1, 2, "test", -3)
    assert DayKey(1, 2, "test", 3).next_attempt() == DayKey(1, 2, "test", 3, 1)
    assert DayKey.from_json(DayKey(1, 2, "test", 3, 4).to_json()) == DayKey(1, 2, "test", 3, 4)


def test_same_streams_give_the_same_schedule() -> None:
    household = load_households()["household_d"]
    first = [sample_schedule(household, TYPICAL_DURATIONS, DayKey(5, 3, "train", d).streams()[0]) for d in range(20)]
    again = [sample_schedule(household, TYPICAL_DURATIONS, DayKey(5, 3, "train", d).streams()[0]) for d in range(20)]
    assert first == again
    assert len({json.dumps(s.to_json()) for s in first}) == 20


def test_schedules_are_well_formed_and_round_trip(sampled: dict[str, list[Schedule]]) -> None:
    for name, schedules in sampled.items():
        counts = []
        for schedule in schedules:
            previous_end = 360.0
            for entry in schedule.entries:
                assert previous_end <= entry.start_min < 1440.0, (name, entry)
                low, high = TYPICAL_DURATIONS[entry.activity]
                assert low - 1e-9 <= entry.end_min - entry.start_min <= high + 1e-9, (name, entry)
                previous_end = entry.end_min
            assert Schedule.from_json(json.loads(json.dumps(schedule.to_json()))) == schedule
            counts.append(len(schedule.entries))
        assert 12.0 <= np.mean(counts) <= 20.0, (name, np.mean(counts))


def test_finished_activities_are_blocked_for_three_hours(sampled: dict[str, list[Schedule]]) -> None:
    for name, schedules in sampled.items():
        for schedule in schedules:
            last_end: dict[str, float] = {}
            for entry in schedule.entries:
                if entry.activity != "come_home":  # returns are governed by the hazard only
                    assert entry.start_min >= last_end.get(entry.activity, -math.inf) + 180.0, (name, entry)
                last_end[entry.activity] = entry.end_min


def test_every_day_ends_at_home(sampled: dict[str, list[Schedule]]) -> None:
    for name, schedules in sampled.items():
        outings = 0
        for schedule in schedules:
            activities = schedule.activities()
            for index, activity in enumerate(activities):
                if activity == "leave_home":
                    assert activities[index + 1 : index + 2] == ("come_home",), name
                    outings += 1
            assert activities.count("come_home") == activities.count("leave_home"), name
        assert outings > 0.3 * len(schedules), name


def test_starts_follow_the_habits_of_real_households(sampled: dict[str, list[Schedule]]) -> None:
    households = load_households()
    for name, schedules in sampled.items():
        habit = households[name].habit_matrix()
        doing = np.zeros_like(habit)
        for index, activity in enumerate(ACTIVITIES):
            started = _start_hours(schedules, activity)
            assert not np.any(started[:, habit[index] == 0.0]), (name, activity)  # zero hour: never starts
            for schedule in schedules:
                hours = {h for e in schedule.entries if e.activity == activity
                         for h in range(hour_slot(e.start_min), hour_slot(min(e.end_min, 1439.0)) + 1)}
                doing[index, list(hours)] += 1
        # The fraction of days doing each activity in each hour tracks the habit's values.
        assert np.corrcoef(doing.ravel(), habit.ravel())[0, 1] > 0.75, name


def test_one_hour_activity_starts_in_that_hour_only() -> None:
    household = _household(showering={6: 1.0}, reading={16: 0.3})  # R = 1, so P(start per decision) = 0.3
    started = _start_hours(_days(household, TEN_MINUTES), "reading")
    expected = 1.0 - 0.7**6  # six decisions in the hour
    assert not started[:, np.arange(18) != 10].any()
    observed = started[:, 10].mean()
    assert abs(observed - expected) < Z_MAX * math.sqrt(expected * (1 - expected) / DAYS)


def test_start_frequencies_follow_a_spread_habit() -> None:
    values = {7: 0.05, 11: 0.15, 15: 0.10, 19: 0.30}  # four hours apart: blocking never interferes
    household = _household(showering={6: 1.0}, reading=values)
    started = _start_hours(_days(household, TEN_MINUTES), "reading")
    slots = [hour - 6 for hour in values]
    assert not np.delete(started, slots, axis=1).any()
    for hour, value in values.items():
        expected = 1.0 - (1.0 - value) ** 6
        observed = started[:, hour - 6].mean()
        assert abs(observed - expected) < Z_MAX * math.sqrt(expected * (1 - expected) / DAYS), hour
    habit = np.array(household.habits["reading"])  # 1 - (1 - v)^6 saturates: even exact values correlate 0.979
    assert np.corrcoef(started.mean(axis=0), habit)[0, 1] > 0.95


def test_come_home_follows_its_habit_after_leaving() -> None:
    come = {7: 0.2, 15: 0.3, 17: 0.6, 21: 0.1}  # 07:00 lies before the leave at 08:00: never used
    household = _household(leave_home={8: 1.0}, come_home=come)
    durations = {"leave_home": (5.0, 5.0), "come_home": (5.0, 5.0)}
    schedules = _days(household, durations)
    assert all(s.entries[0].activity == "leave_home" and s.entries[0].start_min == 480.0 for s in schedules)
    started = _start_hours(schedules, "come_home")
    assert started.sum(axis=1).tolist() == [1] * DAYS
    counts = started.sum(axis=0)
    assert counts.sum() == counts[[9, 11, 15]].sum()
    expected = DAYS * np.array([0.3, 0.6, 0.1])
    chi_square = float(((counts[[9, 11, 15]] - expected) ** 2 / expected).sum())
    assert chi_square < 13.8  # 2 degrees of freedom, p = 0.001


def test_come_home_at_once_when_its_habit_is_over() -> None:
    # Out at 09:00 and back by 13:00 (10:00 or 12:00); out again at 13:00, when come_home's habit is over.
    household = _household(leave_home={9: 1.0, 13: 1.0}, come_home={10: 0.1, 12: 1.0})
    for schedule in _days(household, {"leave_home": (5.0, 5.0), "come_home": (5.0, 5.0)}, days=20):
        first_out, first_back, second_out, second_back = schedule.entries
        assert (first_out.start_min, second_out.start_min) == (540.0, 780.0)
        assert 600.0 <= first_back.start_min < 780.0 and hour_slot(first_back.start_min) in (4, 6)
        assert second_back.activity == "come_home" and second_back.start_min == second_out.end_min


def test_chosen_again_extends_up_to_the_maximum_then_blocks() -> None:
    household = _household(reading=dict.fromkeys(range(6, 24), 0.5))  # R = 0.5: chosen at every decision
    schedule = _days(household, {"reading": (10.0, 60.0)}, days=1)[0]
    starts = [entry.start_min for entry in schedule.entries]
    assert starts[0] == 360.0 and len(starts) == 5
    assert np.allclose(starts, [360.0, 600.0, 840.0, 1080.0, 1320.0], atol=1.0 / 60.0)
    assert all(60.0 - 1.0 / 60.0 <= entry.end_min - entry.start_min <= 60.0 for entry in schedule.entries)


def test_day_ending_outside_is_drawn_again() -> None:
    always_late = _household(showering={6: 1.0}, leave_home={23: 1.0})
    durations = {"showering": (10.0, 10.0), "leave_home": (70.0, 80.0), "come_home": (5.0, 5.0)}
    with pytest.raises(DayEndedOutside, match="ended outside"):
        sample_schedule(always_late, durations, DayKey(0, 0, "train", 0).streams()[0])
    with pytest.raises(DayEndedOutside, match="every one of 3 attempts"):
        sample_day(always_late, durations, DayKey(0, 0, "train", 0), max_attempts=3)
    sometimes_late = _household(showering={6: 1.0}, leave_home={23: 0.3})
    attempts = []
    for day in range(10):
        schedule, key = sample_day(sometimes_late, durations, DayKey(0, 0, "train", day))
        assert "leave_home" not in schedule.activities()
        assert schedule == sample_schedule(sometimes_late, durations, key.streams()[0])
        attempts.append(key.attempt)
    assert max(attempts) > 0


def test_bad_durations_and_schedules_are_rejected() -> None:
    household = _household(reading={9: 0.5})
    with pytest.raises(ScheduleError, match="no duration range for activity 'reading'"):
        sample_schedule(household, {}, np.random.default_rng(0))
    with pytest.raises(ScheduleError, match=r"activity 'reading': duration range \(20.0, 10.0\)"):
        sample_schedule(household, {"reading": (20.0, 10.0)}, np.random.default_rng(0))
    with pytest.raises(ScheduleError, match="overlaps"):
        Schedule.from_json([["reading", 400, 450], ["lunch", 440, 460]])
    with pytest.raises(UnknownNameError, match="closest known: reading"):
        Schedule.from_json([["readin", 400, 450]])
