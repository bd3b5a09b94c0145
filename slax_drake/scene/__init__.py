"""Shelf, objects, target and camera model; random scene sampling; scene JSON I/O."""

from slax_drake.scene.camera import Camera
from slax_drake.scene.io import load_scene, save_scene, scene_from_dict, scene_to_dict, scene_to_json
from slax_drake.scene.model import Scene, SceneObject, Shelf, Target, planar_pose
from slax_drake.scene.sampling import sample_scene, shelf_of, target_visible_fraction

__all__ = [
    "Camera", "Scene", "SceneObject", "Shelf", "Target", "load_scene", "planar_pose", "sample_scene",
    "save_scene", "scene_from_dict", "scene_to_dict", "scene_to_json", "shelf_of", "target_visible_fraction",
]
