"""Fixtures shared by every test area: the repository's paths and one compiled apartment per session.

Compiling the apartment takes about a second; tests that only need the world as declared share one, reset to
its start layout before each test (`world`). Markers: `slow` for the long suites (opt in with `-m slow`) and
`physics` for tests that step a whole apartment for seconds or more (deselect with `-m "not physics"`).
MuJoCo renders offscreen (EGL) unless the caller chose another GL backend: set before mujoco is first imported.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

from pathlib import Path  # noqa: E402

import pytest  # noqa: E402

from homer_sim.world import World  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared"
"""Data beside the checkout that some tests compare against; they skip when it is absent."""


@pytest.fixture(scope="session")
def apartment() -> World:
    """The default apartment, compiled once for the session (no person, no robot)."""
    return World()


@pytest.fixture
def world(apartment: World) -> World:
    """The session's apartment back at its declared start layout, doors closed, time 0."""
    apartment.reset()
    return apartment


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """The shared data folder beside the checkout; skips the test when it is absent."""
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent")
    return SHARED
