"""``slax-drake benchmark``: the paper's Table I protocol in the fast first-order shelf simulator, or with
``--physics`` through full Drake trials beside it; both on local processes or Ray tasks."""

from __future__ import annotations

import argparse

from slax_drake.errors import UserError
from slax_drake.io import plural


def register(subparsers) -> None:
    from slax_drake import arguments
    from slax_drake.backends import add_backend_arguments
    from slax_drake.policies.registry import DEFAULT_BENCHMARK_POLICIES, POLICY_NAMES
    from slax_drake.shelf.tool import add_tool_rule_argument

    p = subparsers.add_parser(
        "benchmark",
        help="run search policies on the Table I protocol (fast shelf simulator; --physics: full Drake trials)",
        description="Run search policies on the same seeded scenes of every density of the protocol "
        "(H = horizon_per_object * n actions) and write table1.md, table1.json and table1.png from every policy in "
        "OUT. Finished trials are kept under OUT/trials and the settings in OUT/settings.json, so a stopped run "
        "resumes; a run with other settings into the same OUT is refused. With --physics: the same scenes through "
        "full Drake trials beside the shelf simulator (OUT/physics_trials, physics.md, physics.json; slow).",
    )
    p.add_argument("--config", default="sim_configs/table1.yaml", help="scenario YAML (default: sim_configs/table1.yaml)")
    p.add_argument("--policies", default=None,
                   help=f"comma-separated policy names from: {', '.join(POLICY_NAMES)} (default: the paper's five and "
                   f"the project's own, {','.join(DEFAULT_BENCHMARK_POLICIES)}; with --physics their non-oracle ones)")
    p.add_argument("--scenes-per-density", type=int, default=None, help="default: the protocol's")
    p.add_argument("--densities", default=None, help="comma-separated object counts (default: the protocol's)")
    p.add_argument("--seed", type=arguments.seed, default=None, help="protocol seed (default: the protocol's)")
    add_backend_arguments(p, "trials")
    p.add_argument("--perception", choices=("ground-truth", "learned"), default="ground-truth",
                   help="distribution model: ground-truth (compute_occupancy) or learned (the shipped network, "
                   "models/perception/unet128); the shelf simulator only")
    p.add_argument("--observation", choices=("privileged", "camera"), default=None,
                   help="what the non-oracle policies see: camera (default: rendered frames -> segmentation -> "
                   "estimator hypotheses, P_t from the frame, predictions by shifting segments in the image) or "
                   "privileged (the objects seen with their true shapes and poses, P_t of the true scene; the "
                   "behaviour before camera mode); the oracles read the true scene in both. With --physics it sets the shelf "
                   "simulator beside the Drake trials (default there: privileged); the Drake trials always see their "
                   "camera")
    p.add_argument("--segmentation", choices=("labels", "depth"), default=None,
                   help="with --observation camera: the render's object labels (default, idealised) or depth-only "
                   "segmentation")
    p.add_argument("--sensor-noise", action="store_true",
                   help="with --observation camera (or --physics): the L515 depth-noise model on every frame (seeded by the "
                   "scene)")
    p.add_argument("--full-resolution", action="store_true",
                   help="with --observation camera: ray-cast each frame at the camera's own resolution and resample "
                   "it to the policy's as the Drake station does (the physics benchmark's shelf simulator always "
                   "does); default: ray-cast at the policy's resolution")
    p.add_argument("--out", default="results/table1", help="output folder (default: results/table1)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--physics", action="store_true",
                   help="run the protocol through full Drake trials beside the shelf simulator on the same scenes "
                   "(non-oracle policies only; writes OUT/physics.md and OUT/physics.json; slow)")
    p.add_argument("--station", default=None,
                   help="with --physics: station YAML (default: station_<config stem>.yaml, else the sim-shelf station)")
    p.add_argument("--sleep", action="store_true", help="with --physics: object sleep in the Drake trials")
    p.add_argument("--oracle-seconds", type=arguments.positive_float, default=None,
                   help="the oracles' CPU-time limit per decision in seconds (default: 20); a search cut by it is "
                   "recorded per trial")
    add_tool_rule_argument(p, "recorded in the trial files (with --physics: for both simulators, over the station "
                           "cup's limits; max_suction_moment=inf and max_seal_angle_deg=90 lift them)")
    p.set_defaults(func=run)


def _densities(text: str | None) -> list[int] | None:
    if text is None:
        return None
    try:
        densities = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise UserError(f"--densities must be comma-separated integers (got '{text}')") from None
    if not densities or any(n < 1 for n in densities):
        raise UserError(f"--densities must be object counts of at least 1 (got '{text}')")
    return densities


def run(args: argparse.Namespace) -> int:
    from slax_drake.backends import check_backend
    from slax_drake.config import load_scenario
    from slax_drake.policies.registry import DEFAULT_BENCHMARK_POLICIES, POLICY_TABLE
    from slax_drake.shelf.tool import parse_tool_rules

    scenario = load_scenario(args.config)
    # the shelf simulator's Table I runs the scenario's profile; --physics (Drake trials) the station's
    profile = args.profile or ("station" if args.physics else scenario.profile)
    tool_rules = parse_tool_rules(args.tool_rule, profile)
    if args.policies is None:
        policies = list(DEFAULT_BENCHMARK_POLICIES)
        if args.physics:
            policies = [p for p in policies if not POLICY_TABLE[p].load().needs_true_scene]
    else:
        policies = [p.strip() for p in args.policies.split(",") if p.strip()]
    for p in policies:
        if p not in POLICY_TABLE:
            raise UserError(f"unknown policy '{p}' (known: {', '.join(POLICY_TABLE)})")
    if not policies:
        raise UserError("--policies is empty")
    n = args.scenes_per_density if args.scenes_per_density is not None else scenario.protocol.scenes_per_density
    if n < 1:
        raise UserError("--scenes-per-density must be at least 1")
    check_backend(args.backend, args.workers, args.ray_address)
    densities = _densities(args.densities)
    seed = args.seed if args.seed is not None else scenario.protocol.seed
    if args.physics:
        return _run_physics(args, policies, n, seed, densities, tool_rules, profile)
    for flag, given in (("--station", args.station is not None), ("--sleep", args.sleep)):
        if given:
            raise UserError(f"{flag} applies to --physics only")
    from slax_drake.evaluation.table1 import CameraMode, run_benchmark

    camera = None
    if args.observation in (None, "camera"):
        camera = CameraMode(segmentation=args.segmentation or "labels", sensor_noise=args.sensor_noise,
                            full_resolution=args.full_resolution)
    elif args.segmentation is not None or args.sensor_noise or args.full_resolution:
        raise UserError("--segmentation, --sensor-noise and --full-resolution apply to --observation camera only")

    table = run_benchmark(scenario, policies, n, seed, args.out, workers=args.workers, backend=args.backend,
                          perception=args.perception, densities=densities, progress=not args.no_progress,
                          tool_rules=tool_rules, config=args.config, ray_address=args.ray_address, camera=camera,
                          profile=profile, oracle_seconds=args.oracle_seconds)
    meta = table["meta"]
    print(f"kept {plural(meta['trials_kept'], 'trial')} already in {args.out}, ran {meta['trials_run']}")
    for p, per in table["policies"].items():
        e = per["all"]
        rate = "-" if e["success_rate"] is None else f"{100 * e['success_rate']:.0f} %"
        note = "" if p in policies else " (from an earlier run in this folder)"
        searches = f"; oracle searches {e['oracle_status']}" if e.get("oracle_status") else ""
        print(f"{p:>18}: success {rate} over {plural(e['trials'], 'trial')}, median steps {e['median_steps']}{searches}{note}")
    print(f"profile: {profile}" + (f", rule overrides {tool_rules}" if tool_rules else ""))
    print(f"wrote {args.out}/table1.md, table1.json, table1.png")
    return 0


def _run_physics(args: argparse.Namespace, policies: list[str], n: int, seed: int, densities, tool_rules: dict,
                 profile: str) -> int:
    """``--physics``: the same protocol through full Drake trials (slax_drake.evaluation.physics)."""
    from slax_drake.evaluation.physics import run_physics_benchmark

    if args.perception != "ground-truth":
        raise UserError("--physics runs ground-truth distributions only: leave out --perception")
    if args.oracle_seconds is not None:
        raise UserError("--oracle-seconds applies to the shelf simulator's oracles only")
    if args.full_resolution:
        raise UserError("--full-resolution applies to the shelf simulator's Table I only (the physics benchmark's "
                        "shelf simulator always renders at the camera's resolution, as its Drake trials do)")
    if args.segmentation is not None:
        raise UserError("--segmentation applies to the shelf simulator only (the physics benchmark's Drake trials "
                        "segment by the render's labels; --sensor-noise adds the L515 model to their camera)")
    shelf_camera = None
    if args.observation == "camera":  # the shelf simulator beside sees the frames the Drake trials see
        from slax_drake.evaluation.table1 import CameraMode

        shelf_camera = CameraMode(segmentation="labels", sensor_noise=bool(args.sensor_noise), full_resolution=True)
    summary = run_physics_benchmark(args.config, policies, n, seed=seed, out=args.out, workers=args.workers,
                                    densities=densities, station=args.station, sleep=args.sleep,
                                    progress=not args.no_progress, tool_rules=tool_rules, backend=args.backend,
                                    ray_address=args.ray_address, profile=profile,
                                    sensor_noise=args.sensor_noise, shelf_camera=shelf_camera)
    meta = summary["meta"]
    print(f"kept {plural(meta['scenes_kept'], 'scene')} already in {args.out}, ran {meta['scenes_run']}")
    for p, per in summary["policies"].items():
        e = per["all"]
        match = "-" if e["match_rate"] is None else f"{100 * e['match_rate']:.0f} %"
        print(f"{p:>18}: success shelf {100 * e['shelf_success_rate']:.0f} %, Drake "
              f"{100 * e['drake_success_rate']:.0f} % over {plural(e['trials'], 'scene')}; actions matching prediction "
              f"{match}; toppled {e['toppled']}, dropped {e['dropped']}")
    print(f"wrote {args.out}/physics.md, physics.json, physics.png")
    return 0
