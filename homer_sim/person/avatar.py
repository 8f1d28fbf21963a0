"""The person: a capsule humanoid whose root and hands are mocap bodies, and welds that hold what it carries.

Building (`add_avatar`) adds the bodies and equality welds to an MjSpec; `Avatar` drives them in a compiled
World. The root moves kinematically along grid paths; a held or worn object is welded to a hand or the torso
with the relative pose it has when the weld is switched on, and does not collide while carried. Physics is
stepped only for grasps, placements and door motions (the executor decides when).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from homer_sim.errors import HomerError

HANDS = ("right", "left")
WELD_SLOTS = 10  # welds shared by hands (held objects and what rides on them) and the torso (worn objects)
START_POSE = (8.3, 5.0, math.pi / 2)  # (x, y, yaw): the bedroom, beside the bed
WELD_SOLREF = (0.005, 1.0)
SKIN = (0.86, 0.7, 0.58, 1.0)
SHIRT = (0.25, 0.45, 0.7, 1.0)
HAND_HEIGHT = 1.0  # m, carrying height of the hands
HAND_FORWARD = 0.3  # m in front of the root
HAND_SIDE = 0.22  # m to each side


class AvatarError(HomerError):
    """The person cannot do what a script asks (hands full, object not held, ...)."""


def _visual(body: mujoco.MjsBody, **kwargs) -> None:
    geom = body.add_geom(**kwargs)
    geom.contype = 0
    geom.conaffinity = 0
    geom.group = 2


def add_avatar(spec: mujoco.MjSpec) -> None:
    """Add the avatar (root and two hands, mocap) and its welds to a spec that holds free objects (use as
    `World(extras=[add_avatar])`); the first free body is the welds' placeholder second body until they are
    switched on."""
    any_object = next(body.name for body in spec.bodies if any(j.type == mujoco.mjtJoint.mjJNT_FREE
                                                                for j in body.joints))
    x, y, yaw = START_POSE
    root = spec.worldbody.add_body(name="avatar", pos=(x, y, 0.0), quat=(math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)),
                                   mocap=True)
    capsule, sphere = mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_SPHERE
    _visual(root, name="avatar/torso", type=capsule, fromto=(0, 0, 0.95, 0, 0, 1.4), size=(0.16, 0, 0), rgba=SHIRT)
    _visual(root, name="avatar/head", type=sphere, pos=(0, 0, 1.62), size=(0.11, 0, 0), rgba=SKIN)
    for side, sy in (("left", 1), ("right", -1)):
        _visual(root, name=f"avatar/leg_{side}", type=capsule, fromto=(0, sy * 0.09, 0.08, 0, sy * 0.09, 0.9),
                size=(0.07, 0, 0), rgba=(0.2, 0.2, 0.25, 1.0))
        hand = spec.worldbody.add_body(name=f"avatar/hand_{side}", mocap=True,
                                       pos=(x, y + sy * HAND_SIDE, HAND_HEIGHT))
        _visual(hand, name=f"avatar/hand_{side}/palm", type=sphere, size=(0.045, 0, 0), rgba=SKIN)
    for k in range(WELD_SLOTS):
        weld = spec.add_equality(name=f"avatar/weld_{k}", type=mujoco.mjtEq.mjEQ_WELD, name1="avatar",
                                 name2=any_object, objtype=mujoco.mjtObj.mjOBJ_BODY, active=False)
        weld.solref = WELD_SOLREF


def relative_pose(pos1, quat1, pos2, quat2) -> tuple[np.ndarray, np.ndarray]:
    """Pose of frame 2 in frame 1 (position m, quaternion wxyz)."""
    inverse = np.zeros(4)
    mujoco.mju_negQuat(inverse, np.asarray(quat1, float))
    rel_pos = np.zeros(3)
    mujoco.mju_rotVecQuat(rel_pos, np.asarray(pos2, float) - np.asarray(pos1, float), inverse)
    rel_quat = np.zeros(4)
    mujoco.mju_mulQuat(rel_quat, inverse, np.asarray(quat2, float))
    return rel_pos, rel_quat


def compose(pos1, quat1, rel_pos, rel_quat) -> tuple[np.ndarray, np.ndarray]:
    """Frame 1 composed with a relative pose: the world pose of frame 2."""
    pos = np.zeros(3)
    mujoco.mju_rotVecQuat(pos, np.asarray(rel_pos, float), np.asarray(quat1, float))
    quat = np.zeros(4)
    mujoco.mju_mulQuat(quat, np.asarray(quat1, float), np.asarray(rel_quat, float))
    return np.asarray(pos1, float) + pos, quat


class Avatar:
    """Drives the avatar of a World built with an avatar: its root, its hands and what it holds or wears.

    held: hand -> object name or None; worn: objects welded to the torso; riders: carrier -> objects that
    rest on it and travel with it.
    """

    def __init__(self, world) -> None:
        model = world.model
        self.world = world
        self.root = model.body("avatar").id
        self.hands = {h: model.body(f"avatar/hand_{h}").id for h in HANDS}
        self.welds = [model.equality(f"avatar/weld_{k}").id for k in range(WELD_SLOTS)]
        self._geom_types = (model.geom_contype.copy(), model.geom_conaffinity.copy())
        self.reset()

    def reset(self) -> None:
        """Hands empty, nothing worn, every object colliding again, the root at its start pose."""
        for eq in self.welds:
            self.world.data.eq_active[eq] = 0
        self.world.model.geom_contype[:], self.world.model.geom_conaffinity[:] = self._geom_types
        self.slots: dict[int, str] = {}
        self.held: dict[str, str | None] = dict.fromkeys(HANDS)
        self.worn: list[str] = []
        self.riders: dict[str, list[str]] = {}
        self.move_to(*START_POSE)

    # --- poses ------------------------------------------------------------------------------------------
    @property
    def pose(self) -> tuple[float, float, float]:
        """(x m, y m, yaw rad) of the root."""
        return self.x, self.y, self.yaw

    def carried(self) -> list[str]:
        """Every object moving with the person: held, riding on something held, or worn."""
        return list(self.slots.values())

    def _mocap(self, body: int) -> int:
        return int(self.world.model.body_mocapid[body])

    def hand_home(self, hand: str) -> np.ndarray:
        """World position (m) of `hand` in its carrying pose."""
        side = -1.0 if hand == "right" else 1.0
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([self.x + c * HAND_FORWARD - s * side * HAND_SIDE,
                         self.y + s * HAND_FORWARD + c * side * HAND_SIDE, HAND_HEIGHT])

    def set_hand(self, hand: str, pos, follow: bool = True) -> None:
        """Put a hand at `pos` (m, world); with `follow`, what it holds is moved there kinematically."""
        data = self.world.data
        data.mocap_pos[self._mocap(self.hands[hand])] = pos
        data.mocap_quat[self._mocap(self.hands[hand])] = data.mocap_quat[self._mocap(self.root)]
        if follow:
            self._follow()

    def move_to(self, x: float, y: float, yaw: float) -> None:
        """Place the root (kinematically) and bring hands and everything carried along."""
        self.x, self.y, self.yaw = float(x), float(y), float(yaw)
        data = self.world.data
        data.mocap_pos[self._mocap(self.root)] = (x, y, 0.0)
        data.mocap_quat[self._mocap(self.root)] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        for hand in HANDS:
            self.set_hand(hand, self.hand_home(hand), follow=False)
        self._follow()

    def _follow(self) -> None:
        """Teleport every welded object to where its weld holds it, at rest, and update kinematics."""
        model, data = self.world.model, self.world.data
        mujoco.mj_kinematics(model, data)
        for slot, name in self.slots.items():
            eq = self.welds[slot]
            body1 = model.eq_obj1id[eq]
            pos, quat = compose(data.xpos[body1], data.xquat[body1], model.eq_data[eq, 3:6], model.eq_data[eq, 6:10])
            self.world.set_object_pose(name, pos, quat, forward=False)
        mujoco.mj_kinematics(model, data)

    # --- welds and collisions ---------------------------------------------------------------------------
    def weld(self, name: str, body1: int) -> None:
        """Weld object `name` to body1 (a hand or the root) at their current relative pose."""
        free = [k for k in range(WELD_SLOTS) if k not in self.slots]
        if not free:
            raise AvatarError(f"cannot carry {name}: already carrying {', '.join(self.slots.values())}")
        model, data = self.world.model, self.world.data
        eq, body2 = self.welds[free[0]], self.world.object_body_ids[self.world.object_index(name)]
        rel_pos, rel_quat = relative_pose(data.xpos[body1], data.xquat[body1], data.xpos[body2], data.xquat[body2])
        model.eq_obj1id[eq], model.eq_obj2id[eq] = body1, body2
        model.eq_data[eq, 0:3] = 0.0
        model.eq_data[eq, 3:6], model.eq_data[eq, 6:10] = rel_pos, rel_quat
        data.eq_active[eq] = 1
        self.slots[free[0]] = name

    def unweld(self, name: str) -> None:
        for slot, held in list(self.slots.items()):
            if held == name:
                self.world.data.eq_active[self.welds[slot]] = 0
                del self.slots[slot]

    def set_collisions(self, name: str, enabled: bool) -> None:
        """Switch contacts of an object's geoms off while it is carried, back on when it is put down."""
        model = self.world.model
        body = self.world.object_body_ids[self.world.object_index(name)]
        start, count = model.body_geomadr[body], model.body_geomnum[body]
        contype, conaffinity = self._geom_types
        model.geom_contype[start : start + count] = contype[start : start + count] if enabled else 0
        model.geom_conaffinity[start : start + count] = conaffinity[start : start + count] if enabled else 0

    def free_hand(self) -> str | None:
        return next((h for h in HANDS if self.held[h] is None), None)

    def hand_of(self, name: str) -> str | None:
        return next((h for h in HANDS if self.held[h] == name), None)
