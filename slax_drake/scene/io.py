"""Scene JSON (schema version 1): reading with validation, atomic writing.

Layout (all lengths metres, poses 4x4 row-major nested lists in the shelf frame S)::

    {"schema_version": 1, "seed": 0,
     "shelf": {"width", "height", "depth", "wall_thickness"},
     "camera": {"X_SC", "width", "height", "fx", "fy", "cx", "cy", "near", "far"},
     "objects": [{"name", "shape": "box" | "cylinder", "size": [x, y, z], "X_SO", "mass" (kg, optional)}],
     "target": {"size": [x, y, z], "X_ST"} | null}

Camera frame C: z along the optical axis, x right and y down in the image. Object frames sit at the object's
centre. ``wall_thickness``, ``near``, ``far`` and ``seed`` are optional on reading.

Validation on reading: no key beyond those above (a misspelt ``mass`` would otherwise be ignored silently), every
field's type and range, every object and the target resting upright on the support
surface inside the bay, and no two of them interpenetrating by more than ``OVERLAP_TOLERANCE`` (1 mm). Objects
stand on the floor only (nothing is stacked), so two bodies interpenetrate exactly when their footprints do; the
exact footprints of :mod:`slax_drake.scene.footprint` (oriented rectangles, discs) decide, and the penetration
depth is the smallest overlap of their projections (the separating-axis measure). Touching is allowed.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from slax_drake.errors import SceneFileError
from slax_drake.io import write_text_atomic
from slax_drake.scene.camera import Camera
from slax_drake.scene.footprint import Footprint, footprints_clear, inside_shelf
from slax_drake.scene.model import Scene, SceneObject, Shelf, Target

SCHEMA_VERSION = 1
DECIMALS = 10
OVERLAP_TOLERANCE = 0.001  # metres: two bodies may interpenetrate this much (rounding, contact) and no more


def scene_to_dict(scene: Scene) -> dict:
    data = {
        "schema_version": SCHEMA_VERSION,
        "seed": scene.seed,
        "shelf": scene.shelf.to_dict(),
        "camera": scene.camera.to_dict(),
        "objects": [o.to_dict() for o in scene.objects],
        "target": scene.target.to_dict() if scene.target is not None else None,
    }
    return _rounded(data)


def scene_to_json(scene: Scene) -> str:
    return json.dumps(scene_to_dict(scene), indent=1, sort_keys=False) + "\n"


def save_scene(scene: Scene, path: str | Path) -> None:
    """Writes the scene as JSON atomically (a temporary file renamed over the destination)."""
    write_text_atomic(Path(path), scene_to_json(scene))


def load_scene(path: str | Path) -> Scene:
    """Reads and validates a scene JSON file; raises SceneFileError with the file and the offending field."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise SceneFileError(f"{path}: cannot read scene file ({e.strerror})") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise SceneFileError(f"{path}: not valid JSON ({e.msg} at line {e.lineno})") from None
    try:
        return scene_from_dict(data)
    except SceneFileError as e:
        raise SceneFileError(f"{path}: {e}") from None


def scene_from_dict(data) -> Scene:
    """Builds a Scene from its JSON dictionary; raises SceneFileError naming the bad field."""
    if not isinstance(data, dict):
        raise SceneFileError("the scene must be a JSON object")
    _known_keys(data, ("schema_version", "seed", "shelf", "camera", "objects", "target"), "")
    version = data.get("schema_version")
    if version != SCHEMA_VERSION:
        raise SceneFileError(f"field 'schema_version' = {version!r}: this version of slax-drake reads version {SCHEMA_VERSION}")
    shelf_d = _field(data, "shelf", dict)
    _known_keys(shelf_d, ("width", "height", "depth", "wall_thickness"), "shelf")
    shelf = Shelf(
        width=_positive(shelf_d, "width", "shelf"),
        height=_positive(shelf_d, "height", "shelf"),
        depth=_positive(shelf_d, "depth", "shelf"),
        wall_thickness=_positive(shelf_d, "wall_thickness", "shelf", default=0.02),
    )
    cam_d = _field(data, "camera", dict)
    _known_keys(cam_d, ("X_SC", "width", "height", "fx", "fy", "cx", "cy", "near", "far"), "camera")
    camera = Camera(
        width=int(_positive(cam_d, "width", "camera")),
        height=int(_positive(cam_d, "height", "camera")),
        fx=_positive(cam_d, "fx", "camera"),
        fy=_positive(cam_d, "fy", "camera"),
        cx=_number(cam_d, "cx", "camera"),
        cy=_number(cam_d, "cy", "camera"),
        X_SC=_pose(cam_d, "X_SC", "camera"),
        near=_positive(cam_d, "near", "camera", default=0.1),
        far=_positive(cam_d, "far", "camera", default=5.0),
    )
    objects = []
    names = set()
    for i, obj_d in enumerate(_field(data, "objects", list)):
        where = f"objects[{i}]"
        if not isinstance(obj_d, dict):
            raise SceneFileError(f"field '{where}' must be an object")
        _known_keys(obj_d, ("name", "shape", "size", "X_SO", "mass"), where)
        name = obj_d.get("name")
        if not isinstance(name, str) or not name or name in names or name == "target":
            raise SceneFileError(f"field '{where}.name' = {name!r}: must be a unique non-empty string other than 'target'")
        names.add(name)
        shape = obj_d.get("shape")
        if shape not in ("box", "cylinder"):
            raise SceneFileError(f"field '{where}.shape' = {shape!r}: must be \"box\" or \"cylinder\"")
        size = _size(obj_d, where)
        if shape == "cylinder" and abs(size[0] - size[1]) > 1e-9:
            raise SceneFileError(f"field '{where}.size' = {list(size)}: a cylinder's size is [diameter, diameter, height]")
        X_SO = _pose(obj_d, "X_SO", where)
        _check_on_shelf(shelf, size, X_SO, where)
        mass = _positive(obj_d, "mass", where) if obj_d.get("mass") is not None else None
        objects.append(SceneObject(name=name, shape=shape, size=size, X_SO=X_SO, mass=mass))
    target = None
    if data.get("target") is not None:
        t_d = _field(data, "target", dict)
        _known_keys(t_d, ("size", "X_ST"), "target")
        size = _size(t_d, "target")
        X_ST = _pose(t_d, "X_ST", "target")
        _check_on_shelf(shelf, size, X_ST, "target")
        target = Target(size=size, X_ST=X_ST)
    _check_no_interpenetration(objects, target)
    seed = data.get("seed")
    if seed is not None and not isinstance(seed, int):
        raise SceneFileError(f"field 'seed' = {seed!r}: must be an integer or null")
    return Scene(shelf=shelf, camera=camera, objects=tuple(objects), target=target, seed=seed)


def _rounded(value):
    if isinstance(value, float):
        r = round(value, DECIMALS)
        return 0.0 if r == 0 else r
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_rounded(v) for v in value]
    if isinstance(value, np.generic):
        return _rounded(value.item())
    return value


def _known_keys(data: dict, known, where: str) -> None:
    """SceneFileError naming the first key of ``data`` that the schema does not have at ``where``."""
    for key in data:
        if key not in known:
            field = f"{where}.{key}" if where else str(key)
            raise SceneFileError(f"unknown field '{field}' (known here: {', '.join(known)})")


def _field(data: dict, key: str, kind: type, where: str = ""):
    name = f"{where}.{key}" if where else key
    if key not in data:
        raise SceneFileError(f"missing field '{name}'")
    value = data[key]
    if not isinstance(value, kind):
        raise SceneFileError(f"field '{name}' = {value!r}: must be a JSON {'object' if kind is dict else 'array' if kind is list else kind.__name__}")
    return value


def _number(data: dict, key: str, where: str, default=None) -> float:
    if key not in data and default is not None:
        return float(default)
    if key not in data:
        raise SceneFileError(f"missing field '{where}.{key}'")
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneFileError(f"field '{where}.{key}' = {value!r}: must be a finite number")
    return float(value)


def _positive(data: dict, key: str, where: str, default=None) -> float:
    value = _number(data, key, where, default)
    if value <= 0:
        raise SceneFileError(f"field '{where}.{key}' = {value!r}: must be positive")
    return value


def _size(data: dict, where: str) -> tuple[float, float, float]:
    size = data.get("size")
    if (
        not isinstance(size, list)
        or len(size) != 3
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in size)
    ):
        raise SceneFileError(f"field '{where}.size' = {size!r}: must be three positive lengths [x, y, z]")
    return tuple(float(v) for v in size)


def _pose(data: dict, key: str, where: str) -> np.ndarray:
    value = data.get(key)
    try:
        X = np.array(value, dtype=float)
    except (TypeError, ValueError):
        X = None
    if X is None or X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise SceneFileError(f"field '{where}.{key}' must be a 4x4 matrix of numbers (row-major nested lists)")
    R = X[:3, :3]
    if not np.allclose(X[3], [0, 0, 0, 1]) or not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise SceneFileError(f"field '{where}.{key}' is not a rigid transform (rotation must be orthonormal, last row 0 0 0 1)")
    return X


def _check_on_shelf(shelf: Shelf, size, X: np.ndarray, where: str) -> None:
    """Objects rest upright on the support surface, inside the bay."""
    if abs(X[2, 2] - 1.0) > 1e-6:
        raise SceneFileError(f"field '{where}' must rest upright: its pose may only yaw about z")
    x, y, z = X[:3, 3]
    if abs(z - size[2] / 2.0) > 1e-4:
        raise SceneFileError(f"field '{where}' has z = {z:.4f} m: it must rest on the shelf at z = size_z / 2 = {size[2] / 2:.4f} m")
    yaw = math.atan2(X[1, 0], X[0, 0])
    footprint = Footprint("box", float(x), float(y), yaw, size[0] / 2.0, size[1] / 2.0)
    if not inside_shelf(footprint, shelf, clearance=-1e-6) or size[2] > shelf.height + 1e-9:
        raise SceneFileError(
            f"field '{where}' at ({x:.3f}, {y:.3f}) m with size {list(size)} does not fit in the "
            f"{shelf.width} x {shelf.depth} x {shelf.height} m bay"
        )


def _check_no_interpenetration(objects: list[SceneObject], target: Target | None) -> None:
    """No two bodies (objects and the target) overlap by more than OVERLAP_TOLERANCE; names the first pair."""
    bodies = [(o.name, Footprint.of(o), o.radius) for o in objects]
    if target is not None:
        t = target.as_object()
        bodies.append(("target", Footprint.of(t), t.radius))
    for i, (name_a, a, radius_a) in enumerate(bodies):
        for name_b, b, radius_b in bodies[i + 1:]:
            if math.hypot(a.x - b.x, a.y - b.y) >= radius_a + radius_b:
                continue  # their bounding circles are apart
            if not footprints_clear(a, b, clearance=-OVERLAP_TOLERANCE):
                raise SceneFileError(
                    f"'{name_a}' at ({a.x:.3f}, {a.y:.3f}) m and '{name_b}' at ({b.x:.3f}, {b.y:.3f}) m "
                    f"interpenetrate by more than {OVERLAP_TOLERANCE * 1000:g} mm"
                )
