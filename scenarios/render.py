"""Camera images of the apartment, headless: MuJoCo's renderer on an offscreen GL context.

Set MUJOCO_GL=egl (or osmesa) before mujoco is first imported; without a display the default (glfw) fails.
"""

from __future__ import annotations

import mujoco
import numpy as np

from homer_sim.errors import HomerError


def render_world(world, height: int, width: int, azimuth: float, elevation: float, distance: float) -> np.ndarray:
    """An RGB image, Shape (height, width, 3) uint8, of `world` now, from a free camera aimed at the centre of the
    apartment's bodies (`azimuth`, `elevation` in degrees, `distance` in m)."""
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.lookat[:] = world.model.stat.center
    camera.azimuth, camera.elevation, camera.distance = azimuth, elevation, distance
    try:
        renderer = mujoco.Renderer(world.model, height, width)
    except Exception as error:  # mujoco raises plain exceptions for a missing GL context
        raise HomerError(f"no offscreen GL context ({error}); set MUJOCO_GL=egl or MUJOCO_GL=osmesa") from error
    try:
        renderer.update_scene(world.data, camera)
        return renderer.render().copy()
    finally:
        renderer.close()
