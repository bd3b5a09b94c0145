"""Which pushes of a physics run went as predicted, by the pushed object's shape and the push model.

    python research/push_matches.py RUN [RUN ...] [--policy slax-belief]

RUN: a physics benchmark folder with its trial files (``physics_trials/POLICY/*.json``; ``docs/results`` keeps
none: run the benchmark's command). Each pushed object's shape is the true object's, from the protocol scene the
trial names (density, seed). A push matches as the physics report judges it (within 2 cm and 10 deg of the
prediction, the object's own turn against the predicted one). Prints one row per run and shape: pushes, matched,
the pushes predicted as turning (``push_turn`` quasi-static), and the median position error and turn error of
the mismatched ones; then one row per run and band of the pushed object's height (below the tube that runs along
the blade's upper edge, at it, above it): pushes, matched and the median offset of the end along the push (mm,
positive: farther than predicted).
"""

import argparse
import json
import math
import statistics
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.evaluation.physics import judge_action
from slax_drake.scene.sampling import sample_scene

HEIGHT_BANDS = ((0.0, 0.068, "below the tube (< 6.8 cm)"), (0.068, 0.085, "at the tube (6.8-8.5 cm)"),
                (0.085, 10.0, "above the tube's axis (>= 8.5 cm)"))  # m; the tube spans 6.8-9.8 cm, axis 8.3 cm


def push_rows(run: Path, policy: str) -> dict:
    """{shape: [(matched, turns, position error m, turn error deg, object height m, offset along the push m),
    ...]} over the run's pushes."""
    settings = json.loads((run / "physics_settings.json").read_text())
    scenario = load_scenario(settings["config"])
    shelf = scenario.shelf
    rows: dict = {}
    for path in sorted((run / "physics_trials" / policy).glob("*.json")):
        trial = json.loads(path.read_text())
        objects = scenario.protocol.occluders(trial["density"])
        scene = sample_scene(scenario, objects, trial["seed"],
                             target_size=tuple(float(v) for v in scenario.target.sizes[0]))
        shapes = {o.name: o.shape for o in scene.objects}
        heights = {o.name: float(o.size[2]) for o in scene.objects}
        for a in trial["drake"].get("actions", []):
            if a["type"] != "push" or a.get("outcome") is None or a.get("before") is None:
                continue
            matched, _ = judge_action(a, shelf.width, shelf.depth)
            p, out, before = a["predicted"], a["outcome"], a["before"]
            error = math.hypot(out["x"] - p["x"], out["y"] - p["y"])
            turn = math.degrees(abs(math.remainder(out["yaw"] - before["yaw"] - p.get("turn", 0.0), 2 * math.pi)))
            along = math.copysign(1.0, a["d"]) * (out["x"] - p["x"])
            rows.setdefault(shapes.get(a.get("true_object"), "unknown"), []).append(
                (bool(matched), "turn" in p, error, turn, heights.get(a.get("true_object"), float("nan")), along))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="physics benchmark folders with trial files")
    parser.add_argument("--policy", default="slax-belief")
    args = parser.parse_args(argv)
    for run in args.runs:
        if not (run / "physics_settings.json").is_file() or not (run / "physics_trials" / args.policy).is_dir():
            parser.error(f"{run}: no physics run with trial files of {args.policy}")
    print("| run | shape | pushes | as predicted | predicted turning | mismatched: median position error (cm), "
          "turn error (deg) |")
    print("|---|---|---|---|---|---|")
    for run in args.runs:
        for shape, rows in sorted(push_rows(run, args.policy).items()):
            bad = [r for r in rows if not r[0]]
            errors = (f"{100 * statistics.median(r[2] for r in bad):.1f}, {statistics.median(r[3] for r in bad):.0f}"
                      if bad else "")
            print(f"| {run.name} | {shape} | {len(rows)} | {sum(r[0] for r in rows)} | {sum(r[1] for r in rows)} | "
                  f"{errors} |")
    print("\n| run | pushed object's height | pushes | as predicted | median offset along the push (mm) |")
    print("|---|---|---|---|---|")
    for run in args.runs:
        pushes = [r for rows in push_rows(run, args.policy).values() for r in rows]
        for lo, hi, band in HEIGHT_BANDS:
            rows = [r for r in pushes if lo <= r[4] < hi]
            if rows:
                print(f"| {run.name} | {band} | {len(rows)} | {sum(r[0] for r in rows)} | "
                      f"{1000 * statistics.median(r[5] for r in rows):+.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
