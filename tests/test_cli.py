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
