"""Research scripts: bad arguments give one line on stderr and exit code 2 before any long run; their small helpers."""

import importlib.util
import json
import math
from pathlib import Path

import pytest

RESEARCH = Path(__file__).resolve().parents[1] / "research"


def script(name):
    """The module of ``research/<name>.py`` (the scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(f"research_script_{name}", RESEARCH / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("content", [None, "not json", '{"n": 1}', '{"candidates": [{"n": 6}]}'])
def test_reach_rule_refuses_an_unreadable_compare_file_before_planning(tmp_path, capsys, content):
    earlier = tmp_path / "earlier.json"
    if content is not None:
        earlier.write_text(content)
    assert script("reach_rule").main(["--compare", str(earlier), "--densities", "6", "--scenes", "1"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # refused before the first scene is planned
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --compare ")


@pytest.mark.parametrize("densities", ["4,x", "", "0,4"])
def test_noisy_faces_refuses_bad_densities(capsys, densities):
    with pytest.raises(SystemExit) as exit_info:
        script("noisy_faces").main(["--densities", densities])
    assert exit_info.value.code == 2
    assert "--densities: takes comma-separated whole numbers" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["--scenes", "0"], ["--width", "8"], ["--config", "no/such.yaml"]])
def test_depth_segment_merges_refuses_bad_arguments(capsys, argv):
    assert script("depth_segment_merges").main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ")


def test_depth_segment_merges_counts_a_merged_segment_and_a_split_object():
    """Hand-made labels: objects 1 and 2 share segment 1 (merged); object 3 spreads over segments 2 and 3 and its own
    region is in two parts (split around an occluder)."""
    import numpy as np

    labels = np.zeros((10, 20), int)
    labels[2:8, 0:4], labels[2:8, 4:8] = 1, 2
    labels[2:8, 10:13], labels[2:8, 15:18] = 3, 3
    seg = np.zeros_like(labels)
    seg[2:8, 0:8] = 1
    seg[2:8, 10:13], seg[2:8, 15:18] = 2, 3
    c = script("depth_segment_merges").frame_counts(None, labels, seg, 3)
    assert c["merged segments"] == 1 and c["objects in merged segments"] == 2
    assert c["split objects"] == 1 and c["split around an occluder"] == 1 and c["visible objects"] == 3


@pytest.mark.parametrize("argv", [["--scenes", "0"], ["--densities", "8,x"], ["--iou", "0"],
                                  ["--config", "no/such.yaml"]])
def test_depth_hypotheses_refuses_bad_arguments(capsys, argv):
    assert script("depth_hypotheses").main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ")


def test_depth_hypotheses_footprint_iou_is_one_for_the_same_object_and_zero_apart():
    from slax_drake.scene.model import SceneObject, planar_pose

    def box(x):
        return SceneObject("a", "box", (0.1, 0.1, 0.1), planar_pose(x, 0.0, 0.05, 0.0))

    iou = script("depth_hypotheses").footprint_iou
    assert iou(box(0.0), box(0.0)) == pytest.approx(1.0)
    assert iou(box(0.0), box(0.05)) == pytest.approx(1 / 3)
    assert iou(box(0.0), box(0.3)) == 0.0


def test_put_back_followups_counts_what_follows_a_put_back(tmp_path, capsys):
    trials = tmp_path / "run" / "trials" / "slax-belief"
    trials.mkdir(parents=True)
    put_back = "could not place the object: put back"
    (trials / "10_0000.json").write_text(json.dumps({
        "actions": ["suction object_1 dx=+0.1 dz=-0.2", "push object_2 d=+0.05", "suction object_1 dx=+0.2 dz=-0.2",
                    "suction object_1 dx=+0.3 dz=-0.1"],
        "notes": [f"step 1: {put_back}", f"step 3: {put_back}"]}))
    (trials / "10_0001.json").write_text(json.dumps({"actions": ["suction object_4 dx=-0.1 dz=0.1"],
                                                      "notes": [f"step 1: {put_back}"]}))
    c = script("put_back_followups").followups(tmp_path / "run", "slax-belief")
    assert (c["put back"], c["suctioned again"], c["put back again"], c["as planned"]) == (3, 2, 1, 1)
    assert c["at the next step"] == 1 and c["trials"] == 2
    assert script("put_back_followups").main([str(tmp_path / "nothing")]) == 2
    assert capsys.readouterr().err.startswith("error: ")


@pytest.mark.parametrize("name", ["put_back_followups", "partly_seen_target"])
def test_a_malformed_trial_file_is_refused_with_one_line(tmp_path, capsys, name):
    trials = tmp_path / "run" / "trials" / "slax-belief"
    trials.mkdir(parents=True)
    (trials / "10_0000.json").write_text('["not", "a", "record"]')
    assert script(name).main([str(tmp_path / "run")]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == f"error: {trials / '10_0000.json'}: not a trial record (a JSON object)\n"


@pytest.mark.parametrize("options", ['{"shuttle_rule": "far"}', "not json", "[1]"])
def test_belief_variants_refuses_bad_options_before_any_trial(capsys, options):
    assert script("belief_variants").main(["--options", options, "--trials", "4:0"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --options: ")


def test_frame_sampling_refuses_a_folder_that_is_no_physics_run_and_reads_first_actions(tmp_path, capsys):
    module = script("frame_sampling")
    assert module.main([str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and "no physics benchmark folder" in err[0]
    (tmp_path / "physics_settings.json").write_text(json.dumps({"config": "sim_configs/table1.yaml", "seed": 0}))
    assert module.main([str(tmp_path)]) == 2
    assert "no slax-belief trials" in capsys.readouterr().err
    assert module.kind_and_amount("push object_2 d=-0.145") == ("push", -0.145)
    assert module.kind_and_amount("suction object_1 dx=+0.200 dz=+0.092 yaw=-16deg") == ("suction", 0.2)
    push = {"type": "push", "d": -0.1449999, "rejected_before": 0}
    assert module.drake_first({"drake": {"actions": [push]}}) == ("push", -0.145)
    assert module.drake_first({"drake": {"actions": [{**push, "rejected_before": 1}]}}) is None


def test_lost_lifts_refuses_a_folder_that_is_no_physics_run(tmp_path, capsys):
    lost_lifts = script("lost_lifts")
    assert lost_lifts.main([str(tmp_path)]) == 2
    assert "is no physics benchmark folder" in capsys.readouterr().err


def test_lost_lifts_bands_a_lift_by_its_true_held_moment():
    lost_lifts = script("lost_lifts")
    assert lost_lifts.band(0.3, 0.4, 0.64).startswith("within the limit")
    assert lost_lifts.band(0.5, 0.4, 0.64).startswith("over the limit, under the lip")
    assert lost_lifts.band(0.7, 0.4, 0.64).startswith("over the lip")


def _physics_record(shelf_actions, drake_actions, shelf_success=True, drake_success=False):
    return {"shelf": {"actions": shelf_actions, "success": shelf_success, "reason": "revealed"},
            "drake": {"actions": drake_actions, "success": drake_success, "toppled": 0, "dropped": 0,
                      "result": "no feasible action"}}


def test_drake_divergence_finds_the_first_step_off_the_shelf_path_and_its_cause():
    module = script("drake_divergence")
    push = {"type": "push", "true_object": "object_2", "d": -0.0851, "rejected_before": 0, "matched": True}
    lift = {"type": "suction", "true_object": "object_4", "dx": 0.40, "dz": -0.19, "rejected_before": 0,
            "matched": True}
    shelf = ["push object_2 d=-0.085", "suction object_4 dx=+0.400 dz=-0.206 yaw=+4deg"]
    assert module.divergence(_physics_record(shelf, [push, lift])) == (2, "same actions")
    assert module.divergence(_physics_record(shelf, [push])) == (1, "Drake stopped (no feasible action)")
    other = {**lift, "dx": 0.10}
    assert module.divergence(_physics_record(shelf, [push, other])) == (1, "same predicted state, other decision")
    assert module.divergence(_physics_record(shelf, [{**push, "mismatch": "slid", "matched": False}, other])) == (
        1, "last action off prediction (slid)")
    assert module.divergence(_physics_record(shelf, [{**push, "true_object": "object_0", "rejected_before": 1}])) == (
        0, "planner refused")
    refused = {**push, "true_object": "object_0", "rejected_before": 1,
               "rejected": [{"action": "push track_3 d=-0.085", "kind": "tool collides", "waypoint": "insert"}]}
    assert module.divergence(_physics_record(shelf, [refused])) == (0, "planner refused (tool collides at insert)")
    assert module.divergence(_physics_record(shelf, [{**push, "d": -0.03}])) == (0, "first decision differs")


def test_drake_divergence_refuses_a_folder_without_trial_files(tmp_path, capsys):
    assert script("drake_divergence").main([str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {tmp_path}")


def test_drake_divergence_tallies_the_planners_refusals(tmp_path, capsys):
    folder = tmp_path / "physics_trials" / "slax-belief"
    folder.mkdir(parents=True)
    refused = {"type": "push", "true_object": "object_0", "d": 0.1, "rejected_before": 2, "matched": True,
               "rejected": [{"action": "a", "kind": "tool collides", "waypoint": "insert"},
                            {"action": "b", "kind": "tool collides", "waypoint": "insert"}]}
    record = _physics_record(["push object_2 d=-0.085"], [refused])
    (folder / "04_0000.json").write_text(json.dumps({**record, "seed": 1}))
    assert script("drake_divergence").main([str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "- 04_0000: step 0, planner refused (tool collides at insert)" in out
    assert "| tool collides | insert | 2 |" in out


def test_belief_variants_known_target_tells_the_search_where_the_target_stands(capsys):
    """Scene 4:14 under the Drake station's rules: the earlier default's first push locks the shelf (no feasible
    action after one move); told where the target stands, its search takes the suction that reveals it."""
    rules = [f"--tool-rule={r}" for r in ("max_drag_pull=42.412", "max_drag_twist=0.6362", "max_seal_angle_deg=10",
                                          "max_suction_moment=0.4", "reach_map=models/reach/station_sim_shelf.json",
                                          "suction_hidden_rule=guarded")]
    args = ["--trials", "4:14", "--policy", "slax-belief-box", "--profile", "station",
            "--config", "sim_configs/table1_household.yaml", *rules]
    module = script("belief_variants")
    assert module.main(args) == 0
    assert "revealed 0 / 1" in capsys.readouterr().out
    assert module.main(args + ["--known-target"]) == 0
    assert "revealed 1 / 1" in capsys.readouterr().out


def test_belief_variants_shows_hidden_objects_only_to_a_privileged_observation(capsys):
    assert script("belief_variants").main(["--trials", "4:0", "--see-hidden", "--observation", "camera"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.strip() == "error: --see-hidden needs the privileged observation"
    # a policy with no belief of placements cannot be told the target: refused before any trial
    assert script("belief_variants").main(["--trials", "4:0", "--known-target", "--policy", "dar"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.strip().startswith("error: --known-target: dar keeps no belief")


def test_partly_seen_target_counts_the_notes_from_the_first_sight_on():
    module = script("partly_seen_target")
    assert module.note_kind("step 4: push stopped after -0.085 m by an unseen obstacle") == (
        "push stopped after X m by an unseen obstacle")
    assert module.note_kind("step 2: blade blocked by object_3") == "blade blocked by OBJ"
    seen_at_2 = {"visible_fractions": [0.0, 0.4, 0.4, 0.4], "actions": ["a", "b", "c", "d"],
                 "notes": ["step 1: could not place the object: put back",  # before the sight: not counted
                           "step 2: could not place the object: put back",
                           "step 4: blade blocked by track_7"]}
    actions, kinds = module.notes_after_sight({"06_0001": seen_at_2})
    assert actions == 3
    assert kinds == {"could not place the object: put back": 1, "blade blocked by OBJ": 1}


@pytest.mark.parametrize("flag", ["--plan-clearance", "--placement-margin"])
def test_belief_variants_refuses_a_margin_out_of_range_before_any_trial(capsys, flag):
    assert script("belief_variants").main([flag, "0.2", "--trials", "4:0"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == f"error: {flag} must be in [0, 0.1) m (got 0.2)\n"


def test_belief_variants_refuses_a_margin_for_a_policy_without_its_action_model_wrapper(capsys):
    assert script("belief_variants").main(["--placement-margin", "0.01", "--policy", "bluction-dar",
                                           "--trials", "4:0"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("error: --plan-clearance / --placement-margin: bluction-dar is not slax-belief")


def test_belief_variants_placement_margin_refuses_placements_the_clearance_alone_allows():
    from slax_drake.config import load_scenario
    from slax_drake.evaluation.table1 import protocol_scene, scene_seed
    from slax_drake.policies.registry import make_policy
    from slax_drake.shelf.actions import Suction

    module = script("belief_variants")
    scenario = load_scenario(Path(__file__).resolve().parents[1] / "sim_configs" / "table1.yaml")
    scene = protocol_scene(scenario, 6, scene_seed(0, 6, 0))
    placements = {}
    for margin in (None, 0.02):
        policy = make_policy("slax-belief", scenario, horizon=12, profile="paper")
        if margin is not None:
            module.plan_with_margin(policy, None, margin)
        found = policy.action_model.enumerate(tuple(scene.objects))
        placements[margin] = {a for a in found.feasible if isinstance(a, Suction)}
    assert placements[0.02] and placements[0.02] < placements[None]  # fewer, none new


def test_stall_analysis_census_counts_stalls_and_the_actions_from_them_on(tmp_path, capsys):
    trials = tmp_path / "run" / "trials" / "slax-belief"
    trials.mkdir(parents=True)
    stalled = [{"revealed": 0.4}, {"revealed": 0.0}, {"revealed": 0.0}, {"revealed": 0.2}]
    (trials / "10_0000.json").write_text(json.dumps({"density": 10, "steps": 4, "success": True,
                                                     "decision_log": stalled}))
    (trials / "10_0001.json").write_text(json.dumps({"density": 10, "steps": 2, "success": True,
                                                     "decision_log": [{"revealed": 0.5}, {"revealed": 1.0}]}))
    (trials / "04_0000.json").write_text(json.dumps({"density": 4, "steps": 3, "success": False,
                                                     "decision_log": str([{"revealed": 0.0, "capped": True},
                                                                          {"revealed": 0.0}, {"revealed": 0.0}])}))
    module = script("stall_analysis")
    assert module.main(["--census", str(tmp_path / "run")]) == 0
    out = capsys.readouterr().out
    assert "  4: 1 / 0 / 1 / 0 / 3 / 2\n" in out  # a capped search is not a stall: it stalled at its second decision
    assert "  10: 2 / 2 / 1 / 1 / 6 / 3\n" in out
    assert "  all: 3 / 2 / 2 / 1 / 9 / 5\n" in out
    (trials / "10_0002.json").write_text('["not", "a", "record"]')
    assert module.main(["--census", str(tmp_path / "run")]) == 2
    assert capsys.readouterr().err.startswith(f"error: {trials / '10_0002.json'}: unreadable trial file")


def test_stall_analysis_census_of_a_physics_folder_cuts_its_trials_at_the_stall(tmp_path, capsys):
    def record(density, stall, success, clean, steps, policy="slax-belief"):
        return {"policy": policy, "density": density, "stall": stall, "drake_success": success,
                "drake_clean_success": clean, "drake_steps": steps}

    run = tmp_path / "physics_run"
    run.mkdir()
    trials = [record(4, [None, 0], True, True, 2),  # never stalled: kept as it was
              record(4, [1, 3], True, True, 4),  # revealed after its stall: stopping there loses it
              record(6, [0, 5], False, False, 5),  # stalled at its first decision, lost an object
              record(6, [None, 0], True, False, 3),  # revealed with an object lost
              record(6, [2, 1], True, True, 3, policy="bluction-dar")]
    (run / "physics.json").write_text(json.dumps({"meta": {}, "policies": {}, "trials": trials}))
    module = script("stall_analysis")
    assert module.main(["--census", str(run)]) == 0
    out = capsys.readouterr().out
    assert "  4: 2 / 2 / 2 / 1 / 1 (1) / 6 / 3; stopped: 1 / 1 / 3\n" in out
    assert "  6: 2 / 1 / 0 / 1 / 0 (0) / 8 / 5; stopped: 1 / 0 / 3\n" in out
    assert "  all: 4 / 3 / 2 / 2 / 1 (1) / 14 / 8; stopped: 2 / 1 / 6\n" in out
    assert module.main(["--census", str(run), "--policy", "der-3"]) == 2
    assert "no Drake trials of der-3" in capsys.readouterr().err
    (run / "physics.json").write_text(json.dumps({"trials": [{"policy": "slax-belief"}]}))
    assert module.main(["--census", str(run)]) == 2
    assert capsys.readouterr().err.startswith(f"error: {run / 'physics.json'}: unreadable physics record")


@pytest.mark.parametrize("argv", [[], ["--trials", "4:x"], ["--trials", "4:0", "--config", "nope.yaml"],
                                  ["--census", "nowhere"]])
def test_stall_analysis_refuses_bad_arguments(capsys, argv):
    assert script("stall_analysis").main(argv) == 2
    assert capsys.readouterr().err.startswith("error: ")


@pytest.mark.slow  # a 4-object trial and two oracle searches of a second each
def test_stall_analysis_follows_a_trial_to_its_stall_and_asks_the_oracle(capsys):
    module = script("stall_analysis")
    rules = ["max_drag_pull=42.412", "max_drag_twist=0.6362", "max_seal_angle_deg=10", "max_suction_moment=0.4",
             "reach_map=models/reach/station_sim_shelf.json", "suction_hidden_rule=guarded"]
    argv = ["--trials", "4:4", "--full-resolution", "--variants", "--oracle-seconds", "1"]
    for rule in rules:
        argv += ["--tool-rule", rule]
    assert module.main(argv) == 0
    out = capsys.readouterr().out
    assert "04_0004 revealed=False" in out and "stall at decision 2" in out
    assert "corrections off: reveals 1.00 of the belief" in out
    assert "  stalled: 1\n" in out


@pytest.mark.parametrize("argv", [["--sizes", "0.1x"], ["--sizes", "0.1x0.2x0.3"], ["--d", "a"], ["--contacts", "back"]])
def test_push_contact_refuses_bad_arguments_before_any_drake_run(capsys, argv):
    with pytest.raises(SystemExit) as e:
        script("push_contact").main(argv)
    assert e.value.code == 2 and "error:" in capsys.readouterr().err


def test_push_matches_refuses_a_folder_that_is_no_physics_run(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        script("push_matches").main([str(tmp_path)])
    assert e.value.code == 2 and "no physics run with trial files" in capsys.readouterr().err


@pytest.mark.parametrize("argv, start", [(["no/such/trial"], "error: no/such/trial: not a trial folder"),
                                         (["."] + ["--stances", "0", "0.1"], "error: --stances: 0 is where")])
def test_ending_stances_refuses_bad_arguments(capsys, monkeypatch, argv, start):
    monkeypatch.syspath_prepend(str(RESEARCH))  # the script imports its sibling reach_rule
    assert script("ending_stances").main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(start)


def test_drag_twist_refuses_a_folder_that_is_no_physics_run_and_quantiles_outside_0_1(tmp_path, capsys):
    drag_twist = script("drag_twist")
    assert drag_twist.main([str(tmp_path)]) == 2
    assert "no physics benchmark folder" in capsys.readouterr().err
    assert drag_twist.main([str(tmp_path), "--quantiles", "0.5,1.5"]) == 2
    assert "outside 0-1" in capsys.readouterr().err


def test_decision_options_tables_a_physics_folder_and_the_decisions_page_holds_its_output(tmp_path, capsys):
    import re

    module = script("decision_options")
    run = tmp_path / "run"
    run.mkdir()
    trials = [{"policy": "p", "density": 4, "drake_success": True, "drake_clean_success": True, "shelf_success": False,
               "drake_steps": 3, "drake_result": "revealed", "toppled": 0, "dropped": 0, "stall": [None, 0]},
              {"policy": "p", "density": 4, "drake_success": True, "drake_clean_success": False, "shelf_success": True,
               "drake_steps": 5, "drake_result": "revealed", "toppled": 1, "dropped": 1, "stall": [2, 3]},
              {"policy": "p", "density": 6, "drake_success": False, "drake_clean_success": False,
               "shelf_success": True, "drake_steps": 2, "drake_result": "no feasible motion", "toppled": 0,
               "dropped": 0, "stall": [1, 1]}]
    policies = {"p": {"all": {"actions_judged": 10, "actions_matched": 9}}}
    (run / "physics.json").write_text(json.dumps({"meta": {}, "policies": policies, "trials": trials}))
    assert module.main([str(run)]) == 0
    assert "| `run` | `p` | 3 | **1** (33.33 %) | 2 | 2 | 10 (90 %) | 1 | 2 | 2 (1) |" in capsys.readouterr().out
    assert module.main([f"{run}:q"]) == 2 and "no Drake trials of q" in capsys.readouterr().err
    assert module.main([str(tmp_path)]) == 2 and "unreadable physics record" in capsys.readouterr().err
    # the page's table is the script's output for the folders its command names
    repo = RESEARCH.parent
    page = (repo / "docs" / "research" / "decisions.md").read_text()
    block = re.search(r"<!-- decision-options:begin -->\n(.*?)\n<!-- decision-options:end -->", page, re.S).group(1)
    args = re.search(r"Generated by `python research/decision_options.py ([^`]*)`", page).group(1).split()
    assert len(args) >= 2 and block == module.table([str(repo / a) for a in args])


def _drake_record(moves):
    """A physics trial's Drake record: two objects, then ``moves`` (true object, x, y, yaw) as executed actions."""
    return {"initial_objects": {"a": {"x": 0.0, "y": 0.0, "yaw": 0.0}, "b": {"x": 0.2, "y": 0.0, "yaw": 0.0}},
            "actions": [{"true_object": n, "outcome": {"x": x, "y": y, "yaw": w}} for n, x, y, w in moves],
            "result": "horizon"}


def test_arrangement_returns_finds_a_cycle_and_not_an_action_that_moved_nothing():
    returns = script("arrangement_returns").returns
    # a around a square: right, deeper, left, and back to the front within 5 mm of where it started
    square = [("a", 0.1, 0.0, 0.0), ("a", 0.1, 0.1, 0.0), ("a", 0.0, 0.1, 0.0), ("a", 0.005, 0.0, 0.0)]
    assert returns(_drake_record(square)) == [(4, 0)]
    assert returns(_drake_record(square[:3])) == []
    # moved nothing twice (a put-back): not a cycle; a box turned by pi stands the same
    assert returns(_drake_record([("a", 0.003, 0.0, 0.0), ("a", 0.0, 0.0, 0.0)])) == []
    turned = [("b", 0.2, 0.1, 0.0), ("b", 0.2, 0.0, math.pi)]
    assert returns(_drake_record(turned)) == [(2, 0)]
    # another object standing elsewhere makes it a new arrangement
    assert returns(_drake_record(square[:3] + [("b", 0.25, 0.0, 0.0), ("a", 0.0, 0.0, 0.0)])) == []


def test_arrangement_returns_refuses_a_folder_without_trial_files(tmp_path, capsys):
    assert script("arrangement_returns").main([str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {tmp_path}")


def test_lost_objects_tells_collateral_losses_and_objects_beneath_the_bay():
    lost_objects = script("lost_objects").lost_objects
    drake = {"toppled": ["b"], "dropped": ["a", "c", "b"],
             "final_objects": {"a": {"x": 0.0, "y": -0.29, "z": -0.09}, "b": {"x": 0.1, "y": 0.0, "z": 0.03},
                               "c": {"x": 0.0, "y": -0.45, "z": -0.75}, "d": {"x": 0.2, "y": 0.1, "z": 0.05}},
             "actions": [{"true_object": "b", "mismatch": None}, {"true_object": "d", "mismatch": None},
                         {"true_object": "b", "mismatch": "toppled"}, {"true_object": "c", "mismatch": "dropped"}]}
    rows = {r["object"]: r for r in lost_objects(drake, 0.6, 0.6)}
    assert set(rows) == {"a", "b", "c"}  # d was moved and kept
    assert rows["a"]["moved_by"] == [] and rows["a"]["beneath"]  # collateral, under the board at the front edge
    assert rows["b"]["how"] == "toppled and dropped" and rows["b"]["moved_by"] == [(1, None), (3, "toppled")]
    assert not rows["b"]["beneath"] and not rows["c"]["beneath"]  # on the board; on the room's floor


def test_lost_objects_refuses_a_folder_without_settings(tmp_path, capsys):
    assert script("lost_objects").main([str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and str(tmp_path) in err[0]


def test_object_motion_joins_samples_into_movements_and_names_the_waypoint():
    module = script("object_motion")
    still, moving = [0.0, 0.0, 0.1], 0.01
    path = [still] * 3 + [[moving * k, 0.0, 0.1] for k in range(1, 4)] + [[0.03, 0.0, 0.1]] * 2 \
        + [[0.04, 0.0, 0.1]] + [[0.04, 0.0, 0.1]] * 6 + [[0.05, 0.0, 0.1]]
    times = [0.1 * k for k in range(len(path))]
    # samples 2..4 move, 7 moves (2 samples later: joined), 14 moves alone (after a gap of 6)
    assert module.movements(times, path, 0.002) == [(2, 7), (14, 14)]
    assert module.tilt_deg((1.0, 0.0, 0.0, 0.0)) == pytest.approx(0.0)
    assert module.tilt_deg((math.cos(math.pi / 8), math.sin(math.pi / 8), 0.0, 0.0)) == pytest.approx(45.0)
    starts = [(1.0, [["approach", 0.5], ["seal", 1.0]]), (5.0, [["approach", 0.5]])]
    assert module.during(0.5, starts) == "before the first action"
    assert module.during(2.2, starts) == "action 0, after seal (+1.2 s)"
    assert module.during(5.2, starts) == "action 1, before its first waypoint (+0.2 s)"


def test_object_motion_refuses_a_folder_without_poses(tmp_path, capsys):
    (tmp_path / "trial.json").write_text('{"steps_log": [], "actions": []}')
    assert script("object_motion").main([str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {tmp_path}")


def test_replay_action_refuses_an_unreadable_folder_and_an_action_the_trial_does_not_hold(tmp_path, capsys):
    import numpy as np

    replay = script("replay_action")
    assert replay.main([str(tmp_path / "none"), "--action", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and "not a readable trial folder" in err[0]
    (tmp_path / "trial.json").write_text(json.dumps({"actions": [{"type": "push"}], "steps_log": [
        {"action": {"type": "push"}, "time": 0.5}]}))
    np.savez(tmp_path / "object_poses.npz", times=np.zeros(1), poses=np.zeros((1, 1, 7)), names=np.array(["object_0"]))
    assert replay.main([str(tmp_path), "--action", "3"]) == 2
    assert "--action 3: the trial has 1 actions" in capsys.readouterr().err
    assert replay.main([str(tmp_path), "--action", "0", "--object", "object_7"]) == 2
    assert "--object 'object_7': not an object of the trial" in capsys.readouterr().err


def test_replay_action_puts_each_object_where_the_recorded_poses_hold_it_at_the_decision():
    import numpy as np

    from slax_drake.scene.model import Scene, SceneObject, planar_pose

    replay = script("replay_action")
    half = math.radians(30.0) / 2.0
    poses = np.zeros((2, 1, 7))
    poses[0, 0] = (0.1, 0.0, 0.05, 1.0, 0.0, 0.0, 0.0)
    poses[1, 0] = (0.2, -0.1, 0.05, math.cos(half), 0.0, 0.0, math.sin(half))  # turned 30 deg about z
    arrays = {"times": np.array([0.0, 10.0]), "poses": poses, "names": np.array(["object_0"])}
    scene = Scene(None, None, (SceneObject("object_0", "box", (0.1, 0.1, 0.1), planar_pose(0.1, 0.0, 0.05, 0.0)),),
                  None, 0)
    early, late = replay.true_scene_at(scene, arrays, 9.9), replay.true_scene_at(scene, arrays, 12.0)
    assert early.objects[0].center[:2].tolist() == [0.1, 0.0]
    assert late.objects[0].center[:2].tolist() == pytest.approx([0.2, -0.1])
    assert late.objects[0].yaw == pytest.approx(math.radians(30.0))
