"""Quaternion order conversion: the one place where wxyz (MuJoCo) becomes xyzw (rerun).

MuJoCo stores quaternions scalar first (w, x, y, z); rerun expects scalar last (x, y, z, w). Convert here and
nowhere else, so a mixed order cannot creep in.
"""

from __future__ import annotations

import numpy as np

from homer_sim.errors import HomerError


class QuaternionShapeError(HomerError, ValueError):
    """An array that is not one quaternion (4,) or a stack of them (N, 4)."""


def wxyz_to_xyzw(q: np.ndarray) -> np.ndarray:
    """Reorder quaternions from scalar-first to scalar-last.

    q: Shape (4,) or (N, 4), (w, x, y, z) as MuJoCo stores them (`data.xquat`, `model.geom_quat`).
    Returns a new array of the same shape and dtype, (x, y, z, w).
    """
    return np.roll(_checked(q), -1, axis=-1)


def xyzw_to_wxyz(q: np.ndarray) -> np.ndarray:
    """The inverse of `wxyz_to_xyzw`. q: Shape (4,) or (N, 4), (x, y, z, w); returns (w, x, y, z)."""
    return np.roll(_checked(q), 1, axis=-1)


def _checked(q: np.ndarray) -> np.ndarray:
    q = np.asarray(q)
    if q.ndim not in (1, 2) or q.shape[-1] != 4:
        raise QuaternionShapeError(f"quaternions must have shape (4,) or (N, 4), got {q.shape}")
    return q
