"""The robot's skills in physics: `Robot` (`robot`) and what each skill does: `pick`, `place`, opening and
closing doors and drawers (`doors`, with the part geometry in `parts`)."""

from planners.skills.robot import Robot, SkillResult

__all__ = ["Robot", "SkillResult"]
