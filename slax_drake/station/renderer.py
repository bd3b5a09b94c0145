"""Depth and instance-label images of shelf scenes through Drake: SceneGraph + RenderEngineVtk + RgbdSensor.

The diagram (a SceneGraph with one VTK render engine and one RgbdSensor) is built once per camera and reused
for every scene: a scene's shelf, objects and target are registered as geometry *in the diagram's context*
(SceneGraph's context-modifying RegisterGeometry / RemoveGeometry), so changing scenes never rebuilds the
diagram. The world frame W of this diagram is the shelf frame S. The sensor's camera frame is the scene
``Camera``'s frame C (Drake and slax-drake share the convention z forward, x right, y down) at X_SC, with the
same fx, fy, cx, cy, so a point projects to the same pixel as ``Camera.project``.

Output images: depth (H, W) float32 metres along the optical axis, 0 where nothing lies within
[camera.near, camera.far]; label (H, W) int32 with the labels of ``SceneRaycaster``: 0 shelf, i + 1 for
``scene.objects[i]``, len(objects) + 1 for the target (when included), -1 for nothing.
RenderEngineVtk runs headless (EGL) on the CPU.
"""

from __future__ import annotations

import numpy as np

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene
from slax_drake.scene.raycast import shelf_boxes

RENDERER_NAME = "slax_vtk"
PIXEL_CENTRE_SHIFT = 0.5


def drake_camera_info(camera: Camera):
    """Drake CameraInfo with exactly the projection of ``camera``.

    RenderEngineVtk puts pixel (0, 0)'s centre at (0.5, 0.5); slax-drake's Camera puts it at (0, 0), so the
    principal point shifts by half a pixel. Measured: with the shift, rendered depth equals
    SceneRaycaster.render to 1e-6 m; without it, depth is off by up to 1.2 cm at object edges."""
    from pydrake.systems.sensors import CameraInfo

    return CameraInfo(camera.width, camera.height, camera.fx, camera.fy, camera.cx + PIXEL_CENTRE_SHIFT,
                      camera.cy + PIXEL_CENTRE_SHIFT)


class SceneRenderer:
    """Renders scenes seen by one ``Camera`` (intrinsics and pose fixed at construction)."""

    def __init__(self, camera: Camera):
        from pydrake.geometry import (
            ClippingRange,
            ColorRenderCamera,
            DepthRange,
            DepthRenderCamera,
            MakeRenderEngineVtk,
            RenderCameraCore,
            RenderEngineVtkParams,
            SceneGraph,
        )
        from pydrake.math import RigidTransform, RotationMatrix
        from pydrake.systems.framework import DiagramBuilder
        from pydrake.systems.sensors import RgbdSensor

        self.camera = camera
        builder = DiagramBuilder()
        scene_graph = builder.AddSystem(SceneGraph())
        scene_graph.AddRenderer(RENDERER_NAME, MakeRenderEngineVtk(RenderEngineVtkParams()))
        info = drake_camera_info(camera)
        core = RenderCameraCore(RENDERER_NAME, info, ClippingRange(camera.near * 0.5, camera.far * 2.0),
                                RigidTransform())
        depth_camera = DepthRenderCamera(core, DepthRange(camera.near, camera.far))
        color_camera = ColorRenderCamera(core, False)
        X_WC = RigidTransform(RotationMatrix(camera.X_SC[:3, :3]), camera.X_SC[:3, 3])
        sensor = builder.AddSystem(
            RgbdSensor(scene_graph.world_frame_id(), X_WC, color_camera, depth_camera))
        sensor.set_name("rgbd_sensor")
        builder.Connect(scene_graph.get_query_output_port(), sensor.query_object_input_port())
        self._source_id = scene_graph.RegisterSource("slax_scene")
        self._diagram = builder.Build()
        self._scene_graph = scene_graph
        self._sensor = sensor
        self._context = self._diagram.CreateDefaultContext()
        self._sg_context = scene_graph.GetMyMutableContextFromRoot(self._context)
        self._sensor_context = sensor.GetMyContextFromRoot(self._context)
        self._geometry_ids: list = []  # the current scene's objects and target
        self._shelf = None  # the shelf whose panels are registered, and their ids
        self._shelf_ids: list = []
        self._label_properties: dict = {}

    def render(self, scene: Scene, include_target: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Depth (H, W) float32 metres and label (H, W) int32 of ``scene`` (its camera is ignored: the
        renderer's own camera is used)."""
        self._set_scene(scene, include_target)
        depth = np.array(self._sensor.depth_image_32F_output_port().Eval(self._sensor_context).data,
                         dtype=np.float32)[:, :, 0]
        raw = np.array(self._sensor.label_image_output_port().Eval(self._sensor_context).data)[:, :, 0]
        depth[~np.isfinite(depth)] = 0.0
        label = raw.astype(np.int32) - 1  # geometry labels are stored shifted by one (RenderLabel 0 is avoided)
        label[(raw < 1) | (raw > self._max_label + 1)] = -1
        label[depth <= 0] = -1
        depth[label < 0] = 0.0
        return depth, label

    # ------------------------------------------------------------------------------------------------

    def _set_scene(self, scene: Scene, include_target: bool) -> None:
        """Registers the scene's geometry in the diagram's context. The shelf's panels stay registered while
        the shelf does not change (every scene of a scenario shares it); the objects and the target are
        removed and registered again for every scene (their sizes differ, and Drake geometry has no scale)."""
        from pydrake.geometry import Box, Cylinder

        sg, ctx = self._scene_graph, self._sg_context
        for gid in self._geometry_ids:
            sg.RemoveGeometry(ctx, self._source_id, gid)
        self._geometry_ids = []
        if scene.shelf != self._shelf:
            for gid in self._shelf_ids:
                sg.RemoveGeometry(ctx, self._source_id, gid)
            self._shelf_ids = []
            for k, (lo, hi) in enumerate(shelf_boxes(scene.shelf)):
                X = np.eye(4)
                X[:3, 3] = (lo + hi) / 2.0
                self._shelf_ids.append(self._register(f"shelf_{k}", Box(*(hi - lo)), X, 0))
            self._shelf = scene.shelf
        for i, obj in enumerate(scene.objects):
            shape = Box(*obj.size) if obj.shape == "box" else Cylinder(obj.size[0] / 2.0, obj.size[2])
            self._geometry_ids.append(self._register(f"object_{i}", shape, obj.X_SO, i + 1))
        self._max_label = len(scene.objects)
        if include_target and scene.target is not None:
            self._geometry_ids.append(
                self._register("target", Box(*scene.target.size), scene.target.X_ST, len(scene.objects) + 1))
            self._max_label += 1

    def _register(self, name: str, shape, X: np.ndarray, label: int):
        from pydrake.geometry import GeometryInstance
        from pydrake.math import RigidTransform, RotationMatrix

        instance = GeometryInstance(RigidTransform(RotationMatrix(X[:3, :3]), X[:3, 3]), shape, name)
        instance.set_perception_properties(self._properties(label))
        return self._scene_graph.RegisterGeometry(self._sg_context, self._source_id,
                                                  self._scene_graph.world_frame_id(), instance)

    def _properties(self, label: int):
        """Perception properties of a geometry with ``label`` (stored shifted by one), made once per label."""
        from pydrake.geometry import PerceptionProperties, RenderLabel, Rgba

        if label not in self._label_properties:
            props = PerceptionProperties()
            props.AddProperty("label", "id", RenderLabel(label + 1))
            props.AddProperty("phong", "diffuse", Rgba(0.6, 0.6, 0.6, 1.0))
            self._label_properties[label] = props
        return self._label_properties[label]
