"""``slax-drake trial``: one full SLAX-RAY trial in Drake (headless by default)."""

from __future__ import annotations

import argparse
import sys

from slax_drake.errors import TrialError
from slax_drake.systems.trial import DEFAULT_OBJECTS, DEFAULT_SEED, TrialOptions


def register(subparsers) -> None:
    from slax_drake import arguments
    from slax_drake.policies.registry import POLICY_NAMES
    from slax_drake.shelf.tool import add_tool_rule_argument

    p = subparsers.add_parser(
        "trial",
        help="run one full trial in Drake: station, policy, motion planner (writes trial.json, PNGs, HTML replay)",
        description="Sample a scene, run the policy through the Drake station with the motion planner until the "
        "target is revealed (v of it visible in the label image) or H = 2n actions are spent. With no arguments: "
        f"a short default trial ({DEFAULT_OBJECTS} objects, seed {DEFAULT_SEED}) that reveals the target.",
    )
    p.add_argument("--config", default=None, help=f"scene scenario YAML (default: {TrialOptions.config})")
    p.add_argument("--station", default=None, help="station YAML (default: sim_configs/station_<config stem>.yaml)")
    p.add_argument("--objects", type=int, default=None, help=f"occluding objects (default {DEFAULT_OBJECTS})")
    p.add_argument("--seed", type=arguments.seed, default=None, help=f"scene seed (default {DEFAULT_SEED})")
    p.add_argument("--benchmark-scene", default=None, metavar="N:INDEX",
                   help="the scene INDEX of N objects of the Table I protocol in --config (e.g. --config "
                   "sim_configs/table1.yaml --benchmark-scene 8:1): the scene seed, target size, horizon and station "
                   "that 'slax-drake benchmark' and the physics benchmark use; replaces --objects and --seed")
    p.add_argument("--from-benchmark", default=None, metavar="FOLDER",
                   help="with --benchmark-scene: that scene's trial as the physics benchmark in FOLDER ran it (its "
                   "--out, or a docs/results copy): the run's scenario, rule profile and rules, policy (--policy when "
                   "it ran several), sensor noise and object sleep; --tool-rule adds rules on top. The summary says "
                   "whether the trial did what the run recorded")
    p.add_argument("--policy", default=None, metavar="NAME",
                   help=f"the search policy, one of: {', '.join(POLICY_NAMES)}. The oracles (oracle-p, oracle-p+s) "
                   "read the true scene and cannot run behind the camera; slax-belief is the project's own "
                   "(default: bluction-dar; with --from-benchmark the run's)")
    p.add_argument("--perception", default="ground-truth", choices=("ground-truth", "learned"),
                   help="how the policy turns its belief of the scene (the objects segmented in the camera frame) "
                   "into the target's occupancy distribution along the image's x: ground-truth computes every "
                   "hidden placement of the target behind the believed objects geometrically; learned renders the "
                   "believed scene's depth image and runs the shipped network (models/perception/unet128) on it "
                   "(default: ground-truth)")
    p.add_argument("--meshcat", action="store_true", help="serve a live view on localhost and print its URL (it lasts while the command runs)")
    p.add_argument("--html", default=None, help="write a self-contained Meshcat replay (e.g. out/trial.html)")
    p.add_argument("--out", default="out/trial", help="output folder for trial.json and step PNGs")
    add_tool_rule_argument(p, "for the policy and the planner, over the station cup's limits "
                           "(max_suction_moment=inf and max_seal_angle_deg=90 give the paper's weightless rules)")
    p.add_argument("--max-sim-time", type=arguments.positive_float, default=None, help="simulated seconds at most")
    p.add_argument("--sensor-noise", action="store_true",
                   help="the L515 depth-noise model between the camera and perception (seeded by the scene seed)")
    p.add_argument("--segmentation", choices=("labels", "depth"), default="labels",
                   help="occluder segmentation: the render's object labels (default, idealised) or depth-only")
    p.add_argument("--sleep", action="store_true",
                   help="lock resting objects out of the physics step until something comes near (faster; "
                   "see slax_drake/systems/sleep.py)")
    p.add_argument("--quiet", action="store_true",
                   help="no line per decision on stderr (by default each decision prints its action, planning time "
                   "and outcome as it happens)")
    p.set_defaults(func=run)
    register_view(subparsers)


def register_view(subparsers) -> None:
    v = subparsers.add_parser(
        "view-trial",
        help="write the Meshcat HTML replay of a finished trial from its records (no simulation)",
        description="Draw a finished trial (the folder `slax-drake trial` wrote) as a self-contained Meshcat HTML "
        "replay without simulating it again: the robot follows the trial's commanded joint trajectory, the objects "
        "their recorded poses (object_poses.npz, every 0.1 s; older trial folders without it: the poses at each "
        "decision and at the end).",
    )
    v.add_argument("trial", help="trial.json (or the trial's folder)")
    v.add_argument("--html", default=None, help="HTML file to write (default: trial.html beside trial.json)")
    v.add_argument("--station", default=None, help="station YAML (default: the one the trial names)")
    v.set_defaults(func=run_view)


def run_view(args: argparse.Namespace) -> int:
    from pathlib import Path

    from slax_drake.evaluation.trial_replay import trial_replay
    from slax_drake.io import write_text_atomic

    path = Path(args.trial)
    folder = path if path.is_dir() else path.parent
    html = Path(args.html) if args.html else folder / "trial.html"
    replay = trial_replay(path, station=args.station)
    html.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(html, replay.html)
    print(f"wrote {html}: {replay.duration_s:.1f} s of the trial, objects from its {replay.objects_from}; open it "
          f"in a web browser ({html.resolve().as_uri()})")
    return 0


def run(args: argparse.Namespace) -> int:
    from slax_drake.shelf.tool import parse_tool_rules
    from slax_drake.systems.trial_summary import trial_summary

    if args.from_benchmark is not None:
        return run_from_benchmark(args)
    profile = args.profile or "station"  # Drake trials plan with the physical tool's rules unless told otherwise

    opts = TrialOptions(config=args.config or TrialOptions.config,
                        objects=DEFAULT_OBJECTS if args.objects is None else args.objects,
                        seed=DEFAULT_SEED if args.seed is None else args.seed,
                        policy=args.policy or TrialOptions.policy,
                        perception=args.perception, station=args.station, meshcat=args.meshcat, html=args.html,
                        out=args.out, max_sim_time=args.max_sim_time, sleep=args.sleep,
                        sensor_noise=args.sensor_noise, segmentation=args.segmentation,
                        tool_rules=parse_tool_rules(args.tool_rule, profile), profile=profile)
    if args.benchmark_scene is not None:
        if args.objects is not None or args.seed is not None:
            raise TrialError("--benchmark-scene replaces --objects and --seed: give one or the other")
        from slax_drake.evaluation.benchmark_trial import benchmark_scene_options

        opts = benchmark_scene_options(opts, args.benchmark_scene)
    record, written, meshcat_url = _run(opts, args)
    print(trial_summary(record.data, written, html=args.html, meshcat_url=meshcat_url))
    return 0


# options --from-benchmark takes from the run's settings: given together, they are refused
_SET_BY_THE_RUN = (("config", "--config"), ("profile", "--profile"), ("sensor_noise", "--sensor-noise"),
                   ("sleep", "--sleep"), ("objects", "--objects"), ("seed", "--seed"))


def run_from_benchmark(args: argparse.Namespace) -> int:
    """``--from-benchmark FOLDER --benchmark-scene N:INDEX``: the run's trial of that scene (slax_drake.evaluation.
    benchmark_trial), then the summary and one line on whether it did what the run recorded."""
    from slax_drake.evaluation.benchmark_trial import agreement, benchmark_record, benchmark_trial_options
    from slax_drake.systems.trial_summary import trial_summary

    if args.benchmark_scene is None:
        raise TrialError("--from-benchmark needs --benchmark-scene N:INDEX (the scene of that run to run again)")
    given = [flag for field, flag in _SET_BY_THE_RUN if getattr(args, field) not in (None, False)]
    if given:
        raise TrialError(f"--from-benchmark sets {', '.join(given)} from the run's settings: give one or the other")
    if (args.perception, args.segmentation) != ("ground-truth", "labels"):
        raise TrialError("--from-benchmark: the physics benchmark's Drake trials perceive with --perception "
                         "ground-truth and --segmentation labels")
    opts, notes = benchmark_trial_options(args.from_benchmark, args.benchmark_scene, policy=args.policy,
                                          station=args.station, extra_rules=args.tool_rule, meshcat=args.meshcat,
                                          html=args.html, out=args.out, max_sim_time=args.max_sim_time)
    density, index = (int(v) for v in args.benchmark_scene.split(":"))
    print(f"the trial of scene {density}:{index} of the physics benchmark in {args.from_benchmark} "
          f"({opts.policy}, the '{opts.profile}' profile with its recorded rules)", flush=True)
    for note in notes:
        print(f"note: {note}: the trial may differ from the run's", file=sys.stderr, flush=True)
    source = {"folder": str(args.from_benchmark), "scene": f"{density}:{index}", "notes": notes}
    record, written, meshcat_url = _run(opts, args, {"from_benchmark": source})
    print(trial_summary(record.data, written, html=args.html, meshcat_url=meshcat_url))
    print("benchmark: " + agreement(record.data, benchmark_record(args.from_benchmark, opts.policy, density, index),
                                    args.from_benchmark))
    return 0


def _run(opts: TrialOptions, args: argparse.Namespace, extra: dict | None = None):
    """Runs the trial of ``opts`` (a live Meshcat view with --meshcat) and writes its folder, ``extra`` entries
    added to its record; returns (the record, the files written, the live view's URL or None)."""
    from slax_drake.evaluation.trial import drake_info_silenced, run_trial, write_trial

    with drake_info_silenced():
        meshcat = None
        if args.meshcat or args.html:
            from pydrake.geometry import Meshcat

            meshcat = Meshcat()
            if args.meshcat:
                print(f"meshcat: {meshcat.web_url()} (a live view while this command runs)", flush=True)
        record = run_trial(opts, meshcat=meshcat, progress=None if args.quiet else sys.stderr, record_poses=True)
    record.data.update(extra or {})
    written = write_trial(record, args.out, html=args.html)
    return record, written, meshcat.web_url() if args.meshcat else None
