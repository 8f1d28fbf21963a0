"""`SkillResult`, what every skill of `planners.skills.Robot` returns."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SkillResult:
    """success, and when not, why (names the object, the place and the measured values)."""

    success: bool
    reason: str = ""
