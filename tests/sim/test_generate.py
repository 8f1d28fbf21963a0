"""Dataset generation: deterministic bytes, atomic days, retries that are logged, statistics, compatibility."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
import pytest

from homer_sim.data.dataset import Dataset, DatasetError, read_day
from homer_sim.data.generate import Generator, Sources, generate
from homer_sim.data.stats import dataset_stats
from homer_sim.days import DayKey
from homer_sim.errors import HomerError
from homer_sim.execution import Backend

pytestmark = pytest.mark.physics  # steps a whole apartment for seconds or more

REFERENCE = Path(__file__).resolve().parents[3] / "shared" / "homer_reference"


def _digest(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and p.name != "generation.log"}


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("data") / "one"
    generate(out, n_households=2, train_days=1, test_days=1, seed=7, progress=False)
    return out


def test_same_seed_same_bytes_whatever_the_workers(small: Path, tmp_path: Path) -> None:
    again = tmp_path / "two"
    generate(again, n_households=2, train_days=1, test_days=1, seed=7, backend=Backend(workers=2), progress=False)
    assert _digest(small) == _digest(again)
    assert len(_digest(small)) == 5  # meta.json and four days


def test_day_file_round_trips_and_is_a_valid_scene_graph_sequence(small: Path) -> None:
    data = Dataset(small)
    day = data.load("household_a", "train")[0]
    assert day.parent.dtype == np.int16 and day.parent.shape == (day.steps, len(data.meta.nodes))
    assert 80 <= day.steps <= 130 and day.minutes[0] == 360 and np.all(np.diff(day.minutes) == 10)
    for step in (0, day.steps // 2, day.steps - 1):
        day.graph(step, data.meta)  # validates the in-tree
    static = ~data.meta.movable_mask
    assert np.all(day.parent[:, static] == day.parent[0, static])  # furniture never moves
    activities = [a for a, _, _ in day.schedule]
    assert activities and all(s < e for _, s, e in day.schedule)
    assert any(m[1] for m in day.moves) and all(isinstance(m[0], float) for m in day.moves)
    copy = read_day(small / "household_a" / "train" / "day_000.npz")
    assert np.array_equal(copy.parent, day.parent) and copy.schedule == day.schedule


def test_corrupted_day_is_a_clear_error(small: Path, tmp_path: Path) -> None:
    broken = tmp_path / "day_000.npz"
    broken.write_bytes((small / "household_a" / "train" / "day_000.npz").read_bytes()[:200])
    with pytest.raises(DatasetError, match="corrupted"):
        read_day(broken)


def test_failed_attempt_is_retried_and_logged(tmp_path: Path, monkeypatch) -> None:
    from homer_sim.home.spots import PlacementError
    from homer_sim.person import executor as executor_module

    real_run_day = executor_module.Executor.run_day
    calls = {"n": 0}

    def flaky(self, entries, scripts, rng):
        calls["n"] += 1
        if calls["n"] == 1:
            raise PlacementError("no free spot for bowl on table_dining_room (injected)")
        return real_run_day(self, entries, scripts, rng)

    monkeypatch.setattr(executor_module.Executor, "run_day", flaky)
    out = tmp_path / "retry"
    generate(out, n_households=1, train_days=1, test_days=0, seed=3, progress=False)
    record = json.loads((out / "generation.log").read_text().splitlines()[0])
    assert record["attempts"] == 2 and "injected" in record["failures"][0]
    assert read_day(out / "household_a" / "train" / "day_000.npz").key == DayKey(3, 0, "train", 0, 1)


def test_a_folder_with_another_dataset_is_refused(small: Path) -> None:
    with pytest.raises(HomerError, match="other settings"):
        generate(small, n_households=2, train_days=1, test_days=1, seed=8, progress=False)


def test_interrupted_generation_resumes_without_rewriting(small: Path) -> None:
    before = _digest(small)
    summary = generate(small, n_households=2, train_days=1, test_days=1, seed=7, progress=False)
    assert summary["days_written"] == 0 and _digest(small) == before


def test_stats_follow_the_design_definitions(small: Path) -> None:
    stats = dataset_stats(small)
    assert set(stats["households"]) == {"household_a", "household_b"}
    for household in stats["households"].values():
        assert household["days"] == 2
        assert 80 <= household["steps_per_day"] <= 130
        assert 10 <= household["moves_per_day"] <= 80
        assert 5 <= household["objects_used"] <= 87
    assert stats["wall_s_per_day"] > 0


def test_unknown_household_habits_folder_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(HomerError):
        Generator(Sources(habits=str(tmp_path)))


@pytest.mark.skipif(not REFERENCE.is_dir(), reason="the HOMER reference folder is not beside the checkout")
def test_compat_check_runs_most_homer_scripts() -> None:
    from homer_sim.person.compat import compat_check

    result = compat_check(REFERENCE / "sourcedScriptsByActivity")
    assert result["scripts"] == len(list((REFERENCE / "sourcedScriptsByActivity").glob("*/*.txt")))
    assert result["executed"] >= 0.9 * result["scripts"], result["failures"]


DAY = """wake_up (06:00 - 06:10)
breakfast (08:05 - 08:{end})

### wake_up-00.txt

[WALK] <bedroom> (162) [1]
370.0
## Wakeup until 06:10

### breakfast-00a.txt

[WALK] <kitchen_counter> (119) [1]
485.0
[GRAB] <{what}> (1026) [2]
486.0
<<Graph Changes>>
   - bowl INSIDE cupboard
## Breakfast until 08:48
"""


def test_homer_plus_blocks_become_activity_scripts_once_each(tmp_path: Path) -> None:
    from homer_sim.person.compat import homer_plus_scripts

    days = (("scripts_train", "000", "48"), ("scripts_train", "001", "15"), ("scripts_test", "000", "30"))
    for split, day, end in days:
        (tmp_path / split).mkdir(exist_ok=True)
        (tmp_path / split / f"{day}.txt").write_text(DAY.format(end=end, what="bowl"))
    scripts = dict(homer_plus_scripts(tmp_path))
    assert sorted(scripts) == ["breakfast/00a.txt", "wake_up/00.txt"]
    assert scripts["breakfast/00a.txt"] == "## 10-43\n[WALK] <kitchen_counter> (119)\n[GRAB] <bowl> (1026)\n"
    assert scripts["wake_up/00.txt"] == "## 10-10\n[WALK] <bedroom> (162)\n"
    (tmp_path / "scripts_test" / "001.txt").write_text(DAY.format(end="30", what="plate"))
    with pytest.raises(HomerError, match="001.txt: block breakfast-00a.txt differs from its first occurrence"):
        homer_plus_scripts(tmp_path)
    with pytest.raises(HomerError, match="no HOMER\\+ day scripts"):
        homer_plus_scripts(tmp_path / "scripts_test" / "nowhere")


CACHE = Path(os.environ.get("HOMER_SIM_CACHE", Path.home() / ".cache" / "homer-sim"))
HOUSEHOLD_A = CACHE / "homer_plus" / "HouseholdA"


@pytest.mark.skipif(not (HOUSEHOLD_A / "scripts_train").is_dir(), reason="HOMER+ household A is not unpacked")
def test_compat_check_runs_most_activity_scripts_of_homer_plus() -> None:
    from homer_sim.person.compat import compat_check_texts, homer_plus_scripts

    result = compat_check_texts(homer_plus_scripts(HOUSEHOLD_A))
    assert result["scripts"] >= 30 and result["executed"] >= 0.9 * result["scripts"], result["failures"]


@pytest.mark.skipif(not REFERENCE.is_dir(), reason="the HOMER reference folder is not beside the checkout")
def test_generation_from_homer_habits_and_scripts(tmp_path: Path) -> None:
    out = tmp_path / "homer"
    sources = Sources(habits=str(REFERENCE / "personaBasedSchedules"),
                      scripts=str(REFERENCE / "sourcedScriptsByActivity"))
    generate(out, n_households=1, train_days=1, test_days=0, seed=0, sources=sources, progress=False)
    day = Dataset(out).load("persona0", "train")[0]
    assert day.steps >= 80 and len(day.schedule) > 3
