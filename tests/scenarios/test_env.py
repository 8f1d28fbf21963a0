"""The assisted-day environment as dm_env: specs on every timestep, the episode lifecycle, and returns of three
policies on the breakfast morning up to 07:20 (the robot sets the table at 06:40, the person fetches at 07:00)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import dm_env
import numpy as np
import pytest

from homer_sim.errors import HomerError
from scenarios.env import MAX_RELOCATIONS, NO_RELOCATION, AssistEnv, make
from scenarios.episodes import Setup, make_setup
from scenarios.policies import EmptyPolicy, PsiPolicy, RandomPolicy, action_of
from scenarios.scoring import day_result

pytestmark = pytest.mark.physics  # steps a whole apartment for seconds or more

END_MIN = 440  # 07:20
TICKS = (END_MIN - 360) // 10 + 1  # snapshots 06:00 ... 07:20


@pytest.fixture(scope="module")
def setup(breakfast_cache: Path) -> Setup:
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("HOMER_SIM_CACHE", str(breakfast_cache))
        yield make_setup("breakfast", end_min=END_MIN, train_days=10, test_days=1)


def _episode(env: AssistEnv, policy) -> tuple[list[dm_env.TimeStep], float]:
    """Every timestep of one episode, checked against the specs as it goes, and the return."""
    steps = [env.reset()]
    while not steps[-1].last():
        steps.append(env.step(policy(steps[-1])))
    for timestep in steps:
        for name, spec in env.observation_spec().items():
            spec.validate(timestep.observation[name])
        assert set(timestep.observation) == set(env.observation_spec())
    return steps, float(sum(t.reward for t in steps[1:]))


def _result(setup: Setup, policy) -> dict:
    task = setup.env.task
    plans = getattr(policy, "plans", ())
    return day_result(task.log, task.reference, task.scene.nodes, task.scene.categories, plans, 30,
                      until=END_MIN)


def test_an_episode_is_one_day_with_specs_matched_at_every_timestep(setup: Setup) -> None:
    env = setup.env
    steps, total = _episode(env, EmptyPolicy(env.scene))
    kinds = [t.step_type for t in steps]
    assert kinds == [dm_env.StepType.FIRST] + [dm_env.StepType.MID] * (TICKS - 1) + [dm_env.StepType.LAST]
    assert steps[0].reward is None and steps[0].discount is None
    assert [float(t.observation["minute"]) for t in steps] == [360.0 + 10 * k for k in range(TICKS)] + [END_MIN]
    assert steps[-1].discount == 1.0  # cut at 07:20: a truncation, not the day's end
    assert total == 0.0 and env.task.log.relocations == []
    # The observation is what a robot perceives: the breakfast items start in the cupboard and the fridge.
    scene, obs = env.scene, steps[0].observation
    assert scene.nodes[obs["parent"][scene.index["milk"]]] == "fridge"
    assert obs["robot_holding"] == NO_RELOCATION and not obs["person_holding"].any()
    assert env.action_spec().shape == (MAX_RELOCATIONS, 2)
    assert env.step(action_of(scene, ())).first()  # a step after the last starts the next episode


def test_the_whole_day_ends_in_a_termination_and_names_are_checked(setup: Setup) -> None:
    env = setup.env
    morning = env.task.days
    env.task.days = tuple(replace(plan, end_min=None) for plan in morning)
    try:
        steps, total = _episode(env, EmptyPolicy(env.scene))
    finally:
        env.task.days = morning
    assert steps[-1].last() and steps[-1].discount == 0.0 and total == 0.0
    assert float(steps[-2].observation["minute"]) == 1440.0  # the last snapshot at midnight
    with pytest.raises(HomerError, match="breakfast"):
        make("brekfast")


def test_actions_name_movable_objects_and_places_the_robot_can_put_them_on(setup: Setup) -> None:
    env = setup.env
    env.reset()
    scene = env.scene
    bad = action_of(scene, ())
    bad[0] = (scene.index["cupboard"], scene.index["table_dining_room"])
    with pytest.raises(HomerError, match="cupboard is a furniture, not a movable object"):
        env.step(bad)
    bad[0] = (scene.index["milk"], scene.index["bowl"])
    with pytest.raises(HomerError, match="destination bowl is a object"):
        env.step(bad)


@pytest.fixture(scope="module")
def episodes(setup: Setup) -> dict:
    """A random and a Psi episode on the breakfast morning: their returns, results and Psi's timesteps."""
    env = setup.env
    _, random_return = _episode(env, RandomPolicy(env.scene, np.random.default_rng(0), rate=0.25))
    random_result = _result(setup, None)
    psi = PsiPolicy(env.scene, setup.predictor)
    steps, psi_return = _episode(env, psi)
    return {"random": (random_return, random_result), "psi": (psi_return, _result(setup, psi)), "steps": steps}


def test_psi_earns_more_than_a_random_or_an_empty_policy(setup: Setup, episodes: dict) -> None:
    (random_return, random_result), (psi_return, psi_result) = episodes["random"], episodes["psi"]
    for result, total in ((random_result, random_return), (psi_result, psi_return)):  # reward = the metric
        assert total == result["fetches_done_by_robot"] - result["relocations_wrong"], result
    print(f"returns on the breakfast morning to 07:20: psi {psi_return}, random {random_return}, empty 0")
    assert psi_return >= 3 and psi_return > random_return
    assert psi_result["relocations_done"] == psi_result["relocations_correct"] >= 3
    # the outcomes of what the robot was asked came back in the observation
    reported = np.concatenate([t.observation["outcomes"] for t in episodes["steps"]])
    assert (reported[:, 0] != NO_RELOCATION).sum() == psi_result["relocations_planned"]


def test_what_psi_set_out_is_seen_on_the_table_when_breakfast_starts(setup: Setup, episodes: dict) -> None:
    env = setup.env
    (_, start, _), = env.task.day.entries
    at_start = max((t for t in episodes["steps"] if t.observation["minute"] <= start),
                   key=lambda t: t.observation["minute"])
    assert all(env.scene.nodes[at_start.observation["parent"][env.scene.index[o]]] == "table_dining_room"
               for o in ("bowl", "milk", "food_cereal")), at_start.observation["minute"]


def test_a_rendered_image_of_the_apartment(setup: Setup, tmp_path: Path) -> None:
    image = setup.env.render(120, 160)
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8
    assert image.std() > 10  # not a blank frame: walls, floors and furniture differ in colour
