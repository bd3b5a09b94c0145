"""The Markdown table of planning time per executed action for runs of ``bench_planning_per_action.py --json``.

Each ``LABEL=FILE[,FILE...]`` is one row: the decisions of its files pooled (e.g. the 6- and the 8-object scenes of
one checkout). Prints executed actions, wall and CPU median / p90, rejected candidates and, for every row after the
first, how many decisions chose the same action as the first row's (the same scenes, the same policy: a speed-up that
changes no decision keeps every one):

    python benchmarks/planning_per_action_table.py before=b6.json,b8.json after=a6.json,a8.json
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np


def _row(spec: str):
    label, _, files = spec.partition("=")
    if not label or not files:
        raise argparse.ArgumentTypeError(f"expected LABEL=FILE[,FILE...], got {spec!r}")
    decisions = []
    for path in files.split(","):
        try:
            with open(path) as f:
                data = json.load(f)
        except (OSError, json.JSONDecodeError) as e:
            raise argparse.ArgumentTypeError(f"{path}: {e}") from None
        objects = data.get("summary", {}).get("objects")
        decisions += [dict(d, objects=objects) for d in data.get("decisions", [])]
    return label, decisions


def _key(d):
    return d["objects"], d["scene_seed"], d["step"]


def _stat(values, q: float) -> str:
    return f"{np.percentile(values, q):.3f} s" if len(values) else "-"


def table(rows) -> str:
    lines = ["| run | executed actions | wall median | wall p90 | CPU median | CPU p90 | rejected candidates | same decisions |",
             "|---|---|---|---|---|---|---|---|"]
    first = {_key(d): d["action"] for d in rows[0][1]}
    for k, (label, decisions) in enumerate(rows):
        executed = [d for d in decisions if d["action"] is not None]
        wall = np.array([d["planning_s"] for d in executed])
        cpu = np.array([d["planning_cpu_s"] for d in executed])
        same = "" if k == 0 else (f"{sum(1 for d in decisions if first.get(_key(d), object()) == d['action'])}"
                                  f" of {len(decisions)}")
        lines.append(f"| {label} | {len(executed)} | {_stat(wall, 50)} | {_stat(wall, 90)} | {_stat(cpu, 50)} | "
                     f"{_stat(cpu, 90)} | {sum(d['rejected'] for d in decisions)} | {same} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="LABEL=FILE[,FILE...]: one row")
    args = parser.parse_args(argv)
    try:
        rows = [_row(s) for s in args.runs]
    except argparse.ArgumentTypeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
