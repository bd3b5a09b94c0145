"""Shelf, objects, target and camera model; random scene sampling; scene JSON I/O.

The names below are imported from their submodule on first use (:mod:`slax_drake.lazy_exports`)."""

from slax_drake.lazy_exports import lazy_exports

_EXPORTS = {
    "Camera": "camera",
    "load_scene": "io", "save_scene": "io", "scene_from_dict": "io", "scene_to_dict": "io", "scene_to_json": "io",
    "Scene": "model", "SceneObject": "model", "Shelf": "model", "Target": "model", "planar_pose": "model",
    "sample_scene": "sampling", "shelf_of": "sampling", "target_visible_fraction": "sampling",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
