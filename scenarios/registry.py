"""Named headless runs: `homer run NAME --rrd PATH` looks them up here.

Each scenario is a function (rrd path or None) -> result dict (JSON-ready) plus a function that formats the
result for people. Scenarios import their heavy dependencies when they run.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from homer_sim.errors import unknown_name

FULL_DAY_HOUSEHOLDS = ("household_a", "household_b", "household_c", "household_d", "household_e")


@dataclass(frozen=True)
class Scenario:
    """A named run: `run(rrd)` returns a result dict; `summary(result)` gives printable lines."""

    name: str
    help: str
    run: Callable[[Path | None], dict]
    summary: Callable[[dict], list[str]]


def _breakfast(rrd: Path | None) -> dict:
    from scenarios.breakfast import run_breakfast

    return run_breakfast(rrd)


def _breakfast_skipped(rrd: Path | None) -> dict:
    from scenarios.breakfast import Morning, run_breakfast

    return run_breakfast(rrd, Morning(skip_breakfast=True))


def _full_day(household: str) -> Callable[[Path | None], dict]:
    def run(rrd: Path | None) -> dict:
        from scenarios.breakfast import run_full_day

        return run_full_day(rrd, household)

    return run


def _grasp_suite(rrd: Path | None) -> dict:
    from planners.suites.grasp_suite import run_suite

    return run_suite(quick=True, progress=True, rrd=rrd)


def _grasp_summary(result: dict) -> list[str]:
    from planners.suites.grasp_suite import format_table

    return [format_table(result)]


def _summary(result: dict) -> list[str]:
    from scenarios.breakfast import format_summary

    return format_summary(result)


SCENARIOS: dict[str, Scenario] = {s.name: s for s in (
    Scenario("breakfast", "a morning of the breakfast household with the robot setting and clearing the table",
             _breakfast, _summary),
    Scenario("breakfast_skipped", "the same morning, but the person skips breakfast: the robot's help is put back "
             "once breakfast time has passed", _breakfast_skipped, _summary),
    *(Scenario(f"day_{h}", f"one whole test day of {h} with the robot helping (its dataset and predictor made "
               "and cached on the first run; long)", _full_day(h), _summary) for h in FULL_DAY_HOUSEHOLDS),
    Scenario("grasp_suite", "the quick grasp suite: pick and hold each class in its home, every trial recorded",
             _grasp_suite, _grasp_summary),
)}


def get(name: str) -> Scenario:
    """The scenario called `name`; the error lists the known ones."""
    if name not in SCENARIOS:
        raise unknown_name("scenario", name, SCENARIOS, limit=len(SCENARIOS))
    return SCENARIOS[name]
