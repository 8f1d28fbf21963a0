"""A corrupted or hostile checkpoint gives a clear ModelError (a HomerError), never an unpickling traceback."""

from __future__ import annotations

import os
import pickle
from pathlib import Path

import pytest
import torch

from homer_sim.errors import HomerError
from model.methods import load_predictor

MARKER = "hostile_checkpoint_ran"


class Hostile:
    """Unpickling this object would call os.system (weights-only loading must refuse to)."""

    def __reduce__(self) -> tuple:
        return os.system, (f"touch {MARKER}",)


def test_a_hostile_checkpoint_is_refused_without_running_its_code(tmp_path: Path,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "hostile.pt"
    torch.save({"format": 1, "payload": Hostile()}, path)
    with pytest.raises(HomerError, match=r"hostile\.pt: not a readable checkpoint.*UnpicklingError"):
        load_predictor(path)
    assert not (tmp_path / MARKER).exists()


@pytest.mark.parametrize("content", [b"not a checkpoint at all", pickle.dumps([1, 2, 3])[:5]])
def test_a_corrupted_checkpoint_is_a_clear_error(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "broken.pt"
    path.write_bytes(content)
    with pytest.raises(HomerError, match=r"broken\.pt: not a readable checkpoint"):
        load_predictor(path)


def test_a_truncated_checkpoint_is_a_clear_error(tmp_path: Path) -> None:
    path = tmp_path / "cut.pt"
    torch.save({"format": 1, "arrays": {"w": torch.zeros(1000)}}, path)
    path.write_bytes(path.read_bytes()[:600])
    with pytest.raises(HomerError, match=r"cut\.pt: not a readable checkpoint"):
        load_predictor(path)
