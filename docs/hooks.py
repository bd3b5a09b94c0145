"""MkDocs hooks: reference tables generated at build time, so they cannot drift from the code.

- ``<!-- cli-reference -->`` becomes every ``slax-drake`` command's usage and options, read from the argparse
  parser that ``slax_drake.cli.build_parser`` builds;
- ``<!-- scenario-reference -->`` and ``<!-- station-reference -->`` become the YAML keys of the scene scenario
  (``slax_drake.config.Scenario``) and of the station (``slax_drake.station.scenario.StationScenario``), read from
  the dataclasses: key, type, default and the comment or docstring that documents it;
- the generated system diagrams in ``diagrams/`` are served as ``diagrams/*.svg``.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import re
import sys
import typing
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def _cell(text) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    if not action.help or action.help == argparse.SUPPRESS:
        return ""
    return parser._get_formatter()._expand_help(action)


def cli_reference() -> str:
    from slax_drake.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {a.dest: a.help for a in sub._choices_actions}
    out = ["Every command prints this with `slax-drake COMMAND --help`. A user error (a bad file, a bad option, an "
           "impossible request) prints one line on stderr and exits with code 2.", "",
           "| command | what it does |", "|---|---|"]
    out += [f"| [`{name}`](#slax-drake-{name}) | {_cell(helps.get(name, ''))} |" for name in sub.choices]
    for name, cmd in sub.choices.items():
        out += ["", f"## slax-drake {name}", "", _cell(cmd.description or helps.get(name, "")), "", "```text",
                cmd.format_usage().strip(), "```", "", "| option | values | default | description |",
                "|---|---|---|---|"]
        for action in cmd._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            names = ", ".join(f"`{s}`" for s in action.option_strings) or f"`{action.metavar or action.dest}`"
            if action.choices is not None:
                values = ", ".join(f"`{c}`" for c in action.choices)
            elif action.nargs == 0:
                values = "flag"
            else:
                values = f"`{action.metavar or action.dest.upper()}`" + (" ..." if action.nargs in ("+", "*") else "")
            default = "" if action.default in (None, False, argparse.SUPPRESS) or not action.option_strings \
                else f"`{action.default}`"
            out.append(f"| {names} | {values} | {default} | {_cell(_help(cmd, action))} |")
    return "\n".join(out) + "\n"


def _field_comments(cls) -> dict[str, str]:
    """Per field of a dataclass: the comment lines just above it and the comment at the end of its line."""
    try:
        lines = inspect.getsource(cls).splitlines()
    except (OSError, TypeError):
        return {}
    comments, above = {}, []
    for line in lines[1:]:
        stripped = line.strip()
        if stripped.startswith("#"):
            above.append(stripped.lstrip("# "))
            continue
        m = re.match(r"\s+(\w+)\s*:\s*[^=]+(?:=.*?)?(?:#\s*(.*))?$", line)
        if m and not stripped.startswith(("def ", "@", "return")):
            comments[m.group(1)] = " ".join(above + ([m.group(2)] if m.group(2) else []))
        above = []
    return comments


def _type_name(tp) -> str:
    if isinstance(tp, type) and not typing.get_args(tp):
        return tp.__name__
    return re.sub(r"\b(typing|builtins|pydrake\.[\w.]+)\.", "", str(tp))


def _default(field: dataclasses.Field):
    if field.default is not dataclasses.MISSING:
        return field.default
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return None


def dataclass_reference(cls, prefix: str = "", seen_docs: list | None = None) -> str:
    rows, sections = [], []
    comments = _field_comments(cls)
    for field in dataclasses.fields(cls):
        key = f"{prefix}{field.name}"
        value = _default(field)
        if dataclasses.is_dataclass(field.type) and field.type.__module__.startswith("slax_drake"):
            doc = inspect.getdoc(field.type) or ""
            sections.append(f"### `{key}`\n\n{doc}\n\n" + dataclass_reference(field.type, key + "."))
            rows.append(f"| `{key}` | section | | see [`{key}`](#{key.replace('.', '')}) |")
            continue
        if dataclasses.is_dataclass(value):
            shown = f"{type(value).__name__} (Drake's defaults, see its documentation)"
        elif isinstance(value, (list, dict)) and not value:
            shown = "empty"
        else:
            shown = f"`{value}`"
        rows.append(f"| `{key}` | `{_cell(_type_name(field.type))}` | {shown} | {_cell(comments.get(field.name, ''))} |")
    table = "| key | type | default | description |\n|---|---|---|---|\n" + "\n".join(rows) + "\n"
    return table + ("\n" + "\n".join(sections) if sections else "")


def scenario_reference() -> str:
    from slax_drake.config import Scenario

    return (inspect.getdoc(Scenario) or "") + "\n\n" + dataclass_reference(Scenario)


def station_reference() -> str:
    from slax_drake.station.scenario import StationScenario

    return (inspect.getdoc(StationScenario) or "") + "\n\n" + dataclass_reference(StationScenario)


PLACEHOLDERS = {"<!-- cli-reference -->": cli_reference, "<!-- scenario-reference -->": scenario_reference,
                "<!-- station-reference -->": station_reference}


def on_page_markdown(markdown: str, page, config, files) -> str:
    for placeholder, render in PLACEHOLDERS.items():
        if placeholder in markdown:
            markdown = markdown.replace(placeholder, render())
    return markdown


def on_files(files, config):
    for svg in sorted((ROOT / "diagrams").glob("*.svg")):
        files.append(File(f"diagrams/{svg.name}", str(ROOT), config["site_dir"], config["use_directory_urls"]))
    return files
