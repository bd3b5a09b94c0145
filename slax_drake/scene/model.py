"""The shelf scene: shelf bay, occluding objects, hidden target and camera, all in the shelf frame S.

Objects rest in a stable pose on the support surface (z = 0): a box on one of its faces, a cylinder upright.
The stable pose is folded into ``size``: the object frame O sits at the object's centre with z_O up, and
``size`` holds the extents along x_O, y_O, z_O (a cylinder: [diameter, diameter, height]). X_SO is then a
yaw about z_S plus a translation with z = height / 2.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.scene.camera import Camera


@dataclasses.dataclass(frozen=True)
class Shelf:
    """The bay's interior: x in [-width/2, width/2], y in [-depth/2, depth/2], z in [0, height] (metres)."""

    width: float
    height: float
    depth: float
    wall_thickness: float = 0.02

    def to_dict(self) -> dict:
        return {"width": self.width, "height": self.height, "depth": self.depth, "wall_thickness": self.wall_thickness}


@dataclasses.dataclass(frozen=True)
class SceneObject:
    """An occluding object: ``shape`` "box" or "cylinder", ``size`` [x, y, z], its pose X_SO (4x4) and, when the
    scenario draws masses, its ``mass`` (kg). ``remembered``: a policy's belief holds it where it was last seen,
    hidden from the camera now (an obstacle no action is planned on); never set on a true scene's objects.

    X_SO is a read-only float array (a writable one given is copied first): the search caches of the action model
    key footprints by the object's identity, so an object whose pose changed in place would read another pose's
    cached footprint. A moved object is a new one (:meth:`moved_to`, ``dataclasses.replace``)."""

    name: str
    shape: str
    size: tuple[float, float, float]
    X_SO: np.ndarray
    mass: float | None = None  # kg; None: from the scenario's density (slax_drake.scene.mass.object_mass)
    remembered: bool = False

    def __post_init__(self):
        X = self.X_SO
        if not (isinstance(X, np.ndarray) and not X.flags.writeable and X.base is None and X.dtype == np.float64):
            X = np.array(X, dtype=float)
            X.flags.writeable = False
            object.__setattr__(self, "X_SO", X)

    @property
    def center(self) -> np.ndarray:
        return self.X_SO[:3, 3]

    @property
    def yaw(self) -> float:
        return math.atan2(self.X_SO[1, 0], self.X_SO[0, 0])

    @property
    def height(self) -> float:
        return self.size[2]

    @property
    def radius(self) -> float:
        """A cylinder's radius; for a box, the radius of the circle through its footprint's corners."""
        if self.shape == "cylinder":
            return self.size[0] / 2.0
        return 0.5 * math.hypot(self.size[0], self.size[1])

    def moved_to(self, x: float, y: float, yaw: float | None = None) -> "SceneObject":
        """The same object translated to (x, y) on the support surface and, with ``yaw``, turned to that yaw (rad,
        about the support's z)."""
        X = self.X_SO.copy()
        X[0, 3], X[1, 3] = x, y
        if yaw is not None:
            c, s = math.cos(yaw), math.sin(yaw)
            X[:2, :2] = [[c, -s], [s, c]]
        X.flags.writeable = False  # taken as it is (see the class docstring)
        return dataclasses.replace(self, X_SO=X)

    def to_dict(self) -> dict:
        data = {"name": self.name, "shape": self.shape, "size": list(self.size), "X_SO": self.X_SO.tolist()}
        if self.mass is not None:
            data["mass"] = self.mass
        return data


@dataclasses.dataclass(frozen=True)
class Target:
    """The hidden target: a box of ``size`` [x, y, z], yaw aligned with the shelf, pose X_ST (4x4)."""

    size: tuple[float, float, float]
    X_ST: np.ndarray

    @property
    def center(self) -> np.ndarray:
        return self.X_ST[:3, 3]

    def as_object(self) -> SceneObject:
        return SceneObject(name="target", shape="box", size=self.size, X_SO=self.X_ST)

    def to_dict(self) -> dict:
        return {"size": list(self.size), "X_ST": self.X_ST.tolist()}


@dataclasses.dataclass(frozen=True)
class Scene:
    """A complete shelf scene. ``target`` is None for a scene of occluders only."""

    shelf: Shelf
    camera: Camera
    objects: tuple[SceneObject, ...]
    target: Target | None
    seed: int | None = None

    def with_objects(self, objects) -> "Scene":
        return dataclasses.replace(self, objects=tuple(objects))

    def object_named(self, name: str) -> SceneObject:
        for obj in self.objects:
            if obj.name == name:
                return obj
        raise KeyError(name)


def planar_pose(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    """A 4x4 pose with a rotation of ``yaw`` about z and translation (x, y, z)."""
    c, s = math.cos(yaw), math.sin(yaw)
    X = np.eye(4)
    X[:2, :2] = [[c, -s], [s, c]]
    X[:3, 3] = (x, y, z)
    return X


def box_yaw_difference(yaw_a: float, yaw_b: float) -> float:
    """``yaw_a - yaw_b`` (rad) in [-pi/2, pi/2): a box turned by pi stands the same."""
    return (float(yaw_a) - float(yaw_b) + math.pi / 2) % math.pi - math.pi / 2


def state_key(objects) -> tuple:
    """A hashable key of the objects' names and planar poses (x, y to 0.1 mm, yaw to 1e-4 rad): the state of a
    shelf as the first-order model sees it, used to cache distributions and to deduplicate search states."""
    return tuple(
        (o.name, round(float(o.center[0]), 4), round(float(o.center[1]), 4), round(float(o.yaw), 4)) for o in objects
    )
