"""Dataset statistics: counts of days, moves and objects per household (numpy and json only).

A move is a change of a movable object's parent between two consecutive grid steps; objects_used counts the
distinct objects with at least one move over all days of a household. Wall time comes from the generation
log, never from the data files.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from homer_sim.data.dataset import Dataset, Day

LOG_NAME = "generation.log"


def day_moves(day: Day, movable: np.ndarray) -> np.ndarray:
    """Shape (T - 1, N) bool: which movable nodes change parent between consecutive steps."""
    return (day.parent[1:] != day.parent[:-1]) & movable[None, :]


def household_stats(days: list[Day], movable: np.ndarray) -> dict:
    if not days:
        return {"days": 0, "steps_per_day": 0.0, "moves_per_day": 0.0, "objects_used": 0}
    used = np.zeros(len(movable), dtype=bool)
    moves = []
    for day in days:
        changed = day_moves(day, movable)
        moves.append(int(changed.sum()))
        used |= changed.any(axis=0)
    return {"days": len(days), "steps_per_day": float(np.mean([d.steps for d in days])),
            "moves_per_day": float(np.mean(moves)), "moves_per_day_range": [int(min(moves)), int(max(moves))],
            "objects_used": int(used.sum())}


def dataset_stats(root: str | Path) -> dict:
    dataset = Dataset(root)
    movable = dataset.meta.movable_mask
    households = {}
    for name in dataset.meta.households:
        days = dataset.load(name, "train") + dataset.load(name, "test")
        households[name] = household_stats(days, movable)
    return {"households": households, "wall_s_per_day": wall_seconds_per_day(Path(root))}


def wall_seconds_per_day(root: Path) -> float | None:
    """Mean wall seconds per generated day, from the generation log (None without a log)."""
    path = Path(root) / LOG_NAME
    if not path.exists():
        return None
    walls = [json.loads(line)["wall_s"] for line in path.read_text().splitlines() if line.strip()]
    return float(np.mean(walls)) if walls else None
