"""Grasp poses from an object's shape (no physics): widths, depths and directions checked in numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from homer_sim.catalog import CATALOG
from planners.grasps import PAD_HALF, SUPPORT_CLEARANCE, TOP_MARGIN, TOP_NARROW_MARGIN, top_grasps


def _yawed(angle_deg: float) -> np.ndarray:
    half = math.radians(angle_deg) / 2
    return np.array([math.cos(half), 0.0, 0.0, math.sin(half)])


def test_grasps_from_above_open_wide_then_narrow_and_stop_above_the_support() -> None:
    paste = CATALOG["tooth_paste"]  # 19 x 4.5 x 3.5 cm: only across its narrow side
    position = np.array([0.0, 0.0, paste.size[2] / 2])
    grasps = top_grasps(paste, position, _yawed(0.0), np.array([-1.0, 0.0]))
    assert [g.kind for g in grasps] == ["top", "top-narrow"]
    assert [g.pre_opening for g in grasps] == pytest.approx([paste.size[1] / 2 + TOP_MARGIN,
                                                             paste.size[1] / 2 + TOP_NARROW_MARGIN])
    tip_z = grasps[0].position[2] - PAD_HALF  # the hand points down: the fingertips are below the grip site
    assert tip_z == pytest.approx(SUPPORT_CLEARANCE)
