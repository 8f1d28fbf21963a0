"""Helpers shared by the benchmark scripts: machine description, one-core pinning, summaries, JSON output.

Each benchmark prints exactly one JSON object on stdout; everything else goes to stderr through `logging`.
"""

from __future__ import annotations

import json
import logging
import os
import platform
import statistics
import sys
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from scenarios.cli.common import positive_int  # noqa: E402, F401 (the one argparse type; re-exported)

log = logging.getLogger("benchmarks")


def setup_logging() -> None:
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(asctime)s %(name)s: %(message)s")


def pin_to_one_core() -> int | None:
    """Pin this process to the lowest CPU it may run on (Linux only); returns that CPU or None."""
    if not hasattr(os, "sched_setaffinity"):
        return None
    cpu = min(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpu})
    return cpu


def machine_info(pinned_cpu: int | None) -> dict[str, Any]:
    """What the numbers were measured on."""
    return {
        "cpu_count": os.cpu_count(),
        "pinned_cpu": pinned_cpu,
        "platform": platform.platform(),
        "processor": platform.processor() or None,
        "machine": platform.machine(),
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "numpy": np.__version__,
    }


def summary(values: Sequence[float], digits: int = 4) -> dict[str, float]:
    """Median, min and max of a non-empty sequence, rounded to `digits` decimals."""
    assert len(values) > 0, "summary of no values"
    return {
        "median": round(statistics.median(values), digits),
        "min": round(min(values), digits),
        "max": round(max(values), digits),
    }


def emit(result: dict[str, Any]) -> None:
    """The benchmark's one line of stdout."""
    json.dump(result, sys.stdout, indent=2)
    sys.stdout.write("\n")
