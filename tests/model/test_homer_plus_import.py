"""`homer import homer-plus` on a slice of the authors' HOMER+ data: two days pulled from the shared archive.

Skipped when the shared data (`../shared/homer_plus` beside the repository, or $HOMER_SIM_SHARED/homer_plus) is
absent. Nothing is unpacked outside pytest's tmp_path.
"""

from __future__ import annotations

import json
import os
import tarfile
from pathlib import Path

import numpy as np
import pytest
import torch

from homer_sim.data.dataset import Dataset, DatasetError
from homer_sim.data.homer_plus import import_household
from scenarios.cli.main import main

SHARED = Path(os.environ.get("HOMER_SIM_SHARED", Path(__file__).resolve().parents[3] / "shared")) / "homer_plus"
ARCHIVE = SHARED / "HouseholdA.tar.gz"
UPSTREAM = "HouseholdA/processed_seqLM_coarse"
MEMBERS = (f"{UPSTREAM}/common_data.json", f"{UPSTREAM}/train/003.pt", f"{UPSTREAM}/test/000.pt")

pytestmark = pytest.mark.skipif(not ARCHIVE.is_file(), reason=f"HOMER+ data not found at {SHARED}")


@pytest.fixture()
def household(tmp_path: Path) -> Path:
    """HouseholdA with one training and one test day, unpacked from the shared archive into tmp_path."""
    with tarfile.open(ARCHIVE) as archive:
        for member in MEMBERS:
            archive.extract(member, tmp_path / "upstream", filter="data")
    return tmp_path / "upstream" / "HouseholdA"


def test_import_keeps_split_names_movability_and_every_parent(household: Path, tmp_path: Path,
                                                               capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "data"
    assert main(["import", "homer-plus", str(household), "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["train_days"] == 1 and summary["test_days"] == 1 and summary["nodes"] == 92
    dataset = Dataset(out)
    meta = dataset.meta
    assert meta.households == ("HouseholdA",) and len(set(meta.nodes)) == len(meta.nodes) == 92
    assert {"kitchen_counter_119", "kitchen_counter_122", "kitchen_counter_123"} <= set(meta.nodes)
    assert "home" not in meta.nodes and meta.grid_min == 10
    movable = dict(zip(meta.nodes, meta.movable, strict=True))
    assert not movable["bedroom"] and not movable["fridge"] and not movable["mat"]  # room, static, static decor
    assert movable["mug"] and movable["knifeblock"] and sum(meta.movable) == 61
    assert dataset.day_indices("HouseholdA", "train") == [3] and dataset.day_indices("HouseholdA", "test") == [0]
    day = dataset.load("HouseholdA", "test")[0]
    raw = torch.load(household / "processed_seqLM_coarse" / "test" / "000.pt", weights_only=True)
    upstream = raw["edges"].argmax(-1).numpy()  # (109, 93) upstream parent index
    ids = json.loads((household / "processed_seqLM_coarse" / "common_data.json").read_text())["node_ids"]
    ours = {name: i for i, name in enumerate(meta.nodes)}
    mug, fridge = ids.index(1148), ids.index(1006)
    assert day.steps == 109 and day.minutes[0] == 360 and day.minutes[-1] == 1440
    assert [meta.nodes[p] if p >= 0 else "home" for p in day.parent[:, ours["mug"]]] == \
        [ids_name(ids, meta, p) for p in upstream[:, mug]]
    assert np.all(day.parent[:, ours["bedroom"]] == -1) and upstream[0, fridge] != upstream[0, mug]
    assert len(day.moves) == int((upstream[1:] != upstream[:-1]).sum()) > 0
    assert day.schedule[0][0] == "wake_up" and day.schedule[0][1] == 360.0


def ids_name(ids: list[int], meta: object, upstream_index: int) -> str:
    """Our name of an upstream node index, via its VirtualHome id."""
    vh = ids[upstream_index]
    return "home" if vh == -1 else meta.nodes[meta.extra["virtualhome_ids"].index(vh)]


def test_bad_inputs_name_the_file_and_leave_nothing_behind(household: Path, tmp_path: Path) -> None:
    out = tmp_path / "data"
    with pytest.raises(DatasetError, match=r"not a HOMER\+ household"):
        import_household(tmp_path, out)
    day = household / "processed_seqLM_coarse" / "train" / "003.pt"
    day.write_bytes(day.read_bytes()[:5000])  # truncated
    with pytest.raises(DatasetError, match=r"003\.pt: corrupted or truncated"):
        import_household(household, out)
    assert not out.exists()
    blob = torch.load(household / "processed_seqLM_coarse" / "test" / "000.pt", weights_only=True)
    torch.save({**blob, "edges": blob["edges"][:, :90, :90]}, day)  # wrong shape
    with pytest.raises(DatasetError, match=r"003\.pt: edges \(109, 90, 90\)"):
        import_household(household, out)
    assert not out.exists()
    torch.save(blob, day)
    import_household(household, out)
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    with pytest.raises(DatasetError, match="already holds household 'HouseholdA'"):
        import_household(household, out)
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
