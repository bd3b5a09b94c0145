"""The station scenario: a typed dataclass (loaded with ``yaml_load_typed``) holding the model directives, the
plant configuration, the observation configuration of the arm, the head's pose and the suction cup's parameters
and limits.

Shelf placement. The paper keeps camera and shelf static relative to each other in one observation
configuration of the arm. The scenario's ``observation_configuration`` is that configuration; the shelf frame S
is welded to the world at X_WS = X_WC(q_obs) * inv(X_SC), with X_SC the scene camera's pose, so that at q_obs
the tool camera's frame is exactly the scene's X_SC (``slax_drake.station.plant.shelf_pose``, computed on the
robot of the directives; it rejects with ConfigError a configuration whose camera is not level).
"""

# No `from __future__ import annotations`: yaml_load_typed needs the real types of the fields.
import dataclasses
import functools
import math
import typing
from pathlib import Path

import numpy as np
from pydrake.multibody.parsing import ModelDirective
from pydrake.multibody.plant import MultibodyPlantConfig

from slax_drake.config import REPO_ROOT
from slax_drake.errors import ConfigError
from slax_drake.scene.camera import Camera
from slax_drake.station import DEFAULT_STATION, robot as robot_model  # noqa: F401  (DEFAULT_STATION re-exported)

@dataclasses.dataclass
class SuctionParameters:
    """Suction cup parameters (SI units). Defaults: a 0.03 m cup, 60 kPa vacuum, 5 mm reach, 30 deg cone."""

    vacuum_pressure: float = 60000.0
    cup_radius: float = 0.015
    max_distance: float = 0.005
    max_angle_deg: float = 30.0
    # The planning limit of this cup, not a force-element parameter: the planner suctions no object whose weight
    # times the horizontal distance from the cup's contact to its centre exceeds this (N m). inf: no limit.
    max_held_moment: float = math.inf
    # Likewise: the planner seals on no box face turned more than this (deg) from the tube's axis. 90: no limit.
    max_seal_angle_deg: float = 90.0

    @property
    def max_force(self) -> float:
        """The largest pull (N): vacuum pressure times cup area (60 kPa on a 15 mm radius: 42.4 N)."""
        return self.vacuum_pressure * math.pi * self.cup_radius**2

    @property
    def lip_moment(self) -> float:
        """The moment (N m) the sealed cup resists before its lip peels: the pull acting at the rim's radius, about
        the rim point opposite (42.4 N x 15 mm = 0.64 N m). ``max_held_moment`` keeps a margin below it."""
        return self.max_force * self.cup_radius


SHELF_BODY = "shelf_body"


def _default_plant_config():
    return MultibodyPlantConfig(time_step=0.005, contact_model="point", discrete_contact_approximation="lagged")


PUSH_TURNS = ("none", "quasi-static")  # the action model's push_turn rule's values (slax_drake.shelf.rules)


@dataclasses.dataclass
class StationScenario:
    """A station: the scene scenario it serves, the model directives and the plant, control and camera settings.

    ``directives`` must add the robot as model ``robot_model`` (welded to the world by an ``add_weld`` from
    ``world``) and the shelf as model ``shelf_model`` (not welded: the station places it from the camera).
    ``observation_configuration`` maps every name of ``PLANNED_JOINTS`` to its value at the observation pose.
    """

    scene_config: str = "sim_configs/sim_shelf.yaml"
    directives: typing.List[ModelDirective] = dataclasses.field(default_factory=list)
    plant_config: MultibodyPlantConfig = dataclasses.field(default_factory=_default_plant_config)
    robot_model: str = "fetch"
    shelf_model: str = "shelf"
    observation_configuration: typing.Dict[str, float] = dataclasses.field(default_factory=dict)
    head_configuration: typing.Dict[str, float] = dataclasses.field(default_factory=dict)
    suction: SuctionParameters = dataclasses.field(default_factory=SuctionParameters)
    camera: bool = True
    # The station's reach map (models/reach/*.json, slax_drake.planning.reach), "" for none: the action model's
    # reach_map rule in Drake trials on this station (slax_drake.shelf.reach).
    reach_map: str = ""
    # A guarded push-in (suction_hidden_rule=guarded) stops when the force resisting the push, estimated from the
    # joint efforts (slax_drake.systems.guard), exceeds this (N).
    guarded_stop_force: float = 5.0
    # Whether this station's arm moves a carried object into space its camera cannot see as a guarded move (stops
    # on the contact its joint efforts sense, slax_drake.systems.guard): when true, trials and plan-step on it plan
    # with suction_hidden_rule=guarded (systems.trial.station_tool_rules), which a --tool-rule overrides.
    guarded_placement: bool = False
    # How a push moves a box on this station (the action model's push_turn rule in trials on it): "quasi-static",
    # it turns as a box standing on its corners does under the blade (slax_drake.shelf.pushing); "none", it
    # translates (the paper's first-order model).
    push_turn: str = "none"
    # How far the tool gives way along a push per newton that the pushed object resists with (m/N): the arm's
    # joint servos hold the commanded pose against a load only up to an error that grows with it, so a push ends
    # short by about this times the object's sliding friction, and the planner pushes that much farther
    # (slax_drake.planning.waypoints.push_give). 0: a stiff arm.
    push_compliance: float = 0.0


def load_station_scenario(path: str | Path = DEFAULT_STATION) -> StationScenario:
    """Reads a station YAML; raises ConfigError naming the file on a missing file or a bad key/value."""
    from pydrake.common.yaml import yaml_load_typed

    path = Path(path)
    if not path.is_file() and not path.is_absolute() and (REPO_ROOT / path).is_file():
        path = REPO_ROOT / path
    if not path.is_file():
        raise ConfigError(f"{path}: no such station file")
    try:
        scenario = yaml_load_typed(schema=StationScenario, filename=str(path), defaults=StationScenario())
    except Exception as e:
        raise ConfigError(f"{path}: {' '.join(str(e).split())}") from None
    _validate(scenario, str(path))
    _check_files_and_limits(scenario, str(path))
    return scenario


def station_for(config: str | Path | None = None, shelf=None) -> str:
    """The path of the station file for a scene scenario ``config`` (a YAML path) or a ``shelf``
    (slax_drake.scene.model.Shelf), the one lookup every command uses:

    1. ``station_<stem>.yaml`` beside ``config``, else in the repository's ``sim_configs/`` (a station made for
       that scenario);
    2. else the first shipped station (``sim_configs/station_*.yaml``, sorted) whose scene scenario has the same
       shelf as ``shelf`` (default: ``config``'s shelf), since the station welds its own shelf and MakeStation
       refuses a scene whose shelf differs.

    Raises StationNotFoundError (a user error: pass ``--station``) when neither finds one."""
    from slax_drake.config import load_scenario
    from slax_drake.errors import StationNotFoundError
    from slax_drake.scene.sampling import shelf_of

    if config is None and shelf is None:
        raise ValueError("station_for needs a config or a shelf")
    if config is not None:
        path = Path(config)
        for candidate in (path.parent / f"station_{path.stem}.yaml",
                          REPO_ROOT / "sim_configs" / f"station_{path.stem}.yaml"):
            if candidate.is_file():
                return str(candidate)
        if shelf is None:
            shelf = shelf_of(load_scenario(config))
    for candidate in sorted((REPO_ROOT / "sim_configs").glob("station_*.yaml")):
        if shelf_of(load_scenario(load_station_scenario(candidate).scene_config)) == shelf:
            return str(candidate)
    what = f"{config}" if config is not None else "the scene"
    raise StationNotFoundError(f"no station file for {what}: no station_<name>.yaml beside it and no shipped "
                               f"station has its {shelf.width} x {shelf.height} x {shelf.depth} m shelf; "
                               "pass --station")


def _validate(scenario: StationScenario, source: str) -> None:
    missing = [n for n in robot_model.PLANNED_JOINTS if n not in scenario.observation_configuration]
    unknown = [n for n in scenario.observation_configuration if n not in robot_model.PLANNED_JOINTS]
    if missing or unknown:
        raise ConfigError(
            f"{source}: key 'observation_configuration' must give exactly the joints {list(robot_model.PLANNED_JOINTS)}"
            f" (missing {missing}, unknown {unknown})"
        )
    if scenario.plant_config.contact_model != "point":
        raise ConfigError(f"{source}: key 'plant_config.contact_model' = {scenario.plant_config.contact_model!r}: must be 'point'")
    if not scenario.plant_config.time_step > 0:
        raise ConfigError(f"{source}: key 'plant_config.time_step' must be positive (a discrete plant)")
    if scenario.plant_config.discrete_contact_approximation not in ("sap", "similar", "lagged"):
        raise ConfigError(
            f"{source}: key 'plant_config.discrete_contact_approximation' = "
            f"{scenario.plant_config.discrete_contact_approximation!r}: PD-controlled actuators need 'sap', 'similar' or 'lagged'"
        )
    if scenario.push_turn not in PUSH_TURNS:
        raise ConfigError(f"{source}: key 'push_turn' = {scenario.push_turn!r}: must be one of "
                          f"{', '.join(map(repr, PUSH_TURNS))}")
    if not (math.isfinite(scenario.push_compliance) and scenario.push_compliance >= 0):
        raise ConfigError(f"{source}: key 'push_compliance' = {scenario.push_compliance!r}: must be a non-negative "
                          "number (m/N; 0 for a stiff arm)")
    p = scenario.suction
    for name in ("vacuum_pressure", "cup_radius", "max_distance", "max_angle_deg"):
        if not getattr(p, name) > 0:
            raise ConfigError(f"{source}: key 'suction.{name}' = {getattr(p, name)!r}: must be positive")
    if math.isfinite(p.max_held_moment) and p.max_held_moment > p.lip_moment:
        raise ConfigError(f"{source}: key 'suction.max_held_moment' = {p.max_held_moment!r}: must not exceed what the "
                          f"cup's model holds, vacuum_pressure x cup area x cup_radius = {p.lip_moment:.3f} N m")
    if not p.max_held_moment > 0:
        raise ConfigError(f"{source}: key 'suction.max_held_moment' = {p.max_held_moment!r}: must be positive "
                          "(.inf for no limit)")
    if not 0 <= p.max_seal_angle_deg <= 90:
        raise ConfigError(f"{source}: key 'suction.max_seal_angle_deg' = {p.max_seal_angle_deg!r}: must lie in "
                          "[0, 90] (90 for no limit)")


def _model_file(uri: str) -> Path | None:
    """The file a directive's ``file`` names (``package://slax_drake_models/...``, ``file://...`` or a path), or
    None for another package's, which Drake's own package map resolves when the station is built."""
    package = f"package://{robot_model.PACKAGE_NAME}/"
    if uri.startswith(package):
        return robot_model.MODELS_DIR / uri[len(package):]
    if uri.startswith("package://"):
        return None
    return Path(uri[len("file://"):] if uri.startswith("file://") else uri)


def _check_files_and_limits(scenario: StationScenario, source: str) -> None:
    """ConfigError when a model file or the reach map the station names does not exist, or when its observation
    configuration lies outside the position limits of the robot model it loads (rad, m)."""
    robot_file = None
    for directive in scenario.directives:
        model = directive.add_model
        if model is None:
            continue
        file = _model_file(model.file)
        if file is not None and not file.is_file():
            raise ConfigError(f"{source}: key 'directives' adds model {model.name!r} from {model.file}, which does not "
                              "exist")
        if model.name == scenario.robot_model:
            robot_file = file
    if scenario.reach_map:
        reach = Path(scenario.reach_map)
        if not (reach.is_file() or (not reach.is_absolute() and (REPO_ROOT / reach).is_file())):
            raise ConfigError(f"{source}: key 'reach_map' = {scenario.reach_map!r}: no such file (give a path from "
                              "the repository root, or \"\" for none)")
    if robot_file is None:
        return
    lower, upper = _position_limits(str(robot_file))
    for name, value in scenario.observation_configuration.items():
        lo, hi = lower.get(name, -math.inf), upper.get(name, math.inf)
        if not (math.isfinite(value) and lo <= value <= hi):
            raise ConfigError(f"{source}: key 'observation_configuration.{name}' = {value!r}: outside the joint's "
                              f"limits [{lo:g}, {hi:g}] in {robot_file.name}")


def joint_position_limits(scenario: StationScenario) -> tuple[dict, dict]:
    """Lower and upper position limits {joint name: value} (rad; m for the torso) of the planned joints of the
    robot model the station loads (continuous joints: -inf, inf)."""
    for directive in scenario.directives:
        model = directive.add_model
        if model is not None and model.name == scenario.robot_model:
            file = _model_file(model.file)
            if file is not None:
                return _position_limits(str(file))
    return {}, {}


@functools.lru_cache(maxsize=8)
def _position_limits(robot_file: str) -> tuple[dict, dict]:
    """Lower and upper position limits (rad or m) of the planned joints of the robot model in ``robot_file``."""
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    parser = Parser(plant)
    robot_model.add_package(parser)
    try:
        parser.AddModels(robot_file)
        plant.Finalize()
    except Exception as e:
        raise ConfigError(f"{robot_file}: the robot model cannot be parsed: {' '.join(str(e).split())[:200]}") from None
    lower, upper = {}, {}
    for name in robot_model.PLANNED_JOINTS:
        if plant.HasJointNamed(name):
            joint = plant.GetJointByName(name)
            lower[name], upper[name] = float(joint.position_lower_limits()[0]), float(joint.position_upper_limits()[0])
    return lower, upper


def observation_positions(scenario: StationScenario) -> np.ndarray:
    """q_obs of ``PLANNED_JOINTS`` (9)."""
    return np.array([scenario.observation_configuration[n] for n in robot_model.PLANNED_JOINTS])


def camera_render_cameras(camera: Camera, renderer_name: str):
    """Drake ColorRenderCamera and DepthRenderCamera with exactly the intrinsics of ``camera``."""
    from pydrake.geometry import ClippingRange, ColorRenderCamera, DepthRange, DepthRenderCamera, RenderCameraCore
    from pydrake.math import RigidTransform
    from slax_drake.station.renderer import drake_camera_info

    info = drake_camera_info(camera)
    core = RenderCameraCore(renderer_name, info, ClippingRange(camera.near, camera.far), RigidTransform())
    return ColorRenderCamera(core, False), DepthRenderCamera(core, DepthRange(camera.near, camera.far))
