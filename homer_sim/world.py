"""The physical apartment: a compiled MuJoCo model and its data, with every name looked up once.

`World` owns the live `MjData`. It steps physics, puts objects where a caller says (tests, the avatar later),
and reports articulation openness. Scene graphs are read by `homer_sim.observe.SceneGraphObserver`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from homer_sim.errors import unknown_name
from homer_sim.home.apartment import default_layout
from homer_sim.home.build import build_spec
from homer_sim.home.catalog import CATALOG, ObjectClass
from homer_sim.home.furniture import furniture_geometry
from homer_sim.home.layout import Layout, declared_graph
from homer_sim.home.placement import start_poses
from homer_sim.home.validate import validate_layout

SETTLE_SPEED = 5e-3  # m/s: a body whose centre of mass moves slower counts as at rest (thin objects may
# keep rocking by a fraction of a degree on curved supports; that does not change where they are)
WAKE_NUDGE = 1e-9  # m/s or rad/s, a velocity too small to matter that keeps a tree from sleeping


@dataclass(frozen=True)
class Articulation:
    """A door (hinge) or drawer (slide) of a piece of furniture."""

    name: str  # "<furniture>/<part>"
    furniture: str
    joint_type: str  # "hinge" or "slide"
    joint_id: int
    qpos_adr: int
    dof_adr: int
    range: tuple[float, float]


class World:
    """A compiled apartment and its simulation state.

    object_names: movable nodes (objects and props) in layout order; object_body_ids aligns with it.
    """

    def __init__(self, layout: Layout | None = None, validate: bool = True,
                 extras: Sequence[Callable[[mujoco.MjSpec], None]] = ()) -> None:
        """extras: functions that add to the spec before it is compiled, in order (the person's
        `add_avatar`, the robot's `add_robot`), so the world never imports what is built on it."""
        self.layout = layout or default_layout()
        if validate:
            validate_layout(self.layout)
        self.spec = build_spec(self.layout)
        for extra in extras:
            extra(self.spec)
        self.compile_warnings: list[str] = []
        previous = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(self.compile_warnings.append)
        try:
            self.model = self.spec.compile()
        finally:
            mujoco.set_mju_user_warning(previous)
        self.data = mujoco.MjData(self.model)
        self.object_names = tuple(o.name for o in self.layout.objects)
        self.object_categories = {name: cls.category for name, cls in CATALOG.items()}
        self.object_body_ids = np.array([self._body_id(n) for n in self.object_names], dtype=np.int32)
        self._object_index = {n: i for i, n in enumerate(self.object_names)}
        self.object_qpos_adr = self.model.jnt_qposadr[self.model.body_jntadr[self.object_body_ids]]
        self.object_dof_adr = self.model.jnt_dofadr[self.model.body_jntadr[self.object_body_ids]]
        self.articulations = self._find_articulations()
        self.start = start_poses(self.layout)
        self._settled_state: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.reset()

    # --- names ------------------------------------------------------------------------------------------
    def _body_id(self, name: str) -> int:
        body_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)
        if body_id < 0:
            raise unknown_name("body", name, [self.model.body(i).name for i in range(self.model.nbody)])
        return body_id

    def _find_articulations(self) -> dict[str, Articulation]:
        found = {}
        for f in self.layout.furniture:
            for part in furniture_geometry(f).parts:
                name = f"{f.name}/{part.name}"
                jid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, name)
                found[name] = Articulation(name, f.name, part.joint, jid, int(self.model.jnt_qposadr[jid]),
                                           int(self.model.jnt_dofadr[jid]), tuple(self.model.jnt_range[jid]))
        return found

    def object_index(self, name: str) -> int:
        try:
            return self._object_index[name]
        except KeyError:
            raise unknown_name("object", name, self.object_names) from None

    def object_class(self, name: str) -> ObjectClass:
        """The catalogue class of the object `name`."""
        return CATALOG[self.layout.objects[self.object_index(name)].cls]

    def articulation(self, name: str) -> Articulation:
        """By `<furniture>/<part>`, or by furniture name when it has exactly one part."""
        if name in self.articulations:
            return self.articulations[name]
        parts = [a for a in self.articulations.values() if a.furniture == name]
        if len(parts) == 1:
            return parts[0]
        raise unknown_name("articulation", name, self.articulations)

    def declared_graph(self):
        return declared_graph(self.layout, self.object_categories)

    # --- state ------------------------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to the declared start layout, all doors and drawers closed, time 0."""
        mujoco.mj_resetData(self.model, self.data)
        for name in self.object_names:
            pose = self.start[name]
            self.set_object_pose(name, pose.pos, pose.quat, forward=False)
        mujoco.mj_forward(self.model, self.data)

    def reset_settled(self) -> None:
        """Back to the start layout after it has settled (computed once, then copied): the start of every day."""
        if self._settled_state is None:
            self.reset()
            self.step(int(round(2.0 / self.model.opt.timestep)))
            self._settled_state = (self.data.qpos.copy(), self.data.qvel.copy(), self.data.tree_asleep.copy())
        mujoco.mj_resetData(self.model, self.data)
        qpos, qvel, asleep = self._settled_state
        self.data.qpos[:], self.data.qvel[:], self.data.tree_asleep[:] = qpos, qvel, asleep
        mujoco.mj_forward(self.model, self.data)

    def start_positions(self) -> np.ndarray:
        """Shape (n_objects, 3): spawn positions in m."""
        return np.array([self.start[n].pos for n in self.object_names])

    def object_positions(self) -> np.ndarray:
        """Shape (n_objects, 3): current body positions in m (world)."""
        return self.data.xpos[self.object_body_ids].copy()

    def object_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(position m, quaternion wxyz) of an object's body."""
        body = self.object_body_ids[self.object_index(name)]
        return self.data.xpos[body].copy(), self.data.xquat[body].copy()

    def set_object_pose(self, name: str, pos, quat=(1.0, 0.0, 0.0, 0.0), forward: bool = True) -> None:
        """Teleport an object (tests, scripted set-up); its velocity is zeroed and it is woken up."""
        i = self.object_index(name)
        adr, dof = self.object_qpos_adr[i], self.object_dof_adr[i]
        self.data.qpos[adr : adr + 3] = pos
        self.data.qpos[adr + 3 : adr + 7] = np.asarray(quat) / np.linalg.norm(quat)
        self.data.qvel[dof : dof + 6] = 0.0
        self.data.qvel[dof + 2] = -WAKE_NUDGE  # nonzero velocity: MuJoCo wakes the tree at the next step
        if forward:
            mujoco.mj_forward(self.model, self.data)

    def wake(self) -> None:
        """Wake every sleeping tree: a tree with nonzero velocity cannot sleep, so MuJoCo's own wake pass
        (at the next step) wakes it together with its island."""
        asleep = self.data.tree_asleep >= 0
        for tree in np.flatnonzero(asleep):
            dof = self.model.tree_dofadr[tree]
            self.data.qvel[dof] = WAKE_NUDGE

    def openness(self, name: str) -> float:
        """0 closed .. 1 fully open."""
        a = self.articulation(name)
        lo, hi = a.range
        return float(np.clip((self.data.qpos[a.qpos_adr] - lo) / (hi - lo), 0.0, 1.0))

    def all_openness(self) -> dict[str, float]:
        return {name: self.openness(name) for name in self.articulations}

    def set_openness(self, name: str, value: float, forward: bool = True) -> None:
        """Put a door or drawer at openness `value` (0..1) with zero velocity."""
        a = self.articulation(name)
        lo, hi = a.range
        self.data.qpos[a.qpos_adr] = lo + float(np.clip(value, 0.0, 1.0)) * (hi - lo)
        self.data.qvel[a.dof_adr] = WAKE_NUDGE
        if forward:
            mujoco.mj_forward(self.model, self.data)

    # --- stepping ---------------------------------------------------------------------------------------
    def step(self, n: int = 1) -> None:
        mujoco.mj_step(self.model, self.data, nstep=n)

    def warnings(self) -> int:
        """Total number of MuJoCo warnings so far: at compile time and while stepping."""
        return len(self.compile_warnings) + int(sum(w.number for w in self.data.warning))

    def objects_at_rest(self) -> np.ndarray:
        """Shape (n_objects,), bool: the centre of mass moves slower than SETTLE_SPEED."""
        return np.linalg.norm(self.data.cvel[self.object_body_ids, 3:], axis=1) < SETTLE_SPEED

    def settle(self, max_seconds: float = 5.0, chunk: int = 25) -> float:
        """Step until every object is at rest (or `max_seconds` of physics pass); returns physics seconds used."""
        start = self.data.time
        while self.data.time - start < max_seconds:
            self.step(chunk)
            if np.all(self.objects_at_rest()):
                break
        return float(self.data.time - start)

    def has_nan(self) -> bool:
        return bool(np.isnan(self.data.qpos).any() or np.isnan(self.data.qvel).any())
