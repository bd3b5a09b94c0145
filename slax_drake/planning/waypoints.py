"""Cartesian tool waypoints of a bluction action, in the shelf frame S (x right, y into the shelf, z up; m).

A motion leaves the observation pose (the blade hanging below the tube, edge-on, out of the camera's view),
moves in free space to the first waypoint, follows straight tool segments through the rest, and returns in
free space to the observation pose. Each waypoint names the tool frame it places, its pose X_SF, the shaft
angle, whether the segment *arriving* at it may touch the manipulated object (``contact``) and the suction
command from it on.

Push (q, d) of ``slax_drake.policies.actions``: q = (x of the blade lane's centre, y of the blade's tip,
blade_height / 2). The blade (``blade_face_frame``, its faces normal to S x, hanging below the tube, the tube
pointing along S +y) goes ``PUSH_STANDOFF`` beside the object's extreme x (so that the 3 cm tube above the blade
clears a tall object) instead of the lane's centre, and pushes d + standoff, so the object moves by d: pre-approach in front of the opening (``APPROACH_MARGIN``), insert along +y to the tip
depth, push d + standoff along x, back off the standoff, retract along -y.

Suction (q, d_x, d_z): q = the contact point on the camera-facing side. The blade is turned up
(``SHAFT_BLADE_UP``), the cup (``cup_tip_frame``, its axis along S +y) approaches to 1 cm before the face,
seals (suction on, pressing ``SEAL_PRESS`` in), lifts ``LIFT`` (about 1 cm), pulls the object out of the shelf
toward the camera, translates d_x, pushes in until the object's centre is at y = d_z, lowers, releases
(suction off), backs off and retracts.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slax_drake.policies.actions import Push, Suction, ToolConfig
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import SceneObject, Shelf
from slax_drake.systems import robot as robot_model

APPROACH_MARGIN = 0.05  # the tool's tip this far in front of the opening before entering (m)
BLADE_HALF_LENGTH = 0.0325  # blade_face_frame to the blade's tip along the tube (m, URDF)
BLADE_HALF_THICKNESS = 0.002  # m (URDF)
TUBE_RADIUS = 0.015  # m (URDF); the tube runs along the blade's upper edge, centred on the blade's plane
PUSH_STANDOFF = TUBE_RADIUS + 0.004 - BLADE_HALF_THICKNESS  # blade face to the object's extreme (m): the tube clears it
BLADE_LIFT = 0.008  # blade's lower edge above the support surface (m)
SEAL_PRESS = 0.001  # cup pressed this far into the face (m)
CUP_STANDOFF = 0.01  # m before the face, then the cup moves in with suction on
LIFT = 0.01  # m
OUT_MARGIN = 0.01  # the carried object's back this far in front of the opening (m)
RELEASE_BACKOFF = 0.02  # m
DWELL = 0.3  # s at rest after sealing and after releasing


def push_rotation() -> np.ndarray:
    """R_SB of ``blade_face_frame`` when pushing: tube (x) along S +y, face normal (y) along S -x, z up."""
    return np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def suction_rotation() -> np.ndarray:
    """R_SC of ``cup_tip_frame`` with the blade up: cup axis (x) along S +y, y along S +x, z down."""
    return np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


@dataclasses.dataclass(frozen=True)
class ToolWaypoint:
    """A tool pose to pass through: ``frame`` at X_SF (4x4, shelf frame), the shaft angle (rad)."""

    label: str
    frame: str
    X_SF: np.ndarray
    shaft: float
    contact: bool = False  # the segment arriving here may touch the manipulated object
    suction: bool = False  # the suction command while moving to this waypoint and during its dwell
    dwell: float = 0.0  # seconds at rest on arrival

    @property
    def position(self) -> np.ndarray:
        return self.X_SF[:3, 3]


def _pose(R: np.ndarray, p) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = p
    return X


def action_waypoints(action, objects: tuple[SceneObject, ...], shelf: Shelf, tool: ToolConfig = ToolConfig()):
    """The tool waypoints of ``action`` (Push or Suction) on the objects as they stand."""
    obj = next((o for o in objects if o.name == action.name), None)
    if obj is None:
        raise ValueError(f"no object named {action.name!r}")
    y_open = -shelf.depth / 2.0
    if isinstance(action, Push):
        sign = 1.0 if action.d > 0 else -1.0
        edge = action.q[0] + sign * tool.blade_width / 2.0
        x = edge - sign * (BLADE_HALF_THICKNESS + PUSH_STANDOFF)
        y = action.q[1] - BLADE_HALF_LENGTH
        z = tool.blade_height / 2.0 + BLADE_LIFT
        y_pre = y_open - APPROACH_MARGIN - BLADE_HALF_LENGTH
        x_end = x + action.d + sign * PUSH_STANDOFF
        R, f, s = push_rotation(), robot_model.BLADE_FACE_FRAME, robot_model.SHAFT_BLADE_DOWN
        return [
            ToolWaypoint("pre-approach", f, _pose(R, (x, y_pre, z)), s),
            ToolWaypoint("insert", f, _pose(R, (x, y, z)), s),
            ToolWaypoint("push", f, _pose(R, (x_end, y, z)), s, contact=True),
            ToolWaypoint("back off", f, _pose(R, (x_end - sign * PUSH_STANDOFF, y, z)), s, contact=True),
            ToolWaypoint("retract", f, _pose(R, (x_end - sign * PUSH_STANDOFF, y_pre, z)), s, contact=True),
        ]
    if isinstance(action, Suction):
        cx, cy, cz = action.q
        _, ey = Footprint.of(obj).extents()
        oy = float(obj.center[1])
        y_out = cy + (y_open - ey - OUT_MARGIN - oy)  # cup y when the object's back is out of the shelf
        y_place = cy + (action.dz - oy)
        y_pre = y_open - APPROACH_MARGIN
        x2 = cx + action.dx
        R, f, s = suction_rotation(), robot_model.CUP_TIP_FRAME, robot_model.SHAFT_BLADE_UP
        return [
            ToolWaypoint("pre-approach", f, _pose(R, (cx, y_pre, cz)), s),
            ToolWaypoint("approach", f, _pose(R, (cx, cy - CUP_STANDOFF, cz)), s),
            ToolWaypoint("seal", f, _pose(R, (cx, cy + SEAL_PRESS, cz)), s, contact=True, suction=True, dwell=DWELL),
            ToolWaypoint("lift", f, _pose(R, (cx, cy + SEAL_PRESS, cz + LIFT)), s, contact=True, suction=True),
            ToolWaypoint("pull out", f, _pose(R, (cx, min(y_out, y_pre), cz + LIFT)), s, contact=True, suction=True),
            ToolWaypoint("translate", f, _pose(R, (x2, min(y_out, y_pre), cz + LIFT)), s, contact=True, suction=True),
            ToolWaypoint("push in", f, _pose(R, (x2, y_place + SEAL_PRESS, cz + LIFT)), s, contact=True, suction=True),
            ToolWaypoint("lower", f, _pose(R, (x2, y_place + SEAL_PRESS, cz)), s, contact=True, suction=True),
            ToolWaypoint("release", f, _pose(R, (x2, y_place + SEAL_PRESS, cz)), s, contact=True, dwell=DWELL),
            ToolWaypoint("back off", f, _pose(R, (x2, y_place - RELEASE_BACKOFF, cz)), s, contact=True),
            ToolWaypoint("retract", f, _pose(R, (x2, y_pre, cz)), s, contact=True),
        ]
    raise TypeError(f"not an action: {action!r}")
