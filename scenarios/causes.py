"""Why a relocation was not done, as a short cause: the rows of `homer assist-eval`'s failure table.

The robot's skills explain a failure in a sentence (`SkillResult.reason`); a cause groups those sentences by what
went wrong. The table is ordered: the first pattern found in the reason names the cause.
"""

from __future__ import annotations

SKILL_ERROR = "skill error"
"""How the assisted day words a skill that raised (a bug): the relocation fails with the exception named."""

CAUSE_PATTERNS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("in the person's hand", ("in the person's hand",)),
    ("not graspable", ("not graspable",)),
    ("container did not open", ("did not open",)),
    ("fell out of the hand", ("fell out of the hand",)),
    ("slipped in the hand", ("in the hand on the way",)),
    ("fell over on the destination", ("fell over on",)),
    ("ended elsewhere", (" ended ",)),
    ("no free spot at the destination", ("no free spot",)),
    ("no free base pose", ("no free base pose", "no checked base pose")),
    ("no path", ("no path",)),
    ("lies fallen over", ("has fallen over",)),
    ("out of the arm's reach", ("leaves the arm's reach",)),
    ("no grasp fits", ("no grasp fits",)),
    ("every grasp failed", ("every grasp",)),
    ("the person in the way", ("someone is in the way",)),
    ("knocked off later", ("knocked off",)),
    ("skill error", (SKILL_ERROR,)),
)
LASTING = ("lies fallen over",)
"""Causes in the object's own state where it lies: trying again before someone has moved it fails the same way."""
OTHER = "other"
CAUSES: tuple[str, ...] = (*(name for name, _ in CAUSE_PATTERNS), OTHER)
"""Every cause, in table order; an index into it is a cause code (never reorder: codes are in observations)."""


def cause_of(reason: str) -> str:
    """The cause of a failed relocation from the skill's `reason` (OTHER when no pattern matches)."""
    for name, patterns in CAUSE_PATTERNS:
        if any(p in reason for p in patterns):
            return name
    return OTHER
