"""The `homer` command line: JSON shapes scripts rely on, exit codes, recordings."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from homer_sim.home.apartment import default_layout
from homer_sim.recording import read_recording
from scenarios.cli.main import main


def _json(capsys, argv: list[str]) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_world_info_json_shape(capsys) -> None:
    info = _json(capsys, ["world", "info", "--json"])
    assert {"name", "category", "movable"} <= set(info["nodes"][0])
    assert {a["joint_type"] for a in info["articulations"]} == {"hinge", "slide"}
    assert sum(n["movable"] for n in info["nodes"]) == len(default_layout().objects)


def test_world_check_writes_a_recording(capsys, tmp_path: Path) -> None:
    rrd = tmp_path / "apartment.rrd"
    result = _json(capsys, ["world", "check", "--rrd", str(rrd), "--seconds", "2", "--json"])
    assert result["warnings"] == 0 and result["graph_matches_layout"] and result["max_drift_m"] < 0.005
    entities = read_recording(rrd)
    assert {"graph/observed", "world/bodies/bowl", "world/bodies/fridge\\/door"} <= set(entities)  # "/" escaped


def test_simulate_day_records_the_person_and_the_graph(capsys, tmp_path: Path) -> None:
    rrd = tmp_path / "day.rrd"
    result = _json(capsys, ["simulate-day", "--household", "household_c", "--seed", "1", "--rrd", str(rrd),
                            "--json"])
    assert 80 <= result["steps"] <= 130 and result["grid_moves"] > 5 and result["schedule"]
    entities = read_recording(rrd)
    assert {"world/bodies/avatar", "world/person/path", "graph/observed", "events"} <= set(entities)
    assert rrd.stat().st_size < 50e6


def test_bad_input_exits_2_with_a_clear_message(capsys) -> None:
    assert main(["simulate-day", "--household", "household_z"]) == 2
    assert "household_a" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["generate", "--households", "5"])  # --out is required: argparse exits 2
