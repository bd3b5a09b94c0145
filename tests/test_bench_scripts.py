"""Bad arguments of the benchmark scripts: one line on stderr and exit code 2, before any long run."""

import importlib.util
import json
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def script(name):
    """The module of ``benchmarks/<name>.py`` (the scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(f"bench_script_{name}", BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_compare_oracle_trials_refuses_folders_without_common_trials(tmp_path, capsys):
    """A mistyped folder or policy compared nothing and passed (exit 0); now it is refused."""
    compare = script("compare_oracle_trials").main
    old, new = tmp_path / "old", tmp_path / "new"
    for folder in (old, new):
        (folder / "trials" / "oracle-p").mkdir(parents=True)
        (folder / "trials" / "oracle-p" / "4_0.json").write_text(
            '{"success": true, "steps": 2, "cost": 2.0, "oracle_status": "optimal", "oracle_searches": []}')
    assert compare([str(old), str(new), "--policies", "oracle-p"]) == 0
    capsys.readouterr()
    for argv in ([str(old), str(tmp_path / "typo"), "--policies", "oracle-p"],
                 [str(old), str(new), "--policies", "oracle-p+s"]):
        assert compare(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: ")


def test_compare_oracle_trials_refuses_a_policy_that_is_not_an_oracle(tmp_path, capsys):
    """A non-oracle policy's trials have no ``oracle_status``: one line and exit 2, not a KeyError traceback."""
    for run in ("old", "new"):
        (tmp_path / run / "trials" / "dar").mkdir(parents=True)
        (tmp_path / run / "trials" / "dar" / "04_0000.json").write_text('{"success": true, "steps": 2, "cost": 2.0}')
    argv = [str(tmp_path / "old"), str(tmp_path / "new"), "--policies", "dar"]
    assert script("compare_oracle_trials").main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: trial ") and "dar records no oracle search" in err[0]


@pytest.mark.parametrize("argv,message", [
    (["--policies", "dar,nope"], "error: unknown policies ['nope']"),
    (["--profile", "nope"], "error: unknown profile 'nope'"),
    (["--scenes-per-density", "0"], "error: --scenes-per-density must be at least 1"),
])
def test_table1_cpu_refuses_bad_arguments_before_any_trial(capsys, argv, message):
    assert script("table1_cpu").main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # refused before the first trial runs
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(message)


def test_table1_ablation_has_one_leave_one_out_variant_per_rule_the_profiles_differ_in():
    """The station profile's per-rule costs: each variant is the station with exactly one rule at its paper value."""
    from slax_drake.shelf.rules import profile_values

    ablation = script("table1_ablation")
    paper, station = profile_values("paper"), profile_values("station")
    differing = {name for name in paper if paper[name] != station[name]}
    variants = {name: v for name, v in ablation.VARIANTS.items() if name.startswith(ablation.LEAVE_ONE_OUT_PREFIX)}
    assert {name[len(ablation.LEAVE_ONE_OUT_PREFIX):] for name in variants} == differing
    for name, (_, profile, rules, changes) in variants.items():
        rule = name[len(ablation.LEAVE_ONE_OUT_PREFIX):]
        assert profile == "station" and changes == {} and rules == {rule: paper[rule]}


def test_table1_ablation_rule_costs_are_the_success_gained_without_the_rule():
    ablation = script("table1_ablation")
    rates = {"station": {"oracle-p": 0.25, "bluction-dar": 0.5},
             "station-without-blade_gap": {"oracle-p": 0.5, "bluction-dar": 0.45},
             "paper": {"oracle-p": 0.6, "bluction-dar": 0.5}}
    lines = ablation.rule_cost_lines(rates, ["oracle-p", "bluction-dar"])
    assert lines == ["- `blade_gap` (station 0.035, paper 0.001): costs oracle-p +25.0, bluction-dar -5.0 points"]
    assert ablation.rule_cost_lines({"station-without-blade_gap": rates["station-without-blade_gap"]},
                                    ["oracle-p"]) == []  # no station row: nothing to subtract from


def test_camera_realism_table_refuses_folders_of_other_protocols(tmp_path, capsys):
    """Folders that differ in more than the camera's realism (here the profile), or that are no camera-mode run,
    are refused with one line and exit code 2."""
    import shutil

    results = BENCHMARKS.parent / "docs" / "results"
    other = tmp_path / "other"
    shutil.copytree(results / "realism_depth", other)
    settings = json.loads((other / "settings.json").read_text())
    (other / "settings.json").write_text(json.dumps({**settings, "profile": "station"}))
    table = script("camera_realism_table").main
    for folders in ([results / "realism_labels", other], [results / "table1_paper"], [tmp_path / "missing"]):
        assert table([str(f) for f in folders] + ["--out", str(tmp_path / "page.md")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: ")
    assert not (tmp_path / "page.md").exists()


def test_compare_variant_runs_counts_moves_back_and_refuses_empty_folders(tmp_path, capsys):
    compare = script("compare_variant_runs")
    actions = ["push object_1 d=+0.100", "suction object_1 dx=-0.050 dz=-0.2", "push object_2 d=-0.005",
               "suction object_1 dx=+0.200 dz=0.1", "push object_2 d=+0.050"]
    assert compare.moves_back(actions) == (2, 1)  # -0.05 undoes part of +0.10; +0.20 goes past; object_2: no move back
    assert compare.main([str(tmp_path / "a"), str(tmp_path / "b")]) == 2
    assert capsys.readouterr().err.startswith("error: ")
    for run, success in (("a", False), ("b", True)):
        trials = tmp_path / run / "trials" / "slax-belief"
        trials.mkdir(parents=True)
        (trials / "08_0000.json").write_text(json.dumps({"success": success, "actions": actions}))
    assert compare.main([str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    assert "| All | 1 | 0.00 % | 100.00 % | 1 | 0 | 2 / 2 | 1 / 1 |" in capsys.readouterr().out


@pytest.mark.parametrize("name,options", [("compare_oracle_trials", ["--policies", "oracle-p"]),
                                          ("compare_trial_outputs", []), ("compare_variant_runs", [])])
def test_comparison_scripts_refuse_a_malformed_trial_file_with_one_line(tmp_path, capsys, name, options):
    policy = "slax-belief" if name == "compare_variant_runs" else "oracle-p"
    for run in ("old", "new"):
        (tmp_path / run / "trials" / policy).mkdir(parents=True)
        (tmp_path / run / "trials" / policy / "04_0000.json").write_text(
            '{"success": true, "steps": 2, "cost": 2.0, "oracle_status": "optimal", "oracle_searches": []}')
    bad = tmp_path / "new" / "trials" / policy / "04_0001.json"
    bad.write_text("{cut short")
    assert script(name).main([str(tmp_path / "old"), str(tmp_path / "new")] + options) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.strip().splitlines() == [captured.err.strip()]
    assert captured.err.startswith(f"error: {bad}: not valid JSON")


def test_rerun_trials_refuses_a_trial_the_folder_does_not_hold_before_any_rerun(tmp_path, capsys):
    rerun = script("rerun_trials").main
    (tmp_path / "trials" / "dar").mkdir(parents=True)
    config = str(BENCHMARKS.parent / "sim_configs" / "table1.yaml")
    (tmp_path / "settings.json").write_text(json.dumps({"config": config, "seed": 0}))
    (tmp_path / "trials" / "dar" / "04_0000.json").write_text(
        '{"success": false, "density": 4, "index": 0, "steps": 8, "reason": "horizon"}')
    for argv, words in ((["--trials", "4:0,6:3"], "no trial of dar for 6:3"), (["--trials", "4-0"], "--trials")):
        assert rerun([str(tmp_path), "--policy", "dar", *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: ") and words in err[0]


def test_planning_per_action_table_pools_runs_and_counts_the_same_decisions(tmp_path, capsys):
    """Rows pool their files; the medians and p90s are over executed actions; a later row counts the decisions
    that chose the first row's action; a missing file is one line and exit 2."""
    def run(name, objects, times, actions):
        path = tmp_path / name
        decisions = [{"scene_seed": 0, "step": k, "planning_s": t, "planning_cpu_s": t, "rejected": 1 if a is None else 0,
                      "action": a} for k, (t, a) in enumerate(zip(times, actions))]
        path.write_text(json.dumps({"summary": {"objects": objects}, "decisions": decisions}))
        return str(path)

    before = f"{run('b6.json', 6, [1.0, 3.0], ['push a', 'push b'])},{run('b8.json', 8, [2.0, 9.0], ['push c', None])}"
    after = f"{run('a6.json', 6, [1.0, 1.0], ['push a', 'push x'])},{run('a8.json', 8, [2.0, 9.0], ['push c', None])}"
    main = script("planning_per_action_table").main
    assert main([f"before={before}", f"after={after}"]) == 0
    rows = capsys.readouterr().out.strip().splitlines()
    assert rows[2].startswith("| before | 3 | 2.000 s |") and rows[2].endswith("| 1 |  |")
    assert rows[3].startswith("| after | 3 | 1.000 s |") and rows[3].endswith("| 1 | 3 of 4 |")
    assert main([f"x={tmp_path / 'missing.json'}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ")


def _physics_row(density, index, policy, revealed, toppled=0, shelf=True):
    return {"density": density, "index": index, "policy": policy, "seed": 100 * density + index,
            "drake_result": "revealed" if revealed else "no feasible action", "drake_success": revealed,
            "toppled": toppled, "dropped": 0, "shelf_success": shelf}


def test_compare_physics_runs_reads_summaries_and_lists_the_scenes_whose_outcome_changed(tmp_path, capsys):
    """The docs folders keep only physics.json: its rows are compared (another policy's on the new side), and a
    scene revealed with an object lost counts as not clean."""
    old, new = tmp_path / "old", tmp_path / "new"
    old.mkdir(), new.mkdir()
    (old / "physics.json").write_text(json.dumps({"trials": [
        _physics_row(4, 0, "slax-belief", True), _physics_row(4, 1, "slax-belief", False),
        _physics_row(6, 0, "slax-belief", True, toppled=1)]}))
    (new / "physics.json").write_text(json.dumps({"trials": [
        _physics_row(4, 0, "v", False), _physics_row(4, 1, "v", True), _physics_row(6, 0, "v", True),
        _physics_row(4, 0, "slax-belief", True)]}))
    main = script("compare_physics_runs").main
    assert main([str(old), str(new), "--policy", "slax-belief", "--new-policy", "v"]) == 0
    out = capsys.readouterr().out
    assert "slax-belief (old) against v (new), the 3 scenes both runs hold" in out
    assert "in new, not in old: 2 (04_0001, 06_0000); in old, not in new: 1 (04_0000)." in out
    assert "| new (new) | all | 3 | 3 | 2 | 2 | - | - | - | no feasible action 1, revealed 2 |" in out
    with pytest.raises(SystemExit) as exit_info:
        main([str(old), str(tmp_path / "typo"), "--policy", "slax-belief"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no physics.json" in err[0]
