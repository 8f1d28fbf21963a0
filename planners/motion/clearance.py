"""Whether a robot configuration touches the apartment (`ClearanceCheck`), with or without an object in the hand
(`Held`), on a scratch copy of the simulation; and the IK base damping of moves whose base pose is planned."""

from __future__ import annotations

import copy
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import mujoco
import numpy as np

from planners.motion.control import robot_geom_ids
from planners.robot import FINGER_GEOMS, PREFIX

FINGER_GRAZE = 0.002  # m: an open finger may graze a neighbour's edge this deep (it slides off)
ARC_BASE_COST = 1e4  # IK damping on the base: the base is placed by the planner, the arm reaches


@dataclass(frozen=True)
class Held:
    """An object in the hand: its geoms, its free joint's qpos address, and its pose in the grip site's frame
    (position m, shape (3,); rotation, shape (3, 3)); it moves with the hand in clearance checks."""

    geoms: frozenset[int]
    qpos_adr: int
    position: np.ndarray
    rotation: np.ndarray


class ClearanceCheck:
    """Whether a robot configuration touches the apartment, on a scratch copy of the data (never the live one).

    Contacts of the fingers are ignored (they are meant to touch the part); every other robot geom must touch
    nothing. With a held object, the fingers are checked too, and the object must touch nothing but the robot.
    The model's geom margins are 0, so mj_collision reports overlaps only: a contact closer than MARGIN counts,
    but none is reported short of touching, and a planned move may pass a neighbour at no distance (the arm's
    tracking lag mid-swing then makes it strike). Giving the check's robot geoms a contact margin of MARGIN for
    every check was tried: an arm's swing no longer swept a radio off a tv stand, but a vegetable carried from a
    cutting board to the fridge then knocked an egg 5.5 cm, so it is not in; a caller may ask for a margin where
    it plans (`keeping`: the ways a held object is lowered along).

    Collisions run on a copy of the model whose filter keeps only the pairs a check reads (robot or held object
    against the rest): apartment geoms lose their conaffinity, so the ~100 resting objects and the furniture are
    not collided with each other at every check.
    """

    MARGIN = 0.005  # m

    def __init__(self, world, controller) -> None:
        self.world = world
        self.model = copy.copy(world.model)
        self.scratch = mujoco.MjData(self.model)
        self.qpos_adr = controller.qpos_adr
        robot = robot_geom_ids(world.model)
        fingers = [world.model.geom(PREFIX + n).id for n in FINGER_GEOMS]
        self.robot = np.zeros(world.model.ngeom, dtype=bool)
        self.robot[robot] = True
        self.fingers = np.zeros(world.model.ngeom, dtype=bool)
        self.fingers[fingers] = True
        self.checked = self.robot & ~self.fingers
        hand = world.model.body(PREFIX + "wrist_flex_link").id  # the wrist, the gripper and the fingers below it
        in_hand = np.zeros(world.model.nbody, dtype=bool)
        for body in range(world.model.nbody):
            b = body
            while b and b != hand:
                b = world.model.body_parentid[b]
            in_hand[body] = b == hand
        self.arm_body = self.robot & ~in_hand[world.model.geom_bodyid]  # the base, torso and arm up to the wrist
        self.base = world.model.geom_bodyid == world.model.body(PREFIX + "base").id
        self.conaffinity = world.model.geom_conaffinity.copy()
        self.model.geom_conaffinity[~self.robot] = 0
        assert _same_filter(world.model, self.robot), "the robot-only collision filter would drop pairs"
        self.grip = world.model.site(PREFIX + "grip").id

    def fingers_clear(self, q: np.ndarray) -> bool:
        """True if the fingers at configuration q (shape (13,), the finger openings included) touch nothing: an
        open hand about to close round an object has both fingers beside it, on nothing else (a graze of at most
        FINGER_GRAZE m aside)."""
        return not self.finger_contacts(q)

    def finger_contacts(self, q: np.ndarray, graze: float = FINGER_GRAZE, whole: bool = False) -> set[int]:
        """Ids of the geoms outside the robot that the fingers at configuration q (shape (13,), the finger
        openings included) touch deeper than `graze` m; with `whole`, that any robot geom touches."""
        mine = self.robot if whole else self.fingers
        d = self.scratch
        d.qpos[:] = self.world.data.qpos
        d.qpos[self.qpos_adr] = q
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_collision(self.model, d)
        g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
        touching = ((mine[g1] != mine[g2]) & ~(self.robot[g1] & self.robot[g2])
                    & (d.contact.dist[: d.ncon] < -graze))
        return {int(g) for g in np.concatenate([g1[touching], g2[touching]]) if not self.robot[g]}

    def clear(self, q: np.ndarray, articulation=None, value: float = 0.0, held: Held | None = None,
              fingers: bool = False, riders: tuple[int, ...] = (), itself: bool = False) -> bool:
        """True if configuration q (shape (13,)) touches nothing in the apartment (within `keeping`, the robot
        comes no closer than its margin), with `articulation` (if given) at joint value `value` (rad or m), `held`
        (if given) in the hand, and everything else where it is now, but the objects whose free joints' qpos
        addresses are `riders` (in a drawer being moved): they move with the drawer. With `fingers`, the fingers
        are checked too (a hand swinging free touches nothing at all). `held` must not touch the robot's base (a
        radio lowered to the floor in front of it met the base on the way down and slid 4 cm in the fingers); with
        `itself`, nor the rest of the robot but its hand (from the wrist on, which holds it): a joint-space way
        planned over the joints' ranges swung a pot in the hand into the robot's base, and it fell out (a laundry
        basket held by its rim at the carry point lies against the shoulder: not checked elsewhere)."""
        d = self.scratch
        d.qpos[:] = self.world.data.qpos
        d.qpos[self.qpos_adr] = q
        if articulation is not None:
            d.qpos[articulation.qpos_adr] = value
        mujoco.mj_kinematics(self.model, d)
        if riders and articulation is not None and articulation.joint_type == "slide":
            body = self.model.jnt_bodyid[articulation.joint_id]
            shift = d.xpos[body] - self.world.data.xpos[body]
            for adr in riders:
                d.qpos[adr:adr + 3] += shift
            mujoco.mj_kinematics(self.model, d)
        robot, checked = self.robot, self.robot if fingers else self.checked
        if held is None:
            mujoco.mj_collision(self.model, d)
        else:
            rotation = d.site_xmat[self.grip].reshape(3, 3)
            d.qpos[held.qpos_adr:held.qpos_adr + 3] = d.site_xpos[self.grip] + rotation @ held.position
            mujoco.mju_mat2Quat(d.qpos[held.qpos_adr + 3:held.qpos_adr + 7], (rotation @ held.rotation).ravel())
            mujoco.mj_kinematics(self.model, d)
            geoms = list(held.geoms)
            robot = checked = robot.copy()  # the fingers are checked too, against all but the object
            robot[geoms] = True
            self._collide(geoms)
        g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
        touching = (checked[g1] != checked[g2]) & ~(robot[g1] & robot[g2])
        if held is not None:
            own = np.zeros_like(robot)
            own[list(held.geoms)] = True
            body = self.arm_body if itself else self.base
            touching |= (own[g1] & body[g2]) | (own[g2] & body[g1])
        return not (touching & (d.contact.dist[: d.ncon] < self.MARGIN)).any()

    def bodies_struck(self, q: np.ndarray, held: Held, bodies: frozenset[int], margin: float = 0.0) -> set[int]:
        """Of `bodies` (body ids), those a robot geom other than a finger, or the `held` object, comes within
        `margin` m of (0: touches) at configuration q (shape (13,)), `held` in the hand."""
        d = self.scratch
        d.qpos[:] = self.world.data.qpos
        d.qpos[self.qpos_adr] = q
        mujoco.mj_kinematics(self.model, d)
        rotation = d.site_xmat[self.grip].reshape(3, 3)
        d.qpos[held.qpos_adr:held.qpos_adr + 3] = d.site_xpos[self.grip] + rotation @ held.position
        mujoco.mju_mat2Quat(d.qpos[held.qpos_adr + 3:held.qpos_adr + 7], (rotation @ held.rotation).ravel())
        mujoco.mj_kinematics(self.model, d)
        geoms = list(held.geoms)
        mine = self.checked.copy()
        mine[geoms] = True
        self._collide(geoms)
        g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
        near = d.contact.dist[: d.ncon] < margin
        other = np.concatenate([g2[near & mine[g1] & ~self.robot[g2]], g1[near & mine[g2] & ~self.robot[g1]]])
        return {int(b) for b in self.model.geom_bodyid[other]} & set(bodies)

    def slide_strikes(self, body: int, shift: np.ndarray, bodies: frozenset[int], graze: float = FINGER_GRAZE
                      ) -> set[int]:
        """Of `bodies` (body ids), those that free body `body`, moved `shift` (m, shape (3,)) from where it stands,
        would press into deeper than `graze` m and does not where it stands (what a grasp's closing fingers push
        it into)."""
        d, model = self.scratch, self.model
        adr = int(model.jnt_qposadr[model.body_jntadr[body]])
        mine = model.geom_bodyid == body
        geoms = np.flatnonzero(mine)

        def pressed(offset: np.ndarray) -> set[int]:
            d.qpos[:] = self.world.data.qpos
            d.qpos[adr:adr + 3] += offset
            mujoco.mj_kinematics(model, d)
            self._collide(geoms)
            g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
            deep = d.contact.dist[: d.ncon] < -graze
            other = np.concatenate([g2[deep & mine[g1] & ~mine[g2]], g1[deep & mine[g2] & ~mine[g1]]])
            return {int(b) for b in model.geom_bodyid[other]} & set(bodies)

        return pressed(np.asarray(shift, dtype=float)) - pressed(np.zeros(3))

    @contextmanager
    def keeping(self, margin: float) -> Iterator[None]:
        """Within it, `clear` fails a configuration where a robot geom comes within `margin` m (at most MARGIN) of
        the apartment: the copy's robot geoms get that contact margin (outside it they have none, see the class
        doc)."""
        saved = self.model.geom_margin[self.robot].copy()
        self.model.geom_margin[self.robot] = min(margin, self.MARGIN)
        try:
            yield
        finally:
            self.model.geom_margin[self.robot] = saved

    def _collide(self, geoms) -> None:
        """mj_collision on the scratch data, an object's `geoms` (ids) colliding with the rest as well as with the
        robot (the copy's other apartment geoms have no conaffinity)."""
        self.model.geom_conaffinity[geoms] = self.conaffinity[geoms]
        try:
            mujoco.mj_collision(self.model, self.scratch)
        finally:
            self.model.geom_conaffinity[geoms] = 0


def _same_filter(model: mujoco.MjModel, robot: np.ndarray) -> bool:
    """Whether MuJoCo's contype/conaffinity test passes the same pairs (any geom that may be in or on the robot,
    against any geom off it) when the geoms off the robot have conaffinity 0, as in `ClearanceCheck.model`."""
    kinds = np.unique(np.stack([model.geom_contype, model.geom_conaffinity], axis=1), axis=0)
    off = np.unique(np.stack([model.geom_contype[~robot], model.geom_conaffinity[~robot]], axis=1), axis=0)
    for contype, conaffinity in kinds:
        before = (contype & off[:, 1]) | (off[:, 0] & conaffinity)
        after = off[:, 0] & conaffinity
        if not np.array_equal(before != 0, after != 0):
            return False
    return True
