"""The physics benchmark: a tiny run (one 2-object scene) writes physics.json/physics.md with the schema, resumes
from its per-scene file, refuses bad requests and corrupt files; the prediction-match rule."""

import json
import math

import pytest

from slax_drake.evaluation.table1 import scene_seed
from slax_drake.cli import main as cli_main
from slax_drake.errors import PhysicsBenchmarkError, UserError
from slax_drake.evaluation.physics import action_matches, run_physics_benchmark, trial_path

CONFIG = "sim_configs/sim_shelf.yaml"
TINY = dict(policies=["bluction-dar"], scenes_per_density=1, seed=3, densities=[2], progress=False)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("physics")
    return run_physics_benchmark(CONFIG, out=out, **TINY), out


@pytest.mark.slow
def test_tiny_benchmark_writes_the_files_with_the_schema(tiny):
    summary, out = tiny
    on_disk = json.loads((out / "physics.json").read_text())
    assert on_disk["policies"] == summary["policies"]
    assert set(on_disk["policies"]["bluction-dar"]) == {"2", "all"}
    e = on_disk["policies"]["bluction-dar"]["2"]
    assert e["trials"] == 1
    for key in ("shelf_success_rate", "drake_success_rate", "same_outcome_rate"):
        assert e[key] in (0.0, 1.0)
    assert 0 <= e["actions_matched"] <= e["actions_judged"]
    assert e["toppled"] >= 0 and e["dropped"] >= 0
    (row,) = on_disk["trials"]
    assert row["seed"] == scene_seed(3, 2, 0)
    assert on_disk["meta"]["densities"] == [2] and on_disk["meta"]["scenes_per_density"] == 1
    assert e["drake_clean_success_rate"] <= e["drake_success_rate"]
    assert sum(e["drake_endings"].values()) == e["trials"]
    assert (out / "physics.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (out / "physics.md").read_text()
    assert md.startswith("| Policy | Objects |") and "| bluction-dar | 2 | 1 |" in md

    scene = json.loads(trial_path(out, "bluction-dar", 2, 0).read_text())
    drake = scene["drake"]
    assert drake["steps"] == len(drake["actions"]) <= 4
    assert e["drake_success_rate"] == float(drake["success"])
    assert e["actions_judged"] == sum(a["matched"] is not None for a in drake["actions"])
    for a in drake["actions"]:
        assert a["matched"] == action_matches(a["predicted"], a["outcome"], a["before"])
        assert a["planning_s"] > 0.0 and a["rejected_before"] >= 0
        assert len(a["rejected"]) == a["rejected_before"]  # each refusal with its kind and waypoint
        assert set(a["motion_timings"]) == {"ik_s", "check_s", "timing_s"}
        assert "reversal_rule" in a  # kept from the trial's record, for undo_rules
    assert sum(e["undo_rules"].values()) == row["undoes"]
    planned = sorted(a["planning_s"] for a in drake["actions"])
    assert e["planned_actions"] == len(planned) == drake["steps"]
    if planned:
        assert planned[0] - 1e-3 <= e["planning_median_s"] <= e["planning_p90_s"] <= planned[-1] + 1e-3
        cpu = sorted(a["planning_cpu_s"] for a in drake["actions"])
        assert cpu[0] - 1e-3 <= e["planning_cpu_median_s"] <= e["planning_cpu_p90_s"] <= cpu[-1] + 1e-3
        assert f"CPU {e['planning_cpu_median_s']:.2f} / {e['planning_cpu_p90_s']:.2f}" in md
    assert set(drake["final_objects"]) == {"object_0", "object_1"}


@pytest.mark.slow
def test_shelf_side_is_the_shelf_benchmarks_scene(tiny):
    """The shelf simulator result in the file is the one of the shelf benchmark's scene for that seed."""
    from slax_drake.config import load_scenario
    from slax_drake.policies.registry import make_policy
    from slax_drake.shelf.simulator import run_trial
    from slax_drake.scene.sampling import sample_scene

    _, out = tiny
    scenario = load_scenario(CONFIG)
    scene = sample_scene(scenario, 2, scene_seed(3, 2, 0), target_size=tuple(scenario.target.sizes[0]))
    saved = json.loads(trial_path(out, "bluction-dar", 2, 0).read_text())
    # Both simulators plan under the station's limits, guarded placement and push model
    # (sim_configs/station_sim_shelf.yaml).
    assert saved["tool_rules"] == {"max_suction_moment": 0.4, "max_drag_pull": 42.412, "max_drag_twist": 0.6362, "max_seal_angle_deg": 10.0, "reach_map": "models/reach/station_sim_shelf.json",
                                   "suction_hidden_rule": "guarded", "push_turn": "quasi-static"}
    expected = run_trial(scene, make_policy("bluction-dar", scenario, perception="ground-truth", horizon=4,
                                            tool_overrides=saved["tool_rules"]), 4)
    shelf = saved["shelf"]
    assert (shelf["success"], shelf["steps"], shelf["actions"]) == (expected.success, expected.steps, expected.actions)


@pytest.mark.slow
def test_rerun_resumes_from_the_scene_file(tiny):
    summary, out = tiny
    again = run_physics_benchmark(CONFIG, out=out, **TINY)
    assert again["policies"] == summary["policies"]
    assert again["meta"]["wall_seconds_this_run"] < 1.0  # nothing was rerun: the file was read


@pytest.mark.slow
def test_corrupt_scene_file_is_refused(tiny, tmp_path):
    import shutil

    _, out = tiny
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    trial_path(copy, "bluction-dar", 2, 0).write_text('{"shelf": ')
    with pytest.raises(PhysicsBenchmarkError, match="unreadable result file"):
        run_physics_benchmark(CONFIG, out=copy, **TINY)


def main(argv):
    """``slax-drake benchmark --physics`` with ``argv``."""
    return cli_main(["benchmark", "--physics", *argv])


def test_bad_requests_exit_with_code_2(capsys, tmp_path):
    assert main(["--config", CONFIG, "--policies", "oracle-p", "--out", str(tmp_path)]) == 2
    assert "cannot run in a Drake trial" in capsys.readouterr().err
    assert main(["--config", CONFIG, "--policies", "nonsense", "--out", str(tmp_path)]) == 2
    assert "unknown policy 'nonsense'" in capsys.readouterr().err
    assert main(["--config", CONFIG, "--scenes-per-density", "0", "--out", str(tmp_path)]) == 2
    assert main(["--config", CONFIG, "--densities", "2,x", "--out", str(tmp_path)]) == 2
    assert main(["--config", CONFIG, "--backend", "local", "--ray-address", "auto", "--out", str(tmp_path)]) == 2
    assert "--ray-address needs --backend ray" in capsys.readouterr().err
    assert main(["--config", "no/such.yaml", "--out", str(tmp_path)]) == 2


def test_action_matches_within_2_cm_and_10_deg():
    p = {"x": 0.1, "y": 0.0, "yaw": math.pi - 0.01}
    assert action_matches(p, {"x": 0.1 + 0.019, "y": 0.0, "yaw": -math.pi + 0.05}) is True  # yaw wraps around pi
    assert action_matches(p, {"x": 0.1, "y": 0.021, "yaw": p["yaw"]}) is False
    assert action_matches(p, {"x": 0.1, "y": 0.0, "yaw": p["yaw"] - math.radians(11)}) is False
    assert action_matches(p, None) is None
    # with the true pose before the action, the object's own turn is judged: a hypothesis whose box axes are the
    # true box's turned by 90 deg predicts a yaw 90 deg off, and the untouched turn still matches
    before = {"x": 0.0, "y": 0.0, "yaw": p["yaw"] + math.pi / 2}
    assert action_matches(p, {"x": 0.1, "y": 0.0, "yaw": before["yaw"] + 0.05}, before) is True
    assert action_matches(p, {"x": 0.1, "y": 0.0, "yaw": before["yaw"] + 0.2}, before) is False


def test_a_diverged_simulation_is_a_failed_trial_not_a_crash(tmp_path, monkeypatch):
    """A Drake trial whose simulation blew up (a non-finite pose) ends "simulation diverged: ..." with its records
    and no final poses (``run_trial``; tests/systems/test_trial.py); the benchmark records that scene as a Drake
    failure with the reason, counts nothing lost, and goes on (one unstable scene stopped a 40-scene run)."""
    import slax_drake.evaluation.trial as trial

    message = "simulation diverged: SceneGraph encountered a non-finite value (e.g., NaN or infinity)"

    class Diverged:
        data = {"success": False, "result": message, "steps": 0, "cost": 0.0, "visible_fraction": 0.0,
                "sim_time_s": 3.0, "wall_s": 1.0, "real_time_factor": 3.0, "actions": [], "final_objects": {},
                "initial_objects": {}, "steps_log": []}

    monkeypatch.setattr(trial, "run_trial", lambda *args, **kwargs: Diverged())
    summary = run_physics_benchmark(CONFIG, out=tmp_path, **TINY)
    row = summary["trials"][0]
    assert row["drake_success"] is False and row["drake_result"] == message
    assert row["toppled"] == 0 and row["dropped"] == 0
    assert summary["policies"]["bluction-dar"]["2"]["drake_success_rate"] == 0.0
    saved = json.loads(trial_path(tmp_path, "bluction-dar", 2, 0).read_text())
    assert saved["drake"]["result"] == row["drake_result"]


def test_tool_rules_are_typed_and_bad_ones_exit_with_code_2(capsys, tmp_path):
    from slax_drake.shelf.tool import parse_tool_rules

    assert parse_tool_rules(["max_suction_moment=0.4", "tube_approach_check=false"]) == {
        "max_suction_moment": 0.4, "tube_approach_check": False}
    for bad, message in ((["no_such_rule=1"], "rule or tool field"), (["max_suction_moment=heavy"], "needs a float"),
                         (["tube_approach_check=maybe"], "needs a bool")):
        assert main(["--config", CONFIG, "--densities", "2", "--scenes-per-density", "1", "--out", str(tmp_path),
                     *[a for rule in bad for a in ("--tool-rule", rule)]]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1


def test_rules_equal_to_the_first_order_defaults_are_no_variant():
    import math

    from slax_drake.shelf.tool import without_defaults

    assert without_defaults({"max_suction_moment": math.inf, "max_seal_angle_deg": 90.0}) == {}
    assert without_defaults({"max_suction_moment": 0.4, "blade_gap": 0.035}) == {"max_suction_moment": 0.4}


@pytest.mark.slow
def test_a_resumed_run_refuses_scene_files_made_under_other_rules(tiny):
    _, out = tiny
    with pytest.raises(UserError, match="made with another --tool-rule"):
        run_physics_benchmark(CONFIG, out=out, tool_rules={"max_suction_moment": 0.3}, **TINY)
    with pytest.raises(UserError, match="made with another --sleep"):
        run_physics_benchmark(CONFIG, out=out, **{**TINY, "sleep": True})
    with pytest.raises(UserError, match="made with another Drake-trial observation"):
        run_physics_benchmark(CONFIG, out=out, **{**TINY, "sensor_noise": True})


@pytest.mark.slow
def test_the_physics_benchmark_runs_with_sensor_noise_and_says_so(tmp_path):
    summary = run_physics_benchmark(CONFIG, out=tmp_path, **{**TINY, "sensor_noise": True})
    assert summary["meta"]["sensor_noise"] is True
    settings = json.loads((tmp_path / "physics_settings.json").read_text())
    assert "L515 depth-noise model" in settings["drake_observation"]
    assert "with the L515 depth-noise model" in (tmp_path / "physics.md").read_text()


@pytest.mark.parametrize("argv, message", [
    (["trial", "--tool-rule", "hidden_space=foo"], "hidden_space = 'foo': must be one of"),
    (["trial", "--tool-rule", "blade_gap=-1"], "blade_gap = -1.0: must be non-negative"),
    (["benchmark", "--config", CONFIG, "--policies", "dar", "--tool-rule", "cell=0.003"],
     "push_resolution = 0.05: must be a multiple of cell"),
])
def test_unusable_tool_rule_values_exit_with_code_2_before_anything_runs(capsys, tmp_path, argv, message):
    from slax_drake.cli import main as cli_main

    assert cli_main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_mismatch_kinds_name_the_first_reason_an_action_missed_its_prediction():
    from slax_drake.evaluation.physics import mismatch_kind

    here = {"x": 0.0, "y": 0.0, "yaw": 0.0}
    predicted = {"x": 0.10, "y": 0.0, "yaw": 0.0}

    def kind(outcome, type_="push", lost=False, before=here):
        a = {"type": type_, "predicted": predicted, "outcome": outcome, "before": before, "lost_after": lost,
             "matched": action_matches(predicted, outcome)}
        return mismatch_kind(a, 0.6, 0.6)

    assert kind({"x": 0.11, "y": 0.0, "yaw": 0.0}) is None  # matched
    assert kind({"x": 0.0, "y": -0.5, "yaw": 0.0}, "suction", lost=True) == "dropped"
    assert kind({"x": 0.05, "y": 0.0, "yaw": 0.0}, lost=True) == "toppled"
    assert kind({"x": 0.005, "y": 0.0, "yaw": 0.02}, "suction") == "seal never formed"
    assert kind({"x": 0.005, "y": 0.0, "yaw": 0.02}, "push") == "slid"  # a push that stopped short slid
    assert kind({"x": 0.05, "y": 0.0, "yaw": 0.0}, "suction") == "slid"
    assert kind({"x": 0.10, "y": 0.0, "yaw": math.radians(25)}) == "turned"
    assert mismatch_kind({"type": "push", "matched": None, "outcome": None, "predicted": predicted}, 0.6, 0.6) is None


def test_summary_counts_match_per_action_kind_and_mismatch_kinds():
    from slax_drake.evaluation.physics import markdown_table, summarise

    def action(type_, matched, mismatch=None):
        a = {"type": type_, "matched": matched, "planning_s": 0.1}
        if mismatch:
            a["mismatch"] = mismatch
        return a

    drake = {"success": False, "result": "horizon", "steps": 4, "toppled": [], "dropped": [],
             "real_time_factor": 1.0, "wall_s": 1.0,
             "actions": [action("push", True), action("push", False, "slid"), action("suction", True),
                         action("suction", False, "seal never formed"), action("suction", None),
                         dict(action("suction", True), grip="drag"), dict(action("suction", False, "turned"),
                                                                           grip="drag")]}
    old = dict(drake, actions=[action("push", False)])  # a file from before the classification
    # a push whose hypothesis named its box 90 deg turned: recorded as turned, judged again as matched
    rejudged = {"type": "push", "matched": False, "mismatch": "turned", "planning_s": 0.1, "lost_after": False,
                "predicted": {"x": 0.1, "y": 0.0, "yaw": 0.0}, "outcome": {"x": 0.1, "y": 0.0, "yaw": 1.58},
                "before": {"x": 0.0, "y": 0.0, "yaw": 1.57}}
    drake = dict(drake, actions=drake["actions"] + [rejudged])
    results = [{"policy": "p", "density": 4, "index": i, "seed": i, "shelf": {"success": False, "steps": 4},
                "drake": d} for i, d in enumerate((drake, old))]
    e = summarise(results, ["p"], [4])["policies"]["p"]["all"]
    assert e["match_by_action"] == {"push": {"matched": 2, "judged": 4, "match_rate": 0.5},
                                    "suction": {"matched": 1, "judged": 2, "match_rate": 0.5},
                                    "drag": {"matched": 1, "judged": 2, "match_rate": 0.5}}
    assert e["mismatch_kinds"] == {"dropped": 0, "toppled": 0, "put back": 0, "seal never formed": 1, "slid": 1,
                                   "turned": 1, "unclassified": 1}
    md = markdown_table({"policies": {"p": {"all": {**e, "trials": 2}}}, "meta": {}})
    assert "| p | All | 50 % (2/4) | 50 % (1/2) | 50 % (1/2) | 0 | 0 | 0 | 1 | 1 | 1 | 1 |" in md


@pytest.mark.slow
def test_the_shelf_simulator_beside_can_see_through_its_camera_and_the_report_names_the_masses(tmp_path):
    from slax_drake.evaluation.table1 import CameraMode

    # as the CLI makes it: the shelf simulator's frames rendered at the camera's resolution, as the station's
    summary = run_physics_benchmark(CONFIG, out=tmp_path, **{**TINY, "shelf_camera": CameraMode(full_resolution=True)})
    assert summary["meta"]["shelf_observation"] == "camera" and summary["meta"]["shelf_full_resolution"] is True
    assert summary["meta"]["mass_model"] == "household"  # the shipped simulated shelf's
    settings = json.loads((tmp_path / "physics_settings.json").read_text())
    assert settings["observation"] == "camera" and settings["camera"] == {"segmentation": "labels",
                                                                          "sensor_noise": False,
                                                                          "full_resolution": True}
    text = (tmp_path / "physics.md").read_text()
    assert "with what its rendered camera sees" in text and "Object masses: household goods' masses" in text
    assert "resampled as the station's" in text


def _moved(x0, y0, x1, y1):
    return {"before": {"x": x0, "y": y0, "yaw": 0.0}, "outcome": {"x": x1, "y": y1, "yaw": 0.0}}


def test_reversals_count_moves_back_against_the_same_objects_previous_move():
    from slax_drake.evaluation.physics import reversals

    # object A pushed +10 cm, object B moved, A pulled back 8 cm: one reversal (A found where it was left)
    assert reversals([_moved(0.0, -0.1, 0.1, -0.1), _moved(-0.2, -0.1, -0.25, -0.1),
                      _moved(0.1, -0.1, 0.02, -0.1)]) == 1
    # the same displacements, but the third object stood elsewhere (another object): no reversal
    assert reversals([_moved(0.0, -0.1, 0.1, -0.1), _moved(0.3, -0.2, 0.22, -0.2)]) == 0
    # a move on along the same direction, and one back by less than 1 cm: no reversal
    assert reversals([_moved(0.0, -0.1, 0.1, -0.1), _moved(0.1, -0.1, 0.2, -0.1),
                      _moved(0.2, -0.1, 0.195, -0.1)]) == 0
    # reversed along y only (a suction pulled it to the front, a push-in... here a second suction sets it back)
    assert reversals([_moved(0.0, -0.05, 0.0, -0.2), _moved(0.0, -0.2, 0.0, -0.06)]) == 1
    # an action with no outcome (the trial ended) is skipped
    assert reversals([_moved(0.0, -0.1, 0.1, -0.1), {"before": None, "outcome": None}]) == 0


def test_undoes_count_the_reversals_that_put_an_object_back_or_just_past():
    from slax_drake.evaluation.physics import reversals, undoes

    # the issue's shuttle: -0.05, +0.10 (past the start by as much as the first move): both reversals undo
    shuttle = [_moved(0.0, -0.1, -0.05, -0.1), _moved(-0.05, -0.1, 0.05, -0.1), _moved(0.05, -0.1, -0.10, -0.1)]
    assert reversals(shuttle) == 2 and undoes(shuttle) == 2
    # a short push, then a suction carrying it far the other way: a reversal, not an undo
    relocation = [_moved(0.0, -0.1, 0.11, -0.1), _moved(0.11, -0.1, -0.24, -0.1)]
    assert reversals(relocation) == 1 and undoes(relocation) == 0


def test_an_undo_along_an_axis_the_action_does_not_command_is_drift_not_a_commanded_undo():
    from slax_drake.evaluation.physics import commanded_axes, commanded_undoes, undo_rules, undoes

    assert commanded_axes({"type": "push", "d": 0.05}) == {0}
    assert commanded_axes({"type": "suction", "dx": 0.0, "dz": -0.2}) == {1}
    assert commanded_axes({"type": "suction", "dx": 0.15, "dz": 0.05}) == {0, 1}
    # a suction pulls the object 5 cm out (y -0.05); a push along x then lets it drift 2 cm back in y (Table I 4:4)
    pulled = {**_moved(0.0, 0.0, -0.15, 0.05), "type": "suction", "dx": -0.15, "dz": 0.05}
    drift = {**_moved(-0.15, 0.05, -0.37, 0.027), "type": "push", "d": -0.22, "reversal_rule": None}
    assert undoes([pulled, drift]) == 1 and commanded_undoes([pulled, drift]) == 0
    assert undo_rules([pulled, drift], commanded=True) == {}
    # the same object pushed back along x, the axis the push commands: a commanded undo
    back = {**_moved(-0.15, 0.05, -0.02, 0.05), "type": "push", "d": 0.13, "reversal_rule": "let through"}
    assert commanded_undoes([pulled, back]) == 1 and undo_rules([pulled, back], commanded=True) == {"let through": 1}


def test_a_cycle_through_a_move_along_the_other_axis_is_an_undo_by_axis_only():
    """Drake trial 10:18: sucked +0.35 m along x, pulled along y alone, carried -0.35 m back along x."""
    from slax_drake.evaluation.physics import commanded_undoes

    out = {**_moved(0.0, -0.1, 0.35, -0.1), "type": "suction", "dx": 0.35, "dz": 0.0}
    pulled = {**_moved(0.35, -0.1, 0.35, -0.2), "type": "suction", "dx": 0.0, "dz": -0.10}
    back = {**_moved(0.35, -0.2, 0.0, -0.2), "type": "suction", "dx": -0.35, "dz": 0.0}
    assert commanded_undoes([out, pulled, back]) == 0
    assert commanded_undoes([out, pulled, back], by_axis=True) == 1
    # a move on along x in between is the last move along x: carrying it back past that one is no undo of it
    on = {**_moved(0.35, -0.2, 0.40, -0.2), "type": "push", "d": 0.05}
    farther = {**_moved(0.40, -0.2, 0.20, -0.2), "type": "push", "d": -0.20}
    assert commanded_undoes([out, pulled, on, farther], by_axis=True) == 0


def test_undo_rules_say_how_the_policys_correction_judged_each_undo():
    from slax_drake.evaluation.physics import undo_rules

    # the shuttle above, its second move let through by an exception and its third passed as uncovering new width
    shuttle = [_moved(0.0, -0.1, -0.05, -0.1), {**_moved(-0.05, -0.1, 0.05, -0.1), "reversal_rule": "let through"},
               {**_moved(0.05, -0.1, -0.10, -0.1), "reversal_rule": "uncovers new width"}]
    assert undo_rules(shuttle) == {"uncovers new width": 1, "let through": 1}
    # on the policy's estimate the move was no reversal (None); a record from before the field
    assert undo_rules([shuttle[0], {**shuttle[1], "reversal_rule": None}]) == {"not a move back by the estimate": 1}
    assert undo_rules([shuttle[0], _moved(-0.05, -0.1, 0.05, -0.1)]) == {"not recorded": 1}
    # a relocation is no undo: nothing to judge
    assert undo_rules([_moved(0.0, -0.1, 0.11, -0.1), {**_moved(0.11, -0.1, -0.24, -0.1), "reversal_rule": None}]) == {}


def test_the_summary_counts_the_lifts_weighed_and_put_back_and_why():
    from slax_drake.evaluation.physics import markdown_table, summarise

    before = {"x": 0.0, "y": -0.2, "yaw": 0.0}

    def lift(weighed, moved=0.1):
        return {"type": "suction", "grip": "lift", "planning_s": 0.1, "lost_after": False, "before": before,
                "predicted": {"x": 0.1, "y": -0.2, "yaw": 0.0}, "outcome": {"x": moved, "y": -0.2, "yaw": 0.0},
                "weighed": weighed}

    dragged = {"put_back": True, "why": "too heavy", "drag_after_weighing": {"drag": {}, "started_at": 12.0}}
    offered_none = {"put_back": True, "why": "too heavy", "drag_after_weighing": {"drag": None, "why": "x"}}
    drake = {"success": True, "result": "revealed", "steps": 5, "toppled": [], "dropped": [],
             "real_time_factor": 1.0, "wall_s": 1.0,
             "actions": [lift({"put_back": False}), lift({"put_back": True, "why": "too heavy"}, 0.0),
                         lift({"put_back": True, "why": "not hanging free"}, 0.0),
                         {**lift(dragged), "grip": "drag"}, lift(offered_none, 0.0)]}
    results = [{"policy": "p", "density": 4, "index": 0, "seed": 0, "shelf": {"success": True, "steps": 2},
                "drake": drake}]
    summary = summarise(results, ["p"], [4])
    assert summary["trials"][0]["weighed"] == [5, 4, 1]
    e = summary["policies"]["p"]["all"]
    assert e["weighed_lifts"] == [5, 4, 1] and e["put_back_why"] == {"not hanging free": 1, "too heavy": 3}
    # the lift dragged to its placement after the put-back is judged where the drag left its object: as predicted
    assert e["mismatch_kinds"]["put back"] == 3
    md = markdown_table(summary)
    assert ("Lifts weighed at the cup: 5, put back 4 (not hanging free 1, too heavy 3), 1 of them then dragged to "
            "the same placement.") in md


def test_the_summary_counts_the_drags_weighed_along_their_pull_apart_from_the_lifts():
    from slax_drake.evaluation.physics import markdown_table, summarise

    before = {"x": 0.0, "y": -0.2, "yaw": 0.0}

    def action(grip, weighed, moved=0.1):
        return {"type": "suction", "grip": grip, "planning_s": 0.1, "lost_after": False, "before": before,
                "predicted": {"x": 0.1, "y": -0.2, "yaw": 0.0}, "outcome": {"x": moved, "y": -0.2, "yaw": 0.0},
                "weighed": weighed}

    pushed_back = {"along": "pull", "friction_n": 8.5, "twist_nm": 1.02, "limit_nm": 0.64, "put_back": True,
                   "why": "twists off the cup", "mass_kg": 1.97}
    slid = {"along": "pull", "friction_n": 4.0, "twist_nm": 0.48, "limit_nm": 0.64, "put_back": False}
    short = {"along": "pull", "friction_n": None, "limit_nm": 0.64, "put_back": False}
    drake = {"success": True, "result": "revealed", "steps": 4, "toppled": [], "dropped": [],
             "real_time_factor": 1.0, "wall_s": 1.0,
             "actions": [action("drag", pushed_back, 0.0), action("drag", slid), action("drag", short),
                         action("lift", {"put_back": True, "why": "too heavy"}, 0.0)]}
    results = [{"policy": "p", "density": 4, "index": 0, "seed": 0, "shelf": {"success": True, "steps": 2},
                "drake": drake}]
    summary = summarise(results, ["p"], [4])
    assert summary["trials"][0]["weighed"] == [1, 1, 0]  # the lift alone
    assert summary["trials"][0]["pulls"] == [2, 1]  # a friction measured twice (one pull too short), pushed back once
    e = summary["policies"]["p"]["all"]
    assert e["weighed_pulls"] == [2, 1] and e["put_back_why"] == {"too heavy": 1}
    assert e["mismatch_kinds"]["put back"] == 2  # the pushed-back drag did not go where predicted either
    md = markdown_table(summary)
    assert "Lifts weighed at the cup: 1, put back 1 (too heavy 1)." in md
    assert "Sideways drags weighed along their pull: 2, pushed back as twisting off the cup 1." in md


def test_why_a_lift_was_put_back_is_read_from_the_values_of_a_record_that_kept_no_reason():
    from slax_drake.evaluation.physics import put_back_why

    assert put_back_why({"why": "too heavy", "weight_n": 0.0, "moment_nm": 0.0, "limit_nm": 0.4}) == "too heavy"
    assert put_back_why({"weight_n": 0.01, "moment_nm": 0.0, "limit_nm": 0.4}) == "nothing held"
    assert put_back_why({"weight_n": 6.0, "moment_nm": 0.45, "limit_nm": 0.4}) == "too heavy"
    assert put_back_why({"weight_n": 7.8, "moment_nm": 0.37, "limit_nm": 0.4}) == "not hanging free"


def test_the_report_says_how_many_no_feasible_motion_endings_refused_the_last_candidate_left():
    from slax_drake.evaluation.physics import markdown_table, summarise

    def trial(i, result, refused=None):
        drake = {"success": False, "result": result, "steps": 1, "toppled": [], "dropped": [],
                 "real_time_factor": 1.0, "wall_s": 1.0, "actions": []}
        if refused is not None:
            drake["end_rejected"] = [{"kind": "no IK solution", "waypoint": "pull out"}] * refused
        return {"policy": "p", "density": 4, "index": i, "seed": i, "shelf": {"success": False, "steps": 1},
                "drake": drake}

    results = [trial(0, "no feasible motion", 1), trial(1, "no feasible motion", 3), trial(2, "no feasible motion", 1),
               trial(3, "no feasible action", 0), trial(4, "horizon")]
    summary = summarise(results, ["p"], [4])
    assert [t["end_refused"] for t in summary["trials"]] == [1, 3, 1, 0, None]
    e = summary["policies"]["p"]["all"]
    assert e["no_motion_one_left"] == 2
    assert ("Of the 3 trials ending \"no feasible motion\", 2 ended when the motion planner refused the one "
            "candidate") in markdown_table(summary)
    # records from before end_rejected: the count is unknown, not 0
    old = [trial(0, "no feasible motion"), trial(1, "horizon")]
    e = summarise(old, ["p"], [4])["policies"]["p"]["all"]
    assert e["no_motion_one_left"] is None
    assert "ended when the motion planner refused" not in markdown_table(summarise(old, ["p"], [4]))


def test_the_stall_step_is_the_first_decision_whose_search_reveals_nothing():
    from slax_drake.evaluation.physics import stall_step

    assert stall_step([{"revealed": 0.3}, {"revealed": 0.0, "capped": True}, {"revealed": 0.0}, {"revealed": 0.0}]) == 2
    assert stall_step([{"revealed": 0.3}, {"stalled": True}]) == 1  # the policy stopped there (stuck_select "stop")
    assert stall_step([{"revealed": 0.3}, None, {}]) is None  # no decision log entry, or none with the share


def test_the_summary_counts_stalled_trials_and_the_actions_from_their_stall_on():
    from slax_drake.evaluation.physics import markdown_table, summarise

    def trial(i, success, stall, actions):
        act = {"type": "push", "d": 0.05, "planning_s": 0.1, "lost_after": False, "before": None,
               "predicted": {"x": 0.05, "y": 0.0, "yaw": 0.0}, "outcome": {"x": 0.05, "y": 0.0, "yaw": 0.0}}
        drake = {"success": success, "result": "revealed" if success else "horizon", "steps": actions,
                 "toppled": [], "dropped": [], "real_time_factor": 1.0, "wall_s": 1.0, "actions": [act] * actions}
        if stall != "unrecorded":
            drake["stall_step"] = stall
        return {"policy": "p", "density": 4, "index": i, "seed": i, "shelf": {"success": success, "steps": 1},
                "drake": drake}

    results = [trial(0, False, 2, 8), trial(1, True, 3, 5), trial(2, True, None, 2)]
    summary = summarise(results, ["p"], [4])
    assert [t["stall"] for t in summary["trials"]] == [[2, 6], [3, 2], [None, 0]]
    assert summary["policies"]["p"]["all"]["stalls"] == [2, 1, 8, 15]
    assert ("Stalls (the first decision at which no plan of the policy's reveals anything): 2 trials, 1 of them "
            "revealed the target after it; 8 of the 15 executed actions came from a stall on.") in markdown_table(summary)
    # a policy keeping no decision log (Bluction-DAR) or a record from before: no stall figures
    old = summarise([trial(0, False, "unrecorded", 3)], ["p"], [4])
    assert "stall" not in old["trials"][0] and "stalls" not in old["policies"]["p"]["all"]


def test_the_summary_counts_the_trials_whose_moves_pushed_the_target():
    from slax_drake.evaluation.physics import markdown_table, summarise

    def trial(i, success, moved):
        drake = {"success": success, "result": "revealed" if success else "horizon", "steps": 1, "toppled": [],
                 "dropped": [], "real_time_factor": 1.0, "wall_s": 1.0, "actions": [], "target_moved_m": moved}
        return {"policy": "p", "density": 4, "index": i, "seed": i, "shelf": {"success": success, "steps": 1},
                "drake": drake}

    summary = summarise([trial(0, True, 0.0645), trial(1, False, 0.012), trial(2, True, 0.004)], ["p"], [4])
    assert summary["policies"]["p"]["all"]["target_moved"] == [2, 1]
    assert ("The target pushed 1 cm or more by a move that brushed it: 2 trials, 1 of them revealed"
            in markdown_table(summary))
    # a diverged simulation (no final pose) is no moved target; none moved, the report says so
    calm = summarise([trial(0, True, 0.002), trial(1, False, None)], ["p"], [4])
    assert calm["policies"]["p"]["all"]["target_moved"] == [0, 0]
    assert "The target pushed 1 cm or more by a move that brushed it: in no trial." in markdown_table(calm)
    # records from before the target's pose was kept: unknown, not 0
    unrecorded = trial(0, True, None)
    del unrecorded["drake"]["target_moved_m"]
    old = summarise([unrecorded], ["p"], [4])
    assert old["policies"]["p"]["all"]["target_moved"] is None
    assert "The target pushed" not in markdown_table(old)


def test_the_report_counts_the_guarded_push_ins_retried_at_the_boards_edge():
    from slax_drake.evaluation.physics import markdown_table, summarise

    def trial(i, guards):
        actions = [{"type": "suction", "matched": True, "mismatch": None, "guard": g} for g in guards]
        drake = {"success": False, "result": "horizon", "steps": len(actions), "toppled": [], "dropped": [],
                 "real_time_factor": 1.0, "wall_s": 1.0, "actions": actions}
        return {"policy": "p", "density": 4, "index": i, "seed": i, "shelf": {"success": False, "steps": 1},
                "drake": drake}

    edge = {"stopped": False, "edge_stop": {"pushed_in_m": 0.018, "peak_force_n": 5.3}}
    unguarded = {"guarded": False, "edge_only": True, "stopped": False, "edge_stop": {"pushed_in_m": 0.015}}
    results = [trial(0, [edge, {"stopped": True}, unguarded]), trial(1, [{"stopped": False}])]
    summary = summarise(results, ["p"], [4])
    # an unguarded lift's retry at the edge is no guarded placement, but a push-in retried
    assert [t["guarded"] for t in summary["trials"]] == [[2, 1, 2], [1, 0, 0]]
    assert summary["policies"]["p"]["all"]["guarded_placements"] == [3, 1, 2]
    text = markdown_table(summary)
    assert "Guarded placements (a push-in into hidden space that stops on contact): 3, stopped on contact 1." in text
    assert "Lifted push-ins stopped at the board's front edge and pushed in again higher: 2." in text
    # a summary from before the retry holds two counts: no such sentence
    summary["policies"]["p"]["all"]["guarded_placements"] = [3, 1]
    assert "pushed in again higher" not in markdown_table(summary)
