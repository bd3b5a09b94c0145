"""Scene JSON: round trip, required fields, and a clear SceneFileError for each malformed case."""

import copy
import json

import numpy as np
import pytest

from slax_drake.errors import SceneFileError
from slax_drake.scene import load_scene, sample_scene, save_scene, scene_to_dict


@pytest.fixture(scope="module")
def scene_dict(sim_scenario):
    return scene_to_dict(sample_scene(sim_scenario, 5, 11))


def test_round_trip(tmp_path, sim_scenario):
    scene = sample_scene(sim_scenario, 5, 11)
    path = tmp_path / "scene.json"
    save_scene(scene, path)
    again = load_scene(path)
    assert scene_to_dict(again) == scene_to_dict(scene)
    data = json.loads(path.read_text())
    assert data["schema_version"] == 1
    assert set(data["shelf"]) >= {"width", "height", "depth"}
    assert set(data["camera"]) >= {"X_SC", "width", "height", "fx", "fy", "cx", "cy"}
    assert set(data["objects"][0]) == {"name", "shape", "size", "X_SO"}
    assert set(data["target"]) == {"size", "X_ST"}
    assert np.asarray(data["camera"]["X_SC"]).shape == (4, 4)


def test_camera_frame_convention(scene_dict):
    """z_C along the optical axis into the shelf (+y_S), x_C to the right (+x_S), y_C down the image."""
    R = np.asarray(scene_dict["camera"]["X_SC"])[:3, :3]
    assert R[:, 2][1] > 0.9  # optical axis mostly along +y_S
    assert R[:, 0] == pytest.approx([1, 0, 0])
    assert R[:, 1][2] < -0.9  # image down is world down


def _mutations():
    def drop(key):
        return lambda d: d.pop(key)

    def setp(path, value):
        def f(d):
            node = d
            for k in path[:-1]:
                node = node[k]
            node[path[-1]] = value
        return f

    return [
        (drop("schema_version"), "schema_version"),
        (setp(["schema_version"], 2), "schema_version' = 2"),
        (drop("shelf"), "missing field 'shelf'"),
        (setp(["shelf", "width"], -1), "shelf.width' = -1.0: must be positive"),
        (setp(["shelf", "height"], "tall"), "shelf.height' = 'tall': must be a finite number"),
        (drop("camera"), "missing field 'camera'"),
        (setp(["camera", "X_SC"], [[1, 0], [0, 1]]), "camera.X_SC' must be a 4x4 matrix"),
        (setp(["camera", "fx"], 0), "camera.fx' = 0.0: must be positive"),
        (setp(["objects"], {}), "field 'objects'"),
        (setp(["objects", 0, "shape"], "sphere"), "objects[0].shape' = 'sphere'"),
        (setp(["objects", 0, "size"], [0.1, 0.1]), "objects[0].size'"),
        (setp(["objects", 0, "size"], [0.1, -0.1, 0.1]), "objects[0].size'"),
        (setp(["objects", 1, "name"], "object_0"), "objects[1].name' = 'object_0'"),
        (setp(["objects", 0, "X_SO"], [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.05], [0, 0, 0, 1]]), "not a rigid transform"),
        (setp(["objects", 0, "X_SO", 0, 3], 5.0), "does not fit in the"),
        (setp(["target", "size"], "big"), "target.size'"),
        (setp(["target", "X_ST"], [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.5], [0, 0, 0, 1]]), "must rest on the shelf"),
        (setp(["seed"], "zero"), "seed"),
    ]


@pytest.mark.parametrize("mutate, expected", _mutations())
def test_malformed_scene_files(tmp_path, scene_dict, mutate, expected):
    data = copy.deepcopy(scene_dict)
    mutate(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(SceneFileError) as info:
        load_scene(path)
    message = str(info.value)
    assert message.startswith(str(path))
    assert expected in message, message


def test_not_json(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"schema_version": 1,')
    with pytest.raises(SceneFileError, match="not valid JSON"):
        load_scene(path)


def test_missing_file(tmp_path):
    with pytest.raises(SceneFileError, match="cannot read scene file"):
        load_scene(tmp_path / "none.json")


def test_save_is_atomic_and_keeps_old_file_on_failure(tmp_path, sim_scenario, monkeypatch):
    scene = sample_scene(sim_scenario, 3, 1)
    path = tmp_path / "scene.json"
    save_scene(scene, path)
    before = path.read_text()

    import slax_drake.io as io_module

    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(io_module.os, "replace", boom)
    with pytest.raises(RuntimeError):
        save_scene(sample_scene(sim_scenario, 4, 2), path)
    assert path.read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["scene.json"]


def test_atomic_writes_get_the_ordinary_file_mode(tmp_path, sim_scenario):
    """mkstemp creates 0600 files; a saved scene must be as readable as any other new file (0666 less umask)."""
    import os

    umask = os.umask(0)
    os.umask(umask)
    path = tmp_path / "scene.json"
    save_scene(sample_scene(sim_scenario, 3, 1), path)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask
