"""``slax-drake diagram``: write the station's and the trial's system diagrams as Graphviz (.dot) and SVG."""

from __future__ import annotations

import argparse
import shutil
import subprocess
from pathlib import Path

from slax_drake.errors import GraphvizMissingError, UserError
from slax_drake.station import DEFAULT_STATION


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "diagram",
        help="write the station's and the trial's system diagrams (.dot and .svg)",
        description="Build the station (empty shelf) and the default trial (station camera -> perception -> "
        "planner -> station, the evaluator beside them) and write their Graphviz diagrams station.dot/.svg and "
        "trial.dot/.svg (the SVGs need Graphviz's `dot`).",
    )
    p.add_argument("--out", default="diagrams", help="output folder (default: diagrams)")
    p.add_argument("--station", default=DEFAULT_STATION, help=f"station YAML (default: {DEFAULT_STATION})")
    from slax_drake import arguments

    p.add_argument("--depth", type=arguments.non_negative_int, default=1,
                   help="levels of subsystems to expand, 0 or more (default: 1)")
    p.set_defaults(func=run)


def write_diagram(station_path: str, out: Path, depth: int = 1, name: str = "station",
                  diagram=None) -> tuple[Path, Path | None]:
    """Writes ``out/<name>.dot`` and, when ``dot`` exists, ``out/<name>.svg``; returns their paths. ``diagram``:
    the Drake diagram to draw (default: the station of ``station_path``, empty shelf)."""
    from slax_drake.io import write_bytes_atomic, write_text_atomic

    if diagram is None:
        from slax_drake.station.scenario import load_station_scenario
        from slax_drake.systems.station import MakeStation

        diagram = MakeStation(load_station_scenario(station_path))
    out.mkdir(parents=True, exist_ok=True)
    dot_path = out / f"{name}.dot"
    text = diagram.GetGraphvizString(max_depth=depth)
    write_text_atomic(dot_path, text)
    dot = shutil.which("dot")
    if dot is None:
        return dot_path, None
    result = subprocess.run([dot, "-Tsvg"], input=text.encode(), capture_output=True, check=False)
    if result.returncode != 0:
        raise UserError(f"dot failed: {result.stderr.decode().strip()}")
    svg_path = out / f"{name}.svg"
    write_bytes_atomic(svg_path, result.stdout)
    return dot_path, svg_path


def trial_diagram(station_path: str):
    """The default trial's diagram (slax_drake.systems.trial.build_trial) on ``station_path``."""
    from slax_drake.systems.trial import TrialOptions, build_trial

    return build_trial(TrialOptions(station=station_path)).diagram


def run(args: argparse.Namespace) -> int:
    drawn = [write_diagram(args.station, Path(args.out), args.depth),
             write_diagram(args.station, Path(args.out), args.depth, "trial", trial_diagram(args.station))]
    for dot_path, svg_path in drawn:
        print(f"wrote {dot_path}")
        if svg_path is None:
            raise GraphvizMissingError(
                f"Graphviz `dot` not found, so no SVG was drawn ({dot_path} is written); install Graphviz "
                "(Debian/Ubuntu: apt-get install graphviz) and run again"
            )
        print(f"wrote {svg_path}")
    return 0
