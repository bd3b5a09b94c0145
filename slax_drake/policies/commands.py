"""``slax-drake benchmark``: the paper's Table I protocol in the fast first-order shelf simulator."""

from __future__ import annotations

import argparse

from slax_drake.errors import UserError


def register(subparsers) -> None:
    from slax_drake.policies.registry import POLICY_NAMES, add_tool_rule_argument

    p = subparsers.add_parser(
        "benchmark",
        help="run search policies on the Table I protocol (fast shelf simulator)",
        description="Run search policies on the same seeded scenes of every density of the protocol "
        "(H = horizon_per_object * n actions) and write table1.md, table1.json and table1.png. "
        "Finished trials are kept under OUT/trials, so a stopped run resumes.",
    )
    p.add_argument("--config", default="sim_configs/table1.yaml", help="scenario YAML (default: sim_configs/table1.yaml)")
    p.add_argument("--policies", default="oracle-p,oracle-p+s,dar,der-3,bluction-dar",
                   help=f"comma-separated policy names from: {', '.join(POLICY_NAMES)}")
    p.add_argument("--scenes-per-density", type=int, default=None, help="default: the protocol's")
    p.add_argument("--seed", type=int, default=None, help="protocol seed (default: the protocol's)")
    p.add_argument("--workers", type=int, default=1, help="parallel worker processes (default: 1)")
    p.add_argument("--backend", choices=("local", "ray"), default="local",
                   help="local: multiprocessing; ray: Ray tasks on a local Ray instance")
    p.add_argument("--perception", choices=("ground-truth", "learned"), default="ground-truth",
                   help="distribution model: ground-truth (compute_occupancy) or learned (the shipped network, "
                   "models/perception/unet128)")
    p.add_argument("--out", default="results/table1", help="output folder (default: results/table1)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--physics", action="store_true",
                   help="run the protocol through full Drake trials beside the shelf simulator on the same scenes "
                   "(non-oracle policies only; writes OUT/physics.md and OUT/physics.json; slow)")
    p.add_argument("--sleep", action="store_true", help="with --physics: object sleep in the Drake trials")
    p.add_argument("--oracle-seconds", type=float, default=None,
                   help="the oracles' time limit per decision in seconds (default: 20); a search cut by it is "
                   "recorded per trial")
    add_tool_rule_argument(p, "recorded in the trial files")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from slax_drake.config import load_scenario
    from slax_drake.evaluation.table1 import run_benchmark
    from slax_drake.policies.registry import POLICY_NAMES, parse_tool_rules

    scenario = load_scenario(args.config)
    # the shelf simulator's Table I runs the scenario's profile; --physics (Drake trials) the station's
    profile = args.profile or ("station" if args.physics else scenario.profile)
    tool_rules = parse_tool_rules(args.tool_rule, profile)
    if args.oracle_seconds is not None and not args.oracle_seconds > 0:
        raise UserError("--oracle-seconds must be positive")
    policies = [p.strip() for p in args.policies.split(",") if p.strip()]
    for p in policies:
        if p not in POLICY_NAMES:
            raise UserError(f"unknown policy '{p}' (known: {', '.join(POLICY_NAMES)})")
    if not policies:
        raise UserError("--policies is empty")
    n = args.scenes_per_density if args.scenes_per_density is not None else scenario.protocol.scenes_per_density
    if n < 1:
        raise UserError("--scenes-per-density must be at least 1")
    if args.workers < 1:
        raise UserError("--workers must be at least 1")
    seed = args.seed if args.seed is not None else scenario.protocol.seed
    if args.physics:
        return _run_physics(args, policies, n, seed, tool_rules, profile)
    table = run_benchmark(scenario, policies, n, seed, args.out, workers=args.workers, backend=args.backend,
                          perception=args.perception, progress=not args.no_progress, tool_rules=tool_rules,
                          profile=profile, oracle_seconds=args.oracle_seconds)
    for p in policies:
        e = table["policies"][p]["all"]
        print(f"{p:>18}: success {100 * e['success_rate']:.0f} % over {e['trials']} trials, median steps "
              f"{e['median_steps']}, {e['mean_trial_seconds']} s per trial"
              + (f"; oracle searches {e['oracle_status']}" if e.get("oracle_status") else ""))
    print(f"profile: {profile}" + (f", rule overrides {tool_rules}" if tool_rules else ""))
    print(f"wrote {args.out}/table1.md, table1.json, table1.png")
    return 0


def _run_physics(args: argparse.Namespace, policies: list[str], n: int, seed: int, tool_rules: dict,
                 profile: str) -> int:
    """``--physics``: the same protocol through full Drake trials. The runner lives in ``slax_drake.systems``
    (the only stage that builds diagrams); this command only dispatches to it."""
    from slax_drake.evaluation.physics import run_physics_benchmark

    drake_policies = [p for p in policies if not p.startswith("oracle")]
    if not drake_policies:
        raise UserError("--physics runs non-oracle policies only: name at least one in --policies")
    summary = run_physics_benchmark(args.config, drake_policies, n, seed=seed, out=args.out, workers=args.workers,
                                    sleep=args.sleep, progress=not args.no_progress, tool_rules=tool_rules,
                                    profile=profile)
    for p in drake_policies:
        e = summary["policies"][p]["all"]
        print(f"{p:>18}: success shelf {100 * e['shelf_success_rate']:.0f} %, Drake "
              f"{100 * e['drake_success_rate']:.0f} %, actions matching prediction {e['match_rate']}, "
              f"toppled {e['toppled']}, dropped {e['dropped']}")
    print(f"wrote {args.out}/physics.md, physics.json")
    return 0
