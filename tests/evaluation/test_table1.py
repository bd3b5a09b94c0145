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
    from slax_drake.errors import BenchmarkError

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


def test_camera_observation_is_recorded_oracles_stay_privileged_and_modes_do_not_mix(sim_scenario, tmp_path, capsys):
    from slax_drake.errors import SettingsMismatchError
    from slax_drake.evaluation.table1 import CameraMode

    table = run_benchmark(sim_scenario, ["oracle-p", "bluction-dar"], 1, 0, tmp_path, densities=[4], progress=False,
                          camera=CameraMode())
    assert table["meta"]["observation"] == "camera"
    settings = json.loads((tmp_path / "settings.json").read_text())
    assert settings["observation"] == "camera" and settings["camera"] == {"segmentation": "labels",
                                                                          "sensor_noise": False}
    trial = json.loads((tmp_path / "trials" / "bluction-dar" / "04_0000.json").read_text())
    oracle = json.loads((tmp_path / "trials" / "oracle-p" / "04_0000.json").read_text())
    assert trial["observation"] == "camera" and oracle["observation"] == "privileged"
    assert "oracles, which read the true scene" in (tmp_path / "table1.md").read_text()
    with pytest.raises(SettingsMismatchError, match="another --observation"):
        run_benchmark(sim_scenario, ["bluction-dar"], 1, 0, tmp_path, densities=[4], progress=False)
    with pytest.raises(SettingsMismatchError, match="camera observation"):
        run_benchmark(sim_scenario, ["bluction-dar"], 1, 0, tmp_path, densities=[4], progress=False,
                      camera=CameraMode(segmentation="depth"))
    assert main(["benchmark", "--policies", "dar", "--observation", "privileged", "--sensor-noise",
                 "--out", str(tmp_path / "x")]) == 2
    assert "--observation camera only" in capsys.readouterr().err


def test_full_resolution_frames_are_recorded_refused_in_a_working_resolution_folder_and_named_in_the_command(
        sim_scenario, tmp_path, capsys):
    from slax_drake.errors import SettingsMismatchError
    from slax_drake.evaluation.report import benchmark_command, load_folder
    from slax_drake.evaluation.table1 import CameraMode

    run_benchmark(sim_scenario, ["bluction-dar"], 1, 0, tmp_path, densities=[4], progress=False,
                  camera=CameraMode(full_resolution=True))
    settings = json.loads((tmp_path / "settings.json").read_text())
    assert settings["camera"] == {"segmentation": "labels", "sensor_noise": False, "full_resolution": True}
    with pytest.raises(SettingsMismatchError, match="camera observation"):
        run_benchmark(sim_scenario, ["bluction-dar"], 1, 0, tmp_path, densities=[4], progress=False,
                      camera=CameraMode())
    assert "--full-resolution" in benchmark_command(load_folder(tmp_path))
    for args in (["--observation", "privileged", "--full-resolution"], ["--physics", "--full-resolution"]):
        assert main(["benchmark", "--policies", "dar", *args, "--out", str(tmp_path / "x")]) == 2
        assert "--full-resolution" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_record_from_before_observation_modes_counts_as_privileged(sim_scenario, tmp_path):
    run_benchmark(sim_scenario, ["dar"], 1, 0, tmp_path, densities=[4], progress=False)
    path = tmp_path / "settings.json"
    record = json.loads(path.read_text())
    assert record["observation"] == "privileged"
    del record["observation"], record["camera"]
    path.write_text(json.dumps(record))
    run_benchmark(sim_scenario, ["dar"], 1, 0, tmp_path, densities=[4], progress=False)  # resumes: not refused


def test_the_record_names_every_code_that_wrote_into_the_folder_and_does_not_compare_it(sim_scenario, tmp_path):
    from slax_drake import __version__
    from slax_drake.evaluation.settings import code_version

    run_benchmark(sim_scenario, ["dar"], 1, 0, tmp_path, densities=[4], progress=False)
    path = tmp_path / "settings.json"
    record = json.loads(path.read_text())
    assert record["code"] == [code_version()] and code_version().startswith(f"slax-drake {__version__}")
    record["code"] = ["slax-drake 0.0.1 (git 0123456789)"]  # an older code made the folder
    path.write_text(json.dumps(record))
    run_benchmark(sim_scenario, ["dar"], 2, 0, tmp_path, densities=[4], progress=False)  # resumes: not refused
    assert json.loads(path.read_text())["code"] == ["slax-drake 0.0.1 (git 0123456789)", code_version()]
    run_benchmark(sim_scenario, ["dar"], 2, 0, tmp_path, densities=[4], progress=False)
    assert len(json.loads(path.read_text())["code"]) == 2  # the same code is named once
