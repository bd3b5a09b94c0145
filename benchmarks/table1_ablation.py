"""Where the gap to the paper's Table I comes from: the Table I protocol on the first K scenes per density under
named variants of the action model's rules (a profile plus single rule overrides, or a scenario change), every
policy on the same scenes; prints a Markdown table of success rates (overall, and per density), the mean
seconds per trial, and how many oracle searches were cut by time.

    python benchmarks/table1_ablation.py [--scenes 10] [--policies oracle-p,oracle-p+s,bluction-dar]
        [--variants station,paper,...] [--oracle-seconds 20] [--out results/table1_ablation]

The ``station-without-<rule>`` variants are the station profile with one rule at its paper value, one per rule in
which the profiles differ; when ``station`` is among the variants, a line per rule follows the table with what the
rule costs each policy (the success without it minus the station's, in points).

Trials are kept under OUT/<variant>/ (the Table I runner's trial files), so a stopped run resumes and a rerun
with more variants or policies runs only what is missing.
"""

from __future__ import annotations

import argparse
import copy
import shlex
import sys
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
    # Readings of the paper's text that the paper profile does not take (issue 19, item 4; rules.py and config.py
    # docstrings quote the line each reads), each alone on top of the paper profile.
    "paper-contact": ("paper + a push stops against its neighbour (push_stop exact, clearance 0)", "paper",
                      {"push_stop": "exact", "clearance": 0.0}, {}),
    "paper-exact-stop": ("paper + a push stops exactly clearance (2 mm) before its neighbour (push_stop exact)",
                         "paper", {"push_stop": "exact"}, {}),
    "paper-push-hidden-end": ("paper + a push may cross hidden space, not come to rest in it", "paper",
                              {"push_hidden_extent": "end"}, {}),
    "paper-target-first": ("paper + the target placed first, the occluders around it", "paper", {},
                           {"target.placement": "first"}),
    "paper-n-includes-target": ("paper + n counts the target (n - 1 occluders, H = 2n)", "paper", {},
                                {"protocol.count_includes_target": True}),
    "paper-readings-combined": ("paper + boxes square to the walls + a push stops exactly 2 mm before its "
                                "neighbour (the two readings of the paper's text that do not contradict it)",
                                "paper", {"push_stop": "exact"}, {"objects.box_yaw": "aligned"}),
    "paper-horizon-4n": ("paper + H = 4n (a horizon that does not bind)", "paper", {},
                         {"protocol.horizon_per_object": 4}),
    # What the Drake station's own limits cost in the shelf simulator (issue 17's Table II): the physical-shelf
    # station's cup limits and reach map (sim_configs/station_physical_shelf.yaml, station_table2.yaml), which a
    # Drake trial on that station adds to the station profile (systems.trial.station_tool_rules); run with
    # --config sim_configs/table2.yaml.
    "station-cup-moment": ("station + the cup's holding limit (max_suction_moment 0.4 N m), alone", "station",
                           {"max_suction_moment": 0.4}, {}),
    "station-seal-angle": ("station + the cup's seal angle (max_seal_angle_deg 10), alone", "station",
                           {"max_seal_angle_deg": 10.0}, {}),
    "station-physical-reach": ("station + the physical-shelf station's reach map, alone", "station",
                               {"reach_map": "models/reach/station_physical_shelf.json"}, {}),
    "station-physical-drake": ("station + every limit of the physical-shelf station (cup moment, seal angle, reach "
                               "map): what a Drake trial on it plans with", "station",
                               {"max_suction_moment": 0.4, "max_seal_angle_deg": 10.0,
                                "reach_map": "models/reach/station_physical_shelf.json"}, {}),
}

# What each physical rule costs (issue 19, "station" done-when: one line per rule): the station profile with one rule
# set to its paper value, every other rule left as the station has it. A variant per rule in which the two profiles
# differ (slax_drake.shelf.rules.profile_values); the cost of a rule is the variant's success rate minus the
# station's, printed after the table by ``rule_cost_lines``.
LEAVE_ONE_OUT_PREFIX = "station-without-"


def leave_one_out_variants() -> dict:
    """{``station-without-<rule>``: (what, "station", {rule: paper value}, {})} for every rule whose paper and station
    values differ."""
    from slax_drake.shelf.rules import profile_values

    paper, station = profile_values("paper"), profile_values("station")
    return {f"{LEAVE_ONE_OUT_PREFIX}{name}": (f"station, {name} = {paper[name]} (paper) instead of {station[name]}",
                                                 "station", {name: paper[name]}, {})
            for name in paper if paper[name] != station[name]}


VARIANTS.update(leave_one_out_variants())


def rule_cost_lines(rates: dict, policies) -> list[str]:
    """One line per leave-one-out variant in ``rates`` ({variant: {policy: success rate}}, "station" among them):
    what the rule costs each policy in points of success (the rate without the rule minus the station's; a
    negative cost means the station's value of the rule helps)."""
    if "station" not in rates:
        return []
    from slax_drake.shelf.rules import profile_values

    station = profile_values("station")
    lines = []
    for name, per in rates.items():
        if not name.startswith(LEAVE_ONE_OUT_PREFIX):
            continue
        rule = name[len(LEAVE_ONE_OUT_PREFIX):]
        costs = ", ".join(f"{p} {100 * (per[p] - rates['station'][p]):+.1f}" for p in policies)
        lines.append(f"- `{rule}` (station {station[rule]}, paper {VARIANTS[name][2][rule]}): costs {costs} points")
    return lines


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
    status = per["all"].get("oracle_status") or {}
    proven = status.get("infeasible")
    cut = status.get("cut by time")
    return text + (f", {proven} infeasible" if proven else "") + (f", {cut} cut" if cut else "")


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
        ap.error(f"unknown variant(s) {unknown} (known: {', '.join(VARIANTS)})")  # one line, exit 2
    densities = list(base.protocol.densities)
    rows, rates = [], {}
    for name in variants:
        what, profile, rules, changes = VARIANTS[name]
        t0 = time.perf_counter()
        table = run_benchmark(scenario_with(base, changes), policies, args.scenes, base.protocol.seed,
                              f"{args.out}/{name}", workers=args.workers, progress=False, tool_rules=rules,
                              profile=profile, oracle_seconds=args.oracle_seconds)
        seconds = [table["policies"][p]["all"]["mean_trial_seconds"] for p in policies]
        rows.append((name, what, [cell(table["policies"][p], densities) for p in policies], seconds,
                     time.perf_counter() - t0))
        rates[name] = {p: table["policies"][p]["all"]["success_rate"] for p in policies}
    print("Made by `python " + " ".join(shlex.quote(a) for a in sys.argv) + "`.")
    print()
    print(f"First {args.scenes} scenes per density of {args.config} ({'/'.join(map(str, densities))} objects; "
          f"protocol seed {base.protocol.seed}), ground-truth distributions, oracle time limit {args.oracle_seconds:g} s per "
          f"decision. Success % overall (successes per density); 'infeasible': oracle trials whose search proved "
          "that no plan exists within H; 'cut': oracle trials whose search hit the limit.")
    print()
    print("| variant | rules | " + " | ".join(policies) + " | s per trial |")
    print("|---|---|" + "---|" * len(policies) + "---|")
    for name, what, cells, seconds, _ in rows:
        per_trial = " / ".join("-" if s is None else f"{s:.1f}" for s in seconds)
        print(f"| {name} | {what} | " + " | ".join(cells) + f" | {per_trial} |")
    costs = rule_cost_lines(rates, policies)
    if costs:
        print()
        print("What each rule of the station profile costs: the success with that rule at its paper value minus the "
              "station's, in points (one scene is 100 / (4 x scenes) points overall):")
        print()
        print("\n".join(costs))


if __name__ == "__main__":
    main()
