"""slax-drake report: the results pages and the README's headline table, generated from committed result folders."""

import json
from pathlib import Path

import pytest

from slax_drake.cli import main
from slax_drake.evaluation.report import README_BEGIN, README_END, load_folder, observation_mode_rows

RESULTS = Path(__file__).resolve().parents[2] / "docs" / "results"


def test_report_writes_every_page_from_the_folders_it_is_given(tmp_path, capsys):
    folders = [str(RESULTS / n) for n in ("table1_privileged", "table1_camera", "table2_physics")]
    assert main(["report", *folders, "--docs", str(tmp_path / "docs")]) == 0
    pages = tmp_path / "docs" / "results"
    assert sorted(p.name for p in pages.iterdir()) == [
        "index.md", "observation-modes.md", "physics-benchmark.md", "table-i.md", "table-ii.md"]
    modes = (pages / "observation-modes.md").read_text()
    # Bluction-DAR, 100 scenes per density: 46.0 % privileged, 36.25 % camera.
    assert "| bluction-dar | ground-truth | 78 / 67 (-11) | 58 / 42 (-16) | 29 / 24 (-5) | 19 / 12 (-7) | 46 / 36 (-10) |" in modes
    table2 = (pages / "table-ii.md").read_text()
    assert "| 8 | der-3 | 0/3 | 1/3 | 1/3 | 0/3 |" in table2
    assert "| all | bluction-dar | 9/9 | 1/9 | 0/9 | 1/9 |" in table2
    table1 = (pages / "table-i.md").read_text()
    assert "--profile paper --observation camera" in table1  # the command each table was made with
    # Every page names the command that regenerates it, folders included.
    for page in pages.iterdir():
        assert f"slax-drake report {' '.join(folders)} --docs {tmp_path / 'docs'}" in page.read_text()
    assert capsys.readouterr().out.count("wrote ") == 5


def test_a_camera_run_pairs_with_the_privileged_run_of_its_own_policy_set():
    folders = [load_folder(RESULTS / n) for n in ("table1_paper", "table1_privileged", "table1_camera",
                                                   "belief100_camera")]
    pairs = {policy: (priv.path.name, cam.path.name) for priv, cam, policy in observation_mode_rows(folders)}
    assert pairs == {"bluction-dar": ("table1_privileged", "table1_camera"),
                     "dar": ("table1_privileged", "table1_camera"),
                     "der-3": ("table1_privileged", "table1_camera"),
                     "slax-belief": ("table1_paper", "belief100_camera")}


def test_report_replaces_only_the_readme_headline(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\n\nbefore\n{README_BEGIN}\nold table\n{README_END}\nafter\n")
    assert main(["report", str(RESULTS / "table1_paper"), "--readme", str(readme)]) == 0
    text = readme.read_text()
    assert text.startswith("# title\n\nbefore\n") and text.endswith(f"{README_END}\nafter\n")
    assert "old table" not in text
    assert "| Oracle-P+S | 100 (100) | 100 (100) | 98 (100) | 92 (100) | 98 (100) |" in text
    assert "profile `paper`, privileged observation, ground-truth distributions, 100 scenes per density" in text
    assert f"slax-drake report {RESULTS / 'table1_paper'} --readme {readme}" in text


def test_the_readme_headline_takes_the_rows_of_a_later_run_of_the_same_protocol(tmp_path):
    """table1_paper_nonoracle reran table1_paper's non-oracle policies on the same protocol: the headline keeps the
    oracles' rows of the first, takes the reran policies' rows of the later run and names both commands. A run of
    another protocol (table1_station) replaces nothing."""
    readme = tmp_path / "README.md"
    readme.write_text(f"{README_BEGIN}\n{README_END}\n")
    folders = [RESULTS / n for n in ("table1_paper", "table1_station_nonoracle", "table1_paper_nonoracle")]
    assert main(["report", *map(str, folders), "--readme", str(readme)]) == 0
    text = readme.read_text()
    assert "| Oracle-P+S | 100 (100) | 100 (100) | 98 (100) | 92 (100) | 98 (100) |" in text  # table1_paper's
    assert "| slax-belief (ours) | 97 | 91 | 73 | 66 | 82 |" in text  # the rerun's (table1_paper: 100 | 94 | 88 | 71 | 88)
    assert "| slax-belief (ours) | 100 |" not in text
    assert "- Oracle-P; Oracle-P+S:\n  `slax-drake benchmark" in text and "--out " + str(folders[0]) + "`" in text
    assert "slax-belief (ours):\n  `slax-drake benchmark" in text and "--out " + str(folders[2]) + "`" in text
    assert str(folders[1]) + "`" not in text


def test_a_rerun_made_by_later_code_is_still_a_rerun(tmp_path):
    """Settings record the code that made a run; a rerun of the same protocol by later code replaces the rows."""
    import shutil

    rerun = tmp_path / "table1_paper_nonoracle_later"
    shutil.copytree(RESULTS / "table1_paper_nonoracle", rerun)
    settings = json.loads((rerun / "settings.json").read_text())
    (rerun / "settings.json").write_text(json.dumps({**settings, "code": ["slax-drake 0.1.0 (git 0123456789)"]}))
    readme = tmp_path / "README.md"
    readme.write_text(f"{README_BEGIN}\n{README_END}\n")
    assert main(["report", str(RESULTS / "table1_paper"), str(rerun), "--readme", str(readme)]) == 0
    assert "| slax-belief (ours) | 97 | 91 | 73 | 66 | 82 |" in readme.read_text()


@pytest.mark.parametrize("setup, message", [
    ("empty", "holds neither table1.json nor physics.json"),
    ("no-markers", "has no <!-- results:begin --> ... <!-- results:end --> section"),
    ("bad-json", "not a JSON file"),
])
def test_report_refuses_bad_input_in_one_line_before_writing(tmp_path, capsys, setup, message):
    folder = tmp_path / "run"
    folder.mkdir()
    readme = tmp_path / "README.md"
    readme.write_text(f"{README_BEGIN}\n{README_END}\n" if setup != "no-markers" else "no markers\n")
    args = [str(folder)]
    if setup == "no-markers":
        args = [str(RESULTS / "table1_paper")]
    if setup == "bad-json":
        (folder / "table1.json").write_text("{not json")
    code = main(["report", *args, "--docs", str(tmp_path / "docs"), "--readme", str(readme)])
    err = capsys.readouterr().err
    assert code == 2
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "docs").exists()


def test_report_writes_the_readme_drake_headline_from_the_first_physics_folder(tmp_path, capsys):
    from slax_drake.evaluation.report import PHYSICS_BEGIN, PHYSICS_END

    readme = tmp_path / "README.md"
    readme.write_text(f"{README_BEGIN}\n{README_END}\nmiddle\n{PHYSICS_BEGIN}\nstale text\n{PHYSICS_END}\nafter\n")
    folders = [str(RESULTS / "table1_paper"), str(RESULTS / "physics_belief_household_first"),
               str(RESULTS / "physics_camera")]
    assert main(["report", *folders, "--readme", str(readme)]) == 0
    text = readme.read_text()
    block = text.split(PHYSICS_BEGIN)[1].split(PHYSICS_END)[0]
    assert "stale text" not in block and "`physics_belief_household_first`" in block and "physics_camera`" not in block
    assert "household goods' masses" in block and "in camera mode (the same labels" in block
    assert text.endswith("after\n") and "middle" in text
    # a physics folder but no place for it in the README: one line, exit 2, nothing written
    readme.write_text(f"{README_BEGIN}\n{README_END}\n")
    assert main(["report", *folders[:2], "--readme", str(readme)]) == 2
    assert "physics:begin" in capsys.readouterr().err and readme.read_text() == f"{README_BEGIN}\n{README_END}\n"


def test_the_command_and_heading_of_a_camera_run_name_its_segmentation_and_noise():
    from slax_drake.evaluation.report import benchmark_command

    realistic = load_folder(RESULTS / "slax_belief_depth_noise100_d98142d")
    assert "--observation camera --segmentation depth --sensor-noise --policies" in benchmark_command(realistic)
    labels = load_folder(RESULTS / "slax_belief_camera100_1339de7")
    assert "--segmentation" not in benchmark_command(labels) and "--sensor-noise" not in benchmark_command(labels)


def test_a_physics_runs_command_names_the_rules_given_on_the_command_line_not_the_stations():
    from slax_drake.evaluation.report import benchmark_command

    # the stations now place by guarded moves and predict pushes as turning: a run recorded with a station's rule
    # needs no --tool-rule for it, one recorded without it needs it taken away
    guarded = benchmark_command(load_folder(RESULTS / "physics_belief_household_guarded"))
    assert "suction_hidden_rule" not in guarded and guarded.count("--tool-rule") == 1
    assert "--tool-rule push_turn=none" in guarded  # recorded before the stations predicted pushes as turning
    before = benchmark_command(load_folder(RESULTS / "physics_belief_household_ace0a2a"))
    assert "--tool-rule suction_hidden_rule=placement" in before and "--tool-rule push_turn=none" in before
    assert "max_suction_moment" not in before and "reach_map" not in before  # the station file's limits


def test_the_drake_headline_counts_the_policys_stalls_where_the_run_recorded_them(tmp_path):
    from slax_drake.evaluation.report import PHYSICS_BEGIN, PHYSICS_END

    readme = tmp_path / "README.md"
    blocks = {}
    for name in ("physics_belief_household_2b8e52a", "physics_belief_household_e66632a"):
        readme.write_text(f"{README_BEGIN}\n{README_END}\n{PHYSICS_BEGIN}\n{PHYSICS_END}\n")
        assert main(["report", str(RESULTS / "table1_paper"), str(RESULTS / name), "--readme", str(readme)]) == 0
        blocks[name] = readme.read_text().split(PHYSICS_BEGIN)[1].split(PHYSICS_END)[0]
    assert ("slax-belief, its stalls (the first decision at which no plan of the policy's reveals anything; "
            "research/stall_analysis.py): 34 trials, 1 of them revealed the target after it; 205 of the 474 executed "
            "actions came from a stall on.") in " ".join(blocks["physics_belief_household_2b8e52a"].split())
    assert "stalls" not in blocks["physics_belief_household_e66632a"]  # recorded before the decision log was kept
