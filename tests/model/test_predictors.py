"""Every method behind the one interface: shapes, masking, checkpoints; baselines checked by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from homer_sim.data.dataset import Dataset, DatasetMeta, Day
from homer_sim.errors import HomerError
from model.baselines import FreMEn, FreMEnPrior, StaticSemantic
from model.markov import TimedMarkov
from model.methods import METHODS, load_predictor, make_predictor, save_predictor
from model.predictor import candidate_mask, one_hot_parents
from model.synthetic import write_synthetic_dataset

TINY = DatasetMeta(("kitchen", "table", "shelf", "cup"), ("room", "furniture", "furniture", "object"),
                   (False, False, False, True), ("h",))
MINUTES = np.arange(360, 1440, 10)


def _tiny_day(cup: np.ndarray, index: int = 0) -> Day:
    """A day of TINY with the cup's parent per grid step (1 table, 2 shelf)."""
    parent = np.stack([np.full(len(MINUTES), -1), np.zeros(len(MINUTES)), np.zeros(len(MINUTES)), cup], axis=1)
    return Day("h", "train", index, MINUTES, parent.astype(np.int16), np.ones_like(parent, dtype=np.int8))


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Dataset:
    root = tmp_path_factory.mktemp("small")
    write_synthetic_dataset(root, np.random.default_rng(1), households=1, train_days=6, test_days=1, size="small")
    return Dataset(root)


@pytest.fixture(scope="module")
def fitted(small: Dataset) -> dict:
    days = small.load("household_a", "train")
    out = {}
    for method in METHODS:
        config = {"max_epochs": 1} if method.startswith("gnn") else {}
        predictor = make_predictor(method, small.meta, progress=False, **config)
        predictor.fit(days[:5], days[5:])
        out[method] = predictor
    return out


@pytest.mark.parametrize("method", METHODS)
def test_probabilities_sum_to_one_over_candidates_and_static_rows_stay(method: str, small: Dataset,
                                                                       fitted: dict) -> None:
    predictor, day = fitted[method], small.load("household_a", "test")[0]
    movable = small.meta.movable_mask
    probs = one_hot_parents(day.parent[[0, 40, 80]], len(movable))
    for _ in range(3):  # feed the probabilities back, as a rollout does
        probs = predictor.step(probs, np.array([600.0, 1000.0, 1400.0]))
        assert probs.shape == (3, len(movable), len(movable))
        np.testing.assert_allclose(probs[:, movable].sum(-1), 1.0, atol=1e-5)
        assert np.all(probs[:, ~candidate_mask(movable)][:, movable[np.nonzero(~candidate_mask(movable))[0]]] == 0)
        assert np.all(probs[:, np.arange(len(movable)), np.arange(len(movable))] == 0)
        np.testing.assert_array_equal(probs[:, ~movable], one_hot_parents(day.parent[[0, 40, 80]], len(movable))[
            :, ~movable])
    rollout = predictor.rollout(day.parent[:20], day.minutes[:20], 4)
    assert rollout.parent.shape == rollout.confidence.shape == (4, 20, len(movable))
    assert np.all(rollout.parent[:, :, ~movable] == day.parent[:20][None, :, ~movable])


@pytest.mark.parametrize("method", METHODS)
def test_checkpoint_round_trip_gives_identical_predictions(method: str, small: Dataset, fitted: dict,
                                                           tmp_path: Path) -> None:
    predictor, day = fitted[method], small.load("household_a", "test")[0]
    predictor.set_params(threshold=0.3)
    path = save_predictor(tmp_path / f"{method}.pt", predictor, {"household": "household_a"})
    loaded, info = load_predictor(path, small.meta, progress=False)
    assert info == {"household": "household_a"} and loaded.params == predictor.params
    assert type(loaded) is type(predictor) and loaded.method == method
    before, after = predictor.rollout(day.parent, day.minutes, 3), loaded.rollout(day.parent, day.minutes, 3)
    np.testing.assert_array_equal(before.parent, after.parent)
    np.testing.assert_array_equal(before.confidence, after.confidence)


def test_checkpoint_for_other_nodes_is_refused(small: Dataset, fitted: dict, tmp_path: Path) -> None:
    path = save_predictor(tmp_path / "s.pt", fitted["static_semantic"])
    with pytest.raises(HomerError, match="nodes differ"):
        load_predictor(path, TINY)
    with pytest.raises(HomerError, match="no such checkpoint"):
        load_predictor(tmp_path / "missing.pt")


def test_unknown_method_names_the_known_ones() -> None:
    with pytest.raises(HomerError, match="unknown method 'fremn'.*fremen"):
        make_predictor("fremn", TINY)
    with pytest.raises(HomerError, match="no parameter 'p'.*p_change"):
        StaticSemantic(TINY, p=0.3)


def test_static_semantic_step_worked_by_hand() -> None:
    # Training: the cup spends 3/4 of the steps on the shelf, 1/4 on the table (the room: never).
    cup = np.where(np.arange(len(MINUTES)) % 4 == 0, 1, 2)
    model = StaticSemantic(TINY, p_change=0.4)
    model.fit([_tiny_day(cup)], [])
    np.testing.assert_allclose(model.prior[0, :3], [0.0, 0.25, 0.75], atol=1e-5)
    probs = model.step(one_hot_parents(np.array([[-1, 0, 0, 1]]), 4), np.array([600.0]))  # cup seen on the table
    # prior * ((1 - p) * A + p / 3): table 0.25 * (0.6 + 0.4 / 3), shelf 0.75 * 0.4 / 3, room ~0 -> normalised
    table, shelf = 0.25 * (0.6 + 0.4 / 3), 0.75 * 0.4 / 3
    np.testing.assert_allclose(probs[0, 3, :3], [0.0, table / (table + shelf), shelf / (table + shelf)], atol=1e-5)


def test_fremen_recovers_a_planted_24_hour_period() -> None:
    # P(cup on the table) = 0.5 + 0.5 cos(2 pi (t - 15:00) / 24 h), sampled every grid step of 20 days.
    rng = np.random.default_rng(0)
    p_table = 0.5 + 0.5 * np.cos(2 * np.pi * (MINUTES - 900) / 1440)
    days = [_tiny_day(np.where(rng.random(len(MINUTES)) < p_table, 1, 2), i) for i in range(20)]
    model = FreMEnPrior(TINY, order=1)
    model.fit(days, [])
    amplitude = np.abs(model.spectrum[0, 1])  # the (cup, table) pair, periods of one day / k, k = 1 ..
    assert int(np.argmax(amplitude)) == 0  # k = 1: the 24-hour period
    peak_min = (-np.angle(model.spectrum[0, 1, 0]) * 1440 / (2 * np.pi)) % 1440
    assert abs(peak_min - 900) < 60
    prior = model.prior_at(np.array([900.0, 400.0]))
    assert prior[0, 0, 1] > 0.85 and prior[1, 0, 1] < 0.6


def test_fremen_blends_observation_into_prior_with_exponential_decay() -> None:
    cup = np.where((MINUTES >= 720) & (MINUTES < 1080), 1, 2)  # on the table 12:00-18:00 every day
    model = FreMEn(TINY, order=0, tau_min=20.0)  # order 0: the prior is the mean occupancy
    model.fit([_tiny_day(cup)], [])
    mean_table = float(np.mean(cup == 1))
    rollout = model.rollout(np.array([[-1, 0, 0, 1]]), np.array([600.0]), 3)  # seen on the table at 10:00
    for s in range(3):
        weight = np.exp(-10.0 * (s + 1) / 20.0)
        table = mean_table + (1 - mean_table) * weight  # prior + (observed - prior) * exp(-dt / tau)
        expected = (1, table) if table >= 0.5 else (2, 1 - table)
        assert rollout.parent[s, 0, 3] == expected[0]
        assert rollout.confidence[s, 0, 3] == pytest.approx(expected[1], abs=1e-4)


def test_markov_learns_a_timed_transition() -> None:
    cup = np.where(MINUTES >= 720, 1, 2)  # shelf -> table at 12:00 every day
    model = TimedMarkov(TINY, sigma_min=10.0, stay_prior=0.25)
    model.fit([_tiny_day(cup, i) for i in range(3)], [])
    rollout = model.rollout(np.array([[-1, 0, 0, 2], [-1, 0, 0, 2]]), np.array([690.0, 540.0]), 3)
    assert rollout.parent[:, 0, 3].tolist() == [2, 2, 1]  # moves at the 12:00 step, not before
    assert rollout.parent[:, 1, 3].tolist() == [2, 2, 2]  # nothing happens around 09:00
    # At 12:00: 3 moves against the kernel-weighted stays of 11:50 and before (3 * (e^-0.5 + e^-2 + ...)) + 0.25.
    assert 0.5 < rollout.confidence[2, 0, 3] < 0.8
