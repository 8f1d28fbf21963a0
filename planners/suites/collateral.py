"""Collateral: objects a robot skill moved that it was not asked to move. Both suites count a trial whose
other objects moved more than MAX_DISPLACEMENT as a failure."""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

MAX_DISPLACEMENT = 0.02  # m any object other than the moved one may end from where it was


def displaced(world, before: np.ndarray, skip: Collection[str] = ()) -> list[tuple[str, float]]:
    """(object name, distance m) of every object but those in `skip` now more than MAX_DISPLACEMENT from its
    position in `before` (`world.object_positions()`, shape (n_objects, 3)), farthest first."""
    moved = np.linalg.norm(world.object_positions() - before, axis=1)
    found = [(name, float(d)) for name, d in zip(world.object_names, moved, strict=True)
             if d > MAX_DISPLACEMENT and name not in skip]
    return sorted(found, key=lambda item: -item[1])


def collateral_reason(found: list[tuple[str, float]]) -> str:
    """The failure reason for displaced objects `found` (see `displaced`), naming the farthest three."""
    names = ", ".join(f"{name} {d * 100:.1f} cm" for name, d in found[:3])
    return f"collateral: moved {names}" + (f" and {len(found) - 3} more" if len(found) > 3 else "")
