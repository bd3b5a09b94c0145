"""``slax-drake diagram``: write the station's system diagram as Graphviz (.dot) and SVG."""

from __future__ import annotations

import argparse
import shutil
import subprocess
from pathlib import Path

from slax_drake.errors import UserError
from slax_drake.station import DEFAULT_STATION


class GraphvizMissingError(UserError):
    """Graphviz's ``dot`` is not installed, so the SVG cannot be drawn."""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "diagram",
        help="write the station's system diagram (.dot and .svg)",
        description="Build the station (empty shelf) and write its Graphviz diagram station.dot and station.svg "
        "(the SVG needs Graphviz's `dot`).",
    )
    p.add_argument("--out", default="diagrams", help="output folder (default: diagrams)")
    p.add_argument("--station", default=DEFAULT_STATION, help=f"station YAML (default: {DEFAULT_STATION})")
    p.add_argument("--depth", type=int, default=1, help="levels of subsystems to expand (default: 1)")
    p.set_defaults(func=run)


def write_diagram(station_path: str, out: Path, depth: int = 1) -> tuple[Path, Path | None]:
    """Writes ``out/station.dot`` and, when ``dot`` exists, ``out/station.svg``; returns their paths."""
    from slax_drake.io import write_bytes_atomic, write_text_atomic
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.station import MakeStation

    diagram = MakeStation(load_station_scenario(station_path))
    out.mkdir(parents=True, exist_ok=True)
    dot_path = out / "station.dot"
    text = diagram.GetGraphvizString(max_depth=depth)
    write_text_atomic(dot_path, text)
    dot = shutil.which("dot")
    if dot is None:
        return dot_path, None
    result = subprocess.run([dot, "-Tsvg"], input=text.encode(), capture_output=True, check=False)
    if result.returncode != 0:
        raise UserError(f"dot failed: {result.stderr.decode().strip()}")
    svg_path = out / "station.svg"
    write_bytes_atomic(svg_path, result.stdout)
    return dot_path, svg_path


def run(args: argparse.Namespace) -> int:
    dot_path, svg_path = write_diagram(args.station, Path(args.out), args.depth)
    print(f"wrote {dot_path}")
    if svg_path is None:
        raise GraphvizMissingError(
            f"Graphviz `dot` not found, so no SVG was drawn ({dot_path} is written); install Graphviz "
            "(Debian/Ubuntu: apt-get install graphviz) and run again"
        )
    print(f"wrote {svg_path}")
    return 0
