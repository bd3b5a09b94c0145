"""Bad input the command line refuses with one line on stderr and exit code 2, before doing any work."""

from __future__ import annotations

import pytest

from slax_drake.cli import main


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "scene.json"
    assert main(["scene", "--objects", "3", "--seed", "1", "--out", str(path)]) == 0
    return path


def _one_error_line(capsys, command: str) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"slax-drake {command}: error:")
    return err[0]


@pytest.mark.parametrize("option, value", [("--grid-step", "10"), ("--surface-spacing", "5.0"),
                                           ("--grid-step", "0.031")])
def test_occupancy_refuses_a_step_coarser_than_half_the_target(scene_file, tmp_path, capsys, option, value):
    out = tmp_path / "occ.npz"
    assert main(["occupancy", str(scene_file), option, value, "--out", str(out)]) == 2
    line = _one_error_line(capsys, "occupancy")
    assert option in line and "0.03" in line
    assert not out.exists()


def test_occupancy_accepts_a_coarse_but_meaningful_grid(scene_file, tmp_path, capsys):
    out = tmp_path / "occ.npz"
    assert main(["occupancy", str(scene_file), "--grid-step", "0.03", "--out", str(out)]) == 0
    assert out.exists()


@pytest.mark.parametrize("where", ["object", "target", "top"])
def test_a_scene_file_with_an_unknown_key_is_refused(scene_file, tmp_path, capsys, where):
    import json

    data = json.loads(scene_file.read_text())
    if where == "object":
        data["objects"][0]["mas"] = 2.0  # a misspelt mass
    elif where == "target":
        data["target"]["colour"] = "red"
    else:
        data["objekts"] = []
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    assert main(["occupancy", str(bad), "--out", str(tmp_path / "occ.npz")]) == 2
    line = _one_error_line(capsys, "occupancy")
    assert {"object": "objects[0].mas", "target": "target.colour", "top": "objekts"}[where] in line


@pytest.mark.parametrize("action", ["push:object_0:nan", "push:object_0:inf", "suction:object_0:0.1:nan"])
def test_check_action_refuses_a_distance_that_is_not_a_finite_number(scene_file, capsys, action):
    assert main(["check-action", "--scene", str(scene_file), "--action", action]) == 2
    assert "finite" in _one_error_line(capsys, "check-action")


def test_diagram_refuses_a_negative_depth_before_making_the_folder(tmp_path, capsys):
    out = tmp_path / "diagrams"
    with pytest.raises(SystemExit) as exit_:
        main(["diagram", "--depth", "-1", "--out", str(out)])
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--depth" in err[0]
    assert not out.exists()
