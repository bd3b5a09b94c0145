"""plan-step: a joint state outside the limits is refused at once, a revealed target plans nothing, and
--from-trial builds the inputs from a simulated trial's decision."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from slax_drake.cli import main
from slax_drake.config import load_scenario
from slax_drake.hardware.plan_step import StepPlanner
from slax_drake.scene.io import save_scene
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.sampling import sample_scene
from slax_drake.station.robot import PLANNED_JOINTS
from slax_drake.station.scenario import load_station_scenario, observation_positions

STATION = "sim_configs/station_sim_shelf.yaml"


def _scene(objects=3, seed=7, empty=False):
    scene = sample_scene(load_scenario(load_station_scenario(STATION).scene_config), objects, seed)
    return scene.with_objects(()) if empty else scene


def _files(tmp_path, scene, q=None):
    depth, labels = SceneRaycaster(scene, include_target=True).render(scene.camera)
    np.save(tmp_path / "frame.npy", np.where(np.isfinite(depth), depth, 0.0).astype(np.float32))
    cv2.imwrite(str(tmp_path / "mask.png"), ((labels == len(scene.objects) + 1) * 255).astype(np.uint8))
    q = observation_positions(load_station_scenario(STATION)) if q is None else q
    (tmp_path / "q.json").write_text(json.dumps({"joint_names": list(PLANNED_JOINTS), "positions": list(map(float, q))}))
    return ["plan-step", "--scenario", STATION, "--depth", str(tmp_path / "frame.npy"), "--target-mask",
            str(tmp_path / "mask.png"), "--joint-state", str(tmp_path / "q.json"), "--out", str(tmp_path / "step.json")]


def test_a_joint_state_outside_the_limits_is_refused(tmp_path, capsys):
    q = observation_positions(load_station_scenario(STATION)).copy()
    q[list(PLANNED_JOINTS).index("elbow_flex_joint")] = 3.0  # the limit is 2.251 rad
    assert main(_files(tmp_path, _scene(), q)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "elbow_flex_joint" in err[0] and "limits" in err[0]
    assert not (tmp_path / "step.json").exists()


def test_a_revealed_target_plans_nothing(tmp_path, capsys):
    assert main(_files(tmp_path, _scene(empty=True))) == 0
    out = capsys.readouterr().out
    assert "no action: the target is revealed" in out
    doc = json.loads((tmp_path / "step.json").read_text())
    assert doc["motions"] == [] and doc["metadata"]["plan_step"]["target_visibility"]["revealed"] is True


def test_the_visible_share_compares_the_mask_with_the_targets_size():
    planner = StepPlanner(STATION)
    scene = _scene(empty=True)
    depth, labels = SceneRaycaster(scene, include_target=True).render(scene.camera)
    alone = planner.target_visibility(depth, labels == 1)
    assert 0.85 <= alone["share"] <= 1.15 and alone["revealed"]
    half = labels == 1
    cols = np.nonzero(half.any(axis=0))[0]
    half[:, cols[len(cols) // 2]:] = False  # the right half hidden
    partly = planner.target_visibility(depth, half)
    assert 0.3 <= partly["share"] <= 0.7 and not partly["revealed"]
    assert planner.target_visibility(depth, np.zeros_like(half))["share"] is None


@pytest.fixture()
def trial_folder(tmp_path):
    """A trial folder reduced to what --from-trial reads: scene.json, step_depth.npz and trial.json with one
    decision at 0.5 s (the robot at the observation pose)."""
    scene = _scene()
    save_scene(scene, tmp_path / "scene.json")
    depth, _ = SceneRaycaster(scene).render(scene.camera.with_resolution(160, 120))
    np.savez(tmp_path / "step_depth.npz", times=np.array([0.5]),
             depth=np.where(np.isfinite(depth), depth, 0.0)[None].astype(np.float32))
    q = observation_positions(load_station_scenario(STATION)).tolist()
    poses = {o.name: {"x": float(o.center[0]), "y": float(o.center[1]), "yaw": float(o.yaw)} for o in scene.objects}
    (tmp_path / "trial.json").write_text(json.dumps({
        "station": STATION, "steps_log": [{"step": 0, "time": 0.5, "poses_before": poses}],
        "executed_trajectory": {"joint_names": list(PLANNED_JOINTS), "times": [0.0, 1.0], "positions": [q, q]}}))
    return tmp_path


def test_from_trial_builds_the_inputs_and_plans(trial_folder, capsys):
    out = trial_folder / "ps" / "step.json"
    assert main(["plan-step", "--from-trial", str(trial_folder), "--step", "1", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "inputs of decision 1" in printed
    inputs = trial_folder / "ps" / "step_inputs"
    assert np.load(inputs / "depth.npy").shape == (120, 160)
    assert json.loads((inputs / "joint_state.json").read_text())["joint_names"] == list(PLANNED_JOINTS)
    assert cv2.imread(str(inputs / "target_mask.png"), cv2.IMREAD_UNCHANGED).shape == (120, 160)
    assert json.loads(out.read_text())["metadata"]["plan_step"]["policy"] == "bluction-dar"


def test_from_trial_plans_with_the_trials_policy_unless_told(trial_folder, capsys):
    record = json.loads((trial_folder / "trial.json").read_text())
    (trial_folder / "trial.json").write_text(json.dumps({**record, "policy": "slax-belief"}))
    out = trial_folder / "ps" / "step.json"
    assert main(["plan-step", "--from-trial", str(trial_folder), "--step", "1", "--out", str(out)]) == 0
    assert "policy slax-belief" in capsys.readouterr().out
    assert json.loads(out.read_text())["metadata"]["plan_step"]["policy"] == "slax-belief"
    told = trial_folder / "ps" / "told.json"
    assert main(["plan-step", "--from-trial", str(trial_folder), "--step", "1", "--out", str(told), "--policy",
                 "dar"]) == 0
    assert json.loads(told.read_text())["metadata"]["plan_step"]["policy"] == "dar"


@pytest.mark.parametrize("extra, message", [(["--step", "2"], "decisions 1 to 1"), ([], "needs --step"),
                                            (["--step", "1", "--depth", "x.npy"], "one or the other")])
def test_from_trial_refuses_what_it_cannot_use(trial_folder, capsys, extra, message):
    assert main(["plan-step", "--from-trial", str(trial_folder), "--out", str(trial_folder / "s.json"), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
