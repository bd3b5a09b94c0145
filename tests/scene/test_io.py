"""Scene JSON: round trip, required fields, and a clear SceneFileError for each malformed case."""

import copy
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st


from slax_drake.errors import SceneFileError
from slax_drake.scene import load_scene, sample_scene, save_scene, scene_to_dict

REPO = Path(__file__).resolve().parents[2]


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
    # the default scenario draws household masses (kg), recorded per object
    assert set(data["objects"][0]) == {"name", "shape", "size", "X_SO", "mass"}
    assert all(0.0 < o["mass"] < 10.0 for o in data["objects"])
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


def _box(name, x, y, size=(0.1, 0.1, 0.1), yaw=0.0):
    from slax_drake.scene.model import planar_pose

    return {"name": name, "shape": "box", "size": list(size), "X_SO": planar_pose(x, y, size[2] / 2, yaw).tolist()}


def _write(tmp_path, data):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize("gap_mm, accepted", [(5.0, True), (0.0, True), (-0.9, True), (-1.1, False), (-30.0, False)])
def test_interpenetration_beyond_one_millimetre_is_refused(tmp_path, scene_dict, gap_mm, accepted):
    """Two boxes side by side along x with a gap (negative: overlap); the tolerance is OVERLAP_TOLERANCE = 1 mm."""
    data = copy.deepcopy(scene_dict)
    data["target"] = None
    data["objects"] = [_box("left", -0.1, 0.0), _box("right", -0.1 + 0.1 + gap_mm / 1000, 0.0)]
    path = _write(tmp_path, data)
    if accepted:
        assert len(load_scene(path).objects) == 2
    else:
        with pytest.raises(SceneFileError) as info:
            load_scene(path)
        assert str(info.value) == (f"{path}: 'left' at (-0.100, 0.000) m and 'right' at ({-0.1 + 0.1 + gap_mm / 1000:.3f}, "
                                   "0.000) m interpenetrate by more than 1 mm")


def test_turned_box_and_cylinder_overlap_is_refused(tmp_path, scene_dict):
    """Exact footprints: a box turned 45 deg whose corner reaches 2 mm into a disc; its bounding box would reach
    much further, so an axis-aligned test would refuse a clear pair too (checked with the corner 2 mm short)."""
    import math

    half_diagonal = 0.05 * math.sqrt(2)
    for reach, refused in ((0.002, True), (-0.002, False)):
        data = copy.deepcopy(scene_dict)
        data["target"] = None
        cylinder = _box("can", 0.1, 0.0, size=(0.08, 0.08, 0.12))
        cylinder["shape"] = "cylinder"
        data["objects"] = [_box("turned", 0.1 - 0.04 - half_diagonal + reach, 0.0, yaw=math.pi / 4), cylinder]
        path = _write(tmp_path, data)
        if refused:
            with pytest.raises(SceneFileError, match="'turned' at .* and 'can' at .* interpenetrate by more than 1 mm"):
                load_scene(path)
        else:
            assert len(load_scene(path).objects) == 2


def test_target_inside_an_object_is_refused(tmp_path, scene_dict):
    data = copy.deepcopy(scene_dict)
    obj = data["objects"][2]
    x, y = obj["X_SO"][0][3], obj["X_SO"][1][3]
    data["target"]["X_ST"][0][3], data["target"]["X_ST"][1][3] = x, y
    with pytest.raises(SceneFileError, match=rf"'{obj['name']}' at .* and 'target' at .* interpenetrate"):
        load_scene(_write(tmp_path, data))


def test_every_command_that_reads_a_scene_refuses_overlap(tmp_path, scene_dict, capsys):
    """One loader serves occupancy, export --scene, check-trajectory --scene and replay --scene: the occupancy
    command (no Drake) shows the user's view of it: one line, exit code 2, nothing written."""
    from slax_drake.cli import main

    data = copy.deepcopy(scene_dict)
    data["objects"][1]["X_SO"][0][3] = data["objects"][0]["X_SO"][0][3]
    data["objects"][1]["X_SO"][1][3] = data["objects"][0]["X_SO"][1][3]
    path = _write(tmp_path, data)
    out = tmp_path / "occ.npz"
    assert main(["occupancy", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"slax-drake occupancy: error: {path}: 'object_0' at ")
    assert "'object_1' at " in err and err.count("\n") == 1
    assert not out.exists()


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**62), n=st.integers(1, 12), config=st.sampled_from(
    ["sim_shelf.yaml", "physical_shelf.yaml", "table1_aligned.yaml"]))
def test_every_sampled_scene_loads(seed, n, config):
    """The loader's overlap check never refuses what the sampler makes (its clearance is 2 mm, the tolerance 1 mm)."""
    from slax_drake.config import load_scenario
    from slax_drake.scene import scene_from_dict

    scenario = load_scenario(REPO / "sim_configs" / config)
    n = min(n, scenario.objects.count_range[1])
    scene = sample_scene(scenario, n, seed)
    assert scene_to_dict(scene_from_dict(json.loads(json.dumps(scene_to_dict(scene))))) == scene_to_dict(scene)
