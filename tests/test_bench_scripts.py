"""Bad arguments of the benchmark scripts: one line on stderr and exit code 2, before any long run."""

import importlib.util
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def script(name):
    """The module of ``benchmarks/<name>.py`` (the scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(f"bench_script_{name}", BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("content", [None, "not json", '{"n": 1}', '{"candidates": [{"n": 6}]}'])
def test_bench_reach_rule_refuses_an_unreadable_compare_file_before_planning(tmp_path, capsys, content):
    earlier = tmp_path / "earlier.json"
    if content is not None:
        earlier.write_text(content)
    assert script("bench_reach_rule").main(["--compare", str(earlier), "--densities", "6", "--scenes", "1"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # refused before the first scene is planned
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --compare ")
