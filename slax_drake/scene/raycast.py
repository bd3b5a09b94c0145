"""Ray casting against a shelf scene with Embree (through embreex), on triangle meshes built with trimesh.

The occluders are the shelf's support, side walls, top and back (boxes of ``wall_thickness``) and every
occluding object; the target is added only when asked. A point is visible from the camera when the first
hit along the segment from the camera's optical centre to the point lies at or beyond the point.
"""

from __future__ import annotations

import functools
import os

import numpy as np
import trimesh
from embreex import mesh_construction, rtcore, rtcore_scene

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, Shelf

NO_HIT = 1e30
CYLINDER_SECTIONS = 32
# Embree works in float32: a hit this close before a point (relative to the segment) still counts as the point.
VISIBILITY_EPS = 2e-5


@functools.cache
def _unit_box() -> np.ndarray:
    return trimesh.creation.box(extents=(1.0, 1.0, 1.0)).triangles.astype(np.float64)


@functools.cache
def _unit_cylinder() -> np.ndarray:
    return trimesh.creation.cylinder(radius=0.5, height=1.0, sections=CYLINDER_SECTIONS).triangles.astype(np.float64)


_DEVICE: list = []  # [(process id, EmbreeDevice)]: one device per process, shared by its scenes


def embree_device() -> rtcore.EmbreeDevice:
    """This process's Embree device, made on first use. A scene made without a device makes its own, which costs
    more than building a small scene; the device holds no geometry, so sharing it changes no ray's result. A
    forked worker makes its own (a device is not carried across a fork)."""
    if not _DEVICE or _DEVICE[0][0] != os.getpid():
        _DEVICE[:] = [(os.getpid(), rtcore.EmbreeDevice())]
    return _DEVICE[0][1]


def object_triangles(obj: SceneObject) -> np.ndarray:
    """Triangles (T, 3, 3) of an object's surface in the shelf frame.

    A cylinder is a prism inscribed in it (32 sides, at most 0.5 % of its radius inside), so an occluder is
    never larger than the real object and a point found hidden is hidden by the real scene too."""
    unit = _unit_cylinder() if obj.shape == "cylinder" else _unit_box()
    local = unit * np.asarray(obj.size, dtype=float)
    return local @ obj.X_SO[:3, :3].T + obj.X_SO[:3, 3]


def shelf_boxes(shelf: Shelf) -> list[tuple[np.ndarray, np.ndarray]]:
    """The shelf's panels as (lower corner, upper corner) boxes in the shelf frame: support, left, right,
    top, back. The front (y = -depth/2) is open."""
    w, h, d, t = shelf.width / 2, shelf.height, shelf.depth / 2, shelf.wall_thickness
    return [
        (np.array([-w - t, -d, -t]), np.array([w + t, d + t, 0.0])),  # support surface
        (np.array([-w - t, -d, 0.0]), np.array([-w, d + t, h])),  # left wall
        (np.array([w, -d, 0.0]), np.array([w + t, d + t, h])),  # right wall
        (np.array([-w - t, -d, h]), np.array([w + t, d + t, h + t])),  # top
        (np.array([-w, d, 0.0]), np.array([w, d + t, h])),  # back
    ]


def shelf_triangles(shelf: Shelf) -> np.ndarray:
    tris = [_unit_box() * (hi - lo) + (lo + hi) / 2 for lo, hi in shelf_boxes(shelf)]
    return np.concatenate(tris)


class SceneRaycaster:
    """An Embree scene of the shelf and the objects (and optionally the target), built once per scene.

    ``geometry_ids`` maps Embree's geomID to a label: 0 for the shelf, i + 1 for ``scene.objects[i]``,
    and len(objects) + 1 for the target when included. ``shelf=False`` leaves the shelf out (then the objects'
    labels start at 0): for rays to points the empty shelf already shows, where only the objects can hide them.
    """

    def __init__(self, scene: Scene, include_target: bool = False, objects=None, shelf: bool = True):
        self.scene = scene
        objects = scene.objects if objects is None else tuple(objects)
        self._embree = rtcore_scene.EmbreeScene(embree_device())
        meshes = ([shelf_triangles(scene.shelf)] if shelf else []) + [object_triangles(o) for o in objects]
        if include_target and scene.target is not None:
            meshes.append(object_triangles(scene.target.as_object()))
        for tris in meshes:
            mesh_construction.TriangleMesh(self._embree, tris.astype(np.float32))
        self.num_geometries = len(meshes)

    def first_hit(self, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ray parameter t of the first hit (origin + t * direction) and its geometry label, per ray.
        Rays that hit nothing get t = NO_HIT and label -1."""
        origins = np.ascontiguousarray(np.broadcast_to(origins, directions.shape), dtype=np.float32)
        directions = np.ascontiguousarray(directions, dtype=np.float32)
        if len(directions) == 0:
            return np.zeros(0), np.zeros(0, dtype=np.int32)
        out = self._embree.run(origins, directions, output=1)
        t = out["tfar"].astype(np.float64)
        label = out["geomID"].astype(np.int32)
        t[label < 0] = NO_HIT
        return t, label

    def hit_distance(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Ray parameter t of the first hit per ray (NO_HIT where none)."""
        origins = np.ascontiguousarray(np.broadcast_to(origins, directions.shape), dtype=np.float32)
        directions = np.ascontiguousarray(directions, dtype=np.float32)
        if len(directions) == 0:
            return np.zeros(0)
        t = self._embree.run(origins, directions, query="DISTANCE").astype(np.float64)
        t[t > 1e36] = NO_HIT
        return t

    def visible(self, eye: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Whether each point (..., 3) in the shelf frame is seen from ``eye`` (3,) past every occluder."""
        points = np.asarray(points, dtype=float)
        flat = points.reshape(-1, 3)
        t = self.hit_distance(eye, flat - eye)
        return (t >= 1.0 - VISIBILITY_EPS).reshape(points.shape[:-1])

    def render(self, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
        """Depth (H, W) float32 metres along the optical axis (0 where nothing is hit or beyond camera.far)
        and label (H, W) int32 image (geometry labels as in the class docstring, -1 for none)."""
        directions = camera.pixel_rays().reshape(-1, 3)
        t, label = self.first_hit(camera.position, directions)
        cos_axis = directions @ camera.X_SC[:3, 2]
        depth = t * cos_axis
        miss = (label < 0) | (depth > camera.far) | (depth < camera.near)
        depth[miss] = 0.0
        label[miss] = -1
        shape = (camera.height, camera.width)
        return depth.reshape(shape).astype(np.float32), label.reshape(shape)
