"""Fixtures of the scenario tests."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def breakfast_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One fresh cache folder (HOMER_SIM_CACHE) for the breakfast morning's dataset and predictor, shared by the
    modules that run that morning on the same data: the first of them generates the days and trains, as on a new
    machine; the others find both cached, as a user's second run does (each generation and training took about
    two minutes of the default test pass)."""
    return tmp_path_factory.mktemp("breakfast_cache")
