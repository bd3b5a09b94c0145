"""Rewrites a physics-benchmark folder's physics.json, physics.md and physics.png from its per-scene files
(OUT/physics_trials) with the current summary code, keeping the run's recorded ``meta``: for counts added to the
summary after the run (e.g. the reversals), without running a scene again.

    python benchmarks/resummarise_physics.py RUN_DIR [--out DOCS_DIR]

``--out``: write the three files and a copy of physics_settings.json there instead (e.g. a docs/results folder,
which keeps no per-scene files).
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.evaluation.physics import bar_chart_png, load_results, markdown_table, summarise
from slax_drake.io import write_bytes_atomic, write_text_atomic


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a folder written by slax-drake benchmark --physics")
    parser.add_argument("--out", type=Path, default=None, help="where to write (default: the run folder)")
    args = parser.parse_args(argv)
    try:
        old = json.loads((args.run / "physics.json").read_text())
        meta = old["meta"]
    except (OSError, json.JSONDecodeError, KeyError) as e:
        print(f"{args.run}: no readable physics.json with its meta ({e})", file=sys.stderr)
        return 2
    policies = list(old["policies"])
    scenario = load_scenario(meta["config"])
    trials = load_results(args.run, policies, meta["densities"], meta["scenes_per_density"])
    summary = summarise(trials, policies, meta["densities"], (scenario.shelf.width, scenario.shelf.depth))
    summary["meta"] = meta
    out = args.out or args.run
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "physics.json", json.dumps(summary, indent=1, sort_keys=True))
    write_text_atomic(out / "physics.md", markdown_table(summary))
    write_bytes_atomic(out / "physics.png", bar_chart_png(summary))
    if out != args.run:
        shutil.copyfile(args.run / "physics_settings.json", out / "physics_settings.json")
    print(f"wrote {out}/physics.json, physics.md, physics.png from {len(trials)} scene files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
