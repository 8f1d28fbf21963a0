"""Compile a declarative Layout to a MuJoCo model with MjSpec.

Naming (the one place MJCF names are made; `homer_sim.observe` and `homer_sim.world` read them back):
- a room's floor: world geom `<room>/floor`; walls: world geoms `wall/<k>`;
- furniture: world geoms `<furniture>/<box>`, posed in the world frame; a door or drawer: a child body of the
  world and joint `<furniture>/<part>`, its handle geom and site `<furniture>/<part>/handle`;
- interior volumes: sites `<furniture>/interior_<k>` on the body that carries them (a part's, or the world's);
- objects: body `<object>` with a free joint `<object>` and geoms `<object>/<part>`.

What never moves lives on the world body: MuJoCo's broadphase cost grows with the number of bodies and of their
geoms, even when they all sleep, so a static body per floor, per table or per cabinet would cost every step. A
door or drawer never touches the world body's geoms (its own carcass is excluded; the layout validator keeps its
swing or travel clear of other furniture); it touches objects, the robot and other parts. A geom's owner is the
name before its first '/' (see `homer_sim.observe`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from homer_sim.home.catalog import CATALOG
from homer_sim.home.floorplan import wall_segments
from homer_sim.home.furniture import Box, Furniture, Part, furniture_geometry
from homer_sim.home.layout import Layout
from homer_sim.home.placement import base_height, start_poses, yaw_quat
from homer_sim.home.shapes import add_object_geoms

TIMESTEP = 0.002  # s
FLOOR_GROUP = 1  # geom group of floors, so a ray can look for the floor alone
VOLUME_GROUP = 4  # site group of interior volumes (hidden)
WALL_RGBA = (0.85, 0.83, 0.78, 1.0)
FLOOR_RGBA = {"outside": (0.45, 0.55, 0.4, 1.0)}
FURNITURE_FRICTION = (0.9, 0.005, 0.002)  # sliding, torsional (m), rolling (m): furniture and floors resist
FURNITURE_CONDIM = 6  # rolling too (a contact takes the larger condim and each friction's larger coefficient of its
# two geoms): without rolling friction, a vacuum cleaner fallen on its side rolled across the kitchen for minutes
CONTACT_SOLREF = (0.005, 1.0)  # stiff enough that a dropped object cannot sink through a 2 cm board
FREE_DAMPING = 0.002  # N s/m and N m s/rad on free objects: damps the chatter of thin objects, negligible in flight
IDENTITY_QUAT = (1.0, 0.0, 0.0, 0.0)

Pose = tuple[np.ndarray, np.ndarray]  # position m (3,) and wxyz quaternion (4,) of a frame in its parent body


def _configure(spec: mujoco.MjSpec) -> None:
    spec.modelname = "apartment"
    spec.option.timestep = TIMESTEP
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    spec.compiler.degree = False
    spec.stat.extent = 12.0
    spec.stat.center = (5.0, 4.0, 1.0)
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 960


def _in_body(frame: Pose | None, local: tuple[float, float, float] | np.ndarray) -> Pose:
    """Pose in the body of an unrotated element at `local` in `frame` (None: the body's own frame).

    Composed here rather than with an `MjsFrame`: `MjSpec.to_xml` prints an unnamed frame's pose at 6
    significant digits, and the export must reload bit-identical (see `homer_sim.home.export`)."""
    if frame is None:
        return np.array(local, dtype=np.float64), np.array(IDENTITY_QUAT)
    offset = np.zeros(3)
    mujoco.mju_rotVecQuat(offset, np.array(local, dtype=np.float64), frame[1])
    return frame[0] + offset, frame[1]


def _add_box(body: mujoco.MjsBody, name: str, box: Box, density: float | None = None,
             frame: Pose | None = None) -> mujoco.MjsGeom:
    pos, quat = _in_body(frame, box.center)
    geom = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, pos=pos, quat=quat, size=box.half, rgba=box.rgba)
    geom.friction = FURNITURE_FRICTION
    geom.condim = FURNITURE_CONDIM
    geom.solref = CONTACT_SOLREF
    if density is not None:
        geom.density = density
    return geom


def _add_floors_and_walls(spec: mujoco.MjSpec, layout: Layout) -> None:
    for room in layout.rooms:
        x0, y0, x1, y1 = room.rect
        geom = spec.worldbody.add_geom(name=f"{room.name}/floor", type=mujoco.mjtGeom.mjGEOM_BOX,
                                       pos=((x0 + x1) / 2, (y0 + y1) / 2, -0.025),
                                       size=((x1 - x0) / 2, (y1 - y0) / 2, 0.025),
                                       rgba=FLOOR_RGBA.get(room.name, (0.72, 0.62, 0.5, 1.0)))
        geom.group = FLOOR_GROUP
        geom.friction = FURNITURE_FRICTION
        geom.condim = FURNITURE_CONDIM
        geom.solref = CONTACT_SOLREF
    for k, (x0, y0, x1, y1) in enumerate(wall_segments(layout)):
        h = layout.wall_height
        spec.worldbody.add_geom(name=f"wall/{k}", type=mujoco.mjtGeom.mjGEOM_BOX,
                                pos=((x0 + x1) / 2, (y0 + y1) / 2, h / 2),
                                size=((x1 - x0) / 2, (y1 - y0) / 2, h / 2), rgba=WALL_RGBA)
    spec.worldbody.add_light(name="sun", pos=(5, 4, 6), dir=(0, 0, -1), type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)


def _add_part(spec: mujoco.MjSpec, frame: Pose, f: Furniture, part: Part) -> mujoco.MjsBody:
    """A door or drawer of `f` (posed at `frame`) hanging from the world body by its joint."""
    name = f"{f.name}/{part.name}"
    pos, quat = _in_body(frame, part.anchor)
    child = spec.worldbody.add_body(name=name, pos=pos, quat=quat)
    jtype = mujoco.mjtJoint.mjJNT_HINGE if part.joint == "hinge" else mujoco.mjtJoint.mjJNT_SLIDE
    child.add_joint(name=name, type=jtype, axis=part.axis, range=part.range, limited=True,
                    damping=part.damping, armature=0.01, frictionloss=0.05)
    volume = sum(8 * np.prod(b.half) for b in part.boxes) + 8 * np.prod(part.handle.half)
    density = part.mass / volume
    for box in part.boxes:
        _add_box(child, f"{name}/{box.name}", box, density)
    _add_box(child, f"{name}/handle", part.handle, density)
    child.add_site(name=f"{name}/handle", pos=part.handle.center, size=(0.01, 0.01, 0.01),
                   type=mujoco.mjtGeom.mjGEOM_SPHERE, rgba=(1, 0, 0, 0), group=VOLUME_GROUP)
    spec.add_exclude(bodyname1="world", bodyname2=name)  # its carcass is on the world body (see above)
    return child


def _add_furniture(spec: mujoco.MjSpec, layout: Layout, f: Furniture) -> None:
    geometry = furniture_geometry(f)
    pose = (np.array([f.pos[0], f.pos[1], base_height(layout, f)]), np.array(yaw_quat(f.yaw)))
    for box in geometry.boxes:
        _add_box(spec.worldbody, f"{f.name}/{box.name}", box, frame=pose)
    parts = {part.name: _add_part(spec, pose, f, part) for part in geometry.parts}
    for k, volume in enumerate(geometry.volumes):
        if volume.part is None:
            holder, (pos, quat) = spec.worldbody, _in_body(pose, volume.center)
        else:  # in the part's own frame
            part = next(p for p in geometry.parts if p.name == volume.part)
            holder, (pos, quat) = parts[volume.part], _in_body(None, np.array(volume.center) - np.array(part.anchor))
        holder.add_site(name=f"{f.name}/interior_{k}", type=mujoco.mjtGeom.mjGEOM_BOX, pos=pos, quat=quat,
                        size=volume.half, rgba=(0.2, 0.6, 1.0, 0.0), group=VOLUME_GROUP)


def _add_objects(spec: mujoco.MjSpec, layout: Layout) -> None:
    poses = start_poses(layout)
    for decl in layout.objects:
        pose = poses[decl.name]
        body = spec.worldbody.add_body(name=decl.name, pos=pose.pos, quat=pose.quat)
        joint = body.add_freejoint(name=decl.name)
        joint.damping = (FREE_DAMPING, 0.0, 0.0)
        add_object_geoms(spec, body, CATALOG[decl.cls], prefix=decl.name)


def build_spec(layout: Layout) -> mujoco.MjSpec:
    """The MjSpec of `layout` (not yet compiled). Call `validate_layout` first for clear errors."""
    spec = mujoco.MjSpec()
    _configure(spec)
    _add_floors_and_walls(spec, layout)
    for f in layout.furniture:
        _add_furniture(spec, layout, f)
    _add_objects(spec, layout)
    return spec
