"""The command line: outputs, --help on every command, user errors as one line with exit code 2."""

import json
import subprocess
import sys

import pytest

from slax_drake.cli import build_parser, main


def test_scene_command_writes_json_and_png(tmp_path, capsys):
    out, png = tmp_path / "scene.json", tmp_path / "scene.png"
    assert main(["scene", "--objects", "6", "--seed", "3", "--out", str(out), "--png", str(png)]) == 0
    data = json.loads(out.read_text())
    assert len(data["objects"]) == 6
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "hidden" in capsys.readouterr().out


def test_every_command_has_help(capsys):
    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    for name in commands:
        with pytest.raises(SystemExit) as info:
            main([name, "--help"])
        assert info.value.code == 0
        assert "usage:" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, expected",
    [
        (["scene", "--config", "missing.yaml"], "no such config file"),
        (["scene", "--objects", "500"], "at most"),
        (["scene", "--objects", "0"], "positive integer"),
    ],
)
def test_user_errors_exit_2_with_one_line(args, expected, capsys, tmp_path):
    code = main(args + ["--out", str(tmp_path / "s.json")])
    err = capsys.readouterr().err
    assert code == 2
    assert expected in err
    assert err.count("\n") == 1
    assert "Traceback" not in err


def test_console_script_reports_bad_config_with_exit_2(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("shelf:\n  width: -1\n")
    proc = subprocess.run(
        [sys.executable, "-m", "slax_drake.cli", "scene", "--config", str(bad), "--out", str(tmp_path / "s.json")],
        capture_output=True, text=True,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().endswith("key 'shelf.width' = -1.0: must be a positive number")
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "s.json").exists()


def test_unwritable_output_is_a_one_line_error(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    code = main(["scene", "--objects", "3", "--out", str(blocker / "scene.json")])
    err = capsys.readouterr().err
    assert code == 2
    assert "Traceback" not in err and err.count("\n") == 1
    assert str(blocker) in err


def test_unwritable_output_names_the_users_path_not_the_temporary_file(tmp_path, capsys, monkeypatch):
    """The system refuses the temporary file beside the output (as in a folder without write permission; the
    tests may run as root, which no permission stops, so the refusal is simulated at mkstemp)."""
    import slax_drake.io as io_module

    out = tmp_path / "scene.json"

    def refuse(dir, prefix, suffix):
        raise PermissionError(13, "Permission denied", f"{dir}/{prefix}x1y2z3{suffix}")

    monkeypatch.setattr(io_module.tempfile, "mkstemp", refuse)
    assert main(["scene", "--objects", "3", "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"slax-drake scene: error: {out}: Permission denied\n"


def test_output_that_is_a_folder_names_it(tmp_path, capsys):
    out = tmp_path / "taken"
    out.mkdir()
    assert main(["scene", "--objects", "3", "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"slax-drake scene: error: {out}: Is a directory\n"
    assert list(out.iterdir()) == []


@pytest.mark.parametrize("below", ["scene.json", "deeper/scene.json"])
def test_output_below_a_file_says_so(tmp_path, capsys, below):
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = blocker / below
    assert main(["scene", "--objects", "3", "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"slax-drake scene: error: {out}: {blocker} is a file, not a folder\n"


def test_output_folder_that_is_a_file_says_so(tmp_path, capsys):
    """A command that makes a folder (dataset --out) where a file stands: not the system's "File exists"."""
    blocker = tmp_path / "data"
    blocker.write_text("keep me")
    assert main(["dataset", "--scenes", "1", "--out", str(blocker), "--no-progress"]) == 2
    assert capsys.readouterr().err == f"slax-drake dataset: error: {blocker}: is a file, not a folder\n"
    assert blocker.read_text() == "keep me"


def test_check_trajectory_prints_plain_numbers(tmp_path, capsys):
    """A trajectory file error quotes times as numbers (1.01), not as numpy's repr (np.float64(1.01))."""
    from trial_records import fake_trial

    from slax_drake.hardware.export import export_trial
    from slax_drake.hardware.trajectory_file import save_trajectory

    path = tmp_path / "traj.json"
    save_trajectory(export_trial(fake_trial()), path)
    doc = json.loads(path.read_text())
    points = doc["motions"][0]["trajectory"]["points"]
    points[0]["time_from_start"] = 1.01
    path.write_text(json.dumps(doc))
    assert main(["check-trajectory", str(path), "--no-collision"]) == 2
    err = capsys.readouterr().err
    assert err == (f"slax-drake check-trajectory: error: {path}: motions[0]: the first point's time_from_start "
                   "must be 0 (got 1.01 s)\n")
    points[0]["time_from_start"] = 0.0
    points[2]["time_from_start"] = points[1]["time_from_start"]
    path.write_text(json.dumps(doc))
    assert main(["check-trajectory", str(path), "--no-collision"]) == 2
    err = capsys.readouterr().err
    assert "np." not in err and err.endswith(f"({points[1]['time_from_start']!r} then "
                                             f"{points[1]['time_from_start']!r} s)\n")
