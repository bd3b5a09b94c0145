"""The command line answers ``--help`` and argument errors without importing the heavy libraries.

Drake, torch, trimesh, matplotlib, scipy, OpenCV and shapely take seconds to import together; the parser and
every command's ``register`` must not need them, so that ``slax-drake --help`` answers at once
(benchmarks/bench_cli_latency.py measures the wall time). Each case runs in a fresh interpreter, so no other
test's imports leak in.
"""

import json
import subprocess
import sys

import pytest

HEAVY = ("pydrake", "torch", "trimesh", "matplotlib", "scipy", "cv2", "shapely", "h5py")

PROBE = """
import contextlib, io, json, sys
from slax_drake.cli import main
for argv in {argvs!r}:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        try:
            main(argv)
        except SystemExit:
            pass
print(json.dumps(sorted({{m.split(".")[0] for m in sys.modules}} & set({heavy!r}))))
"""


def heavy_modules_after(argvs: list[list[str]]) -> list[str]:
    """The heavy top-level packages a fresh interpreter holds after ``slax-drake ARGV`` for each of ``argvs``."""
    proc = subprocess.run([sys.executable, "-c", PROBE.format(argvs=argvs, heavy=HEAVY)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("argv", [
    ["--help"],
    ["trial", "--help"],
    ["trial", "--objects", "three"],  # an argument error, answered by argparse
    ["benchmark", "--policies"],  # an argument error: the option needs a value
])
def test_help_and_argument_errors_import_no_heavy_library(argv):
    assert heavy_modules_after([argv]) == []


def test_every_command_help_imports_no_heavy_library():
    from slax_drake.cli import build_parser

    commands = build_parser()._subparsers._group_actions[0].choices
    assert heavy_modules_after([[name, "--help"] for name in commands]) == []
