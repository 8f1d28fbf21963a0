"""Where a person stands to reach something, and where an object can be put down.

Standing spots come from the floor plan (a free disk in front of the furniture, within reach). Free
placements are sampled on a place's rectangle, away from the footprints of objects already there, from
their current physical poses (never from the layout's declared ones).
"""

from __future__ import annotations

import itertools
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
from homer_sim.home.shapes import cavity
from homer_sim.home.validate import base_pose_for

PERSON_RADIUS = 0.25  # m
_RAY_GROUPS = np.array([1, 1, 0, 0, 0, 0], dtype=np.uint8)  # furniture, objects and floors, not agents
PLACE_TRIES = 80
CONTAINER_KINDS = ("cabinet", "sink", "shower")  # furniture whose everyday use is putting things inside
DROP_LIFT = 0.004  # m above the surface an object is released
LIES_AS_IT_LANDS = ("cloth", "sphere")  # families with no up: dropped into a container, they go in as they fall


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
        self.keep_out = keep_out_rects(self.layout)

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

    def landing_in(self, name: str, target: str, xy: tuple[float, float], from_z: float) -> float:
        """Body z at which object `name` centred at xy rests on or in object `target` (see `landing_z`), but no
        lower than across the rim of a container unless it fits through the opening lying flat at every yaw (its
        half-diagonal within the rim's radius; things that lie as they land, cloth and balls, go in as they fall).
        Put in at the height of the mail at the bottom of a bin, a newspaper was set right into the bin's walls, and
        the contacts pushed it through the bin's floor or knocked the bin over (which then crept on, 6-10 cm while
        the robot only stood by)."""
        z = self.landing_z(name, xy, from_z)
        cls = self.world.object_class(name)
        holder = self.world.object_class(target)
        opening = cavity(holder)
        if opening is None or cls.family in LIES_AS_IT_LANDS or math.hypot(*cls.size[:2]) / 2 <= opening.rim_radius:
            return z
        rim = float(self.world.object_pose(target)[0][2]) + opening.rim_z
        return max(z, rim + cls.size[2] / 2 + DROP_LIFT)

    # --- placements -------------------------------------------------------------------------------------
    @cached_property
    def _places(self) -> dict[str, list[Place]]:
        return {f.name: list(furniture_geometry(f).places) for f in self.layout.furniture}

    def places_of(self, node: str, relation: int | None) -> list[tuple[int, Place]]:
        """Places of furniture `node` with `relation`. None means as the furniture is used: inside what is
        built to hold things inside (cabinets, appliances with doors, sinks, showers), else on top. Empty for
        a node without fixed places (a room: its floor is searched for a free spot instead)."""
        places = list(enumerate(self._places.get(node, [])))
        if relation is None and places:
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
                  exclude: set[int], packed: bool = False) -> Spot | None:
        """A random free spot for object `name` on a place of furniture `node` (drawers assumed open); with
        `packed`, the first in packing order (see `free_spots`)."""
        return next(self.free_spots(name, node, place_index, rng, exclude, packed), None)

    def free_spots(self, name: str, node: str, place_index: int, rng: np.random.Generator,
                   exclude: set[int], packed: bool = False) -> Iterator[Spot]:
        """Every free spot for object `name` on a place of furniture `node` (drawers assumed open): PLACE_TRIES
        random ones, then a scan on a 2 cm grid (so a crowded shelf with one gap left still finds it), then, for
        cloth, spots on top of what is there. With `packed`, the grid alone, row by row from the front, each
        from one end (in a cabinet from the middle out), as the start layout packs
        (`homer_sim.home.placement.pack_spot`): set down against what is there, a thing leaves the free room in
        one piece for the next (a pot set down in the middle of the stove left no room for the frying pan beside
        it). On a place with open ends an object longer than the place is wide lies across it, its middle on the
        place's middle line, where its ends are clear of walls and furniture."""
        f = self.furniture[node]
        place = self._places[node][place_index]
        world_place = place_world(self.layout, f, place, opened=place.part is not None)
        cls = self.world.object_class(name)
        size = cls.size
        if size[2] > place.clearance - 0.005:
            return
        yaw = stored_yaw(f, place, cls)
        half_x, half_y = _rotated_half(size, yaw)
        x0, y0, x1, y1 = world_place["rect"]
        across = place.open_ends and size[1] <= 2 * place.half_xy[0] and 2 * place.half_xy[1] < size[0]
        if not across and (x1 - x0 < 2 * half_x or y1 - y0 < 2 * half_y):
            return
        z = world_place["z"]
        boxes = self.footprints(exclude)
        near = boxes[(boxes[:, 4] > z - 0.05) & (boxes[:, 4] < z + place.clearance)]
        standing = [(*footprint(o), z) for o in self.layout.furniture if o.on == node]
        if standing and place.center[2] >= f.size[2] - 1e-6:  # its top: an appliance standing there is in the way
            near = np.vstack([near, standing])
        xs = (x0 + half_x, x1 - half_x) if x1 - x0 >= 2 * half_x else ((x0 + x1) / 2,) * 2  # across: its middle
        ys = (y0 + half_y, y1 - half_y) if y1 - y0 >= 2 * half_y else ((y0 + y1) / 2,) * 2
        drawn = [(rng.uniform(*xs), rng.uniform(*ys)) for _ in range(PLACE_TRIES)]
        if packed:
            # in a cabinet from the middle out, as its start layout: where a hand reaches past the door and the walls
            candidates = _packing_order(f, near, xs, ys, half_x, half_y, place.center[1] if f.kind == "cabinet"
                                        else None)
        else:
            grid = ((x, y) for x in np.arange(xs[0], xs[1] + 1e-9, 0.02) for y in np.arange(ys[0], ys[1] + 1e-9, 0.02))
            candidates = itertools.chain(drawn, grid)  # the grid made only as far as it is tried
        for x, y in candidates:
            rect = (x - half_x, y - half_y, x + half_x, y + half_y)
            if across and not self._ends_clear(rect, footprint(f)):
                continue
            if not _overlaps_any(near, rect):
                yield Spot((float(x), float(y), z + size[2] / 2 + DROP_LIFT), yaw, node, place_index)
        if cls.family == "cloth":
            for x, y in drawn:  # soft things pile up: on top of what is there
                landing = self.landing_z(name, (x, y), z + place.clearance)
                if landing + size[2] / 2 <= z + place.clearance:
                    yield Spot((float(x), float(y), landing), yaw, node, place_index)

    def _ends_clear(self, rect: tuple[float, float, float, float], under: tuple[float, float, float, float]) -> bool:
        """Whether the parts of world rectangle `rect` beyond the furniture footprint `under` are clear of walls
        and other furniture (by the floor plan: whatever their height)."""
        ends = [(rect[0], rect[1], under[0], rect[3]), (under[2], rect[1], rect[2], rect[3]),
                (rect[0], rect[1], rect[2], under[1]), (rect[0], under[3], rect[2], rect[3])]
        return all(self.plan.rect_is_free(end, shrink=0.0) for end in ends if end[2] > end[0] and end[3] > end[1])

    def floor_spot(self, name: str, room: str, near: tuple[float, float], rng: np.random.Generator,
                   exclude: set[int], blocked: np.ndarray | None = None) -> Spot:
        """A free spot on the floor of `room` near `near` (m), away from furniture, other objects and the cells of
        `blocked` (a grid of the floor plan's shape: where a robot stands)."""
        size = self.world.object_class(name).size
        boxes = self.footprints(exclude)
        boxes = boxes[boxes[:, 4] < 0.05]
        rect = next(r.rect for r in self.layout.rooms if r.name == room)
        radius = math.hypot(size[0], size[1]) / 2
        for attempt in range(PLACE_TRIES):
            spread = 0.4 + 0.05 * attempt
            x, y = near[0] + rng.uniform(-spread, spread), near[1] + rng.uniform(-spread, spread)
            inside = rect[0] + radius < x < rect[2] - radius and rect[1] + radius < y < rect[3] - radius
            if inside and self.plan.disk_is_free(x, y, radius + 0.02, self.keep_out, blocked) and not _overlaps_any(
                    boxes, (x - radius, y - radius, x + radius, y + radius)):
                return Spot((float(x), float(y), size[2] / 2 + DROP_LIFT), 0.0, room, None)
        raise PlacementError(f"no free floor for {name} in {room} near {np.round(near, 2).tolist()}")


def keep_out_rects(layout) -> list[tuple[float, float, float, float]]:
    """World rectangles in front of doors and drawers (their swing and a person's room to use them), where
    nothing may be left on the floor."""
    return [rect for f in layout.furniture if (rect := keep_out_rect(f)) is not None]


def keep_out_rect(f) -> tuple[float, float, float, float] | None:
    """The world rectangle (x0, y0, x1, y1, m) in front of furniture `f`'s doors and drawers (their swing and a
    person's room to use them), None for furniture without any (or standing on other furniture)."""
    parts = furniture_geometry(f).parts
    if not parts or f.on is not None:
        return None
    w, d, _ = f.size
    reach = max(w if p.joint == "hinge" else p.range[1] for p in parts) + 0.3
    corners = local_to_world(f, np.array([[d / 2, -w / 2 - 0.05, 0], [d / 2 + reach, w / 2 + 0.05, 0]]))
    return corners[:, 0].min(), corners[:, 1].min(), corners[:, 0].max(), corners[:, 1].max()


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


def _packing_order(f, near: np.ndarray, xs: tuple[float, float], ys: tuple[float, float], half_x: float,
                   half_y: float, centre: float | None = None) -> list[tuple[float, float]]:
    """The free points of the 2 cm grid over xs x ys (world, m) for a footprint of half sizes half_x, half_y, in
    packing order: in the frame of furniture `f` (x out of its front, y along its width), the front row first,
    each from -y, or from the middle out if `centre` (its y there) is given, as
    `homer_sim.home.placement.pack_spot` packs. `near`: footprints in the way (nan: none)."""
    gx, gy = np.meshgrid(np.arange(xs[0], xs[1] + 1e-9, 0.02), np.arange(ys[0], ys[1] + 1e-9, 0.02), indexing="ij")
    gx, gy = gx.ravel(), gy.ravel()
    c, s = math.cos(f.yaw), math.sin(f.yaw)
    depth = np.round(c * (gx - f.pos[0]) + s * (gy - f.pos[1]), 3)
    width = np.round(-s * (gx - f.pos[0]) + c * (gy - f.pos[1]), 3)
    g = SPOT_GAP
    if len(near):
        hit = ((near[None, :, 0] < gx[:, None] + half_x + g) & (gx[:, None] - half_x < near[None, :, 2] + g)
               & (near[None, :, 1] < gy[:, None] + half_y + g) & (gy[:, None] - half_y < near[None, :, 3] + g))
        free = ~hit.any(axis=1)
    else:
        free = np.ones(len(gx), dtype=bool)
    order = np.lexsort((width, -depth) if centre is None else (width, np.round(np.abs(width - centre), 3), -depth))
    order = order[free[order]]
    return list(zip(gx[order].tolist(), gy[order].tolist(), strict=True))


def _footprint_rect(f) -> tuple[float, float, float, float]:

    return footprint(f)


__all__ = ["Spots", "Spot", "PlacementError", "PERSON_RADIUS", "base_height", "keep_out_rect", "keep_out_rects"]
