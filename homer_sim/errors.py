"""The one root exception of homer-sim and its kinds.

Messages name the bad value and, where there is a closed set, the valid ones.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class HomerError(Exception):
    """Root of every error homer-sim raises on purpose."""


class LayoutError(HomerError):
    """A declarative layout is inconsistent or violates the robot's envelope."""


class UnknownNameError(HomerError, KeyError):
    """A name (node, object class, articulation, ...) that does not exist."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


def unknown_name(kind: str, name: str, known: Iterable[str], limit: int = 5) -> UnknownNameError:
    """An error for an unknown `name` of `kind`, listing the closest known names."""
    known = sorted(known)
    close = difflib.get_close_matches(name, known, n=limit, cutoff=0.5)
    hint = ", ".join(close) if close else ", ".join(known[:limit]) + (", ..." if len(known) > limit else "")
    return UnknownNameError(f"unknown {kind} {name!r}; closest known: {hint}")


class PhysicsError(HomerError):
    """The simulation reached a state it cannot continue from (an object left the apartment, NaN)."""


class HabitError(HomerError):
    """Household habits that are malformed (wrong length, out of range, unknown activity)."""
