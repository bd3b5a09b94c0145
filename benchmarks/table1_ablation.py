"""Where the gap to the paper's Table I comes from: the Table I protocol on the first K scenes per density under
named variants of the action model's rules (a profile plus single rule overrides, or a scenario change), every
policy on the same scenes; prints a Markdown table of success rates (overall, and per density), the mean
seconds per trial, and how many oracle searches were cut by time.

    python benchmarks/table1_ablation.py [--scenes 10] [--policies oracle-p,oracle-p+s,bluction-dar]
        [--variants station,paper,...] [--oracle-seconds 20] [--out results/table1_ablation]

Trials are kept under OUT/<variant>/ (the Table I runner's trial files), so a stopped run resumes and a rerun
with more variants or policies runs only what is missing.
"""

from __future__ import annotations

import argparse
import copy
import time

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import run_benchmark

THIN_BLADE = {"blade_gap": 0.001, "tube_past_blade": 0.0, "tube_approach_check": False}

# name -> (what it is, profile, rule overrides, scenario changes {"section.key": value})
VARIANTS = {
    "station": ("today's rules (the station profile)", "station", {}, {}),
    "station-thin-blade": ("station + blade lane = blade thickness (1 mm), no tube allowance, no tube way-in check",
                           "station", THIN_BLADE, {}),
    "station-thin-blade-no-hidden-placement": ("... + no hidden-space rule for suction placements", "station",
                                               {**THIN_BLADE, "suction_hidden_rule": "none"}, {}),
    "paper": ("the paper profile (... + unlimited tube reach, any cylinder sealable)", "paper", {}, {}),
    "paper-aligned": ("paper + boxes square to the walls", "paper", {}, {"objects.box_yaw": "aligned"}),
    "paper-push-hidden-off": ("paper + pushes may enter hidden space", "paper", {"push_hidden_check": False}, {}),
    "station-push-hidden-off": ("station + pushes may enter hidden space, alone", "station",
                                {"push_hidden_check": False}, {}),
    "station-camera-1.5m": ("station + camera 1.5 m from the shelf, alone", "station", {},
                            {"camera.position": [0.0, -1.5, 0.20]}),
}


def scenario_with(scenario, changes: dict):
    """A copy of ``scenario`` with ``{"section.key": value}`` set."""
    out = copy.deepcopy(scenario)
    for dotted, value in changes.items():
        section, key = dotted.split(".")
        setattr(getattr(out, section), key, value)
    return out


def cell(per: dict, densities) -> str:
    rates = [per[str(d)]["success_rate"] for d in densities]
    counts = "/".join(f"{round(r * per[str(d)]['trials'])}" for r, d in zip(rates, densities))
    text = f"{100 * per['all']['success_rate']:.0f} ({counts} of {per[str(densities[0])]['trials']})"
    cut = (per["all"].get("oracle_status") or {}).get("cut by time")
    return text + (f", {cut} cut" if cut else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=10, help="the first K scenes per density (default 10)")
    ap.add_argument("--policies", default="oracle-p,oracle-p+s,bluction-dar")
    ap.add_argument("--variants", default=",".join(VARIANTS), help=f"from: {', '.join(VARIANTS)}")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    ap.add_argument("--oracle-seconds", type=float, default=20.0, help="the oracles' time limit per decision")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--out", default="results/table1_ablation")
    args = ap.parse_args()
    base = load_scenario(args.config)
    policies = [p.strip() for p in args.policies.split(",") if p.strip()]
    variants = [v.strip() for v in args.variants.split(",") if v.strip()]
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        raise SystemExit(f"unknown variant(s) {unknown} (known: {', '.join(VARIANTS)})")
    densities = list(base.protocol.densities)
    rows = []
    for name in variants:
        what, profile, rules, changes = VARIANTS[name]
        t0 = time.perf_counter()
        table = run_benchmark(scenario_with(base, changes), policies, args.scenes, base.protocol.seed,
                              f"{args.out}/{name}", workers=args.workers, progress=False, tool_rules=rules,
                              profile=profile, oracle_seconds=args.oracle_seconds)
        seconds = [table["policies"][p]["all"]["mean_trial_seconds"] for p in policies]
        rows.append((name, what, [cell(table["policies"][p], densities) for p in policies], seconds,
                     time.perf_counter() - t0))
    print(f"First {args.scenes} Table I scenes per density ({'/'.join(map(str, densities))} objects; protocol seed "
          f"{base.protocol.seed}), ground-truth distributions, oracle time limit {args.oracle_seconds:g} s per "
          f"decision. Success % overall (successes per density); 'cut': oracle trials whose search hit the limit.")
    print()
    print("| variant | rules | " + " | ".join(policies) + " | s per trial |")
    print("|---|---|" + "---|" * len(policies) + "---|")
    for name, what, cells, seconds, _ in rows:
        per_trial = " / ".join("-" if s is None else f"{s:.1f}" for s in seconds)
        print(f"| {name} | {what} | " + " | ".join(cells) + f" | {per_trial} |")


if __name__ == "__main__":
    main()
