"""Test-wide setup: MuJoCo renders offscreen (EGL) unless the caller chose a GL backend; it must be set before
mujoco is first imported."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
