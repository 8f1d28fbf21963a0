"""Grasps by a grip feature or a rim: the handle on top of an object (from above, or pitched in from a shelf's
front), rim pinches of open containers (from above, or tilted in from a shelf's front) and a pot's side handles;
and for a container held at one point, how far the hand rises and how it turns until the object hangs. No mujoco
import.
"""

from __future__ import annotations

import math

import numpy as np

from homer_sim.home.catalog import ObjectClass
from homer_sim.home.shapes import WALL_THICKNESS, handle_boxes
from planners.grasps.candidate import (
    FINGER_HALF_THICKNESS,
    GRIPPER_OPEN,
    MAX_WIDTH,
    PAD_HALF,
    SHELF_APPROACH,
    SHELF_PITCHES,
    SUPPORT_CLEARANCE,
    TOP_DEPTH,
    TOP_MARGIN,
    TOP_NARROW_MARGIN,
    Family,
    Grasp,
    GraspKind,
)
from planners.grasps.geometry import box_extent, shelf_frame, top_rotation

HANDLE_APPROACH = 0.06  # m: the approach onto a handle from above (nothing else stands as high)
RIM_DEPTH = 0.015  # m below the rim of the grip site of a rim pinch (a flared wall leans away lower down)
RIM_DEEP = PAD_HALF + 0.003  # m: the same on a straight wall: the pads' whole length on it, their top ends
# 3 mm under the rim (the palm 7 mm above it)
RIM_CLEARANCE = 0.03  # m the hand rises a straight-walled container's far bottom edge above its support
POT_HANDLE_FACING = math.radians(60.0)  # rad: a pot's side handle is taken from the front when it points at
# most this far off the furniture's front normal
POT_HANDLE_GAP = 0.003  # m between the pads' inner ends and the pot's wall
POT_HANDLE_MARGIN = 0.015  # m per finger between an open pad and the handle plate
POT_HANDLE_PITCHES = (math.radians(30.0), math.radians(45.0), math.radians(60.0))  # rad below the horizontal
HANG_RISE = 0.15  # m a hung object's centre is to end above where it stood (its drop as it swings added)
RIM_TURNS = tuple(math.radians(a) for a in (0.0, 30.0, -30.0, 60.0, -60.0, 90.0, -90.0))  # rad off the rim point
# nearest the robot of the rim pinches tried, the first RIM_POINTS clear of a side handle
RIM_POINTS = 3
RIM_OPENING = 0.03  # m per finger a rim pinch opens
FINGER_HALF_TRAVEL = 0.005  # m: half a finger link's extent along the finger travel
HANDLE_MARGIN = 0.005  # m a rim pinch's fingers keep clear of a pot's side handle


def handle_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray,
                  outward: np.ndarray | None = None) -> list[Grasp]:
    """Grasps of the grip feature on top of an upright object of a class with one (`ObjectClass.handle`), at
    `position` (m, body centre) with body `quat` (wxyz), best first. The fingertips stop SUPPORT_CLEARANCE
    above the body under the feature.

    On an open top (`outward` None): from straight above, the fingers closing across the feature's width, open
    TOP_MARGIN past it, then TOP_NARROW_MARGIN; a square feature (a tie) also turned a quarter. Inside furniture
    (`outward`, a horizontal unit vector out of its front, shape (2,) or (3,)): approached SHELF_PITCHES down
    against `outward` (not level: the hand must come over the body), the fingers closing along the front.
    """
    length, width, height = cls.handle
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    top = position[2] + cls.size[2] / 2
    if outward is None:
        centre = np.array([position[0], position[1], max(top - TOP_DEPTH, top - height + PAD_HALF + SUPPORT_CLEARANCE)])
        turns = ((0.0, width), (math.pi / 2, length)) if length <= MAX_WIDTH else ((0.0, width),)
        return [Grasp(centre, top_rotation(yaw + math.pi / 2 + turn), min(GRIPPER_OPEN, span / 2 + margin),
                      GraspKind(Family.HANDLE, turned=bool(turn), narrow=narrow), HANDLE_APPROACH)
                for margin, narrow in ((TOP_MARGIN, False), (TOP_NARROW_MARGIN, True)) for turn, span in turns]
    out, across, _ = shelf_frame(outward, quat)
    span = box_extent(across, length, width, yaw)  # the feature's extent along the front
    if span > MAX_WIDTH:
        return []
    grasps = []
    for pitch in SHELF_PITCHES[1:]:
        x = math.cos(pitch) * -out + np.array([0.0, 0.0, -math.sin(pitch)])
        tip_drop = PAD_HALF * math.sin(pitch) + FINGER_HALF_THICKNESS * math.cos(pitch)
        z = max(top - TOP_DEPTH, top - height + tip_drop + SUPPORT_CLEARANCE)
        kind = GraspKind(Family.HANDLE, pitch=round(math.degrees(pitch)))
        grasps.append(Grasp(np.array([position[0], position[1], z]), np.column_stack([x, across, np.cross(x, across)]),
                            min(GRIPPER_OPEN, span / 2 + TOP_MARGIN), kind, SHELF_APPROACH))
    return grasps


def _at_a_handle(hollow, handles, radial: np.ndarray) -> bool:
    """Whether the fingers of a rim pinch at the rim point in body-frame horizontal direction `radial` (unit,
    shape (2,)), closing along it, come within HANDLE_MARGIN of one of `handles` (body-frame (centre, half
    extents) boxes, `homer_sim.home.shapes.handle_boxes`) seen from above: a pot's side handles lie just under
    its rim, where the pads go down beside the wall, and the outer finger lands on the handle plate."""
    point = np.asarray(hollow.center_xy) + radial * (hollow.rim_radius + 0.004)
    tangent = np.array([-radial[1], radial[0]])
    reach = RIM_OPENING + FINGER_HALF_TRAVEL  # from the rim point to either finger's far face
    for centre, half in handles:
        apart = np.asarray(centre[:2]) - point
        # separating axes of two rectangles: the fingers' footprint (radial, tangent) and the handle's (x, y)
        if abs(apart @ radial) > reach + abs(half[0] * radial[0]) + abs(half[1] * radial[1]) + HANDLE_MARGIN:
            continue
        if abs(apart @ tangent) > FINGER_HALF_THICKNESS + abs(half[0] * tangent[0]) + abs(half[1] * tangent[1]) \
                + HANDLE_MARGIN:
            continue
        if abs(apart[0]) > half[0] + reach * abs(radial[0]) + FINGER_HALF_THICKNESS * abs(tangent[0]) + HANDLE_MARGIN:
            continue
        if abs(apart[1]) > half[1] + reach * abs(radial[1]) + FINGER_HALF_THICKNESS * abs(tangent[1]) + HANDLE_MARGIN:
            continue
        return True
    return False


def tilted_rims(hollow, position: np.ndarray, yaw: float, support: float, out: np.ndarray,
                handles=()) -> list[Grasp]:
    """Pinches of a wide container's front rim from the compartment's front, pitched down SHELF_PITCHES (not
    horizontal), the fingers closing across the wall along the outward direction; none where a side handle
    (`handles`, body-frame boxes) lies at the front rim (see `_at_a_handle`)."""
    c, s = math.cos(yaw), math.sin(yaw)
    if _at_a_handle(hollow, handles, np.array([c * out[0] + s * out[1], -s * out[0] + c * out[1]])):
        return []
    centre = position[:2] + np.array([c * hollow.center_xy[0] - s * hollow.center_xy[1],
                                      s * hollow.center_xy[0] + c * hollow.center_xy[1]])
    rim_z = position[2] + hollow.rim_z
    across = np.array([-out[1], out[0], 0.0])
    grasps = []
    for pitch in SHELF_PITCHES[:0:-1]:
        x = math.cos(pitch) * -out + np.array([0.0, 0.0, -math.sin(pitch)])
        y = np.cross(across, x)  # in the vertical plane of the approach, pointing out of the compartment
        xy = centre + out[:2] * (hollow.rim_radius + 0.004)
        z = max(rim_z - 0.015, support + PAD_HALF + SUPPORT_CLEARANCE)
        grasps.append(Grasp(np.array([xy[0], xy[1], z]), np.column_stack([x, y, np.cross(x, y)]), RIM_OPENING,
                            GraspKind(Family.RIM, pitch=round(math.degrees(pitch))), SHELF_APPROACH))
    return grasps


def rim_grasps(hollow, position: np.ndarray, yaw: float, support: float, robot_xy: np.ndarray,
               handles=()) -> list[Grasp]:
    """Pinches of a container's wall at the rim, the fingers closing radially: the rim point nearest the robot
    at `robot_xy` first, then 30 degrees either side; a point where the fingers would meet a side handle
    (`handles`, body-frame boxes, see `_at_a_handle`) is skipped for the next of RIM_TURNS, 60 then 90 degrees
    aside, up to RIM_POINTS pinches. A straight wall (a bin) is pinched RIM_DEEP at the rim
    point farthest from the robot instead: held at one point of its rim, the container's weight tilts it about
    the tangent there (a 44 cm bin some 20 degrees, its far side on the floor after a 15 cm lift) and keeps it
    creeping round in the pads while its centre of mass is off to the side (4-5 mm in 3 s); so the hand rises
    `rim_lift` (the lowest edge clears the floor; at least `hang_lift`) and turns towards where the container
    would hang (`hang`, see `hang_rotation`), its bottom swinging away from the robot (from the near rim it
    swings onto the robot's base). Seen in the grasp suite: the 44 cm bin turns only part of the way, the pads
    turn about its wall and jam it (slip under 1 mm). Its near rim is pinched last, not hung (it tilts about the
    pinch, bottom towards the robot): for a bin whose far rim the arm cannot reach (in the middle of a bed)."""
    c, s = math.cos(yaw), math.sin(yaw)
    centre = position[:2] + np.array([c * hollow.center_xy[0] - s * hollow.center_xy[1],
                                      s * hollow.center_xy[0] + c * hollow.center_xy[1]])
    toward = math.atan2(robot_xy[1] - centre[1], robot_xy[0] - centre[0])
    rim_z = position[2] + hollow.rim_z
    straight = _straight(hollow)
    z = max(rim_z - (RIM_DEEP if straight else RIM_DEPTH), support + PAD_HALF + SUPPORT_CLEARANCE)
    lift = 0.0
    if straight:  # the grip site lies rim_radius out and z - position[2] up from the body centre
        lift = max(rim_lift(hollow, rim_z - support, rim_z - z),
                   hang_lift(np.array([hollow.rim_radius + 0.004, 0.0, z - position[2]])))
    grasps = []
    for side in (math.pi, 0.0) if straight else (0.0,):  # a bin's far rim, then its near one
        points = 0
        for delta in RIM_TURNS:
            angle = toward + side + delta
            if points == RIM_POINTS or _at_a_handle(hollow, handles, np.array([math.cos(angle - yaw),
                                                                               math.sin(angle - yaw)])):
                continue
            radial = np.array([math.cos(angle), math.sin(angle)])
            xy = centre + radial * (hollow.rim_radius + 0.004)
            grasps.append(Grasp(np.array([xy[0], xy[1], z]), top_rotation(angle), RIM_OPENING,
                                GraspKind(Family.RIM), lift=lift, hang=side != 0.0))
            points += 1
    return grasps


def _straight(hollow) -> bool:
    """Whether a container's inner wall is vertical (as wide at the floor as at the rim)."""
    return abs(hollow.floor_radius - hollow.rim_radius) < 1e-6


def rim_lift(hollow, height: float, depth: float) -> float:
    """How far (m) the hand must rise after pinching a straight-walled container of `height` m at `depth` m
    below its rim so that, whatever it tilts about the pinch, its far bottom edge stays RIM_CLEARANCE above
    the support: the grip site ends the edge's distance from it (the wall's diameter by its height) above."""
    far = math.hypot(2.0 * hollow.rim_radius, height - depth)
    return float(far + RIM_CLEARANCE - (height - depth))


def hang_lift(offset: np.ndarray) -> float:
    """How far (m) the hand must rise so that an object gripped `offset` (m, shape (3,)) from its centre ends
    with its centre HANG_RISE above where it stood once it hangs straight below the grip site."""
    return float(HANG_RISE + np.linalg.norm(offset) - offset[2])


def hang_rotation(rotation: np.ndarray, grip: np.ndarray, com: np.ndarray) -> np.ndarray:
    """The grip rotation (shape (3, 3)) turned about the grip site, by the least turn (about a horizontal axis),
    until a held object's centre of mass `com` (m, shape (3,)) lies straight below the grip site `grip` (m,
    shape (3,)), the object turning with the hand: then its weight pulls through the grasp instead of twisting
    it (a rim pinch's pads hold that twist only while they creep)."""
    v = (com - grip) / np.linalg.norm(com - grip)
    down = np.array([0.0, 0.0, -1.0])
    axis = np.cross(v, down)
    sin, cos = float(np.linalg.norm(axis)), float(v @ down)
    if sin < 1e-9:
        return rotation.copy()
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]]) / sin
    turn = np.eye(3) + sin * k + (1.0 - cos) * k @ k  # Rodrigues
    return turn @ rotation


def pot_handle_grasps(cls: ObjectClass, position: np.ndarray, quat: np.ndarray, outward: np.ndarray) -> list[Grasp]:
    """Grasps of an upright pot at `position` (m, body centre; body `quat`, wxyz) by a flat side handle (see
    `homer_sim.home.shapes.handle_boxes`) pointing within POT_HANDLE_FACING of horizontal unit `outward` (shape (3,),
    out of the furniture's front), along the handle towards the pot: first level, the fingers closing
    vertically on the plate (the pads' length along it); then pitched POT_HANDLE_PITCHES down, the fingers
    closing across the plate's width on its side faces (a level hand that low is often out of the arm's reach
    from a base pose clear of the cabinet). The pads end POT_HANDLE_GAP short of the wall. Lifted, the hand
    turns until the pot hangs (`hang`): a 1.5 kg pot held 13 cm out twists in the pads."""
    yaw = 2.0 * math.atan2(quat[3], quat[0])
    c, s = math.cos(yaw), math.sin(yaw)
    body = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    up = np.array([0.0, 0.0, 1.0])
    grasps = []
    for centre, half in handle_boxes(cls):
        h = body @ np.array([math.copysign(1.0, centre[0]), 0.0, 0.0])  # horizontal, out along the handle
        if float(h @ outward) < math.cos(POT_HANDLE_FACING):
            continue
        face = abs(centre[0]) - half[0] + WALL_THICKNESS[cls.family]  # m from the axis: the wall's outer face
        for pitch in (0.0, *POT_HANDLE_PITCHES):
            x = -math.cos(pitch) * h - math.sin(pitch) * up
            y = up if pitch == 0.0 else np.cross(up, h)
            # the grip site: the pads' low inner end POT_HANDLE_GAP off the wall, at least half of them on the plate
            along = min(face + POT_HANDLE_GAP + PAD_HALF * math.cos(pitch), abs(centre[0]) + half[0])
            offset = body @ np.array([0.0, centre[1], centre[2]]) + h * along  # from the body centre
            opening = (half[2] if pitch == 0.0 else half[1]) + POT_HANDLE_MARGIN
            kind = GraspKind(Family.POT_HANDLE, pitch=round(math.degrees(pitch)))
            grasps.append(Grasp(position + offset, np.column_stack([x, y, np.cross(x, y)]), opening, kind,
                                SHELF_APPROACH, lift=hang_lift(offset), hang=True))
    return grasps
