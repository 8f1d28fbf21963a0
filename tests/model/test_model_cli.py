"""`homer train` / `homer evaluate` through the registered subcommands, and the synthetic dataset generator."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from homer_sim.data.dataset import Dataset
from homer_sim.graph import validate_in_tree
from homer_sim.home.apartment import default_layout
from model.synthetic import make_apartment, write_synthetic_dataset
from scenarios.cli.model import add_commands


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="homer")
    add_commands(parser.add_subparsers(dest="command", required=True))
    return parser


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("data")
    write_synthetic_dataset(root, np.random.default_rng(3), households=2, train_days=5, test_days=1, size="small")
    return root


def _run(argv: list[str], capsys: pytest.CaptureFixture) -> dict:
    args = _parser().parse_args(argv)
    assert args.func(args) == 0
    return json.loads(capsys.readouterr().out)


def test_evaluate_prints_the_documented_json_and_reuses_checkpoints(data: Path, tmp_path: Path,
                                                                      capsys: pytest.CaptureFixture) -> None:
    argv = ["evaluate", "--data", str(data), "--methods", "last_seen,static_semantic", "--window", "30",
            "--checkpoints", str(tmp_path), "--quiet", "--json"]
    result = _run(argv, capsys)
    assert result["window_min"] == 30 and set(result["methods"]) == {"last_seen", "static_semantic"}
    for row in result["methods"].values():
        assert set(row["used"]) == {"correct", "wrong", "missed"} and set(row["unused"]) == {"correct", "wrong"}
        assert sum(row["used"].values()) == pytest.approx(100.0, abs=0.01)  # rounded to 3 decimals
        assert sum(row["unused"].values()) == pytest.approx(100.0, abs=0.01)  # rounded to 3 decimals
    assert result["methods"]["last_seen"]["used"]["missed"] == 100.0
    cached = sorted(tmp_path.rglob("*.pt"))
    assert len(cached) == 4  # 2 households x 2 methods
    stamps = [p.stat().st_mtime_ns for p in cached]
    assert _run(argv, capsys) == result
    assert [p.stat().st_mtime_ns for p in cached] == stamps  # loaded, not refitted


def test_train_writes_a_checkpoint_and_refuses_to_overwrite(data: Path, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "markov.pt"
    argv = ["train", "--data", str(data), "--household", "household_a", "--method", "markov", "--out", str(out),
            "--quiet", "--json"]
    result = _run(argv, capsys)
    # markov is cross-validated: fitted on all 5 training days, each of them held out in turn for tuning
    assert out.is_file() and result["method"] == "markov" and result["fit_days"] == 5 and result["val_days"] == 0
    assert result["cross_validation_days"] == 5
    assert set(result["params"]) == {"threshold", "act_steps", "sigma_min", "stay_prior"}
    args = _parser().parse_args(argv)
    with pytest.raises(Exception, match="--overwrite"):
        args.func(args)


def test_unknown_method_is_rejected_with_the_known_names(capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit):
        _parser().parse_args(["evaluate", "--data", "x", "--methods", "gnn,fremn"])
    assert "fremn" in capsys.readouterr().err


def test_bad_window_names_the_value(data: Path) -> None:
    args = _parser().parse_args(["evaluate", "--data", str(data), "--methods", "last_seen", "--window", "25",
                                 "--quiet"])
    with pytest.raises(Exception, match="25 min"):
        args.func(args)


def test_synthetic_apartment_has_the_real_size_and_valid_days(tmp_path: Path) -> None:
    apartment = make_apartment("real")
    layout = default_layout()
    assert set(apartment.nodes) == set(layout.node_names()) and sum(apartment.movable) == len(layout.objects)
    meta = write_synthetic_dataset(tmp_path, np.random.default_rng(0), households=1, train_days=3, test_days=1)
    days = Dataset(tmp_path).load(meta.households[0], "train")
    for day in days:
        assert day.steps == 108 and day.minutes[0] == 360 and day.minutes[-1] == 1430
        for parent, relation in zip(day.parent, day.relation, strict=True):
            validate_in_tree(meta.nodes, meta.categories, parent.astype(np.int32), relation)
        moves = int(np.sum(day.parent[1:] != day.parent[:-1]))
        assert 10 <= moves <= 80
        assert np.all(day.parent[:, ~meta.movable_mask] == day.parent[0, ~meta.movable_mask])


def test_synthetic_dataset_is_deterministic(tmp_path: Path) -> None:
    for name in ("a", "b"):
        write_synthetic_dataset(tmp_path / name, np.random.default_rng(7), households=1, train_days=2, test_days=1,
                                size="small")
    files = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*.npz"))
    assert files
    for rel in files:
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes()


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
