"""A day's identity is a value: replaying a dataset day from its stored key gives the same day, in any household."""

from __future__ import annotations

import numpy as np
import pytest

from homer_sim.days import DayKey
from scenarios.breakfast_data import DataSpec, ensure_dataset, make_generator

pytestmark = pytest.mark.physics  # steps a whole apartment for seconds or more


@pytest.fixture(scope="module")
def household_b_day(tmp_path_factory: pytest.TempPathFactory):
    """One test day of household_b (index 1 among the project's households), made as the day scenarios make it."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("HOMER_SIM_CACHE", str(tmp_path_factory.mktemp("cache")))
        generator = make_generator()
        dataset, _ = ensure_dataset(generator, DataSpec(train_days=0, test_days=1, household="household_b"))
        yield generator, dataset.load("household_b", "test")[0]


def test_a_dataset_day_remembers_the_key_it_was_simulated_from(household_b_day) -> None:
    _, day = household_b_day
    assert day.replay_key() == DayKey(0, 1, "test", 0, day.key.attempt)


def test_replaying_a_day_of_another_household_than_the_first_gives_the_same_day(household_b_day) -> None:
    generator, day = household_b_day
    replayed = generator.replay("household_b", day.replay_key(), [tuple(e) for e in day.schedule])
    assert np.array_equal(np.array(replayed.parents), day.parent)
    assert [tuple(m) for m in replayed.moves] == [tuple(m) for m in day.moves]
    # the scenarios used to replay every household's days with household index 0: another physics stream
    wrong = DayKey(0, 0, "test", 0, day.key.attempt)
    elsewhere = generator.replay("household_b", wrong, [tuple(e) for e in day.schedule])
    assert [tuple(m) for m in elsewhere.moves] != [tuple(m) for m in day.moves]
