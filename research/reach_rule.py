"""How often the action model offers an action the arm cannot execute ("false feasible"): a proxy, without
physics, for the trials' "no feasible motion" endings.

For K seeded Table I scenes per density (the protocol's scene seeds, ``slax_drake.evaluation.table1.scene_seed``),
on their initial state: the candidate actions the station's action model deems feasible (``station`` profile with
the station's rules: the cup's limits and its reach map, as in a Drake trial; the objects known, the target not),
each planned by the Drake motion planner from the observation pose. Prints, per density and in all, how many
candidates the model offered, how many the planner rejected (the false-feasible rate) and by which waypoint, how
many the reach map refused before planning, and the planning time per candidate (median, p90; one process).
With ``--baseline RULE=VALUE`` (repeatable, e.g. ``push_tube_check=false``) the candidates the model offers with
those rule values but not with the station's (the ones the station's rules remove before planning) are planned
too: "removed" counts them and "removed plannable" those the planner would have planned (a conservative rule
removes none); the rejected rate of the baseline model is printed beside. The JSON holds every planned candidate
(verdict, planning seconds); ``--compare EARLIER.json`` prints the candidates whose verdict changed since that run
and the planning times of those both runs planned. ``--stances DX [DX ...]`` (m) plans every candidate the planner
rejects (offered, or removed by the station's rules beyond the baseline) again with the robot's base moved DX along
the shelf's x (the shelf, the objects and the observation pose relative to the base unchanged: the scene camera moved
with the base), and counts those that some stance plans: whether choosing the base's stance per action would make
them executable.

    python research/reach_rule.py --station sim_configs/station_sim_shelf.yaml --scenes 2
    python research/reach_rule.py --config sim_configs/table2.yaml \\
        --station sim_configs/station_physical_shelf.yaml --densities 8 10 12 --scenes 2
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import sys
import time

import numpy as np


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/table1.yaml", help="the protocol scenario YAML")
    parser.add_argument("--station", default="sim_configs/station_sim_shelf.yaml")
    parser.add_argument("--densities", type=int, nargs="+", default=[6, 8, 10])
    parser.add_argument("--scenes", type=int, default=2, help="scenes per density (the protocol's first K)")
    parser.add_argument("--seed", type=int, default=None, help="protocol seed (default: the config's)")
    parser.add_argument("--json", default=None, help="write the figures here too")
    parser.add_argument("--list-rejected", action="store_true",
                        help="print every candidate the planner rejects, with its full reason")
    parser.add_argument("--baseline", nargs="+", default=[], metavar="RULE=VALUE",
                        help="rule values of a baseline model whose extra candidates are planned too")
    parser.add_argument("--compare", default=None, metavar="EARLIER.json",
                        help="an earlier run's --json: list the candidates whose verdict changed")
    parser.add_argument("--stances", type=float, nargs="+", default=[], metavar="DX",
                        help="base shifts along the shelf's x (m) from which to plan every rejected candidate again")
    args = parser.parse_args(argv)
    from slax_drake.config import load_scenario
    from slax_drake.errors import UserError
    from slax_drake.evaluation.table1 import protocol_scene, scene_seed
    from slax_drake.hardware.check_action import make_checker
    from slax_drake.shelf.actions import ActionModel
    from slax_drake.shelf.tool import parse_tool_rules

    try:
        earlier = _earlier_candidates(args.compare) if args.compare else None  # read before the long run
        scenario = load_scenario(args.config)
        baseline = parse_tool_rules(args.baseline) if args.baseline else None
        seed = scenario.protocol.seed if args.seed is None else args.seed
        rows = collections.defaultdict(lambda: collections.Counter())
        times = collections.defaultdict(list)
        why = collections.Counter()
        planned = []  # every offered candidate: density, scene index, action, verdict, planning seconds
        print(f"{args.station} on {args.config}: {args.scenes} scenes per density, protocol seed {seed}", flush=True)
        for n in args.densities:
            for index in range(args.scenes):
                scene = protocol_scene(scenario, n, scene_seed(seed, n, index))
                checker = make_checker(scene, args.station)
                cands = checker.candidates()
                removed = []
                if baseline is not None:
                    tool = checker.model.tool
                    base_tool = dataclasses.replace(tool, rules=dataclasses.replace(tool.rules, **baseline))
                    base = ActionModel(checker.scene.shelf, checker.scene.camera.position[:2], base_tool)
                    offered = set(cands.feasible)
                    removed = [a for a in base.enumerate(checker.scene.objects).feasible if a not in offered]
                row = rows[n]
                row["scenes"] += 1
                row["offered"] += len(cands.feasible)
                row["reach_refused"] += sum(r.reason.endswith("(reach map)") for r in cands.rejected)
                for action in cands.feasible:
                    t0 = time.perf_counter()
                    result = checker.planner.plan(action, checker.scene)
                    times[n].append(time.perf_counter() - t0)
                    planned.append({"n": n, "scene": index, "action": str(action), "kind": action.kind,
                                    "feasible": bool(result.feasible), "plan_s": round(times[n][-1], 4),
                                    "reason": "" if result.feasible else result.reason})
                    if not result.feasible:
                        row["rejected"] += 1
                        row[f"rejected_{action.kind}"] += 1
                        why[result.reason.split(":")[0][:40]] += 1
                        if args.list_rejected:
                            print(f"    rejected {action}: {result.reason}", flush=True)
                    row[f"offered_{action.kind}"] += 1
                failed = [a for a, c in zip(cands.feasible, planned[-len(cands.feasible):] if cands.feasible else [])
                          if not c["feasible"]]
                for action in removed:
                    result = checker.planner.plan(action, checker.scene)
                    row["removed"] += 1
                    row[f"removed_{action.kind}"] += 1
                    if result.feasible:
                        row["removed_plannable"] += 1
                        print(f"    removed but plannable: {action}", flush=True)
                    else:
                        failed.append(action)
                if args.stances:
                    for action, shifts in plan_from_stances(checker, failed, args.stances):
                        row["stance_tried"] += 1
                        row["stance_planned"] += bool(shifts)
                        for dx in shifts:
                            row[f"stance_planned_{dx:+.2f}"] += 1
                        print(f"    rejected {action}: planned from base shift "
                              f"{', '.join(f'{dx:+.2f}' for dx in shifts) or 'none'}", flush=True)
                print(f"  n={n} scene {index}: {len(cands.feasible)} offered, "
                      f"{row['rejected']} rejected so far at this density"
                      + (f"; {len(removed)} removed by the rules beyond the baseline" if baseline is not None else ""),
                      flush=True)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    summary = {}
    print(f"{'n':>4} {'offered':>8} {'rejected':>9} {'false feasible':>15} {'push':>9} {'suction':>9} "
          f"{'reach-map refused':>18} {'plan median s':>14} {'p90 s':>7}")
    for n in [*args.densities, "all"]:
        if n == "all":
            row = sum(rows.values(), collections.Counter())
            t = np.concatenate([times[k] for k in args.densities])
        else:
            row, t = rows[n], np.array(times[n])
        rate = row["rejected"] / max(1, row["offered"])
        med, p90 = (float(np.median(t)), float(np.percentile(t, 90))) if len(t) else (float("nan"),) * 2
        print(f"{n:>4} {row['offered']:>8} {row['rejected']:>9} {rate:>14.1%} "
              f"{row['rejected_push']:>4}/{row['offered_push']:<4} {row['rejected_suction']:>4}/{row['offered_suction']:<4} "
              f"{row['reach_refused']:>18} {med:>14.3f} {p90:>7.3f}")
        summary[str(n)] = {**dict(row), "false_feasible": round(rate, 4), "plan_median_s": round(med, 3),
                           "plan_p90_s": round(p90, 3)}
    if args.baseline:
        row = sum(rows.values(), collections.Counter())
        base_offered = row["offered"] + row["removed"]
        base_rejected = row["rejected"] + row["removed"] - row["removed_plannable"]
        print(f"baseline ({' '.join(args.baseline)}): {base_offered} offered, {base_rejected} rejected "
              f"({base_rejected / max(1, base_offered):.1%}); the station's rules remove {row['removed']} of them "
              f"(push {row['removed_push']}, suction {row['removed_suction']}), {row['removed_plannable']} of which "
              "the planner would have planned")
        summary["baseline"] = {"rules": args.baseline, "offered": base_offered, "rejected": base_rejected,
                               "removed": row["removed"], "removed_plannable": row["removed_plannable"]}
    if args.stances:
        row = sum(rows.values(), collections.Counter())
        print(f"base stances {' '.join(f'{dx:+.2f}' for dx in args.stances)} m: {row['stance_planned']} of "
              f"{row['stance_tried']} rejected candidates plan from some stance ("
              + ", ".join(f"{dx:+.2f}: {row[f'stance_planned_{dx:+.2f}']}" for dx in args.stances) + ")")
        summary["stances"] = {"shifts": args.stances, "tried": row["stance_tried"], "planned": row["stance_planned"],
                              **{f"{dx:+.2f}": row[f"stance_planned_{dx:+.2f}"] for dx in args.stances}}
    print("planner rejections by first reason:")
    for reason, count in why.most_common(8):
        print(f"  {count:4d}  {reason}")
    if earlier is not None:
        _compare(earlier, planned)
    if args.json:
        from pathlib import Path

        from slax_drake.io import write_text_atomic

        summary["reasons"] = dict(why)
        summary["station"], summary["config"] = args.station, args.config
        summary["candidates"] = planned
        write_text_atomic(Path(args.json), json.dumps(summary, indent=1) + "\n")
    return 0


def plan_from_stances(checker, actions, shifts):
    """(action, [the base shifts (m, along S x) from which the planner plans it]) per action: each planned with a
    fresh planner in the checker's scene whose camera (on the robot, at the observation pose) is moved by the
    shift along S x, so the shelf stands shifted the other way relative to the base."""
    from slax_drake.planning.planner import MotionPlanner

    planners = {}
    for dx in shifts:
        X = np.array(checker.scene.camera.X_SC, float, copy=True)
        X[0, 3] += dx
        scene = dataclasses.replace(checker.scene, camera=dataclasses.replace(checker.scene.camera, X_SC=X))
        planners[dx] = (MotionPlanner(checker.planner.scenario, checker.planner.tool), scene)
    for action in actions:
        yield action, [dx for dx, (planner, scene) in planners.items() if planner.plan(action, scene).feasible]


def _earlier_candidates(path: str) -> list:
    """The candidate records of an earlier run's --json at ``path``; BenchmarkError (one line, exit 2) when it
    cannot be read or holds none."""
    from slax_drake.errors import BenchmarkError

    try:
        candidates = json.loads(open(path).read()).get("candidates")
    except (OSError, ValueError, AttributeError) as e:
        raise BenchmarkError(f"--compare {path}: not an earlier run's --json ({e})") from None
    fields = {"n", "scene", "action", "feasible", "plan_s", "reason"}
    if not isinstance(candidates, list) or not all(isinstance(c, dict) and fields <= set(c) for c in candidates):
        raise BenchmarkError(f"--compare {path}: no candidate records (a --json of this script holds them)")
    return candidates


def _compare(earlier: list, planned: list) -> None:
    """Prints the candidates whose verdict differs from ``earlier`` (records of an earlier --json), and the median
    and p90 planning seconds, in each run, of the candidates both runs planned and of those both rejected."""
    before = {(c["n"], c["scene"], c["action"]): c for c in earlier}
    both = [(before[(c["n"], c["scene"], c["action"])], c) for c in planned
            if (c["n"], c["scene"], c["action"]) in before]
    print(f"compared with the earlier run: {len(both)} of {len(planned)} candidates in both")
    for old, new in both:
        if old["feasible"] != new["feasible"]:
            verdict = "now planned" if new["feasible"] else "now rejected: " + new["reason"].split(" [")[0]
            print(f"  n={new['n']} scene {new['scene']} {new['action']}: {verdict} ({new['plan_s']:.2f} s)")
    for label, keep in (("planned in both", True), ("rejected in both", False)):
        pairs = [(o["plan_s"], c["plan_s"]) for o, c in both if o["feasible"] == keep and c["feasible"] == keep]
        if pairs:
            t = np.array(pairs)
            print(f"  {label} ({len(pairs)}): median {np.median(t[:, 0]):.3f} -> {np.median(t[:, 1]):.3f} s, "
                  f"p90 {np.percentile(t[:, 0], 90):.3f} -> {np.percentile(t[:, 1], 90):.3f} s")


if __name__ == "__main__":
    raise SystemExit(main())
