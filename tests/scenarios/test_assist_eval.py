"""`homer assist-eval` on a tiny dataset made here (1 household, 2 training days, 1 test day), up to 06:30: the
oracle sets the breakfast table at 06:00 for the person's 06:25 breakfast."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from homer_sim.data.generate import generate
from scenarios.cli.main import main
from scenarios.env import run_episode
from scenarios.episodes import make_setup
from scenarios.policies import EmptyPolicy
from scenarios.scoring import day_result

UNTIL = 390  # 06:30
KEYS = {"relocations_planned", "relocations_done", "relocations_correct", "relocations_wrong", "fetches",
        "fetches_done_by_robot", "fetch_share", "collateral", "days", "wall_s_per_day"}


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("tiny") / "data"
    generate(out, 1, 2, 1, seed=0, progress=False)
    return out


def test_the_oracle_day_adds_up_and_beats_an_empty_plan(data: Path, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "oracle"
    status = main(["assist-eval", "--data", str(data), "--method", "oracle", "--until", str(UNTIL), "--out", str(out),
                   "--quiet", "--json"])
    assert status == 0
    result = json.loads(capsys.readouterr().out)
    assert result["method"] == "oracle" and set(result["per_household"]) == {"household_a"}
    for row in (result["total"], result["per_household"]["household_a"]):
        assert KEYS <= set(row)
        not_done = row["relocations_planned"] - row["relocations_done"]
        assert not_done == sum(result["failures"].values()), result  # every relocation not done has a cause
        assert row["relocations_correct"] + row["relocations_wrong"] == row["relocations_done"]
    total = result["total"]
    assert total["days"] == 1 and total["fetches"] >= 4
    assert total["fetches_done_by_robot"] >= 2, result  # the oracle set out breakfast before the person came
    assert {p.name for p in out.iterdir()} >= {"assist_eval.json", "assist_eval.md", "assist_eval.png", "days"}
    assert "| household_a |" in (out / "assist_eval.md").read_text()

    # The same day with nothing asked of the robot: no fetch made ahead, nothing moved.
    setup = make_setup("dataset_day", data=str(data), household="household_a", end_min=UNTIL)
    assert run_episode(setup.env, EmptyPolicy(setup.env.scene)) == 0.0
    task = setup.env.task
    empty = day_result(task.log, task.reference, task.scene.nodes, task.scene.categories, (), 30)
    assert empty["fetches"] == total["fetches"] and empty["fetches_done_by_robot"] == 0
    day = json.loads((out / "days" / "household_a_000.json").read_text())
    assert day["return"] == total["fetches_done_by_robot"] - total["relocations_wrong"] > 0


def test_unknown_households_are_named_with_the_known_ones(data: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["assist-eval", "--data", str(data), "--households", "household_z", "--method", "oracle",
                 "--quiet"]) == 2
    assert "household_a" in capsys.readouterr().err
