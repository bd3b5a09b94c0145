"""Typed scenario configuration, loaded from ``sim_configs/*.yaml`` with Drake's ``yaml_load_typed``.

All lengths are metres, angles degrees where the key says ``_deg``, otherwise radians.
The shelf frame S: origin at the centre of the support surface, x to the right as seen from the camera, y into
the shelf, z up.

Scenarios are layered as Drake's scenario loaders layer them: each layer is loaded with
``yaml_load_typed(..., defaults=<the layers below>)``, so a layer sets only the keys it changes (a nested mapping
merges key by key; a list replaces the whole list). A file names the layer below it with a top-level ``base:``
key, a path relative to the file itself or absolute (an overlay copied elsewhere names its base by an absolute
path); the bottom file's defaults are :class:`Scenario`'s. For example
``sim_configs/table1_aligned.yaml`` is::

    base: table1.yaml
    objects:
      box_yaw: aligned

and :func:`load_scenario` ("sim_configs/table1_aligned.yaml") is Table I's scenario with square boxes. Every layer
is checked for unknown keys and value types; the scenario they make together is validated once
(:func:`validate_scenario`).
"""

# No `from __future__ import annotations`: yaml_load_typed needs the real types of the fields.
import dataclasses
import math
from pathlib import Path

import typing

from slax_drake.errors import ConfigError

REPO_ROOT = Path(__file__).resolve().parents[1]
BASE_KEY = "base"  # a scenario file's key naming the file it overlays (a path relative to the file)
DEFAULT_CONFIG = "sim_configs/sim_shelf.yaml"
PROFILES = ("paper", "station")  # the action model's rule profiles (slax_drake.shelf.rules.PROFILES)
TARGET_PLACEMENTS = ("after-objects", "first")  # target.placement


@dataclasses.dataclass
class ShelfConfig:
    """The shelf bay's interior: width along x, height along z, depth along y (metres)."""

    width: float = 0.60
    height: float = 0.60
    depth: float = 0.60
    wall_thickness: float = 0.02


@dataclasses.dataclass
class ShelfCameraConfig:
    """The depth camera (RealSense L515 on the bluction tool's mount), static relative to the shelf: its pose in
    the shelf frame S and its pinhole intrinsics (:class:`slax_drake.scene.camera.Camera`).

    ``position`` is the optical centre in the shelf frame; the optical axis points along +y of the shelf,
    pitched down by ``pitch_deg``. Pixels are square: fx = fy from the horizontal field of view.

    Not Drake's ``pydrake.systems.sensors.CameraConfig``: that one mounts a sensor on a frame of a
    MultibodyPlant for ``ApplyCameraConfig``, while this camera is fixed in the shelf frame of a scenario that the
    first-order simulator and the occupancy code use without any plant; the station places the shelf so that the
    robot's tool camera at its observation pose is this camera (:mod:`slax_drake.station.scenario`), and the
    renderer builds Drake's render cameras from the same intrinsics.
    """

    width: int = 640
    height: int = 480
    horizontal_fov_deg: float = 70.0
    position: list[float] = dataclasses.field(default_factory=lambda: [0.0, -0.75, 0.20])
    pitch_deg: float = 12.0
    near: float = 0.1
    far: float = 5.0


@dataclasses.dataclass
class ObjectsConfig:
    """Occluding objects: boxes or upright cylinders with every dimension in [min_size, max_size]."""

    min_size: float = 0.06
    max_size: float = 0.20
    box_probability: float = 0.5
    box_yaw: str = "random"  # "random": uniform in [0, pi); "aligned": sides parallel to the shelf's walls
    clearance: float = 0.002
    count_range: list[int] = dataclasses.field(default_factory=lambda: [2, 12])
    density: float = 400.0


# Household goods' masses by package volume, from published product data (kg; [largest volume in litres of the
# class, lightest, heaviest]). Sources (approximate: masses as published, volumes of the bounding box or
# cylinder from the published dimensions, rounded): the YCB object set (Calli et al., "Benchmarking in
# Manipulation Research: The YCB Object and Model Set", IEEE RAM 2015, its object table): boxes: gelatin box 0.097
# kg / 0.11 L, pudding box 0.187 kg / 0.31 L, sugar box 0.514 kg / 0.63 L, cracker box 0.411 kg / 2.0 L; cylinders:
# tuna can 0.171 kg / 0.19 L, tomato soup can 0.349 kg / 0.35 L, coffee can 0.414 kg / 1.1 L, chips can
# 0.205 kg / 1.1 L, mustard bottle 0.603 kg / 1.0 L; and net contents printed on common packages (a 500 g cereal
# box about 4-5 L, a tissue box about 0.15 kg / 2.6 L, a 1 L detergent or shampoo bottle about 1.1 kg, a 2 L
# bottle about 2.1 kg in about 3 L). Larger packages hold more air: the heaviest per class grows slower than the
# volume. Objects larger than the last class take its range.
HOUSEHOLD_BOX_MASSES = [[0.5, 0.05, 0.50], [2.0, 0.10, 0.80], [8.0, 0.15, 1.20]]
HOUSEHOLD_CYLINDER_MASSES = [[0.5, 0.10, 0.50], [2.0, 0.20, 1.10], [8.0, 0.30, 2.10]]


@dataclasses.dataclass
class PhysicsConfig:
    """The objects' physical properties.

    ``mass_model``: "density" (mass = ``objects.density`` x volume; the default) or "household"
    (each object's mass drawn log-uniformly, per scene seed, between the lightest and heaviest of its shape's
    volume class in ``box_masses`` / ``cylinder_masses``: [[largest volume (L), lightest (kg), heaviest (kg)],
    ...] in increasing volume; see HOUSEHOLD_BOX_MASSES for the sources). ``object_friction``: the Coulomb
    friction coefficient of the objects (static = dynamic) in the Drake station; 0.5, cardboard and plastic
    packaging on a laminated board (published static coefficients: paperboard on paperboard 0.3-0.6 by TAPPI T 815
    inclined-plane tests, wood on plastic or cardboard 0.3-0.5; approximate). The shelf board's 0.4 is fixed in the
    shelf models (Drake combines the two as 2 mu1 mu2 / (mu1 + mu2), 0.44)."""

    mass_model: str = "density"
    box_masses: list[list[float]] = dataclasses.field(default_factory=lambda: [list(r) for r in HOUSEHOLD_BOX_MASSES])
    cylinder_masses: list[list[float]] = dataclasses.field(
        default_factory=lambda: [list(r) for r in HOUSEHOLD_CYLINDER_MASSES])
    object_friction: float = 0.5


@dataclasses.dataclass
class TargetConfig:
    """Target sizes [x, y, z] (metres) to draw from, and the spacing of points sampled on its surface."""

    sizes: list[list[float]] = dataclasses.field(
        default_factory=lambda: [[0.06, 0.06, 0.03], [0.06, 0.06, 0.06], [0.06, 0.06, 0.12]]
    )
    surface_point_spacing: float = 0.005
    visibility_threshold: float = 0.80
    # How the target's place is drawn (slax_drake.scene.sampling): "after-objects" (the paper's Fig. 3 and Sec.
    # V-A: the occluders are placed first, then the target uniformly over the fully hidden placements they leave)
    # or "first" (a reading to measure: the target uniformly on the free floor first, the occluders placed
    # around it, the scene kept when the target is fully hidden: arrangements that hide more weigh more).
    placement: str = "after-objects"


@dataclasses.dataclass
class SamplingConfig:
    """Retry budgets of the scene sampler."""

    object_attempts: int = 200
    target_attempts: int = 2048
    scene_attempts: int = 100


@dataclasses.dataclass
class ProtocolConfig:
    """An evaluation protocol (the paper's Table I): scenes per density, horizon H = horizon_per_object * n."""

    densities: list[int] = dataclasses.field(default_factory=lambda: [4, 6, 8, 10])
    scenes_per_density: int = 100
    horizon_per_object: int = 2
    suction_cost: float = 1.3
    seed: int = 0
    # Whether a density n counts the target among its n objects (n - 1 occluders and the target, H = 2n still): a
    # reading to measure of the paper's "H = 2n, where n is the number of objects" (Sec. VI-A). False (the
    # default, the paper's own Table I caption: "4, 6, 8, and 10 occluding objects"): n occluders and the target.
    count_includes_target: bool = False

    def occluders(self, density: int) -> int:
        """The number of occluding objects in a scene of ``density`` objects (see ``count_includes_target``)."""
        return int(density) - 1 if self.count_includes_target else int(density)


@dataclasses.dataclass
class Scenario:
    """Everything that defines a shelf world and how scenes are drawn in it, and the action model's rule profile
    (``profile``: "paper", the paper's first-order simulator, or "station", our physical tool; see
    :mod:`slax_drake.shelf.rules`)."""

    profile: str = "station"
    shelf: ShelfConfig = dataclasses.field(default_factory=ShelfConfig)
    camera: ShelfCameraConfig = dataclasses.field(default_factory=ShelfCameraConfig)
    objects: ObjectsConfig = dataclasses.field(default_factory=ObjectsConfig)
    physics: PhysicsConfig = dataclasses.field(default_factory=PhysicsConfig)
    target: TargetConfig = dataclasses.field(default_factory=TargetConfig)
    sampling: SamplingConfig = dataclasses.field(default_factory=SamplingConfig)
    protocol: ProtocolConfig = dataclasses.field(default_factory=ProtocolConfig)


def load_scenario(path: str | Path) -> Scenario:
    """Loads and validates a scenario YAML file and the files under it (``base:``, see the module docstring);
    raises ConfigError naming the file, key and value."""
    path = Path(path)
    if not path.is_file() and not path.is_absolute() and (REPO_ROOT / path).is_file():
        path = REPO_ROOT / path  # the shipped sim_configs/ when run from another folder
    if not path.is_file():
        raise ConfigError(f"{path}: no such config file")
    scenario = _load_layers(path, ())
    validate_scenario(scenario, source=str(path))
    return scenario


def _load_layers(path: Path, above: tuple) -> Scenario:
    """The scenario of ``path`` on top of the layers its ``base:`` names (``above``: the files that named it)."""
    import copy

    from pydrake.common.yaml import yaml_load, yaml_load_typed  # here, not at the top: the CLI parser imports us

    try:
        raw = yaml_load(filename=str(path))
    except Exception as e:
        message = " ".join(str(e).split())
        raise ConfigError(f"{path}: not valid YAML ({message})") from None
    raw = raw if raw is not None else {}
    defaults = Scenario()
    base = raw.pop(BASE_KEY, None) if isinstance(raw, dict) else None
    if base is not None:
        if not isinstance(base, str) or not base:
            raise ConfigError(f"{path}: key '{BASE_KEY}' = {base!r}: must be the path of a scenario file, relative "
                              "to this one")
        below = (path.parent / base).resolve()
        if not below.is_file():
            raise ConfigError(f"{path}: key '{BASE_KEY}' = {base!r}: no such config file ({below})")
        if below in above or below == path.resolve():
            raise ConfigError(f"{path}: key '{BASE_KEY}' = {base!r}: the files' bases form a cycle")
        defaults = _load_layers(below, above + (path.resolve(),))
    _check_schema(raw, Scenario, "", str(path))
    try:
        # The base key is checked above; the typed load reads the rest of the file over the layers below.
        return yaml_load_typed(schema=Scenario, filename=str(path), defaults=copy.deepcopy(defaults),
                               allow_yaml_with_no_schema=base is not None)
    except Exception as e:  # Drake raises RuntimeError/TypeError/ValueError with a descriptive text.
        message = " ".join(str(e).split())
        raise ConfigError(f"{path}: {message}") from None


def _check_schema(value, schema, key: str, source: str) -> None:
    """Checks keys and value types against the dataclass schema, naming the first offending key."""

    def fail(why: str):
        raise ConfigError(f"{source}: key '{key or '<top>'}' = {value!r}: {why}")

    if dataclasses.is_dataclass(schema):
        if not isinstance(value, dict):
            fail(f"must be a mapping with keys {[f.name for f in dataclasses.fields(schema)]}")
        fields = {f.name: f.type for f in dataclasses.fields(schema)}
        for name, item in value.items():
            sub = f"{key}.{name}" if key else str(name)
            if name not in fields:
                raise ConfigError(f"{source}: unknown key '{sub}' (known here: {', '.join(fields)})")
            _check_schema(item, fields[name], sub, source)
    elif typing.get_origin(schema) is list:
        if not isinstance(value, list):
            fail("must be a list")
        (item_type,) = typing.get_args(schema)
        for i, item in enumerate(value):
            _check_schema(item, item_type, f"{key}[{i}]", source)
    elif schema is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            fail("must be a number")
    elif schema is int:
        if isinstance(value, bool) or not isinstance(value, int):
            fail("must be an integer")
    elif schema is str:
        if not isinstance(value, str):
            fail("must be a string")


def validate_scenario(scenario: Scenario, source: str = "<scenario>") -> None:
    """Raises ConfigError on a non-positive, impossible or inconsistent value."""

    def fail(key: str, value, why: str):
        raise ConfigError(f"{source}: key '{key}' = {value!r}: {why}")

    def positive(key: str, value):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            fail(key, value, "must be a positive number")

    if scenario.profile not in PROFILES:
        fail("profile", scenario.profile, f"must be one of {', '.join(map(repr, PROFILES))}")
    shelf = scenario.shelf
    for name in ("width", "height", "depth", "wall_thickness"):
        positive(f"shelf.{name}", getattr(shelf, name))

    camera = scenario.camera
    positive("camera.width", camera.width)
    positive("camera.height", camera.height)
    if not 1.0 < camera.horizontal_fov_deg < 170.0:
        fail("camera.horizontal_fov_deg", camera.horizontal_fov_deg, "must lie in (1, 170) degrees")
    if len(camera.position) != 3:
        fail("camera.position", camera.position, "must be [x, y, z] in the shelf frame")
    if not camera.position[1] < -shelf.depth / 2 - shelf.wall_thickness:
        fail("camera.position", camera.position,
             f"the camera must stand in front of the shelf's opening (y < {-shelf.depth / 2:.3f})")
    if not -80.0 < camera.pitch_deg < 80.0:
        fail("camera.pitch_deg", camera.pitch_deg, "must lie in (-80, 80) degrees")
    positive("camera.near", camera.near)
    if not camera.far > camera.near:
        fail("camera.far", camera.far, "must exceed camera.near")

    if scenario.target.placement not in TARGET_PLACEMENTS:
        fail("target.placement", scenario.target.placement, f"must be one of {', '.join(map(repr, TARGET_PLACEMENTS))}")
    if scenario.protocol.count_includes_target and min(scenario.protocol.densities or [2]) < 2:
        fail("protocol.densities", scenario.protocol.densities,
             "with protocol.count_includes_target every density must be at least 2 (one occluder and the target)")

    objects = scenario.objects
    positive("objects.min_size", objects.min_size)
    positive("objects.max_size", objects.max_size)
    positive("objects.density", objects.density)
    if objects.max_size < objects.min_size:
        fail("objects.max_size", objects.max_size, "must be at least objects.min_size")
    if not 0.0 <= objects.box_probability <= 1.0:
        fail("objects.box_probability", objects.box_probability, "must lie in [0, 1]")
    if objects.box_yaw not in ("random", "aligned"):
        fail("objects.box_yaw", objects.box_yaw, "must be 'random' or 'aligned'")
    if objects.clearance < 0:
        fail("objects.clearance", objects.clearance, "must not be negative")
    bay_min = min(shelf.width, shelf.depth)
    if objects.max_size > bay_min or objects.max_size > shelf.height:
        fail("objects.max_size", objects.max_size,
             f"an object this large does not fit the {shelf.width} x {shelf.height} x {shelf.depth} m bay")
    if len(objects.count_range) != 2 or objects.count_range[0] < 1 or objects.count_range[1] < objects.count_range[0]:
        fail("objects.count_range", objects.count_range, "must be [min, max] with 1 <= min <= max")
    check_object_count(scenario, objects.count_range[1], source=source, key="objects.count_range")

    physics = scenario.physics
    if physics.mass_model not in ("density", "household"):
        fail("physics.mass_model", physics.mass_model, "must be 'density' or 'household'")
    for key in ("box_masses", "cylinder_masses"):
        table = getattr(physics, key)
        if not table:
            fail(f"physics.{key}", table, "must list at least one [largest volume (L), lightest (kg), heaviest (kg)]")
        for i, row in enumerate(table):
            if len(row) != 3 or not 0 < row[1] <= row[2] or not row[0] > 0 or (i and not row[0] > table[i - 1][0]):
                fail(f"physics.{key}[{i}]", row, "must be [largest volume (L), lightest (kg), heaviest (kg)] with "
                     "0 < lightest <= heaviest, volumes increasing")
    positive("physics.object_friction", physics.object_friction)

    target = scenario.target
    if not target.sizes:
        fail("target.sizes", target.sizes, "must list at least one [x, y, z] size")
    for i, size in enumerate(target.sizes):
        if len(size) != 3 or not all(isinstance(s, (int, float)) and s > 0 for s in size):
            fail(f"target.sizes[{i}]", size, "must be three positive lengths [x, y, z]")
        if size[0] > shelf.width or size[1] > shelf.depth or size[2] > shelf.height:
            fail(f"target.sizes[{i}]", size, "the target does not fit in the bay")
    positive("target.surface_point_spacing", target.surface_point_spacing)
    if not 0.0 < target.visibility_threshold <= 1.0:
        fail("target.visibility_threshold", target.visibility_threshold, "must lie in (0, 1]")

    sampling = scenario.sampling
    for name in ("object_attempts", "target_attempts", "scene_attempts"):
        value = getattr(sampling, name)
        if not (isinstance(value, int) and value > 0):
            fail(f"sampling.{name}", value, "must be a positive integer")

    protocol = scenario.protocol
    if not protocol.densities:
        fail("protocol.densities", protocol.densities, "must list at least one object count")
    for n in protocol.densities:
        check_object_count(scenario, n, source=source, key="protocol.densities")
    if protocol.scenes_per_density < 1:
        fail("protocol.scenes_per_density", protocol.scenes_per_density, "must be at least 1")
    if protocol.horizon_per_object < 1:
        fail("protocol.horizon_per_object", protocol.horizon_per_object, "must be at least 1")
    if protocol.suction_cost <= 0:
        fail("protocol.suction_cost", protocol.suction_cost, "must be positive")


def max_placeable_objects(scenario: Scenario) -> int:
    """An upper bound on how many objects of the smallest size fit on the shelf's floor beside a target.

    Objects are at least min_size square (plus clearance) and the target needs its own footprint, so more
    objects than this can never be placed; fewer may still fail by chance, which the retry budget handles.
    """
    shelf, objects = scenario.shelf, scenario.objects
    cell = objects.min_size + objects.clearance
    smallest_target = min(s[0] * s[1] for s in scenario.target.sizes)
    free_area = shelf.width * shelf.depth - smallest_target
    # A disc of diameter min_size covers pi/4 of the square; use the disc as the smallest footprint.
    return int(free_area // (math.pi / 4 * cell * cell))


def check_object_count(scenario: Scenario, count: int, source: str = "<request>", key: str = "objects") -> None:
    """Raises ConfigError when ``count`` objects cannot be placed in the scenario's bay."""
    if not isinstance(count, int) or count < 1:
        raise ConfigError(f"{source}: key '{key}' = {count!r}: the number of objects must be a positive integer")
    bound = max_placeable_objects(scenario)
    if count > bound:
        raise ConfigError(
            f"{source}: key '{key}' = {count!r}: at most {bound} objects of at least "
            f"{scenario.objects.min_size} m fit on a {scenario.shelf.width} x {scenario.shelf.depth} m shelf"
        )
