"""What stands beside an object in the world: the footprints a grasp's palm must keep clear of. No physics."""

from __future__ import annotations

import numpy as np

from homer_sim.home.catalog import CATALOG
from planners.grasps.geometry import footprint

NEIGHBOUR_RADIUS = 0.4  # m between object centres beyond which a neighbour is not in a grasp's way
LEVEL_OVERLAP = 0.02  # m of common height above which two objects stand on the same level


def neighbour_footprints(world, name: str) -> list[tuple[np.ndarray, float]]:
    """(footprint, top z m) (world xy points, m, each shape (n, 2); see `planners.grasps.geometry.footprint`) of
    the objects within NEIGHBOUR_RADIUS of object `name` whose height range overlaps its own (they stand beside it
    on the same shelf or surface), as they stand now."""
    index = world.object_index(name)
    position = world.object_pose(name)[0]
    height = CATALOG[world.layout.objects[index].cls].size[2]
    low, high = position[2] - height / 2, position[2] + height / 2
    outlines = []
    for k, decl in enumerate(world.layout.objects):
        if k == index:
            continue
        other, quat = world.object_pose(decl.name)
        size = CATALOG[decl.cls].size
        if np.linalg.norm(other[:2] - position[:2]) > NEIGHBOUR_RADIUS:
            continue
        if min(high, other[2] + size[2] / 2) - max(low, other[2] - size[2] / 2) < LEVEL_OVERLAP:
            continue
        outlines.append((footprint(CATALOG[decl.cls], other, quat), float(other[2] + size[2] / 2)))
    return outlines


PASS_ABOVE = 0.015  # m a shelf's object drawn out (or carried in) passes over what stands in front of it
IN_LINE = 0.01  # m beside an object's outline within which a neighbour in front is in its way out


def rise_to_pass(world, name: str, position: np.ndarray, out: np.ndarray, front: float) -> float:
    """How far (m) object `name`, standing with its centre at `position` (m, shape (3,)), must rise above its
    support so that, drawn straight out along `out` (a horizontal unit vector, shape (2,) or (3,)) past the
    furniture's front plane `front` m out from it, its bottom passes PASS_ABOVE over every other object standing on
    the same support in front of it within its width (IN_LINE to spare); 0 where none stands there. Drawn out 3 cm
    off a dishwasher's rack, a wine glass took the cup standing in front of it along."""
    index = world.object_index(name)
    size = CATALOG[world.layout.objects[index].cls].size
    bottom = position[2] - size[2] / 2
    out = np.asarray(out, dtype=float)[:2]
    across = np.array([-out[1], out[0]])
    own = footprint(CATALOG[world.layout.objects[index].cls], position, world.object_pose(name)[1])
    half = float(np.max(np.abs((own - np.asarray(position[:2])) @ across))) + IN_LINE  # as it stands turned
    highest = -np.inf
    for k, decl in enumerate(world.layout.objects):
        if k == index:
            continue
        other, quat = world.object_pose(decl.name)
        other_size = CATALOG[decl.cls].size
        low, top = other[2] - other_size[2] / 2, other[2] + other_size[2] / 2
        if top <= bottom or low > bottom + LEVEL_OVERLAP:  # below the support, or on a level above
            continue
        rel = footprint(CATALOG[decl.cls], other, quat) - np.asarray(position[:2])
        ahead, beside = rel @ out, rel @ across
        if np.any((ahead > 0.0) & (ahead < front + IN_LINE) & (np.abs(beside) < half)) or (
                beside.min() < 0.0 < beside.max() and ahead.min() < front and ahead.max() > 0.0):
            highest = max(highest, top)
    return max(0.0, highest + PASS_ABOVE - bottom)


def tallest_beside(world, name: str, xy: np.ndarray, surface_z: float, radius: float) -> float:
    """The highest top (m) of the objects other than `name` standing on the surface at `surface_z` (m; their bottom
    within LEVEL_OVERLAP of it) or lower (on the furniture a cutting board lies on: the knife block beside the board
    was not counted for a vegetable going onto the board, and the carried vegetable was driven into it) with their
    centre within `radius` m of `xy` (m, world); `surface_z` where none does."""
    highest = surface_z
    for decl in world.layout.objects:
        if decl.name == name:
            continue
        other, _ = world.object_pose(decl.name)
        half = CATALOG[decl.cls].size[2] / 2
        if other[2] - half - surface_z < LEVEL_OVERLAP and np.linalg.norm(other[:2] - np.asarray(xy)[:2]) < radius:
            highest = max(highest, float(other[2] + half))
    return highest
