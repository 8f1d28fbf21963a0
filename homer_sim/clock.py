"""The routine clock: minutes since midnight of the simulated day, and the 10-minute grid the world is observed on.

Days run from DAY_START_MIN (06:00) to DAY_END_MIN (24:00); a routine may run a little past midnight. The
habits of a household hold one value per hour of that span (HOURS_PER_DAY).
"""

from __future__ import annotations

MINUTES_PER_DAY = 1440
DAY_START_MIN = 360  # 06:00
DAY_END_MIN = 1440  # 24:00
GRID_MIN = 10  # the snapshot grid: the scene graph is read every 10 routine minutes
HOURS_PER_DAY = (DAY_END_MIN - DAY_START_MIN) // 60  # 18 hourly habit values, 06:00-24:00
DEFAULT_WINDOW_MIN = 30  # how far ahead the robot looks (the paper's headline window)


def clock_text(minute: float) -> str:
    """'HH:MM' of a routine minute (past midnight wraps: 1450 -> '00:10')."""
    whole = int(minute) % MINUTES_PER_DAY
    return f"{whole // 60:02d}:{whole % 60:02d}"
