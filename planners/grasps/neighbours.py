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
