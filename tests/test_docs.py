"""The README and the documentation site: the README's limits and command blocks, results pages that are exactly
what the report command regenerates, and the reference tables the MkDocs hooks generate."""

import importlib.util
import os
import re
import shlex
from pathlib import Path

import pytest

from slax_drake.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]


def fenced_block(text: str, marker: str) -> str:
    """The first ```bash block after ``marker``, as .ci/run extracts it."""
    rest = text[text.index(marker):]
    start = rest.index("```bash\n") + len("```bash\n")
    return rest[start:rest.index("\n```", start)]


def test_readme_is_a_front_page_with_both_command_blocks():
    text = (ROOT / "README.md").read_text()
    lines = text.splitlines()
    assert len(lines) <= 300 and max(map(len, lines)) <= 400
    assert fenced_block(text, "<!-- main-command -->").endswith("slax-drake trial --html out/trial.html")
    assert "pip install -e '.[test,cluster,docs]'" in fenced_block(text, "<!-- test-command -->")
    assert not re.search(r"\bsession \d+|\bissue \d+", text, re.IGNORECASE)


def _regenerate(command: str, flag: str, target: Path, monkeypatch) -> None:
    argv = shlex.split(command)
    assert argv[:2] == ["slax-drake", "report"]
    argv = argv[1:]
    argv[argv.index(flag) + 1] = str(target)
    monkeypatch.chdir(ROOT)
    assert main(argv) == 0


def test_the_results_pages_are_what_the_report_command_regenerates(tmp_path, monkeypatch, capsys):
    index = (ROOT / "docs" / "results" / "index.md").read_text()
    command = fenced_block(index, "regenerate them all with")
    _regenerate(command, "--docs", tmp_path, monkeypatch)
    docs_arg = shlex.split(command)[shlex.split(command).index("--docs") + 1]
    for page in sorted((tmp_path / "results").iterdir()):
        text = page.read_text().replace(f"--docs {tmp_path}", f"--docs {docs_arg}")
        assert text == (ROOT / "docs" / "results" / page.name).read_text(), page.name


def test_the_readme_headline_is_what_the_report_command_regenerates(tmp_path, monkeypatch, capsys):
    text = (ROOT / "README.md").read_text()
    command = re.search(r"Regenerate with `(slax-drake report [^`]+)`", text).group(1)
    copy = tmp_path / "README.md"
    copy.write_text(text)
    _regenerate(command, "--readme", copy, monkeypatch)
    assert copy.read_text().replace(f"--readme {copy}", "--readme README.md") == text


@pytest.fixture(scope="module")
def hooks():
    pytest.importorskip("mkdocs")
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "docs" / "hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_command_reference_lists_every_command_and_option(hooks):
    text = hooks.cli_reference()
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name, command in sub.choices.items():
        assert f"## slax-drake {name}" in text
        for action in command._actions:
            for option in action.option_strings if action.dest != "help" else ():
                assert f"`{option}`" in text, (name, option)


def test_the_yaml_references_list_nested_keys_with_defaults_and_comments(hooks):
    scenario = hooks.scenario_reference()
    assert "| `protocol.densities` | `list[int]` | `[4, 6, 8, 10]` |" in scenario
    assert "`objects.box_yaw`" in scenario and '"aligned": sides parallel' in scenario
    station = hooks.station_reference()
    assert "`suction.max_held_moment`" in station and "`reach_map`" in station


def test_mkdocs_config_lists_only_pages_that_exist():
    nav = re.findall(r":\s*([\w\-/]+\.md)$|^\s*-\s*([\w\-/]+\.md)$", (ROOT / "mkdocs.yml").read_text(), re.MULTILINE)
    pages = [a or b for a, b in nav]
    assert pages and all(os.path.isfile(ROOT / "docs" / p) for p in pages), [p for p in pages if not (ROOT / "docs" / p).is_file()]
