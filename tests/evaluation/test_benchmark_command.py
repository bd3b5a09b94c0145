"""One benchmark command over one evaluation package (issues 15.1, 15.12, 18.4): the settings a folder was made
with are recorded and a resume with other ones is refused naming the setting; the table covers every policy in
the folder; the default policies; resumed runs say what they kept; Ray and local give the same trial files."""

import json
import shutil
from pathlib import Path

import pytest

import slax_drake
from slax_drake.cli import main
from slax_drake.evaluation.trial_records import without_keys

CONFIG = "sim_configs/table1.yaml"
TINY = ["--config", CONFIG, "--densities", "4", "--scenes-per-density", "1", "--no-progress"]


def bench(out, *argv):
    return main(["benchmark", *TINY, "--out", str(out), *argv])


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A folder made by a tiny DAR run with seed 0."""
    out = tmp_path_factory.mktemp("table1") / "out"
    assert bench(out, "--policies", "dar", "--seed", "0") == 0
    return out


def copy_of(made, tmp_path) -> Path:
    out = tmp_path / "copy"
    shutil.copytree(made, out)
    return out


@pytest.mark.parametrize("argv, named", [
    (["--seed", "1"], "--seed"),
    (["--perception", "learned"], "--perception"),
    (["--tool-rule", "max_suction_moment=0.4"], "--tool-rule"),
])
def test_a_resume_with_another_setting_is_refused_naming_it(made, tmp_path, capsys, argv, named):
    out = copy_of(made, tmp_path)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert bench(out, "--policies", "dar", *([] if "--seed" in argv else ["--seed", "0"]), *argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"made with another {named}" in err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before  # nothing rewritten


@pytest.mark.parametrize("overlay, named", [
    ("protocol:\n  horizon_per_object: 3\n", "horizon"),
    ("target:\n  visibility_threshold: 0.70\n", "visibility threshold"),
    ("objects:\n  clearance: 0.004\n", "scenario (the --config file's content)"),
])
def test_another_config_content_is_refused_but_the_same_content_elsewhere_is_not(made, tmp_path, capsys, overlay,
                                                                                  named):
    base = f"base: {(Path(slax_drake.__file__).parent.parent / CONFIG).resolve()}\n"
    same, other = tmp_path / "same.yaml", tmp_path / "other.yaml"
    same.write_text("# the same content in another file\n" + base)
    other.write_text(base + overlay)
    out = copy_of(made, tmp_path)
    argv = ["benchmark", "--densities", "4", "--scenes-per-density", "1", "--no-progress", "--policies", "dar",
            "--seed", "0", "--out", str(out)]
    assert main([*argv, "--config", str(other)]) == 2
    assert f"made with another {named}" in capsys.readouterr().err
    assert main([*argv, "--config", str(same)]) == 0
    assert "kept 1 trial " in capsys.readouterr().out


def test_a_reach_map_is_recorded_by_content_not_path(tmp_path, capsys):
    """The same --tool-rule reach_map path holding another map is another setting (a map is regenerated in place)."""
    shipped = Path(slax_drake.__file__).parent.parent / "models" / "reach" / "station_sim_shelf.json"
    rmap = tmp_path / "map.json"
    rmap.write_text(shipped.read_text())
    out = tmp_path / "out"
    argv = ["--policies", "dar", "--seed", "0", "--profile", "station", "--tool-rule", f"reach_map={rmap}"]
    assert bench(out, *argv) == 0
    recorded = json.loads((out / "settings.json").read_text())["reach_map_sha256"]
    data = json.loads(rmap.read_text())
    data["station"] = data["station"] + " (moved)"  # any change of content
    rmap.write_text(json.dumps(data))
    assert bench(out, *argv) == 2
    assert "made with another reach map" in capsys.readouterr().err
    rmap.write_text(shipped.read_text())
    assert bench(out, *argv) == 0 and "kept 1 trial " in capsys.readouterr().out
    assert json.loads((out / "settings.json").read_text())["reach_map_sha256"] == recorded


def test_our_policies_trial_files_keep_their_decision_logs(tmp_path):
    out = tmp_path / "out"
    assert bench(out, "--policies", "slax-belief,dar", "--seed", "0", "--profile", "paper",
                 "--observation", "privileged") == 0
    belief = json.loads(next((out / "trials" / "slax-belief").glob("*.json")).read_text())
    assert len(belief["decision_log"]) == belief["steps"] >= 1  # one entry per decision taken
    assert all({"placements", "samples", "capped", "plan"} <= set(d) for d in belief["decision_log"])
    assert belief["decision_log"][0]["plan"][0] == belief["actions"][0]  # the plan whose first action was taken
    dar = json.loads(next((out / "trials" / "dar").glob("*.json")).read_text())
    assert "decision_log" not in dar  # the paper's policies keep none


def test_the_table_covers_every_policy_in_the_folder_and_resumes_say_what_they_kept(made, tmp_path, capsys):
    out = copy_of(made, tmp_path)
    assert bench(out, "--policies", "bluction-dar", "--seed", "0") == 0
    printed = capsys.readouterr().out
    assert "kept 0 trials" in printed and "ran 1" in printed
    assert "(from an earlier run in this folder)" in printed
    table = json.loads((out / "table1.json").read_text())
    assert set(table["policies"]) == {"dar", "bluction-dar"}
    header = (out / "table1.md").read_text().splitlines()[0]
    assert header == "| No. | Metric | dar | bluction-dar |"  # the registry's order
    settings = json.loads((out / "settings.json").read_text())
    assert set(settings["policies"]) == {"dar", "bluction-dar"} and settings["seed"] == 0
    assert bench(out, "--policies", "dar,bluction-dar", "--seed", "0") == 0
    assert "kept 2 trials" in capsys.readouterr().out


def test_a_folder_of_results_without_a_settings_record_is_refused(made, tmp_path, capsys):
    out = copy_of(made, tmp_path)
    (out / "settings.json").unlink()
    assert bench(out, "--policies", "dar", "--seed", "0") == 2
    assert "no settings.json" in capsys.readouterr().err


def test_without_policies_the_benchmark_runs_the_papers_five_and_ours(monkeypatch, tmp_path):
    import slax_drake.evaluation.table1 as table1

    seen = {}

    def fake(scenario, policies, *args, **kwargs):
        seen["policies"] = list(policies)
        return {"policies": {}, "meta": {"trials_kept": 0, "trials_run": 0}}

    monkeypatch.setattr(table1, "run_benchmark", fake)
    assert bench(tmp_path / "o") == 0
    assert seen["policies"] == ["oracle-p", "oracle-p+s", "dar", "der-3", "bluction-dar", "bluction-la2", "slax-hindsight",
                                "slax-belief"]


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"slax-drake {slax_drake.__version__}"


def test_physics_exposes_the_options_of_the_old_module_cli():
    from slax_drake.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command").choices["benchmark"]
    options = {s for a in sub._actions for s in a.option_strings}
    assert {"--config", "--station", "--policies", "--scenes-per-density", "--densities", "--seed", "--workers",
            "--sleep", "--tool-rule", "--out", "--no-progress", "--backend", "--ray-address"} <= options
    import slax_drake.evaluation.physics as physics

    assert not hasattr(physics, "main") and not hasattr(physics, "build_parser")


def _trial_files(out):
    """Trial files less their timings (seconds differ from run to run; the oracles' searches record theirs)."""
    files = {}
    for p in sorted((Path(out) / "trials").glob("*/*.json")):
        d = json.loads(p.read_text())
        d.pop("decision_seconds")
        d.pop("trial_seconds")
        for search in d.get("oracle_searches", ()):
            search.pop("seconds")
        files[p.relative_to(out).as_posix()] = d
    return files


@pytest.mark.slow
def test_ray_and_local_give_the_same_trial_files(tmp_path, capsys):
    pytest.importorskip("ray")
    argv = ["--config", CONFIG, "--densities", "4,6", "--scenes-per-density", "2", "--no-progress",
            "--policies", "oracle-p,dar,bluction-dar"]
    assert main(["benchmark", *argv, "--out", str(tmp_path / "local"), "--workers", "2"]) == 0
    assert main(["benchmark", *argv, "--out", str(tmp_path / "ray"), "--backend", "ray", "--workers", "2"]) == 0
    local, ray = _trial_files(tmp_path / "local"), _trial_files(tmp_path / "ray")
    assert len(local) == 12 and local == ray


# What a clock measured: the record's keys that differ between two runs of the same trial (at any depth: an action's
# own planning, and the drag planned inside a weighed lift's record)
TIMING_KEYS = {"wall_s", "total_s", "real_time_factor", "planning_s", "planning_cpu_s", "motion_timings", "timings"}


@pytest.mark.slow
def test_physics_on_ray_gives_the_same_scene_files_as_local(tmp_path):
    pytest.importorskip("ray")
    from slax_drake.evaluation.physics import run_physics_benchmark

    tiny = dict(policies=["bluction-dar"], scenes_per_density=1, seed=3, densities=[2], progress=False)
    files = {}
    for backend in ("local", "ray"):
        out = tmp_path / backend
        run_physics_benchmark("sim_configs/sim_shelf.yaml", out=out, backend=backend, **tiny)
        (path,) = (out / "physics_trials").glob("*/*.json")
        files[backend] = without_keys(json.loads(path.read_text()), TIMING_KEYS)
    assert files["local"] == files["ray"]
