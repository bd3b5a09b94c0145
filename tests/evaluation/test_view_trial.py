"""``slax-drake view-trial``: the HTML replay of a finished trial from its records, without simulating again."""

from __future__ import annotations

import json

import numpy as np
import pytest

from slax_drake.cli import main
from slax_drake.evaluation.trial import OBJECT_POSES_FILE
from slax_drake.evaluation.trial_replay import _blend, _decision_poses
from slax_drake.scene.io import load_scene
from slax_drake.station import robot as robot_model
from slax_drake.station.scenario import load_station_scenario, observation_positions

STATION = "sim_configs/station_sim_shelf.yaml"


@pytest.fixture()
def trial_folder(tmp_path):
    """A trial folder as `slax-drake trial` writes it, reduced to what the replay reads: scene.json and a trial.json
    whose robot holds the observation pose for 2 s while object_0 is pushed 5 cm."""
    assert main(["scene", "--objects", "3", "--seed", "1", "--out", str(tmp_path / "scene.json")]) == 0
    scene = load_scene(tmp_path / "scene.json")
    q = observation_positions(load_station_scenario(STATION)).tolist()
    o = scene.objects[0]
    before = {"x": float(o.center[0]), "y": float(o.center[1]), "yaw": float(o.yaw)}
    after = {**before, "x": before["x"] + 0.05, "z": float(o.X_SO[2, 3]), "upright": True, "inside": True}
    data = {"station": STATION,
            "executed_trajectory": {"joint_names": list(robot_model.PLANNED_JOINTS), "times": [0.0, 1.0, 2.0],
                                    "positions": [q, q, q], "velocities": [[0.0] * 9] * 3,
                                    "accelerations": [[0.0] * 9] * 3},
            "steps_log": [{"time": 0.5, "poses_before": {o.name: before},
                           "motion": {"duration_s": 1.0}}],
            "final_objects": {o.name: after}}
    (tmp_path / "trial.json").write_text(json.dumps(data))
    return tmp_path


def test_an_older_trial_folder_replays_from_its_decision_poses(trial_folder, capsys):
    html = trial_folder / "view.html"
    assert main(["view-trial", str(trial_folder / "trial.json"), "--html", str(html)]) == 0
    assert "decision poses" in capsys.readouterr().out
    assert html.read_text().lstrip().lower().startswith("<!doctype html>")


def test_recorded_object_poses_are_used_when_present(trial_folder, capsys):
    scene = load_scene(trial_folder / "scene.json")
    poses = np.zeros((2, len(scene.objects), 7), np.float32)
    for i, o in enumerate(scene.objects):
        poses[:, i, :3] = o.X_SO[:3, 3]
        poses[:, i, 3] = 1.0
    np.savez(trial_folder / OBJECT_POSES_FILE, times=np.array([0.0, 2.0]), poses=poses,
             names=np.array([o.name for o in scene.objects]))
    assert main(["view-trial", str(trial_folder)]) == 0
    assert "recorded poses" in capsys.readouterr().out
    assert (trial_folder / "trial.html").is_file()


def test_decision_poses_move_the_object_when_its_motion_ends(trial_folder):
    data = json.loads((trial_folder / "trial.json").read_text())
    scene = load_scene(trial_folder / "scene.json")
    times, poses = _decision_poses(data, scene)
    assert list(times) == [0.0, 0.5, 2.0]
    x0 = scene.objects[0].X_SO[0, 3]
    assert poses[1, 0, 0] == pytest.approx(x0) and poses[2, 0, 0] == pytest.approx(x0 + 0.05)
    assert np.allclose(poses[:, 1, :3], scene.objects[1].X_SO[:3, 3])


def test_blend_interpolates_position_and_turn():
    a = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    b = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])  # a half turn about z
    mid = _blend(a, b, 0.5)
    assert mid[0] == pytest.approx(0.5) and np.linalg.norm(mid[3:]) == pytest.approx(1.0)


@pytest.mark.parametrize("remove", ["scene.json", "trial.json"])
def test_a_folder_missing_its_records_is_one_line(trial_folder, capsys, remove):
    (trial_folder / remove).unlink()
    assert main(["view-trial", str(trial_folder)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and remove in err[0]


def test_replay_given_a_trial_record_points_to_view_trial(trial_folder, capsys):
    assert main(["replay", str(trial_folder / "trial.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "slax-drake view-trial" in err[0]


@pytest.mark.slow
def test_the_replay_of_the_default_trial_ends_with_the_target_in_view(tmp_path):
    import shutil
    import subprocess

    import cv2

    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        pytest.skip("Debian's chromium package is not installed (apt-get install chromium)")
    assert main(["trial", "--quiet", "--out", str(tmp_path / "t")]) == 0
    assert main(["view-trial", str(tmp_path / "t")]) == 0
    shot = tmp_path / "shot.png"
    subprocess.run([browser, "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                    "--disable-background-networking", "--disable-component-update", "--disable-sync",
                    "--no-first-run", f"--user-data-dir={tmp_path / 'chromium'}", "--window-size=800,600",
                    "--virtual-time-budget=60000", f"--screenshot={shot}", (tmp_path / "t" / "trial.html").as_uri()],
                   check=True, timeout=180, capture_output=True)
    image = cv2.imread(str(shot))
    b, g, r = (image[..., i].astype(int) for i in range(3))
    assert np.count_nonzero((r > 150) & (g < 90) & (b < 90)) > 50  # the revealed target, red
