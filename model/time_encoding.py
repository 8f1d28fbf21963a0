"""Time codes of the routine clock: sin and cos at fixed periods (the paper's Time2Vec-like prior), or linear."""

from __future__ import annotations

import torch

from homer_sim.clock import MINUTES_PER_DAY
from homer_sim.errors import HomerError

PERIODS_MIN = (1440.0, 720.0, 360.0, 180.0, 60.0, 30.0, 10.0)  # 1 day, 12 h, 6 h, 3 h, 1 h, 30 min, 10 min
TIME_ENCODINGS = ("periodic", "linear")


class TimeEncodingError(HomerError):
    """An unknown kind of time encoding."""


def time_dim(kind: str) -> int:
    """Width of the time code: 2 per period for "periodic", 1 for "linear"."""
    if kind == "periodic":
        return 2 * len(PERIODS_MIN)
    if kind == "linear":
        return 1
    raise TimeEncodingError(f"unknown time encoding {kind!r}; known: {', '.join(TIME_ENCODINGS)}")


def encode_time(minute: torch.Tensor, kind: str = "periodic") -> torch.Tensor:
    """Code routine minutes (minutes since midnight).

    minute: Shape (B,), float, routine minutes of the target step.
    Returns: Shape (B, time_dim(kind)); periodic = [sin(2 pi t / P) for P in PERIODS_MIN] + [cos(...)],
    linear = [t / 1440] (the time as one number, in days).
    """
    minute = minute.to(torch.float32)
    if time_dim(kind) == 1:
        return (minute / MINUTES_PER_DAY)[:, None]
    periods = torch.tensor(PERIODS_MIN, dtype=torch.float32, device=minute.device)
    phase = 2.0 * torch.pi * minute[:, None] / periods[None, :]
    return torch.cat([torch.sin(phase), torch.cos(phase)], dim=1)
