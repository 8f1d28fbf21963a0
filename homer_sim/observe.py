"""Scene graphs read from physics only: support contacts and downward rays give ON, interior volumes INSIDE.

Never from the layout: the observer looks at `MjData` (body poses, contacts, rays against geoms, interior
volume sites) and names what it finds with the node that owns each geom or site. The one exception is where
furniture stands, which never changes: furniture is fused into the world body (only its doors and drawers have
bodies; see `homer_sim.home.build`), so it has no body pose to read. It keeps the graph incrementally:
`update()` re-observes only bodies that moved since they were last observed and have come to rest, so sleeping
bodies cost one vectorised pose comparison.
"""

from __future__ import annotations

from collections.abc import Collection

import mujoco
import numpy as np

from homer_sim.errors import PhysicsError
from homer_sim.graph import INSIDE, NONE, ON, SceneGraph
from homer_sim.home.build import FLOOR_GROUP, VOLUME_GROUP
from homer_sim.home.catalog import CATALOG
from homer_sim.home.placement import base_height
from homer_sim.home.shapes import cavity
from homer_sim.world import World

SUPPORT_TOL = 0.02  # m: a support surface may lie this far below an object's lowest point
RAY_LIFT = 0.005  # m above an object's lowest point where its downward rays start
BASE_RAY_LIFT = 0.01  # m above a furniture piece's base where its downward ray starts
PAST_OWN = 1e-6  # m past a geom of the furniture itself where its ray starts again
NO_BODY = -1  # mj_ray's bodyexclude for "exclude nothing"; 0 would exclude the floors, walls and fused furniture
MOVED_DISTANCE = 1e-3  # m
MOVED_COS_HALF_ANGLE = np.cos(np.deg2rad(0.5) / 2)  # |q1 . q2| below this: rotated more than 0.5 degree
VOLUME_TOL = 0.01  # m of slack around interior volumes
CONTAINER_FAMILIES = ("bin", "pot")  # objects that hold others INSIDE rather than ON
CAVITY_HEADROOM = 0.05  # m above a bin's rim that still counts as in it (a heap)
_RAY_GROUPS = np.array([1, 1, 0, 0, 0, 0], dtype=np.uint8)  # furniture, objects, floors; not agents (group 2)
_FLOOR_GROUPS = np.array([int(g == FLOOR_GROUP) for g in range(6)], dtype=np.uint8)
# Fractions of the half extents where downward rays start: the centre, and near the rim and corners, so an
# object bridging a cavity (a spoon across a bowl) still finds what holds it.
_RAY_OFFSETS = np.array([[0, 0], [0.35, 0.35], [-0.35, 0.35], [0.35, -0.35], [-0.35, -0.35],
                         [0.9, 0], [-0.9, 0], [0, 0.9], [0, -0.9]])
_DOWN = np.array([0.0, 0.0, -1.0])


class SceneGraphObserver:
    """Observes the scene graph of a World; `graph` is the latest observation."""

    def __init__(self, world: World) -> None:
        self.world = world
        model = world.model
        self.nodes = world.layout.node_names()
        self.categories = world.declared_graph().categories
        index = {name: i for i, name in enumerate(self.nodes)}
        roots = model.body_rootid
        body_node = np.array([index.get(model.body(int(roots[b])).name.split("/")[0], -1) for b in range(model.nbody)])
        # A geom belongs to the node its root body's name begins with (an object; a door or drawer, as
        # "<furniture>/<part>"); one on the world body (floors, furniture) to the node its name begins with, and
        # walls ("wall/<k>") to none.
        self.geom_node = np.array([index.get(model.geom(g).name.split("/")[0], -1) if model.geom_bodyid[g] == 0
                                   else body_node[model.geom_bodyid[g]] for g in range(model.ngeom)])
        self.movable = np.array([index[n] for n in world.object_names], dtype=np.int32)
        self.movable_bodies = world.object_body_ids
        self.half_extents = np.array([np.array(CATALOG[o.cls].size) / 2 for o in world.layout.objects])
        colliding = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
        self.object_geoms = [np.flatnonzero((model.geom_bodyid == b) & colliding) for b in self.movable_bodies]
        holds_inside = {i for i, o in zip(self.movable, world.layout.objects, strict=True)
                        if CATALOG[o.cls].family in CONTAINER_FAMILIES}
        self.holds_inside = np.array([i in holds_inside for i in range(len(self.nodes))])
        self.supports = np.zeros(len(self.nodes), dtype=bool)
        self.supports[[i for i, o in zip(self.movable, world.layout.objects, strict=True)
                       if CATALOG[o.cls].supports]] = True
        self.cavities = [(k, cavity(CATALOG[o.cls])) for k, o in enumerate(world.layout.objects)
                         if CATALOG[o.cls].family in CONTAINER_FAMILIES]
        self.is_room = np.array([c == "room" for c in self.categories])
        volume_sites = [s for s in range(model.nsite) if model.site_group[s] == VOLUME_GROUP
                        and "/interior_" in model.site(s).name]
        self.volume_sites = np.array(volume_sites, dtype=np.int32)
        self.volume_node = np.array([index[model.site(s).name.split("/")[0]] for s in volume_sites], dtype=np.int32)
        self.volume_half = model.site_size[self.volume_sites] + VOLUME_TOL
        self._geomid = np.zeros(1, dtype=np.int32)
        self._last_pos = np.full((len(self.movable), 3), np.nan)
        self._last_quat = np.zeros((len(self.movable), 4))
        self._parent = np.full(len(self.nodes), -1, dtype=np.int32)
        self._relation = np.zeros(len(self.nodes), dtype=np.int8)
        self.graph: SceneGraph | None = None

    # --- public -----------------------------------------------------------------------------------------
    def observe_all(self) -> SceneGraph:
        """A full observation of every node."""
        self._observe_static()
        self._observe(np.arange(len(self.movable)))
        return self._publish()

    def update(self, skip: Collection[int] = ()) -> SceneGraph:
        """Re-observe the movable bodies that moved since last observed and are now at rest.

        skip: indices (into world.object_names) of bodies not to re-observe now, such as objects in a hand:
        they keep their last observed parent until they are put down.
        """
        if self.graph is None:
            return self.observe_all()
        due = self.due()
        if len(skip):
            due = due[~np.isin(due, list(skip))]
        if len(due):
            self._observe(due)
            return self._publish()
        return self.graph

    def due(self) -> np.ndarray:
        """Indices (into world.object_names) of bodies that moved and came to rest since last observed."""
        data = self.world.data
        pos = data.xpos[self.movable_bodies]
        quat = data.xquat[self.movable_bodies]
        moved = (np.linalg.norm(pos - self._last_pos, axis=1) > MOVED_DISTANCE) | (
            np.abs(np.einsum("ij,ij->i", quat, self._last_quat)) < MOVED_COS_HALF_ANGLE)
        if not moved.any():
            return np.zeros(0, dtype=np.int64)
        return np.flatnonzero(moved & self.world.objects_at_rest())

    # --- observation ------------------------------------------------------------------------------------
    def _observe_static(self) -> None:
        """Parents of furniture, appliances and decor: what a ray from just above their base hits, past their
        own geoms. Their bases come from the layout (they never move)."""
        layout = self.world.layout
        for f in layout.furniture:
            node = self.nodes.index(f.name)
            start = np.array([f.pos[0], f.pos[1], base_height(layout, f) + BASE_RAY_LIFT])
            geom = self._geom_below(start, node, _RAY_GROUPS)
            support = self.geom_node[geom] if geom >= 0 else -1
            if support < 0 or self.is_room[support]:
                self._parent[node], self._relation[node] = self._room_below(start, NO_BODY), INSIDE
            else:
                self._parent[node], self._relation[node] = support, ON

    def _observe(self, which: np.ndarray) -> None:
        data = self.world.data
        supports = self._contact_supports()
        for k in which:
            body = self.movable_bodies[k]
            node = self.movable[k]
            parent, relation = self._classify(k, body, supports.get(int(body), []))
            if parent >= 0 and not self._creates_cycle(node, parent):
                self._parent[node], self._relation[node] = parent, relation
            elif self._parent[node] < 0:  # first observation and nothing sensible: the room below
                self._parent[node], self._relation[node] = self._room_below(data.xpos[body], body), INSIDE
            else:
                continue  # nothing supports it yet: look again at the next update
            self._last_pos[k] = data.xpos[body]
            self._last_quat[k] = data.xquat[body]

    def _classify(self, k: int, body: int, contacts: list[tuple[int, float]]) -> tuple[int, int]:
        """(parent node, relation) of movable k from its supports and the interior volumes around it."""
        data = self.world.data
        center = data.xpos[body]
        half_world = np.abs(data.xmat[body].reshape(3, 3)) @ self.half_extents[k]
        bottom = max(center[2] - half_world[2], self._lowest(k))  # a tilted box bound reaches far below a bowl's rim
        top = bottom + min(SUPPORT_TOL, 0.3 * half_world[2])
        found = [(z, node) for node, z in contacts]  # none while its tree sleeps: MuJoCo skips sleeping contacts
        for dx, dy in _RAY_OFFSETS:  # rays start just above the bottom: what lies in a cavity is not support
            start = np.array([center[0] + dx * half_world[0], center[1] + dy * half_world[1], bottom + RAY_LIFT])
            found += self._support_below(start, body)
        candidates = [(z, node) for z, node in found if bottom - SUPPORT_TOL <= z <= top]
        if not candidates:  # the rays began inside what it rests on (a rim sunk into the floor): look from the centre
            candidates = [(z, node) for z, node in self._support_below(center, body)
                          if bottom - SUPPORT_TOL <= z <= top]
        support = max(candidates)[1] if candidates else -1
        if support >= 0 and self.supports[support]:  # a plate, a bowl, a bin: what holds objects
            return support, INSIDE if self.holds_inside[support] else ON
        container = self._object_container(k, center)
        if container < 0:
            container = self._container(center)
        if container >= 0:  # a pile of clothes in the basket is INSIDE the basket
            return container, INSIDE
        if support >= 0 and not self.is_room[support]:
            return support, ON
        if support >= 0:
            return support, INSIDE
        return -1, NONE

    def _support_below(self, start: np.ndarray, body: int) -> list[tuple[float, int]]:
        """[(height m, node)] of the first named geom straight below `start` other than `body`'s, if any."""
        hit = self._ray(start, body, _RAY_GROUPS)
        if hit is None or self.geom_node[hit[0]] < 0:
            return []
        return [(float(start[2] - hit[1]), int(self.geom_node[hit[0]]))]

    def _lowest(self, k: int) -> float:
        """The height (m) of movable k's lowest point: the lowest corner of its colliding geoms' bounding boxes."""
        geoms, data = self.object_geoms[k], self.world.data
        if not len(geoms):
            return -np.inf
        rows = data.geom_xmat[geoms].reshape(-1, 3, 3)[:, 2]  # each geom's local axes' world heights
        aabb = self.world.model.geom_aabb[geoms]  # (G, 6): box centre and half sizes in the geom's frame
        low = (data.geom_xpos[geoms, 2] + np.einsum("gj,gj->g", rows, aabb[:, :3])
               - np.einsum("gj,gj->g", np.abs(rows), aabb[:, 3:]))
        return float(low.min())

    def _object_container(self, k: int, point: np.ndarray) -> int:
        """The container object (bin or pot) whose cavity holds `point`, other than movable k itself, or -1."""
        data = self.world.data
        for j, hollow in self.cavities:
            if j == k:
                continue
            body = self.movable_bodies[j]
            local = data.xmat[body].reshape(3, 3).T @ (point - data.xpos[body])
            radial = np.hypot(local[0] - hollow.center_xy[0], local[1] - hollow.center_xy[1])
            if radial <= hollow.rim_radius and hollow.floor_z - 0.01 <= local[2] <= hollow.rim_z + CAVITY_HEADROOM:
                return int(self.movable[j])
        return -1

    def _contact_supports(self) -> dict[int, list[tuple[int, float]]]:
        """body -> [(supporting node, contact z)] for awake contacts whose normal points up into the body."""
        data, model = self.world.data, self.world.model
        found: dict[int, list[tuple[int, float]]] = {}
        if data.ncon == 0:
            return found
        contacts = data.contact
        geoms, normal_z, pos_z = contacts.geom, contacts.frame[:, 2], contacts.pos[:, 2]
        for side, sign in ((1, 1.0), (0, -1.0)):  # the normal points from geom[0] to geom[1]
            upward = sign * normal_z > 0.7
            for c in np.flatnonzero(upward):
                body = int(model.geom_bodyid[geoms[c, side]])
                other = int(self.geom_node[geoms[c, 1 - side]])
                if other >= 0:
                    found.setdefault(body, []).append((other, float(pos_z[c])))
        return found

    def _container(self, point: np.ndarray) -> int:
        """The node owning the smallest interior volume that contains `point`, or -1."""
        data = self.world.data
        if len(self.volume_sites) == 0:
            return -1
        offset = point - data.site_xpos[self.volume_sites]
        rot = data.site_xmat[self.volume_sites].reshape(-1, 3, 3)
        local = np.einsum("nji,nj->ni", rot, offset)
        inside = np.all(np.abs(local) <= self.volume_half, axis=1)
        if not inside.any():
            return -1
        hits = np.flatnonzero(inside)
        return int(self.volume_node[hits[np.argmin(np.prod(self.volume_half[hits], axis=1))]])

    def _ray(self, start: np.ndarray, exclude_body: int, groups: np.ndarray) -> tuple[int, float] | None:
        """(geom, distance m) of the first geom straight below `start` not on `exclude_body` (-1: none), or None."""
        assert exclude_body != 0, "body 0 holds the floors, walls and fused furniture"
        dist = mujoco.mj_ray(self.world.model, self.world.data, start, _DOWN, groups, 1, exclude_body, self._geomid)
        return None if dist < 0 else (int(self._geomid[0]), float(dist))

    def _geom_below(self, start: np.ndarray, node: int, groups: np.ndarray) -> int:
        """The first geom straight below `start` that does not belong to `node`, or -1."""
        point = start.copy()
        while (hit := self._ray(point, NO_BODY, groups)) is not None and self.geom_node[hit[0]] == node:
            point[2] -= hit[1] + PAST_OWN  # from inside its own geom the ray stops where it leaves it
            # where its own geom ends on what it stands on, the point past it lies inside that: a ray from there
            # stops where it leaves that too, level with the floor's top under it (a coffee maker on a counter
            # read as standing on the floor)
            holding = self._box_holding(point, node, groups)
            if holding >= 0:
                return holding
        return -1 if hit is None else hit[0]

    def _box_holding(self, point: np.ndarray, node: int, groups: np.ndarray) -> int:
        """A box geom of `groups` not of `node` (nor of no node, a wall) whose inside holds `point`, or -1."""
        model, data = self.world.model, self.world.data
        boxes = np.flatnonzero((model.geom_type == mujoco.mjtGeom.mjGEOM_BOX) & (groups[model.geom_group] > 0)
                               & (self.geom_node >= 0) & (self.geom_node != node))
        local = np.einsum("nji,nj->ni", data.geom_xmat[boxes].reshape(-1, 3, 3), point - data.geom_xpos[boxes])
        inside = np.all(np.abs(local) <= model.geom_size[boxes], axis=1)
        return int(boxes[np.argmax(inside)]) if inside.any() else -1

    def _room_below(self, point: np.ndarray, exclude_body: int) -> int:
        hit = self._ray(np.array([point[0], point[1], max(point[2], 0.0) + 0.05]), exclude_body, _FLOOR_GROUPS)
        if hit is None:
            raise PhysicsError(f"no floor below {np.round(point, 3).tolist()}: the body left the apartment")
        return int(self.geom_node[hit[0]])

    def _creates_cycle(self, node: int, parent: int) -> bool:
        at, hops = parent, 0
        while at >= 0 and hops <= len(self.nodes):
            if at == node:
                return True
            at, hops = int(self._parent[at]), hops + 1
        return False

    def _publish(self) -> SceneGraph:
        self.graph = SceneGraph(self.nodes, self.categories, self._parent.copy(), self._relation.copy())
        return self.graph
