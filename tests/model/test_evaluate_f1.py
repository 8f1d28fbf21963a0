"""`homer evaluate --metric f1|both`: the documented JSON keys, household averaging, and tuning reuse."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from model.synthetic import write_synthetic_dataset
from scenarios.cli.model import add_commands as register


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("data")
    write_synthetic_dataset(root, np.random.default_rng(3), households=2, train_days=5, test_days=1, size="small")
    return root


def _run(argv: list[str], capsys: pytest.CaptureFixture) -> dict:
    parser = argparse.ArgumentParser(prog="homer")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    assert args.func(args) == 0
    return json.loads(capsys.readouterr().out)


def test_f1_keys_are_household_means_of_the_per_household_results(data: Path, tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture) -> None:
    argv = ["evaluate", "--data", str(data), "--methods", "last_seen,markov", "--metric", "both",
            "--checkpoints", str(tmp_path), "--quiet", "--json"]
    result = _run(argv, capsys)
    houses = result["households"]
    for name in ("last_seen", "markov"):
        f1 = result["methods"][name]["f1"]
        assert len(f1["per_step"]) == 6 and "used" in result["methods"][name]
        rows = [result["per_household"][h][name]["f1"] for h in houses]
        assert f1["mean"] == pytest.approx(np.mean([r["mean"] for r in rows]), abs=1e-4)
        assert f1["per_step"] == pytest.approx(np.mean([r["per_step"] for r in rows], axis=0), abs=1e-4)
        assert f1["tp"] == sum(r["tp"] for r in rows) and f1["fn"] == sum(r["fn"] for r in rows)
        for row in rows:
            assert row["mean"] == pytest.approx(np.mean(row["per_step"]), abs=1e-4)
    last = result["methods"]["last_seen"]["f1"]
    assert last["tp"] == 0 and last["fp"] == 0 and last["fn"] > 0 and last["mean"] == 0.0
    assert result["methods"]["markov"]["f1"]["tp"] > 0
    # Both tunings are kept in the one checkpoint per fit: a second run loads them and refits nothing.
    cached = sorted(tmp_path.rglob("*.pt"))
    stamps = [p.stat().st_mtime_ns for p in cached]
    only_f1 = _run([a if a != "both" else "f1" for a in argv], capsys)
    assert [p.stat().st_mtime_ns for p in cached] == stamps
    assert only_f1["methods"]["markov"] == {"f1": result["methods"]["markov"]["f1"], "per_household":
                                            only_f1["methods"]["markov"]["per_household"]}
    assert "used" not in only_f1["methods"]["markov"]
