"""How the person gets about: where a node is reached (`Walker.anchor`) and walking there along the floor plan's grid
paths, kinematically (`Walker.go`, `Walker.walk_to`)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from homer_sim.home.floorplan import find_path
from homer_sim.home.spots import Spots
from homer_sim.person.avatar import Avatar, AvatarError
from homer_sim.person.state import DayState
from homer_sim.world import World


class Walker:
    """Walks the `avatar` in `world` to where a node is used.

    Inputs, declared: the world, the avatar, the free spots and standing poses (`spots`), the day so far (`day`:
    the observed graph says where an object is, the minute stamps recorded paths), the names of the movable
    objects and of the rooms, and an optional recording. `dynamic_obstacles`, when set, returns extra blocked
    grid cells (a robot in the way) for each walk; paths are cached only without it. `make_way`, when set, is
    asked to clear a path (waypoints, m) that only those cells block (the robot drives off it; True when it did),
    and the walk is planned again.
    """

    def __init__(self, world: World, avatar: Avatar, spots: Spots, day: DayState, movable: set[str],
                 rooms: set[str], recording=None) -> None:
        self.world = world
        self.avatar = avatar
        self.spots = spots
        self.day = day
        self.movable = movable
        self.rooms = rooms
        self.recording = recording
        self.dynamic_obstacles: Callable[[], np.ndarray | None] | None = None
        self.make_way: Callable[[list[tuple[float, float]]], bool] | None = None
        self._paths: dict[tuple, list] = {}

    def anchor(self, node: str) -> str:
        """The furniture or room a node is reached at: an object's first non-movable ancestor."""
        graph = self.day.graph
        while node in self.movable:
            node = graph.parent_of(node)
        return node

    def go(self, node: str) -> None:
        """Walk to where `node` is used (an object: where it lies now)."""
        anchor = self.anchor(node)
        if anchor in self.rooms and node in self.movable:
            pos = self.world.object_pose(node)[0]
            x, y, _ = self.spots.free_floor_near((pos[0], pos[1]), anchor)
            yaw = math.atan2(pos[1] - y, pos[0] - x)
        else:
            x, y, yaw = self.spots.standing_for(anchor)
        self.walk_to(x, y, yaw)

    def walk_to(self, x: float, y: float, yaw: float) -> None:
        """Walk to (x m, y m) along a grid path and turn to `yaw` rad (the avatar moves kinematically)."""
        if math.hypot(x - self.avatar.x, y - self.avatar.y) > 0.05:
            key = (self.spots.plan.cell(self.avatar.x, self.avatar.y), self.spots.plan.cell(x, y))
            extra = self.dynamic_obstacles() if self.dynamic_obstacles else None
            path = self._paths.get(key) if extra is None else None
            if path is None:
                path = find_path(self.spots.blocked, self.spots.plan, (self.avatar.x, self.avatar.y), (x, y), extra)
                if path is None and extra is not None and self.make_way is not None:  # ask whoever is in the way
                    clear = find_path(self.spots.blocked, self.spots.plan, (self.avatar.x, self.avatar.y), (x, y))
                    if clear is not None and self.make_way(clear):
                        path = find_path(self.spots.blocked, self.spots.plan, (self.avatar.x, self.avatar.y), (x, y),
                                         self.dynamic_obstacles())
                if path is None:
                    raise AvatarError(f"no path from {self.avatar.x:.2f}, {self.avatar.y:.2f} to {x:.2f}, {y:.2f}")
                if extra is None:
                    self._paths[key] = path
            if self.recording is not None:
                self.recording.log_path(path, routine_minute=self.day.minute)
        self.avatar.move_to(x, y, yaw)
        if self.recording is not None:
            self.recording.log_body_poses(self.world.data, force=True)
