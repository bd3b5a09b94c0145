"""The Table I runner: files and schema, same scenes for every policy, resume, CLI errors."""

import json

import pytest

from slax_drake.cli import main
from slax_drake.evaluation.table1 import run_benchmark, scene_seed


def test_tiny_benchmark_writes_tables_and_resumes(sim_scenario, tmp_path):
    table = run_benchmark(sim_scenario, ["oracle-p", "dar"], 1, 0, tmp_path, densities=[4], progress=False)
    for f in ("table1.md", "table1.json", "table1.png"):
        assert (tmp_path / f).stat().st_size > 0
    data = json.loads((tmp_path / "table1.json").read_text())
    for p in ("oracle-p", "dar"):
        for k in ("4", "all"):
            e = data["policies"][p][k]
            assert set(e) >= {"success_rate", "median_steps", "iqr", "trials"} and e["trials"] == 1
    seeds = {t["policy"]: t["seed"] for t in data["trials"]}
    assert seeds["oracle-p"] == seeds["dar"] == scene_seed(0, 4, 0)
    before = {p: p.stat().st_mtime_ns for p in tmp_path.glob("trials/*/*.json")}
    again = run_benchmark(sim_scenario, ["oracle-p", "dar"], 1, 0, tmp_path, densities=[4], progress=False)
    assert {p: p.stat().st_mtime_ns for p in tmp_path.glob("trials/*/*.json")} == before  # nothing rerun
    assert again["policies"] == table["policies"]


def test_corrupt_trial_file_is_a_user_error(sim_scenario, tmp_path, capsys):
    run_benchmark(sim_scenario, ["oracle-p"], 1, 0, tmp_path, densities=[4], progress=False)
    (tmp_path / "trials" / "oracle-p" / "04_0000.json").write_text("{not json")
    from slax_drake.evaluation.table1 import BenchmarkError

    with pytest.raises(BenchmarkError, match="unreadable trial file"):
        run_benchmark(sim_scenario, ["oracle-p"], 1, 0, tmp_path, densities=[4], progress=False)


def test_cli_rejects_bad_requests(capsys):
    assert main(["benchmark", "--policies", "nope", "--out", "/tmp/unused"]) == 2
    assert "unknown policy 'nope'" in capsys.readouterr().err
    assert main(["benchmark", "--physics", "--policies", "oracle-p", "--out", "/tmp/unused"]) == 2
    assert "cannot run in a Drake trial" in capsys.readouterr().err


def test_tool_rules_are_recorded_and_a_folder_of_other_rules_is_refused(sim_scenario, tmp_path, capsys):
    from slax_drake.errors import UserError

    rules = {"max_suction_moment": 0.4}
    table = run_benchmark(sim_scenario, ["bluction-dar"], 1, 0, tmp_path, densities=[4], progress=False,
                          tool_rules=rules)
    assert table["meta"]["tool_rules"] == rules
    trial = json.loads((tmp_path / "trials" / "bluction-dar" / "04_0000.json").read_text())
    assert trial["tool_rules"] == rules
    assert "max_suction_moment = 0.4" in (tmp_path / "table1.md").read_text()
    with pytest.raises(UserError, match="made with another --tool-rule"):
        run_benchmark(sim_scenario, ["bluction-dar"], 1, 0, tmp_path, densities=[4], progress=False)
    assert main(["benchmark", "--policies", "dar", "--tool-rule", "max_suction_moment=heavy",
                 "--out", str(tmp_path / "x")]) == 2
    assert "needs a float" in capsys.readouterr().err
