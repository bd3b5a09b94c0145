"""The real Fetch's joint limits, typed in here on purpose (not read from ``models/`` nor from the planner).

Sources (see /work/shared/reference/fetch-kinematics.md): position range and velocity limit from the Fetch's
published ``fetch_description`` URDF (the limits its controllers enforce); acceleration from
``fetch_moveit_config/config/joint_limits.yaml``; mechanical hard stops from the Fetch mechanical spec. No jerk
limit is published: we use 10 x the acceleration limit per second (full acceleration reached in 0.1 s), the rule
recommended in the facts sheet. The tool shaft joint is the bluction tool's own servo (not part of the Fetch):
its limits are the tool's design values (+-3.2 rad, 3 rad/s, 10 rad/s^2, 100 rad/s^3).

Units: metres (torso) and radians; per second, per second squared, per second cubed. Continuous joints
(the three roll joints) have no position limit (+-inf).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

INF = math.inf

# name: (lower, upper, velocity, acceleration, jerk, hard_lower, hard_upper)
_TABLE = {
    "torso_lift_joint": (0.0, 0.38615, 0.1, 0.5, 5.0, 0.0, 0.40),
    "shoulder_pan_joint": (-1.6056, 1.6056, 1.256, 1.5, 15.0, -math.radians(92), math.radians(92)),
    "shoulder_lift_joint": (-1.221, 1.518, 1.454, 1.0, 10.0, -math.radians(70), math.radians(87)),
    "upperarm_roll_joint": (-INF, INF, 1.571, 1.5, 15.0, -INF, INF),
    "elbow_flex_joint": (-2.251, 2.251, 1.521, 1.5, 15.0, -math.radians(129), math.radians(129)),
    "forearm_roll_joint": (-INF, INF, 1.571, 1.5, 15.0, -INF, INF),
    "wrist_flex_joint": (-2.16, 2.16, 2.268, 2.5, 25.0, -math.radians(125), math.radians(125)),
    "wrist_roll_joint": (-INF, INF, 2.268, 2.5, 25.0, -INF, INF),
    "tool_shaft_joint": (-3.2, 3.2, 3.0, 10.0, 100.0, -3.2, 3.2),
}

#: The joints of an exported trajectory, in order: the Fetch's torso and arm joints as named on the real robot,
#: then the bluction tool's shaft joint.
FETCH_JOINTS = tuple(_TABLE)


@dataclasses.dataclass(frozen=True)
class FetchLimits:
    """Limits per joint of ``names`` (arrays of the same length), SI units: the real Fetch's, for the hardware
    checker.

    Independent of ``slax_drake.station.robot.JointLimits`` (the limits of the robot model the station loads, which
    the planner plans within) by design: this table is typed in from the robot's published sources, never read from
    ``models/`` nor from the station's scenario, so that a trajectory planned against a model whose limits drifted
    from the real robot's is caught before it is sent to the robot. It adds the mechanical hard stops."""

    names: tuple[str, ...]
    position_lower: np.ndarray
    position_upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    hard_lower: np.ndarray
    hard_upper: np.ndarray

    @staticmethod
    def real_fetch() -> "FetchLimits":
        cols = np.array([_TABLE[n] for n in FETCH_JOINTS], dtype=float).T
        return FetchLimits(FETCH_JOINTS, *cols)
