"""Households: one habit per activity, a fixed script variant per activity and a fixed activity order.

A habit is 18 hourly values for 06:00-24:00 (index 0 is 06:00-07:00, index 17 is 23:00-24:00), each the
fraction of people with that habit who do the activity in that hour, in [0, 1]. The hourly values of one
household need not sum to 1 over activities (that is what the sampler's R is for, see `homer_sim.person.sampler`).

Two sources: the project's own five households (`homer_sim/data/households.json`, `load_households`) and,
for compatibility checks only, the HOMER layout of the original dataset (`load_homer_habits`: a folder with
`cluster_histograms.json` and `optimized_persona.json`). numpy and json only.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from homer_sim.clock import DAY_START_MIN, HOURS_PER_DAY
from homer_sim.errors import HabitError, unknown_name

COMPULSORY: tuple[str, ...] = ("brushing_teeth", "showering", "breakfast", "dinner", "lunch")
"""The five compulsory activities, in the order the sampler walks them (always first)."""
OPTIONAL: tuple[str, ...] = (
    "computer_work", "cleaning", "laundry", "leave_home", "come_home", "socializing", "taking_medication",
    "watching_tv", "vaccuum_cleaning", "reading", "going_to_the_bathroom", "getting_dressed",
    "kitchen_cleaning", "take_out_trash", "wash_dishes", "playing_music", "listening_to_music",
)
ACTIVITIES: tuple[str, ...] = COMPULSORY + OPTIONAL
"""The 22 activities of HOMER, spelled as HOMER spells them (`vaccuum_cleaning` included)."""

FIRST_HOUR = DAY_START_MIN // 60
"""Clock hour of habit slot 0; slot i covers routine minutes [DAY_START_MIN + 60 i, DAY_START_MIN + 60 (i + 1))."""
DEFAULT_PATH = Path(__file__).resolve().parent / "households.json"
HOMER_FILES = ("cluster_histograms.json", "optimized_persona.json")
HOMER_ORDER_SEED = 20_211_021
"""Seed of the per-persona shuffle of the optional activities for HOMER habits (HOMER stores no order)."""
DISTINCTNESS_SMOOTHING = 0.01
"""Added to every hourly value before normalising in `household_distinctness` (one person in a hundred), so
that a habit that is zero where another is not gives a large but finite divergence."""
_HOUSEHOLD_KEYS = ("description", "habits", "variants", "optional_order")


@dataclass(frozen=True)
class Household:
    """One fictitious household: habits (activity -> 18 hourly values), script variants and activity order.

    habits and variants hold every activity of ACTIVITIES; optional_order is a permutation of OPTIONAL.
    """

    name: str
    description: str
    habits: dict[str, tuple[float, ...]]
    variants: dict[str, int]
    optional_order: tuple[str, ...]

    def __post_init__(self) -> None:
        _check_names(self.name, "habits", self.habits)
        _check_names(self.name, "variants", self.variants)
        habits = {activity: tuple(float(value) for value in self.habits[activity]) for activity in ACTIVITIES}
        for activity, habit in habits.items():
            _check_hourly(f"household {self.name!r}: activity {activity!r}", habit)
        for activity in ACTIVITIES:
            variant = self.variants[activity]
            if isinstance(variant, bool) or not isinstance(variant, int | np.integer) or variant < 0:
                raise HabitError(f"household {self.name!r}: activity {activity!r}: variant must be a "
                                 f"non-negative integer, got {variant!r}")
        _check_order(self.name, tuple(self.optional_order))
        object.__setattr__(self, "habits", habits)
        object.__setattr__(self, "variants", {activity: int(self.variants[activity]) for activity in ACTIVITIES})
        object.__setattr__(self, "optional_order", tuple(self.optional_order))
        _check_outing(self.name, habits)

    @property
    def order(self) -> tuple[str, ...]:
        """The order the sampler walks: the five compulsory activities, then `optional_order`."""
        return COMPULSORY + self.optional_order

    def habit_matrix(self, activities: Iterable[str] = ACTIVITIES) -> np.ndarray:
        """Hourly values, shape (len(activities), 18), rows in the given order (default: ACTIVITIES)."""
        return np.array([self.habits[activity] for activity in activities], dtype=float)

    def expected_hour(self, activity: str) -> float | None:
        """Mean clock hour of the activity under its habit (slot midpoints, 6.5 .. 23.5); None if all zero."""
        return expected_hour(self.habits[activity])


def expected_hour(habit: Iterable[float]) -> float | None:
    """Mean clock hour of a habit (slot i counts as 6.5 + i); None for an all-zero habit."""
    values = np.asarray(tuple(habit), dtype=float)
    total = values.sum()
    if total <= 0.0:
        return None
    return float((values * (FIRST_HOUR + 0.5 + np.arange(values.size))).sum() / total)


def _check_names(household: str, what: str, mapping: Mapping[str, object]) -> None:
    for activity in mapping:
        if activity not in ACTIVITIES:
            raise HabitError(f"household {household!r}: {what}: {unknown_name('activity', activity, ACTIVITIES)}")
    missing = [activity for activity in ACTIVITIES if activity not in mapping]
    if missing:
        raise HabitError(f"household {household!r}: {what}: missing activities {', '.join(missing)}")


def _check_hourly(where: str, habit: tuple[float, ...]) -> None:
    """18 values in [0, 1]; `where` opens the error message."""
    if len(habit) != HOURS_PER_DAY:
        raise HabitError(f"{where}: habit has {len(habit)} values; expected {HOURS_PER_DAY} (one per hour 06:00-24:00)")
    for index, value in enumerate(habit):
        if not 0.0 <= value <= 1.0:  # also rejects NaN
            raise HabitError(f"{where}: value {value!r} at {FIRST_HOUR + index:02d}:00 is outside [0, 1]")


def _check_order(household: str, order: tuple[str, ...]) -> None:
    where = f"household {household!r}: optional_order"
    for activity in order:
        if activity not in OPTIONAL:
            hint = "it is compulsory (always first)" if activity in COMPULSORY else unknown_name(
                "optional activity", activity, OPTIONAL)
            raise HabitError(f"{where}: {activity!r} does not belong there: {hint}")
    repeated = sorted({activity for activity in order if order.count(activity) > 1})
    missing = [activity for activity in OPTIONAL if activity not in order]
    if repeated or missing:
        raise HabitError(f"{where}: must list each of the {len(OPTIONAL)} optional activities once; "
                         f"repeated: {', '.join(repeated) or 'none'}; missing: {', '.join(missing) or 'none'}")


def _check_outing(household: str, habits: Mapping[str, tuple[float, ...]]) -> None:
    """The paper's one dependency between habits: leave_home is expected before come_home."""
    leave, come = expected_hour(habits["leave_home"]), expected_hour(habits["come_home"])
    if leave is not None and come is not None and leave >= come:
        raise HabitError(f"household {household!r}: activity 'leave_home': expected hour {leave:.2f} is not "
                         f"before come_home's {come:.2f}")


def _read_json(path: Path) -> object:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise HabitError(f"{path}: file not found") from None
    except json.JSONDecodeError as error:
        raise HabitError(f"{path}: not valid JSON: {error}") from None


def _hourly(values: object, where: str) -> tuple[float, ...]:
    """A JSON list of numbers as floats (length and range are checked by Household)."""
    if not isinstance(values, list):
        raise HabitError(f"{where}: habit must be a list of {HOURS_PER_DAY} numbers, got {type(values).__name__}")
    for value in values:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise HabitError(f"{where}: habit value {value!r} is not a number")
    return tuple(float(value) for value in values)


def _parse_household(name: str, raw: object) -> Household:
    if not isinstance(raw, dict):
        raise HabitError(f"household {name!r}: expected an object with keys {', '.join(_HOUSEHOLD_KEYS)}")
    keys = set(raw)
    if keys != set(_HOUSEHOLD_KEYS):
        raise HabitError(f"household {name!r}: keys {sorted(keys)}; expected {', '.join(_HOUSEHOLD_KEYS)}")
    habits, variants, order = raw["habits"], raw["variants"], raw["optional_order"]
    if not isinstance(habits, dict) or not isinstance(variants, dict) or not isinstance(order, list):
        raise HabitError(f"household {name!r}: habits and variants must be objects, optional_order a list")
    parsed = {activity: _hourly(values, f"household {name!r}: activity {activity!r}")
              for activity, values in habits.items()}
    return Household(name, str(raw["description"]), parsed, dict(variants), tuple(order))


def load_households(path: str | Path | None = None) -> dict[str, Household]:
    """Households from a project habits file (default: the packaged `homer_sim/data/households.json`).

    Layout: {"households": {NAME: {"description": str, "habits": {ACTIVITY: [18 values]},
    "variants": {ACTIVITY: int}, "optional_order": [17 optional activities]}}} (other top-level keys are
    documentation). Raises HabitError naming the file, household, activity and the problem.
    """
    path = DEFAULT_PATH if path is None else Path(path)
    raw = _read_json(path)
    if not isinstance(raw, dict) or not isinstance(raw.get("households"), dict) or not raw["households"]:
        raise HabitError(f"{path}: expected an object with a non-empty 'households' object")
    households = {}
    for name, entry in raw["households"].items():
        try:
            households[name] = _parse_household(name, entry)
        except HabitError as error:
            raise HabitError(f"{path}: {error}") from None
    return households


def _homer_folder(path: str | Path) -> Path:
    path = Path(path)
    folder = path.parent if path.is_file() else path
    for name in HOMER_FILES:
        if not (folder / name).is_file():
            raise HabitError(f"{folder / name}: file not found (a HOMER habits folder holds {', '.join(HOMER_FILES)})")
    return folder


def _homer_clusters(path: Path) -> dict[str, list[tuple[float, ...]]]:
    raw = _read_json(path)
    if not isinstance(raw, dict):
        raise HabitError(f"{path}: expected an object activity -> list of clusters")
    clusters = {}
    for activity, entries in raw.items():
        if activity not in ACTIVITIES:
            raise HabitError(f"{path}: {unknown_name('activity', activity, ACTIVITIES)}")
        if not isinstance(entries, list) or not entries:
            raise HabitError(f"{path}: activity {activity!r}: expected a non-empty list of clusters")
        clusters[activity] = []
        for index, values in enumerate(entries):
            where = f"{path}: activity {activity!r}: cluster {index}"
            clusters[activity].append(_hourly(values, where))
            _check_hourly(where, clusters[activity][-1])
    return clusters


def _homer_habits(persona: str, choice: object, clusters: Mapping[str, list[tuple[float, ...]]],
                  path: Path) -> dict[str, tuple[float, ...]]:
    if not isinstance(choice, dict):
        raise HabitError(f"{path}: household {persona!r}: expected an object activity -> cluster index")
    habits = {activity: (0.0,) * HOURS_PER_DAY for activity in ACTIVITIES}
    for activity, index in choice.items():
        where = f"{path}: household {persona!r}: activity {activity!r}"
        if activity not in ACTIVITIES:
            raise HabitError(f"{path}: household {persona!r}: {unknown_name('activity', activity, ACTIVITIES)}")
        if activity not in clusters:
            raise HabitError(f"{where}: no clusters for it in {HOMER_FILES[0]}")
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(clusters[activity]):
            raise HabitError(f"{where}: cluster index {index!r} out of range; it has {len(clusters[activity])}")
        habits[activity] = clusters[activity][index]
    return habits


def load_homer_habits(path: str | Path) -> dict[str, Household]:
    """The original HOMER personas (persona0..4) as Households, for compatibility checks.

    path: a folder holding cluster_histograms.json and optimized_persona.json, or either file. Each activity's
    habit is the persona's chosen cluster histogram; activities the persona file omits get all-zero habits;
    variants are 0; the optional order is a fixed-seed shuffle of the alphabetically sorted optional activities.
    """
    folder = _homer_folder(path)
    clusters = _homer_clusters(folder / HOMER_FILES[0])
    persona_path = folder / HOMER_FILES[1]
    personas = _read_json(persona_path)
    if not isinstance(personas, dict) or not personas:
        raise HabitError(f"{persona_path}: expected a non-empty object household -> activity -> cluster index")
    households = {}
    for index, (persona, choice) in enumerate(personas.items()):
        habits = _homer_habits(persona, choice, clusters, persona_path)
        rng = np.random.default_rng([HOMER_ORDER_SEED, index])
        alphabetical = sorted(OPTIONAL)
        order = tuple(alphabetical[i] for i in rng.permutation(len(alphabetical)))
        try:
            households[persona] = Household(persona, f"HOMER optimized persona {persona!r} ({folder.name})",
                                            habits, dict.fromkeys(ACTIVITIES, 0), order)
        except HabitError as error:
            raise HabitError(f"{folder}: {error}") from None
    return households


def activity_time_distribution(household: Household, smoothing: float = DISTINCTNESS_SMOOTHING) -> np.ndarray:
    """The household's joint distribution over (activity, hour), shape (22, 18), summing to 1.

    Each hourly value plus `smoothing`, divided by the total; rows in ACTIVITIES order.
    """
    matrix = household.habit_matrix() + smoothing
    return matrix / matrix.sum()


def household_distinctness(households: Mapping[str, Household] | Iterable[Household],
                           smoothing: float = DISTINCTNESS_SMOOTHING) -> float:
    """Mean pairwise KL divergence (nats) between households' normalised activity-time distributions.

    The paper's fitness for choosing its five personas: the mean of KL(P_i || P_j) over all ordered pairs
    i != j, with P the joint (activity, hour) distribution of `activity_time_distribution`.
    """
    items = list(households.values()) if isinstance(households, Mapping) else list(households)
    if len(items) < 2:
        raise HabitError(f"household_distinctness needs at least two households, got {len(items)}")
    dists = [activity_time_distribution(household, smoothing) for household in items]
    divergences = [float(np.sum(p * np.log(p / q))) for i, p in enumerate(dists) for j, q in enumerate(dists)
                   if i != j]
    return float(np.mean(divergences))
