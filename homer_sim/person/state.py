"""`DayState`: how far the person's day has got, shared by the executor, which advances it, and the parts that act
for the person (`homer_sim.person.walking.Walker`, `homer_sim.person.handling.Handling`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from homer_sim.graph import SceneGraph


@dataclass
class DayState:
    """The routine minute (min since midnight), the day's random stream and the scene graph last observed (None
    before the day starts)."""

    minute: float
    rng: np.random.Generator
    graph: SceneGraph | None = None
