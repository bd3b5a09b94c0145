"""Random shelf scenes with a completely hidden target (paper Sec. V-A).

Objects: a box (probability ``objects.box_probability``) or an upright cylinder, every dimension uniform in
[min_size, max_size]. A box rests on one of its three face pairs (its stable poses), chosen uniformly, with a
yaw uniform in [0, pi) (``objects.box_yaw`` "random", the default) or square to the walls ("aligned"); a
cylinder stands on its flat face. Positions are uniform over the bay and rejected when the exact footprint
(rectangle or disc) comes within ``objects.clearance`` of a wall or a placed object.
Positions are tried in batches of 32; an object that finds no free position in its batch is redrawn (shape,
size, pose), so dense scenes lean toward smaller objects, as any sequential placement must.

Target (``target.placement`` "after-objects", the paper's order): yaw aligned with the shelf, resting on the
support surface, its position uniform over the free floor, kept only if no ray from the camera reaches any of the
points sampled on its surface (every face but the bottom, ``target.surface_point_spacing`` apart), with the shelf's
walls, top and back counted as occluders.
A coarse point set screens candidates in batches; the dense set decides. With ``target.placement`` "first" the
target is drawn uniformly on the empty floor before the occluders, which are placed clear of it, and the scene is
kept only when the target is then fully hidden (the same dense test).

Determinism: everything is drawn from ``numpy.random.default_rng(seed)`` in a fixed order, and the returned
scene is rounded to 1e-10 m so that its JSON is byte-identical on any machine.
"""

from __future__ import annotations

import math

import numpy as np

from slax_drake.config import Scenario, check_object_count
from slax_drake.errors import SceneGenerationError
from slax_drake.scene.camera import Camera
from slax_drake.scene.io import DECIMALS
from slax_drake.scene.footprint import Footprint, clear_of
from slax_drake.scene.mass import sample_masses
from slax_drake.scene.model import Scene, SceneObject, Shelf, Target, planar_pose
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.surface import box_surface_points

OBJECT_BATCH = 32
TARGET_BATCH = 256
COARSE_SPACING = 0.02


def shelf_of(scenario: Scenario) -> Shelf:
    s = scenario.shelf
    return Shelf(width=s.width, height=s.height, depth=s.depth, wall_thickness=s.wall_thickness)


def sample_scene(
    scenario: Scenario,
    num_objects: int,
    seed: int,
    target_size: tuple[float, float, float] | None = None,
) -> Scene:
    """Draws a scene of ``num_objects`` occluders and a completely hidden target.

    ``target_size`` defaults to one of ``scenario.target.sizes`` drawn uniformly.
    Raises SceneGenerationError when no scene is completed within ``scenario.sampling.scene_attempts``.
    """
    check_object_count(scenario, num_objects, key="objects")
    rng = np.random.default_rng(seed)
    shelf = shelf_of(scenario)
    camera = Camera.from_config(scenario.camera)
    if target_size is None:
        sizes = scenario.target.sizes
        target_size = tuple(float(v) for v in sizes[int(rng.integers(len(sizes)))])
    first = scenario.target.placement == "first"
    for _ in range(scenario.sampling.scene_attempts):
        target = _draw_target(scenario, shelf, target_size, rng) if first else None
        objects = _place_objects(scenario, shelf, num_objects, rng,
                                 fixed=[Footprint.of(target.as_object())] if target is not None else ())
        if objects is None:
            continue
        scene = Scene(shelf=shelf, camera=camera, objects=tuple(objects), target=None, seed=seed)
        if first:
            target = target if _fully_hidden(scenario, scene, target) else None
        else:
            target = _place_hidden_target(scenario, scene, target_size, rng)
        if target is not None:
            objects = sample_masses(tuple(_rounded_object(o) for o in scene.objects), scenario.physics, seed)
            return Scene(shelf, camera, objects, _rounded_target(target), seed)
    raise SceneGenerationError(
        f"could not place {num_objects} objects with a hidden {target_size} m target in "
        f"{scenario.sampling.scene_attempts} attempts (seed {seed}); use fewer objects or a larger shelf"
    )


def _rounded_pose(X: np.ndarray) -> np.ndarray:
    """The pose as scene JSON stores it (Python's correctly rounded ``round`` to DECIMALS), so that a sampled
    scene equals its own JSON round trip."""
    return np.array([[_round(v) for v in row] for row in X.tolist()])


def _round(v: float) -> float:
    r = round(v, DECIMALS)
    return 0.0 if r == 0 else r


def _rounded_object(obj: SceneObject) -> SceneObject:
    return SceneObject(obj.name, obj.shape, tuple(_round(v) for v in obj.size), _rounded_pose(obj.X_SO))


def _rounded_target(target: Target) -> Target:
    return Target(tuple(_round(v) for v in target.size), _rounded_pose(target.X_ST))


def _random_object(scenario: Scenario, rng: np.random.Generator) -> tuple[str, tuple, float]:
    """Shape, size [x, y, z] in the resting pose, and yaw of a new object."""
    cfg = scenario.objects
    is_box = rng.random() < cfg.box_probability
    dims = rng.uniform(cfg.min_size, cfg.max_size, size=3)
    if is_box:
        up = int(rng.integers(3))  # which of the box's three axes points up: its stable pose
        lateral = [dims[a] for a in range(3) if a != up]
        size = (float(lateral[0]), float(lateral[1]), float(dims[up]))
        yaw = float(rng.uniform(0.0, math.pi))  # drawn either way: "aligned" keeps the random stream
        return "box", size, yaw if cfg.box_yaw == "random" else 0.0
    return "cylinder", (float(dims[0]), float(dims[0]), float(dims[2])), 0.0


def _place_objects(scenario: Scenario, shelf: Shelf, count: int, rng: np.random.Generator, fixed=()):
    """``count`` occluders placed one by one clear of each other and of ``fixed`` (footprints already there: the
    target, with ``target.placement`` "first"); None when one finds no place."""
    clearance = scenario.objects.clearance
    fixed = list(fixed)
    placed: list[Footprint] = []
    objects: list[SceneObject] = []
    for i in range(count):
        position = None
        for _ in range(math.ceil(scenario.sampling.object_attempts / OBJECT_BATCH)):
            shape, size, yaw = _random_object(scenario, rng)
            half = (size[0] / 2.0, size[1] / 2.0)
            ex, ey = Footprint(shape, 0.0, 0.0, yaw, *half).extents()
            x_max = shelf.width / 2.0 - clearance - ex
            y_max = shelf.depth / 2.0 - clearance - ey
            if x_max < 0 or y_max < 0 or size[2] > shelf.height:
                continue
            centers = np.column_stack([rng.uniform(-x_max, x_max, OBJECT_BATCH), rng.uniform(-y_max, y_max, OBJECT_BATCH)])
            ok = np.ones(OBJECT_BATCH, dtype=bool)
            for other in fixed + placed:
                ok &= clear_of(shape, centers, yaw, half, other, clearance)
            if ok.any():
                position = centers[int(np.argmax(ok))]
                break
        if position is None:
            return None
        placed.append(Footprint(shape, float(position[0]), float(position[1]), yaw, *half))
        objects.append(
            SceneObject(
                name=f"object_{i}",
                shape=shape,
                size=size,
                X_SO=planar_pose(float(position[0]), float(position[1]), size[2] / 2.0, yaw),
            )
        )
    return objects


def _place_hidden_target(scenario: Scenario, scene: Scene, size: tuple, rng: np.random.Generator):
    clearance = scenario.objects.clearance
    shelf = scene.shelf
    half = (size[0] / 2.0, size[1] / 2.0)
    x_max = shelf.width / 2.0 - clearance - half[0]
    y_max = shelf.depth / 2.0 - clearance - half[1]
    if x_max < 0 or y_max < 0:
        return None
    footprints = [Footprint.of(o) for o in scene.objects]
    raycaster = SceneRaycaster(scene)
    eye = scene.camera.position
    coarse, _ = box_surface_points(tuple(size), max(COARSE_SPACING, scenario.target.surface_point_spacing))
    dense, _ = box_surface_points(tuple(size), scenario.target.surface_point_spacing)
    z = size[2] / 2.0
    for _ in range(math.ceil(scenario.sampling.target_attempts / TARGET_BATCH)):
        centers = np.column_stack([rng.uniform(-x_max, x_max, TARGET_BATCH), rng.uniform(-y_max, y_max, TARGET_BATCH)])
        ok = np.ones(TARGET_BATCH, dtype=bool)
        for fp in footprints:
            ok &= clear_of("box", centers, 0.0, half, fp, clearance)
        candidates = centers[ok]
        if len(candidates) == 0:
            continue
        offsets = np.column_stack([candidates, np.full(len(candidates), z)])
        coarse_visible = raycaster.visible(eye, coarse[None, :, :] + offsets[:, None, :]).any(axis=1)
        for offset in offsets[~coarse_visible]:
            if not raycaster.visible(eye, dense + offset).any():
                return Target(size=tuple(size), X_ST=planar_pose(offset[0], offset[1], z, 0.0))
    return None


def _draw_target(scenario: Scenario, shelf: Shelf, size: tuple, rng: np.random.Generator) -> Target | None:
    """``target.placement`` "first": the target, shelf-aligned, uniformly on the empty floor (None when it does not
    fit the bay)."""
    clearance = scenario.objects.clearance
    x_max = shelf.width / 2.0 - clearance - size[0] / 2.0
    y_max = shelf.depth / 2.0 - clearance - size[1] / 2.0
    if x_max < 0 or y_max < 0:
        return None
    x, y = float(rng.uniform(-x_max, x_max)), float(rng.uniform(-y_max, y_max))
    return Target(size=tuple(size), X_ST=planar_pose(x, y, size[2] / 2.0, 0.0))


def _fully_hidden(scenario: Scenario, scene: Scene, target: Target | None) -> bool:
    """Whether no ray from the camera reaches any of the target's surface points (the dense set of
    :func:`_place_hidden_target`) in ``scene`` (its occluders, no target)."""
    if target is None:
        return False
    dense, _ = box_surface_points(tuple(target.size), scenario.target.surface_point_spacing)
    return not SceneRaycaster(scene).visible(scene.camera.position, dense + target.center).any()


def target_visible_fraction(scene: Scene, spacing: float = 0.005) -> float:
    """How much of the target the camera sees: the fraction of its surface points visible in the scene among
    those visible when the shelf holds the target alone (so its own far faces do not count against it).
    The target is revealed when this reaches ``target.visibility_threshold`` (the paper's v)."""
    if scene.target is None:
        raise ValueError("the scene has no target")
    points, _ = box_surface_points(tuple(scene.target.size), spacing)
    points = points + scene.target.center
    eye = scene.camera.position
    unoccluded = SceneRaycaster(scene, include_target=True, objects=()).visible(eye, points)
    if not unoccluded.any():
        return 0.0
    seen = SceneRaycaster(scene, include_target=True).visible(eye, points)
    return float(seen[unoccluded].mean())
