"""Where a person stands to reach something, and where an object can be put down.

Standing spots come from the floor plan (a free disk in front of the furniture, within reach). Free
placements are sampled on a place's rectangle, away from the footprints of objects already there, from
their current physical poses (never from the layout's declared ones).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property

import mujoco
import numpy as np

from homer_sim.errors import HomerError
from homer_sim.graph import INSIDE, ON
from homer_sim.home.catalog import CATALOG
from homer_sim.home.floorplan import floor_plan, inflate
from homer_sim.home.furniture import Place, footprint, furniture_geometry, local_to_world
from homer_sim.home.placement import SPOT_GAP, base_height, place_world, stored_yaw
from homer_sim.home.validate import base_pose_for

PERSON_RADIUS = 0.25  # m
_RAY_GROUPS = np.array([1, 1, 0, 0, 0, 0], dtype=np.uint8)  # furniture, objects and floors, not agents
PLACE_TRIES = 80
CONTAINER_KINDS = ("cabinet", "sink", "shower")  # furniture whose everyday use is putting things inside
DROP_LIFT = 0.004  # m above the surface an object is released


class PlacementError(HomerError):
    """No free spot for an object on the place asked for."""


@dataclass(frozen=True)
class Spot:
    """A target pose for an object: position (m) and yaw (rad), on `place` of `node` (None for a floor)."""

    pos: tuple[float, float, float]
    yaw: float
    node: str
    place: int | None


class Spots:
    """Standing spots and free placements in one World."""

    def __init__(self, world) -> None:
        self.world = world
        self.layout = world.layout
        self.furniture = self.layout.furniture_by_name()
        self.plan = floor_plan(self.layout)
        self.blocked = inflate(self.plan, PERSON_RADIUS)
        self.sizes = np.array([CATALOG[o.cls].size for o in self.layout.objects])
        self._standing: dict[str, tuple[float, float, float]] = {}
        self._geomid = np.zeros(1, dtype=np.int32)
        self.keep_out = _keep_out_rects(self.layout)
        self.standing_on = _standing_on(self.layout)

    # --- standing ---------------------------------------------------------------------------------------
    def standing_for(self, node: str) -> tuple[float, float, float]:
        """(x, y, yaw) where the person stands to use `node` (furniture, appliance or room)."""
        if node not in self._standing:
            self._standing[node] = self._find_standing(node)
        return self._standing[node]

    def _find_standing(self, node: str) -> tuple[float, float, float]:
        if node in self.furniture:
            f = self.furniture[node]
            if f.on is not None:
                return self.standing_for(f.on)
            geometry = furniture_geometry(f)
            rect = place_world(self.layout, f, geometry.places[0])["rect"] if geometry.places else _footprint_rect(f)
            pose = base_pose_for(self.layout, self.plan, f, rect, [])
            if pose is None:
                raise PlacementError(f"no place to stand in front of {node}")
            return pose
        room = next((r for r in self.layout.rooms if r.name == node), None)
        if room is None:
            raise PlacementError(f"{node!r} is neither furniture nor a room")
        return self.free_floor_near(((room.rect[0] + room.rect[2]) / 2, (room.rect[1] + room.rect[3]) / 2), room.name)

    def free_floor_near(self, xy: tuple[float, float], room: str) -> tuple[float, float, float]:
        """The free standing cell of `room` nearest to `xy` (spiral search), facing +x."""
        rect = next(r.rect for r in self.layout.rooms if r.name == room)
        free = ~self.blocked
        best, best_d = None, math.inf
        xs, ys = self.plan.cell_centers(0, free.shape[0], 0, free.shape[1])
        inside = (xs > rect[0]) & (xs < rect[2]) & (ys > rect[1]) & (ys < rect[3]) & free
        if inside.any():
            d = (xs - xy[0]) ** 2 + (ys - xy[1]) ** 2
            d[~inside] = math.inf
            k = np.unravel_index(np.argmin(d), d.shape)
            best, best_d = (float(xs[k]), float(ys[k])), d[k]
        if best is None or not math.isfinite(best_d):
            raise PlacementError(f"no free floor in {room}")
        return best[0], best[1], 0.0

    def neighbours(self, node: str) -> list[str]:
        """Other furniture of the same room with ON places, nearest first."""
        f = self.furniture[node]
        others = [o for o in self.layout.furniture if o.room == f.room and o.name != node
                  and any(p.relation == ON for p in self._places[o.name])]
        return [o.name for o in sorted(others, key=lambda o: math.dist(o.pos, f.pos))]

    def landing_z(self, name: str, xy: tuple[float, float], from_z: float) -> float:
        """Body z at which object `name` centred at xy rests on what lies below (rays over its footprint)."""
        model, data = self.world.model, self.world.data
        body = self.world.object_body_ids[self.world.object_index(name)]
        size = self.sizes[self.world.object_index(name)]
        highest = -math.inf
        for dx, dy in ((0, 0), (0.4, 0.4), (-0.4, 0.4), (0.4, -0.4), (-0.4, -0.4)):
            start = np.array([xy[0] + dx * size[0], xy[1] + dy * size[1], from_z])
            dist = mujoco.mj_ray(model, data, start, np.array([0.0, 0.0, -1.0]), _RAY_GROUPS, 1, body, self._geomid)
            if dist >= 0:
                highest = max(highest, from_z - dist)
        if not math.isfinite(highest):
            raise PlacementError(f"nothing below {np.round(xy, 2).tolist()} to put {name} on")
        return float(highest + size[2] / 2 + DROP_LIFT)

    # --- placements -------------------------------------------------------------------------------------
    @cached_property
    def _places(self) -> dict[str, list[Place]]:
        return {f.name: list(furniture_geometry(f).places) for f in self.layout.furniture}

    def places_of(self, node: str, relation: int | None) -> list[tuple[int, Place]]:
        """Places of furniture `node` with `relation`. None means as the furniture is used: inside what is
        built to hold things inside (cabinets, appliances with doors, sinks, showers), else on top."""
        places = list(enumerate(self._places.get(node, [])))
        if relation is None:
            first = INSIDE if self.furniture[node].kind in CONTAINER_KINDS else ON
            preferred = [(k, p) for k, p in places if p.relation == first]
            return preferred or places
        return [(k, p) for k, p in places if p.relation == relation]

    def footprints(self, exclude: set[int]) -> np.ndarray:
        """Shape (n_objects, 5): world (x0, y0, x1, y1, z_bottom) of every object, nan for excluded ones."""
        data = self.world.data
        bodies = self.world.object_body_ids
        rot = np.abs(data.xmat[bodies].reshape(-1, 3, 3))
        half = np.einsum("nij,nj->ni", rot, self.sizes / 2)
        pos = data.xpos[bodies]
        boxes = np.column_stack([pos[:, 0] - half[:, 0], pos[:, 1] - half[:, 1], pos[:, 0] + half[:, 0],
                                 pos[:, 1] + half[:, 1], pos[:, 2] - half[:, 2]])
        boxes[list(exclude)] = np.nan
        return boxes

    def free_spot(self, name: str, node: str, place_index: int, rng: np.random.Generator,
                  exclude: set[int]) -> Spot | None:
        """A random free spot for object `name` on a place of furniture `node` (drawers assumed open)."""
        return next(self.free_spots(name, node, place_index, rng, exclude), None)

    def free_spots(self, name: str, node: str, place_index: int, rng: np.random.Generator,
                   exclude: set[int], clear_of_furniture: bool = False) -> Iterator[Spot]:
        """Every free spot for object `name` on a place of furniture `node` (drawers assumed open): PLACE_TRIES
        random ones, then a scan on a 2 cm grid (so a crowded shelf with one gap left still finds it), then, for
        cloth, spots on top of what is there. With `clear_of_furniture`, none under furniture standing on the
        place (a coffee maker on a counter: the robot lowered a pill bottle onto it); the person's recorded days
        were made without, and their replays must choose as they did."""
        f = self.furniture[node]
        place = self._places[node][place_index]
        world_place = place_world(self.layout, f, place, opened=place.part is not None)
        cls = CATALOG[self.world.layout.objects[self.world.object_index(name)].cls]
        size = cls.size
        if size[2] > place.clearance - 0.005:
            return
        yaw = stored_yaw(f, place, cls)
        half_x, half_y = _rotated_half(size, yaw)
        x0, y0, x1, y1 = world_place["rect"]
        if x1 - x0 < 2 * half_x or y1 - y0 < 2 * half_y:
            return
        z = world_place["z"]
        boxes = self.footprints(exclude)
        if clear_of_furniture:
            boxes = np.vstack([boxes, self.standing_on.get(node, np.zeros((0, 5)))])
        near = boxes[(boxes[:, 4] > z - 0.05) & (boxes[:, 4] < z + place.clearance)]
        candidates = [(rng.uniform(x0 + half_x, x1 - half_x), rng.uniform(y0 + half_y, y1 - half_y))
                      for _ in range(PLACE_TRIES)]
        candidates += [(x, y) for x in np.arange(x0 + half_x, x1 - half_x + 1e-9, 0.02)
                       for y in np.arange(y0 + half_y, y1 - half_y + 1e-9, 0.02)]
        for x, y in candidates:
            if not _overlaps_any(near, (x - half_x, y - half_y, x + half_x, y + half_y)):
                yield Spot((float(x), float(y), z + size[2] / 2 + DROP_LIFT), yaw, node, place_index)
        if cls.family == "cloth":
            for x, y in candidates[:PLACE_TRIES]:  # soft things pile up: on top of what is there
                landing = self.landing_z(name, (x, y), z + place.clearance)
                if landing + size[2] / 2 <= z + place.clearance:
                    yield Spot((float(x), float(y), landing), yaw, node, place_index)

    def floor_spot(self, name: str, room: str, near: tuple[float, float], rng: np.random.Generator,
                   exclude: set[int]) -> Spot:
        """A free spot on the floor of `room` near `near` (m), away from furniture and other objects."""
        size = CATALOG[self.world.layout.objects[self.world.object_index(name)].cls].size
        boxes = self.footprints(exclude)
        boxes = boxes[boxes[:, 4] < 0.05]
        rect = next(r.rect for r in self.layout.rooms if r.name == room)
        radius = math.hypot(size[0], size[1]) / 2
        for attempt in range(PLACE_TRIES):
            spread = 0.4 + 0.05 * attempt
            x, y = near[0] + rng.uniform(-spread, spread), near[1] + rng.uniform(-spread, spread)
            inside = rect[0] + radius < x < rect[2] - radius and rect[1] + radius < y < rect[3] - radius
            if inside and self.plan.disk_is_free(x, y, radius + 0.02, self.keep_out) and not _overlaps_any(
                    boxes, (x - radius, y - radius, x + radius, y + radius)):
                return Spot((float(x), float(y), size[2] / 2 + DROP_LIFT), 0.0, room, None)
        raise PlacementError(f"no free floor for {name} in {room} near {np.round(near, 2).tolist()}")


def _keep_out_rects(layout) -> list[tuple[float, float, float, float]]:
    """World rectangles in front of doors and drawers (their swing and a person's room to use them), where
    nothing may be left on the floor."""

    rects = []
    for f in layout.furniture:
        parts = furniture_geometry(f).parts
        if not parts or f.on is not None:
            continue
        w, d, _ = f.size
        reach = max(w if p.joint == "hinge" else p.range[1] for p in parts) + 0.3
        corners = local_to_world(f, np.array([[d / 2, -w / 2 - 0.05, 0], [d / 2 + reach, w / 2 + 0.05, 0]]))
        rects.append((corners[:, 0].min(), corners[:, 1].min(), corners[:, 0].max(), corners[:, 1].max()))
    return rects


def _standing_on(layout) -> dict[str, np.ndarray]:
    """Per furniture, (x0, y0, x1, y1, z_bottom) rows of the furniture standing on it (a coffee maker on a
    counter): no free spot lies under them."""
    rows: dict[str, list] = {}
    for f in layout.furniture:
        if f.on is not None:
            rows.setdefault(f.on, []).append([*footprint(f), base_height(layout, f)])
    return {name: np.array(r, dtype=float) for name, r in rows.items()}


def _rotated_half(size, yaw: float) -> tuple[float, float]:
    c, s = abs(math.cos(yaw)), abs(math.sin(yaw))
    return (c * size[0] + s * size[1]) / 2, (s * size[0] + c * size[1]) / 2


def _overlaps_any(boxes: np.ndarray, rect: tuple[float, float, float, float]) -> bool:
    if len(boxes) == 0:
        return False
    g = SPOT_GAP
    hit = (boxes[:, 0] < rect[2] + g) & (rect[0] < boxes[:, 2] + g) & (boxes[:, 1] < rect[3] + g) & (
        rect[1] < boxes[:, 3] + g)
    return bool(np.any(hit))


def _footprint_rect(f) -> tuple[float, float, float, float]:

    return footprint(f)


__all__ = ["Spots", "Spot", "PlacementError", "PERSON_RADIUS", "base_height"]
