"""The Fetch + bluction tool model as data: file locations, the planned joints in order, tool frames and limits.

The shipped model is ``models/fetch_bluction.urdf`` (package ``slax_drake_models``, see ``models/package.xml``);
which file a station loads is named only by its scenario's model directives (``sim_configs/station_*.yaml``),
and every plant of the robot is built from them by ``slax_drake.station.plant.make_station_plant``. A robot file
must have the joints and frames named here. The planner drives nine joints, in this order (``PLANNED_JOINTS``): the torso lift (metres), the seven arm joints and
the tool shaft (radians). The head's pan and tilt are actuated too but held still by the station.

Tool frames (all on the model, names of ``plant.GetFrameByName``):

- ``camera_optical_frame``: the L515's optical frame C (z along the optical axis, x right, y down in the image).
- ``cup_tip_frame``: centre of the suction cup's lip, x along the cup axis pointing away from the tool.
- ``blade_face_frame``: centre of the 0.065 x 0.075 m blade, which lies in its x-z plane (faces normal to +-y).
  At ``tool_shaft_joint`` = 0 the blade hangs below the tube (pushing); at pi it stands above it (suction).

Limits: position, velocity, acceleration and effort from the loaded robot model, jerk from
``models/fetch_bluction_limits.yaml`` (our documented choice; none is published for Fetch).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from slax_drake.config import REPO_ROOT

MODELS_DIR = REPO_ROOT / "models"
PACKAGE_XML = MODELS_DIR / "package.xml"
PACKAGE_NAME = "slax_drake_models"
LIMITS_YAML = MODELS_DIR / "fetch_bluction_limits.yaml"

PLANNED_JOINTS = (
    "torso_lift_joint",
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
    "tool_shaft_joint",
)
HEAD_JOINTS = ("head_pan_joint", "head_tilt_joint")

CAMERA_FRAME = "camera_optical_frame"
CUP_TIP_FRAME = "cup_tip_frame"
BLADE_FACE_FRAME = "blade_face_frame"
TOOL_BODY = "tool_shaft_link"
BASE_BODY = "base_link"

# Tool shaft angles (radians): blade below the tube, edge-on to the camera (push and imaging); blade up (suction).
SHAFT_BLADE_DOWN = 0.0
SHAFT_BLADE_UP = np.pi

# Tuck pose of the facts sheet: torso 0.05 m, arm [1.32, 1.40, -0.2, 1.72, 0.0, 1.66, 0.0], shaft 0.
TUCK_CONFIGURATION = (0.05, 1.32, 1.40, -0.2, 1.72, 0.0, 1.66, 0.0, 0.0)


@dataclasses.dataclass(frozen=True)
class JointLimits:
    """Per-joint limits of ``PLANNED_JOINTS`` as arrays of 9 (SI units; continuous joints: +-inf position): the
    limits of the robot model the station loads, which the planner plans and times within.

    Not to be merged with ``slax_drake.hardware.fetch_limits.FetchLimits``: that table is the real Fetch's, typed in
    independently on purpose, so that the hardware checker catches a model whose limits drifted from the robot's.
    """

    names: tuple[str, ...]
    position_lower: np.ndarray
    position_upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    effort: np.ndarray


def add_package(parser) -> None:
    """Registers ``package://slax_drake_models`` with a Drake Parser."""
    if not parser.package_map().Contains(PACKAGE_NAME):
        parser.package_map().AddPackageXml(str(PACKAGE_XML))


def planned_joint_indices(plant, model_instance=None) -> np.ndarray:
    """Positions of ``PLANNED_JOINTS`` in the plant's generalized position vector q."""
    if model_instance is None:
        return np.array([plant.GetJointByName(n).position_start() for n in PLANNED_JOINTS])
    return np.array([plant.GetJointByName(n, model_instance).position_start() for n in PLANNED_JOINTS])


def joint_limits(plant) -> JointLimits:
    """Limits of ``PLANNED_JOINTS`` of the robot in ``plant`` (a finalized plant holding the robot once, e.g. the
    station's controller plant, ``slax_drake.station.plant.station_joint_limits``): position, velocity,
    acceleration (``drake:acceleration``) and effort from the parsed model, jerk from the limits YAML."""
    from pydrake.common.yaml import yaml_load

    lower, upper, vel, acc, eff = [], [], [], [], []
    for name in PLANNED_JOINTS:
        joint = plant.GetJointByName(name)
        lower.append(joint.position_lower_limits()[0])
        upper.append(joint.position_upper_limits()[0])
        vel.append(joint.velocity_upper_limits()[0])
        acc.append(joint.acceleration_upper_limits()[0])
        actuator = next(
            plant.get_joint_actuator(i) for i in plant.GetJointActuatorIndices() if plant.get_joint_actuator(i).joint().name() == name
        )
        eff.append(actuator.effort_limit())
    data = yaml_load(filename=str(LIMITS_YAML))
    return JointLimits(
        names=PLANNED_JOINTS,
        position_lower=np.array(lower),
        position_upper=np.array(upper),
        velocity=np.array(vel),
        acceleration=np.array(acc),
        jerk=np.array([float(data["jerk"][n]) for n in PLANNED_JOINTS]),
        effort=np.array(eff),
    )


def model_path(name: str) -> Path:
    """The file of a model in ``models/``."""
    return MODELS_DIR / name
