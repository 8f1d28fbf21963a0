"""What a grasp candidate is: `Grasp`, a grip-site pose with its `GraspKind` (a `Family` and the variant fields
that say how it was derived); the gripper's numbers the generators share; why a class cannot be picked, and
whether a failed grasp shoved its object.

A grasp is the grip site's world pose at the moment the fingers close: position (m) and rotation matrix
(shape (3, 3), columns = grip x (approach, out of the palm), y (finger travel), z). The candidates for an object's
shape come from `planners.grasps.above` (from above), `planners.grasps.shelf` (inside furniture, from its front)
and `planners.grasps.features` (grip features, rims, a pot's side handles), in the order `planners.grasps.ranking`
gives. A kind's `label` (for example "shelf-45-along-faced") names it in failure reasons and logs; no decision
reads it. No mujoco import.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from homer_sim.home.catalog import ObjectClass
from homer_sim.home.shapes import cavity
from homer_sim.robot_spec import ROBOT, RobotSpec
from planners.grasps.geometry import matrix_to_quat

MAX_WIDTH = ROBOT.max_grasp_width  # m: widest grasp (stroke 0.16 m minus a margin)
PAD_HALF = ROBOT.pad_half_length  # m: half length of a finger pad along the approach axis
SUPPORT_CLEARANCE = 0.003  # m between the fingertips and the supporting surface
GRIPPER_OPEN = ROBOT.finger_stroke  # m per finger, the gripper's stroke
SHELF_PITCHES = (0.0, math.radians(30), math.radians(45), math.radians(60), math.radians(90))  # rad below the
# horizontal of an in-furniture grasp's approach: 0 is the side grasp, 90 degrees straight down
FINGER_HALF_THICKNESS = ROBOT.finger_half_thickness  # m: half the finger links' extent across the pads' plane
TOP_DEPTH = 0.02  # m: a grasp from above holds this far below the object's top
SHELF_APPROACH = 0.05  # m: the approach onto a grasp under a shelf
TOP_MARGIN = 0.025  # m per finger between an open pad and the object before a grasp from above closes,
TOP_NARROW_MARGIN = 0.005  # m: the same where a neighbour stands too close for the wide opening
OFFSET_MARGIN = 0.005  # m between the object and the near finger of an off-centre grasp, opened wide
DISTURBED_MOVE = 0.005  # m an object must have moved for a failed grasp to count as having shoved it
DISTURBED_TURN = math.radians(3.0)  # rad: the same for a turn about the vertical


class Family(Enum):
    """How the hand meets the object."""

    TOP = "top"  # from above, the fingers closing across the object
    HANDLE = "handle"  # the grip feature on top (from above, or pitched in from a shelf's front)
    RIM = "rim"  # a container's wall at its rim (from above, or tilted in from a shelf's front)
    SIDE = "side"  # level, from the front of the furniture it stands in
    SHELF = "shelf"  # pitched down from the front of the furniture it stands in
    POT_HANDLE = "pot-handle"  # a pot's flat side handle


@dataclass(frozen=True)
class GraspKind:
    """A grasp's family and how it was derived; two grasps of one kind differ only in their pose."""

    family: Family
    pitch: int | None = None  # degrees below the horizontal of an approach from a furniture's front (shelf,
    # handle and rim grasps from the front, pot handles); None from straight above or level from the side
    turned: bool = False  # (from above) the fingers close along the object's long side, a quarter turned
    narrow: bool = False  # (from above) opened only TOP_NARROW_MARGIN past the object
    high: bool = False  # (side) held at the higher of the side grasp heights
    slant: int = 0  # (side, round objects) degrees off the furniture's front normal
    aside: bool = False  # (shelf) moved along the front, the palm clear of a neighbour in front
    along: bool = False  # (shelf) the fingers closing front to back in the approach's vertical plane
    roll: int = 0  # (shelf, straight down) leaning aside about the finger travel: +1 or -1
    faced: bool = False  # square to the face of an object standing turned, not to the furniture's front
    halfway: bool = False  # (side) halfway between the furniture's front and the face of a turned object
    squared: bool = False  # (from above, in a drawer) the palm turned square to the drawer's walls
    raised: bool = False  # (from above) raised until the pads hold only the object's top
    offset: int = 0  # (from above) off the object's centre along the finger travel, the fingers open wide: +1 or -1

    @property
    def label(self) -> str:
        """The kind's name in failure reasons and logs, e.g. "top-turned-narrow", "shelf-90-rolled+-faced"."""
        parts = [self.family.value]
        parts += [] if self.pitch is None else [f"-{self.pitch}"]
        parts += [f"-rolled{_sign(self.roll)}"] if self.roll else []
        flags = (("turned", self.turned), ("high", self.high), ("aside", self.aside), ("along", self.along),
                 ("narrow", self.narrow), ("squared", self.squared), ("raised", self.raised))
        parts += [f"-{name}" for name, on in flags if on]
        parts += [f"{self.slant:+d}"] if self.slant else []
        parts += ["-faced"] * self.faced + ["-halfway"] * self.halfway
        parts += [f"-offset{_sign(self.offset)}"] if self.offset else []
        return "".join(parts)

    def __str__(self) -> str:
        return self.label


def _sign(value: int) -> str:
    return "+" if value > 0 else "-"


@dataclass(frozen=True)
class Grasp:
    """A grip-site pose in world coordinates, the finger opening before closing (m per finger), its kind, the
    approach and the least lift."""

    position: np.ndarray
    rotation: np.ndarray
    pre_opening: float
    kind: GraspKind
    approach: float = 0.12  # m the gripper travels along its x axis onto the grasp (short inside furniture)
    lift: float = 0.0  # m the hand rises at least in all after closing (the last upward leg lengthened; out
    # of a drawer, past its front)
    hang: bool = False  # lifted, the hand turns about its z axis until the object hangs (see `hang_rotation`)

    @property
    def label(self) -> str:
        """The kind's label (see `GraspKind.label`)."""
        return self.kind.label

    def quat(self) -> np.ndarray:
        """The rotation as a unit wxyz quaternion."""
        return matrix_to_quat(self.rotation)


def ungraspable_reason(cls: ObjectClass, robot: RobotSpec = ROBOT) -> str | None:
    """Why the gripper of `robot` cannot pick this class from a surface, or None if it can."""
    sx, sy, sz = cls.size
    widest, thinnest = robot.max_grasp_width, robot.min_grasp_height
    if sz < thinnest:
        return f"flat, {sz * 1000:.0f} mm thin: thinner than {thinnest * 1000:.0f} mm"
    if cls.is_container:
        return None if cavity(cls) is not None else "container without a cavity"
    if cls.handle is not None:  # taken by its grip feature
        width = min(cls.handle[:2])
        return None if width <= widest else f"its {width * 100:.0f} cm handle is wider than the grasp"
    if min(sx, sy) > widest:
        return f"{min(sx, sy) * 100:.0f} cm across its narrow side, wider than the {widest * 100:.0f} cm grasp"
    return None


def disturbed(position: np.ndarray, quat: np.ndarray, now: np.ndarray, quat_now: np.ndarray) -> bool:
    """Whether an object that stood at `position` (m) turned `quat` (wxyz) and now stands at `now` turned
    `quat_now` has moved more than DISTURBED_MOVE or turned more than DISTURBED_TURN about the vertical: grasps
    planned for where it stood would pinch it off centre (a failed side grasp turns a box between the pads)."""
    turn = 2.0 * (math.atan2(quat_now[3], quat_now[0]) - math.atan2(quat[3], quat[0]))
    turn = abs(math.remainder(turn, 2.0 * math.pi))
    return bool(np.linalg.norm(np.asarray(now) - np.asarray(position)) > DISTURBED_MOVE or turn > DISTURBED_TURN)
