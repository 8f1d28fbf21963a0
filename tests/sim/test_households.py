"""Households: the packaged habits file, the HOMER layout loader, distinctness and validation errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from homer_sim.person.households import (
    ACTIVITIES,
    COMPULSORY,
    DEFAULT_PATH,
    OPTIONAL,
    HabitError,
    Household,
    household_distinctness,
    load_homer_habits,
    load_households,
)

HOMER_FOLDER = Path(__file__).resolve().parents[3] / "shared" / "homer_reference" / "personaBasedSchedules"
# The paper's five optimised personas score 1.41 nats under the same metric (smoothing 0.01); our households
# were designed to be at least as distinct. 1.5 also sits far above near-copies (see the perturbation test).
MIN_DISTINCTNESS = 1.5
# Script variants the households may name (scripts module owns the real counts; 1 for unlisted activities).
TWO_VARIANTS = ("breakfast", "lunch", "dinner", "brushing_teeth", "showering", "getting_dressed", "computer_work",
                "watching_tv", "reading", "wash_dishes", "leave_home", "come_home")


@pytest.fixture(scope="module")
def households() -> dict[str, Household]:
    return load_households()


def test_activities_are_homers_22_compulsory_first() -> None:
    assert len(ACTIVITIES) == 22 and len(set(ACTIVITIES)) == 22
    assert ACTIVITIES[:5] == ("brushing_teeth", "showering", "breakfast", "dinner", "lunch") == COMPULSORY
    assert "vaccuum_cleaning" in OPTIONAL


def test_packaged_file_holds_five_complete_households(households: dict[str, Household]) -> None:
    assert DEFAULT_PATH.is_file()
    assert list(households) == [f"household_{letter}" for letter in "abcde"]
    for household in households.values():
        matrix = household.habit_matrix()
        assert matrix.shape == (22, 18)
        assert np.all((matrix >= 0.0) & (matrix <= 1.0))
        assert len(household.description) > 40
        assert household.order[:5] == COMPULSORY and sorted(household.order) == sorted(ACTIVITIES)


def test_distinctness_is_at_least_homers(households: dict[str, Household]) -> None:
    ours = household_distinctness(households)
    assert ours >= MIN_DISTINCTNESS
    if HOMER_FOLDER.is_dir():
        assert ours >= household_distinctness(load_homer_habits(HOMER_FOLDER))


def test_distinctness_is_zero_for_copies_and_small_for_near_copies(households: dict[str, Household]) -> None:
    first = households["household_a"]
    assert household_distinctness([first, first, first]) == pytest.approx(0.0, abs=1e-12)
    rng = np.random.default_rng(0)
    habits = {a: tuple(np.clip(np.array(v) + rng.uniform(-0.05, 0.05, 18) * (np.array(v) > 0), 0, 1))
              for a, v in first.habits.items()}
    near = Household("near", "a", habits, first.variants, first.optional_order)
    assert household_distinctness([first, near]) < 0.05 < MIN_DISTINCTNESS


def test_leave_home_is_expected_before_come_home(households: dict[str, Household]) -> None:
    for household in households.values():
        leave, come = household.expected_hour("leave_home"), household.expected_hour("come_home")
        assert leave is not None and come is not None, household.name
        assert leave < come, household.name


def test_variants_exist_and_differ_between_households(households: dict[str, Household]) -> None:
    vectors = set()
    for household in households.values():
        for activity, variant in household.variants.items():
            assert 0 <= variant < (2 if activity in TWO_VARIANTS else 1), (household.name, activity)
        vectors.add(tuple(household.variants[a] for a in TWO_VARIANTS))
    assert len(vectors) == len(households)
    for activity in TWO_VARIANTS:  # every two-variant activity is done both ways by someone
        assert {household.variants[activity] for household in households.values()} == {0, 1}, activity


def test_optional_orders_are_distinct_shuffles(households: dict[str, Household]) -> None:
    orders = {household.optional_order for household in households.values()}
    assert len(orders) == 5 and OPTIONAL not in orders


def test_homer_reference_personas_load() -> None:
    if not HOMER_FOLDER.is_dir():
        pytest.skip(f"HOMER reference data not present at {HOMER_FOLDER}")
    personas = load_homer_habits(HOMER_FOLDER)
    assert list(personas) == [f"persona{i}" for i in range(5)]
    clusters = json.loads((HOMER_FOLDER / "cluster_histograms.json").read_text())
    choice = json.loads((HOMER_FOLDER / "optimized_persona.json").read_text())
    for name, household in personas.items():
        for activity in ACTIVITIES:
            assert household.habits[activity] == tuple(clusters[activity][choice[name][activity]])
        assert set(household.variants.values()) == {0}
    same = load_homer_habits(HOMER_FOLDER / "optimized_persona.json")  # either file names its folder
    assert {n: h.optional_order for n, h in same.items()} == {n: h.optional_order for n, h in personas.items()}


def _homer_folder(tmp_path: Path, clusters: dict, personas: dict) -> Path:
    (tmp_path / "cluster_histograms.json").write_text(json.dumps(clusters))
    (tmp_path / "optimized_persona.json").write_text(json.dumps(personas))
    return tmp_path


def test_homer_layout_fills_missing_activities_with_zeros(tmp_path: Path) -> None:
    morning = [1.0] + [0.0] * 17
    folder = _homer_folder(tmp_path, {"breakfast": [morning, [0.0] * 18]}, {"p0": {"breakfast": 0}, "p1": {}})
    personas = load_homer_habits(folder / "cluster_histograms.json")
    assert personas["p0"].habits["breakfast"] == tuple(morning)
    assert personas["p1"].habit_matrix().sum() == 0.0
    assert personas["p0"].optional_order != personas["p1"].optional_order
    assert load_homer_habits(folder)["p0"].optional_order == personas["p0"].optional_order  # fixed seed


@pytest.mark.parametrize(("clusters", "personas", "expected"), [
    ({"breakfast": [[0.5] * 17]}, {}, "cluster_histograms.json: activity 'breakfast': cluster 0: habit has 17 values"),
    ({"lunch": [[0.0] * 18, [1.5] + [0.0] * 17]}, {},
     "cluster_histograms.json: activity 'lunch': cluster 1: value 1.5 at 06:00 is outside [0, 1]"),
    ({"vacuum_cleaning": [[0.0] * 18]}, {},
     "cluster_histograms.json: unknown activity 'vacuum_cleaning'; closest known: vaccuum_cleaning"),
    ({"breakfast": [[0.0] * 18]}, {"p0": {"breakfast": 3}},
     "optimized_persona.json: household 'p0': activity 'breakfast': cluster index 3 out of range; it has 1"),
    ({"breakfast": [[0.0] * 18]}, {"p0": {"lunch": 0}},
     "optimized_persona.json: household 'p0': activity 'lunch': no clusters for it"),
    ({"breakfast": [[0.0] * 18]}, {"p0": {"brekfast": 0}},
     "optimized_persona.json: household 'p0': unknown activity 'brekfast'; closest known: breakfast"),
])
def test_malformed_homer_files_name_the_problem(tmp_path: Path, clusters: dict, personas: dict,
                                                expected: str) -> None:
    folder = _homer_folder(tmp_path, clusters, personas)
    with pytest.raises(HabitError) as info:
        load_homer_habits(folder)
    assert str(info.value).startswith(str(folder))
    assert expected in str(info.value)


def test_missing_homer_file_is_named(tmp_path: Path) -> None:
    (tmp_path / "cluster_histograms.json").write_text("{}")
    with pytest.raises(HabitError, match="optimized_persona.json: file not found"):
        load_homer_habits(tmp_path)


def _write_edited(tmp_path: Path, edit) -> Path:
    raw = json.loads(DEFAULT_PATH.read_text())
    edit(raw["households"]["household_c"])
    path = tmp_path / "households.json"
    path.write_text(json.dumps(raw))
    return path


def _set(keys: tuple, value):
    def edit(household: dict) -> None:
        target = household
        for key in keys[:-1]:
            target = target[key]
        target[keys[-1]] = value
    return edit


@pytest.mark.parametrize(("edit", "expected"), [
    (_set(("habits", "dinner"), [0.2] * 19), "activity 'dinner': habit has 19 values; expected 18"),
    (_set(("habits", "reading"), [0.0] * 17 + [-0.1]), "activity 'reading': value -0.1 at 23:00 is outside [0, 1]"),
    (_set(("habits", "readnig"), [0.0] * 18), "unknown activity 'readnig'; closest known: reading"),
    (_set(("habits", "lunch"), "noon"), "activity 'lunch': habit must be a list of 18 numbers"),
    (_set(("habits", "lunch"), [None] * 18), "activity 'lunch': habit value None is not a number"),
    (_set(("variants", "dinner"), -1), "activity 'dinner': variant must be a non-negative integer"),
    (_set(("optional_order",), list(OPTIONAL[1:])), "missing: computer_work"),
    (_set(("optional_order",), ["breakfast", *OPTIONAL]), "'breakfast' does not belong there: it is compulsory"),
    (_set(("habits", "leave_home"), [0.0] * 17 + [1.0]), "'leave_home': expected hour 23.50 is not before"),
    (lambda household: household["habits"].pop("showering"), "habits: missing activities showering"),
])
def test_malformed_households_file_names_the_problem(tmp_path: Path, edit, expected: str) -> None:
    path = _write_edited(tmp_path, edit)
    with pytest.raises(HabitError) as info:
        load_households(path)
    message = str(info.value)
    assert message.startswith(f"{path}: household 'household_c'")
    assert expected in message


def test_unreadable_households_file(tmp_path: Path) -> None:
    with pytest.raises(HabitError, match="file not found"):
        load_households(tmp_path / "absent.json")
    (tmp_path / "bad.json").write_text("{\"households\": ")
    with pytest.raises(HabitError, match="bad.json: not valid JSON"):
        load_households(tmp_path / "bad.json")
