"""``slax-drake trial --from-benchmark FOLDER --benchmark-scene N:INDEX``: the options of the trial a physics
benchmark ran for that scene, read from its settings (no simulation in the fast tests); the line that says whether
the trial did what the run recorded; one clear message with exit code 2 for a bad request. The slow test runs a
tiny benchmark and then its scene as a trial."""

import json
import shutil
from pathlib import Path

import pytest

from slax_drake.cli import main
from slax_drake.errors import TrialError
from slax_drake.evaluation.benchmark_trial import (
    agreement, benchmark_record, benchmark_trial_options, read_benchmark_settings,
)
from slax_drake.evaluation.table1 import scene_seed
from slax_drake.shelf.tool import parse_tool_rules

RUN = Path("docs/results/physics_belief_household_20580ad")  # a docs/results copy: settings and physics.json


def test_the_runs_settings_give_the_trial_of_the_scene():
    opts, notes = benchmark_trial_options(RUN, "8:14")
    settings = json.loads((RUN / "physics_settings.json").read_text())
    assert (opts.config, opts.policy, opts.profile) == ("sim_configs/table1_household.yaml", "slax-belief", "station")
    assert (opts.objects, opts.seed, opts.horizon) == (8, scene_seed(0, 8, 14), 16)
    assert opts.tool_rules == settings["tool_rules"] and opts.tool_rules["max_seal_angle_deg"] == 10.0
    assert opts.sensor_noise is False and opts.sleep is False
    assert opts.station.endswith("sim_configs/station_sim_shelf.yaml")  # the run's own path was a worktree
    assert not any("station" in n or "scenario" in n for n in notes)  # the same files' content
    assert any("20580ad" in n for n in notes)  # another commit made the run


def test_tool_rules_go_on_top_of_the_runs_and_are_noted():
    opts, notes = benchmark_trial_options(RUN, "4:0", extra_rules=["max_suction_moment=0.3"])
    assert opts.tool_rules["max_suction_moment"] == 0.3 and opts.tool_rules["max_drag_pull"] == 42.412
    assert any("max_suction_moment=0.3" in n for n in notes)


def _copy_with(tmp_path, **changes):
    folder = tmp_path / "run"
    folder.mkdir()
    settings = json.loads((RUN / "physics_settings.json").read_text())
    settings.update(changes)
    (folder / "physics_settings.json").write_text(json.dumps(settings))
    shutil.copy(RUN / "physics.json", folder / "physics.json")
    return folder


def test_the_runs_protocol_seed_and_a_changed_station_are_kept_and_noted(tmp_path):
    folder = _copy_with(tmp_path, seed=3, station_sha256="0" * 64)
    opts, notes = benchmark_trial_options(folder, "2:0")
    assert opts.seed == scene_seed(3, 2, 0) != scene_seed(0, 2, 0)
    assert any(n.startswith("the station file") for n in notes)


def test_a_run_of_several_policies_needs_one_named(tmp_path):
    folder = _copy_with(tmp_path, policies={"slax-belief": {}, "bluction-dar": {}})
    with pytest.raises(TrialError, match="name one with --policy"):
        benchmark_trial_options(folder, "4:0")
    assert benchmark_trial_options(folder, "4:0", policy="bluction-dar")[0].policy == "bluction-dar"
    with pytest.raises(TrialError, match="not der-3"):
        benchmark_trial_options(folder, "4:0", policy="der-3")


def test_the_runs_record_of_the_scene_comes_from_its_trial_file_else_its_summary(tmp_path):
    summary = benchmark_record(RUN, "slax-belief", 8, 14)
    assert summary == {"result": "no feasible motion", "actions_executed": 14}
    folder = _copy_with(tmp_path)
    trial = folder / "physics_trials" / "slax-belief" / "08_0014.json"
    trial.parent.mkdir(parents=True)
    actions = [{"type": "push", "object": "track_3", "d": -0.08}, {"type": "suction", "object": "track_4", "dx": 0.0,
                                                                  "dz": -0.2}]
    trial.write_text(json.dumps({"drake": {"result": "horizon", "actions": actions}}))
    assert benchmark_record(folder, "slax-belief", 8, 14) == {
        "result": "horizon",
        "actions": [("push", "track_3", -0.08, None, None), ("suction", "track_4", None, 0.0, -0.2)]}
    assert benchmark_record(folder, "slax-belief", 8, 99) is None
    old = benchmark_record("docs/results/physics_bdar_household", "bluction-dar", 4, 1)  # a summary of ed09d30
    assert set(old) == {"result", "actions_executed"} and isinstance(old["actions_executed"], int)


def test_the_agreement_line_says_where_the_trial_parted_from_the_run():
    run = {"result": "horizon",
           "actions": [("push", "track_3", -0.08, None, None), ("push", "track_4", 0.05, None, None)]}
    same = {"result": "horizon", "actions": [{"type": "push", "object": "track_3", "d": -0.08},
                                             {"type": "push", "object": "track_4", "d": 0.05}]}
    assert agreement(same, run, "F") == 'as the run in F: the same 2 actions, ended "horizon"'
    other = {"result": "revealed", "actions": [same["actions"][0], {"type": "push", "object": "track_4", "d": 0.06}]}
    line = agreement(other, run, "F")
    assert line.startswith("NOT as the run in F") and "at action 2" in line and 'this trial ended "revealed"' in line
    shorter = {"result": "horizon", "actions": same["actions"][:1]}
    assert "at action 2" in agreement(shorter, run, "F")
    assert agreement(same, {"result": "horizon", "actions_executed": 2}, "F").startswith("as the run in F")
    assert agreement(same, {"result": "horizon", "actions_executed": 3}, "F").startswith("NOT as")
    assert agreement(same, None, "F") == "the run in F holds no record of this scene"


@pytest.mark.parametrize("argv, message", [
    (["--from-benchmark", str(RUN)], "needs --benchmark-scene"),
    (["--from-benchmark", "no/such/folder", "--benchmark-scene", "8:1"], "no folder no/such/folder"),
    (["--from-benchmark", "docs", "--benchmark-scene", "8:1"], "not a physics benchmark's folder"),
    (["--from-benchmark", str(RUN), "--benchmark-scene", "8:1", "--config", "sim_configs/table1.yaml"],
     "sets --config from the run's settings"),
    (["--from-benchmark", str(RUN), "--benchmark-scene", "8:1", "--sensor-noise", "--sleep"],
     "sets --sensor-noise, --sleep"),
    (["--from-benchmark", str(RUN), "--benchmark-scene", "8:1", "--perception", "learned"], "ground-truth"),
    (["--from-benchmark", str(RUN), "--benchmark-scene", "8:1", "--policy", "der-3"], "not der-3"),
    (["--from-benchmark", str(RUN), "--benchmark-scene", "8-1"], "N:INDEX"),
    (["--from-benchmark", str(RUN), "--benchmark-scene", "8:1", "--tool-rule", "max_suction_moment=heavy"],
     "needs a float"),
])
def test_bad_requests_exit_with_code_2(capsys, argv, message):
    assert main(["trial", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("content, message", [
    ("{not json", "not a settings file"),
    ('{"config": "sim_configs/table1.yaml"}', "lacks seed, policies"),
    ("[1, 2]", "lacks config"),
])
def test_a_corrupt_settings_file_is_refused(tmp_path, content, message):
    (tmp_path / "physics_settings.json").write_text(content)
    with pytest.raises(TrialError, match=message):
        read_benchmark_settings(tmp_path)


def test_recorded_rules_are_typed_as_the_command_line_types_them():
    opts, _ = benchmark_trial_options(RUN, "4:0")
    assert opts.tool_rules == parse_tool_rules([f"{k}={v}" for k, v in opts.tool_rules.items()], "station")


@pytest.mark.slow
def test_a_benchmark_scene_run_again_does_what_the_run_recorded(tmp_path, capsys):
    from slax_drake.evaluation.physics import run_physics_benchmark

    out = tmp_path / "physics"
    run_physics_benchmark("sim_configs/sim_shelf.yaml", out=out, policies=["bluction-dar"], scenes_per_density=1,
                          seed=3, densities=[2], progress=False)
    capsys.readouterr()
    assert main(["trial", "--from-benchmark", str(out), "--benchmark-scene", "2:0", "--out", str(tmp_path / "t"),
                 "--quiet"]) == 0
    printed = capsys.readouterr().out
    last = printed.strip().splitlines()[-1]
    assert last.startswith(f"benchmark: as the run in {out}: the same "), last
    record = json.loads((tmp_path / "t" / "trial.json").read_text())
    assert record["from_benchmark"]["scene"] == "2:0" and record["seed"] == scene_seed(3, 2, 0)
