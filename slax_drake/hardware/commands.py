"""``slax-drake export``, ``slax-drake check-trajectory``, ``slax-drake replay`` and ``slax-drake plan-step``: a
trial's motions for a real Fetch, and one search step planned from a real camera frame."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from slax_drake import arguments
from slax_drake.io import plural
from slax_drake.hardware.trajectory_file import FORMATS

BYTES_PER_CONFIGURATION = 400  # one interpolated configuration to check: times, positions, index arrays


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "export", help="export a trial's executed motions as ROS JointTrajectory messages (JSON, YAML goals, CSV) "
        "or the whole trial as a ROS 2 bag (MCAP)",
        description="Cut trial.json's executed trajectory into one JointTrajectory-shaped message per motion (joint "
        "names as on the real Fetch plus tool_shaft_joint) with timed suction events. Without --rate the points "
        "are the trial's own records; with --rate they are resampled (quintic positions, linear accelerations). "
        "--format mcap writes a ROS 2 bag folder (MCAP storage) with /joint_states, /planned_trajectory, "
        "/suction_command, /tf, /tf_static and the depth camera per decision, stamped in simulation time.")
    p.add_argument("trial", help="trial.json written by 'slax-drake trial' (or the trial's folder)")
    p.add_argument("--format", choices=tuple(FORMATS) + ("mcap",), default=None,
                   help="ros-json, ros-yaml (FollowJointTrajectory goals), csv (default: from --out's extension), "
                   "or mcap (a ROS 2 bag folder)")
    p.add_argument("--rate", type=arguments.positive_float, default=None, help="resample at this rate in Hz (default: the trial's records)")
    p.add_argument("--out", required=True, help="output file (.json, .yaml or .csv; the extension must match "
                   "--format), or the bag folder for mcap")
    p.add_argument("--scene", default=None, help="scene JSON to embed (default: sampled again from the trial's config and seed)")
    p.add_argument("--write-scene", default=None, help="also write the trial's initial scene as a scene JSON here")
    p.set_defaults(func=run_export)

    c = subparsers.add_parser(
        "check-trajectory", help="check an exported trajectory against the real Fetch's limits and for collisions",
        description="Independent of the planner, trusting nothing in the file: positions (with --margin), velocity, "
        "acceleration and jerk from the positions on the file's time grid, the velocity and acceleration fields "
        "against the positions, continuity within and between motions, collisions of the robot with itself, the "
        "shelf and the scene's objects (the scene given is the world; an object may be touched only by the tool, as "
        "the action's recorded estimate and the checker's own push and suction model allow). Exit code 0 when all "
        "pass, 1 with a report otherwise, 2 for an unusable file.")
    c.add_argument("trajectory", help="exported trajectory (.json, .yaml or .csv) or the ROS 2 bag folder (or its "
                   ".mcap) of 'export --format mcap'")
    c.add_argument("--scene", default=None, help="scene JSON (default: the scene embedded by export, if any)")
    c.add_argument("--station", default=None, help="station YAML (default: the trial's, or the scene's shelf's)")
    c.add_argument("--margin", type=arguments.non_negative_float, default=0.0, help="position margin inside the limits (rad, m for the torso)")
    c.add_argument("--no-collision", action="store_true", help="skip the collision checks")
    c.add_argument("--collision-step", type=arguments.non_negative_float, default=0.005,
                   help="seconds between checked configurations (0: the records only)")
    c.add_argument("--json", default=None, help="also write the report as JSON here")
    c.set_defaults(func=run_check)

    r = subparsers.add_parser(
        "replay", help="play an exported trajectory open loop in the Drake station",
        description="Feed the exported motions and suction events to the station (the trial's scene) and report the "
        "final object poses; compares with the trial's final poses when the file carries them. To watch a trial "
        "(its trial.json) without simulating it again: slax-drake view-trial.")
    r.add_argument("trajectory", help="exported trajectory (.json, .yaml or .csv)")
    r.add_argument("--scene", default=None, help="scene JSON (default: the scene embedded by export)")
    r.add_argument("--station", default=None, help="station YAML (default: the trial's, or the scene's shelf's)")
    r.add_argument("--html", default=None, help="write a self-contained Meshcat replay here")
    r.add_argument("--meshcat", action="store_true", help="serve the live view on localhost and print its URL")
    r.add_argument("--json", default=None, help="write the replayed final object poses as JSON here")
    r.set_defaults(func=run_replay)

    s = subparsers.add_parser(
        "plan-step", help="plan one search step for a real robot from a depth frame, a target mask and the joint state",
        description="From one camera frame only (no object poses): validate the frame, segment it, estimate the "
        "objects, compute the target distribution, let the policy choose an action, plan, Ruckig-time and check its "
        "joint trajectory, and write it in the export format (check it again with 'slax-drake check-trajectory "
        "OUT'), with the chosen action and the updated history under metadata.plan_step. When the target already "
        "counts as revealed (the mask's pixels against those the target's known size covers where the mask is "
        "seen, at least the scenario's visibility threshold v) it says so and plans nothing. An unusable frame or a "
        "joint state outside the robot's limits is refused (exit code 2). --from-trial DIR --step N builds the four "
        "inputs from a simulated trial's decision N as a worked example.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="where each input comes from on a robot:\n"
        "  --scenario     the station YAML of this robot, shelf and camera (its scene_config holds the camera's\n"
        "                 intrinsics and its pose relative to the shelf; observation_configuration the arm pose\n"
        "                 from which the camera sees the shelf that way)\n"
        "  --depth        one depth image of the tool camera at the observation pose, e.g. the RealSense topic\n"
        "                 /camera/depth/image_rect_raw (16UC1, millimetres) saved as a 16-bit PNG, or metres as\n"
        "                 .npy; any resolution with the camera's aspect ratio\n"
        "  --target-mask  the target's pixels in that depth image, e.g. a colour threshold of the RGB image\n"
        "                 aligned to depth (/camera/color/image_raw registered to the depth frame), non-zero\n"
        "                 where the target's colour is seen\n"
        "  --joint-state  the arm's positions when the frame was taken, from /joint_states (sensor_msgs/\n"
        "                 JointState: name and position fields), as {\"joint_names\": [...], \"positions\": [...]}\n"
        "  --history      the previous step's OUT, so that the policy remembers its search (earlier steps are replayed)")
    s.add_argument("--scenario", default=None,
                   help="station YAML (e.g. sim_configs/station_sim_shelf.yaml; with --from-trial: the trial's)")
    s.add_argument("--depth", default=None, help="depth frame: .npy (float metres) or .png (16-bit millimetres)")
    s.add_argument("--target-mask", default=None, help="target mask: .png or .npy, non-zero where the target is seen")
    s.add_argument("--joint-state", default=None,
                   help='joint state JSON: {"joint_names": [...], "positions": [...]} (rad, m for torso and shaft)')
    s.add_argument("--from-trial", default=None, metavar="DIR",
                   help="instead of --depth, --target-mask and --joint-state: build them from decision --step of "
                   "the trial in DIR (written beside OUT in OUT_STEM_inputs/)")
    s.add_argument("--step", type=arguments.positive_int, default=None,
                   help="with --from-trial: the decision, 1 to the trial's count (as its 'step N/H' lines count)")
    s.add_argument("--history", default=None,
                   help="the previous step's OUT (its frames are replayed: the policy remembers its search)")
    s.add_argument("--policy", default=None, help="a non-oracle policy name (default bluction-dar; with --from-trial "
                   "the trial's)")
    s.add_argument("--tool-rule", action="append", default=[], metavar="FIELD=VALUE",
                   help="override an action-model rule of the station's, as for 'trial' (repeatable; with "
                   "--from-trial the default is the rules the trial planned with; a --history must have been planned "
                   "with the same rules)")
    s.add_argument("--out", required=True, help="output step JSON (the export format, ros-json)")
    s.set_defaults(func=run_plan_step)

    a = subparsers.add_parser(
        "check-action", help="is an action kinematically feasible on a scene? (the action model, then the planner)",
        description="Ask the station's action model (the 'station' profile with the station cup's limits) whether "
        "the action exists on the scene, then plan its motion (IK, collision checks, Ruckig timing) from the "
        "observation pose and back. Prints feasible with the motion's duration and the IK / check / Ruckig times, "
        "or the first reason it is not. Exit code 0 when feasible, 1 when not. --all: every candidate action of "
        "the scene with its verdict (a table; --png: a top-down picture coloured by verdict).")
    where = a.add_mutually_exclusive_group(required=True)
    where.add_argument("--scene", default=None, help="scene JSON (slax-drake scene, or a trial's scene.json: its "
                       "initial scene)")
    where.add_argument("--from-trial", default=None, metavar="DIR",
                       help="the scene of a trial's folder (slax-drake trial --out) as it stood at a decision "
                       "(--step; default the last, where a trial that ended with no action stopped), each object "
                       "where the trial recorded it; the trial's station and rules")
    a.add_argument("--step", type=int, default=None, help="with --from-trial: the decision, 1-based as the trial's "
                   "lines 'step N/H' count (default: the last)")
    a.add_argument("--station", default=None, help="station YAML (default: the shipped station of the scene's "
                   "shelf; with --from-trial the trial's)")
    what = a.add_mutually_exclusive_group(required=True)
    what.add_argument("--action", default=None,
                      help="push:OBJECT:D (blade push by D m along the shelf's x) or suction:OBJECT:DX:DZ (move by "
                      "DX along x, place at depth y = DZ), e.g. push:object_5:-0.10, feasible on the scene that "
                      "`slax-drake scene` writes by default")
    what.add_argument("--all", action="store_true", help="every candidate action of the scene")
    a.add_argument("--png", default=None, help="with --all: write the top-down verdict picture here")
    a.add_argument("--json", default=None, help="also write the verdict(s) as JSON here")
    a.set_defaults(func=run_check_action)


def _scene_and_station(traj, scene_path, station_path):
    from slax_drake.errors import TrajectoryFileError
    from slax_drake.scene.io import load_scene, scene_from_dict
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.station.scenario import station_for

    if scene_path:
        scene = load_scene(scene_path)
    elif traj.metadata.get("scene"):
        try:
            scene = scene_from_dict(traj.metadata["scene"])
        except Exception as e:  # noqa: BLE001 - any malformed embedded scene
            raise TrajectoryFileError(f"the trajectory's embedded scene is malformed ({e}); pass --scene") from None
    else:
        scene = None
    station = station_path or traj.metadata.get("station")
    if station is None:
        station = station_for(traj.metadata.get("config") or "sim_configs/sim_shelf.yaml")
    return scene, load_station_scenario(station)


def run_export(args: argparse.Namespace) -> int:
    from slax_drake.hardware.export import export_trial, read_trial, trial_scene
    from slax_drake.hardware.trajectory_file import format_of, save_trajectory
    from slax_drake.scene.io import load_scene, save_scene

    from slax_drake.errors import TrialFileError

    if not args.out.strip():
        raise TrialFileError("--out is empty: give the output file (.json, .yaml or .csv), or the bag folder for "
                             "--format mcap")
    if args.format != "mcap":
        fmt = format_of(args.out)  # refuses an unknown extension before any work
        if args.format is not None and args.format != fmt:
            raise TrialFileError(f"--out {args.out} has the extension of {fmt} but --format is {args.format}: the "
                                 f"extension must match the format (use {Path(args.out).with_suffix(FORMATS[args.format])})")
    data = read_trial(args.trial)
    if args.format == "mcap":
        return _export_bag(args, data)
    scene = load_scene(args.scene) if args.scene else trial_scene(data)
    traj = export_trial(data, rate=args.rate, source=str(args.trial), scene=scene)
    save_trajectory(traj, args.out, fmt)
    if args.write_scene:
        save_scene(scene, args.write_scene)
    points = sum(len(m.times) for m in traj.motions)
    events = sum(len(m.suction_events) for m in traj.motions)
    print(f"wrote {args.out} ({fmt}): {plural(len(traj.motions), 'motion')}, {plural(points, 'point')}, "
          f"{plural(events, 'suction event')}, "
          f"{'trial records' if args.rate is None else f'{args.rate:g} Hz'}")
    return 0


def _export_bag(args: argparse.Namespace, data: dict) -> int:
    from slax_drake.errors import TrialFileError
    from slax_drake.hardware.export import trial_scene
    from slax_drake.hardware.rosbag_export import STEP_DEPTH_FILE, read_step_depth, robot_description, write_trial_bag
    from slax_drake.scene.io import load_scene, save_scene

    out = Path(args.out)
    if out.exists() or out.is_symlink():  # before any slow work
        raise TrialFileError(f"{out} exists: a bag is never overwritten (remove it or choose another --out)")
    scene = load_scene(args.scene) if args.scene else trial_scene(data)
    depth = read_step_depth(Path(args.trial).parent / STEP_DEPTH_FILE)
    X_WS, X_WB, station = _station_frames(data, scene)
    summary = write_trial_bag(data, out, scene=scene, depth=depth, X_WS=X_WS, X_WB=X_WB, rate=args.rate,
                              source=str(args.trial), robot_description=robot_description(station))
    if args.write_scene:
        save_scene(scene, args.write_scene)
    counts = ", ".join(f"{topic} {n}" for topic, n in summary.counts.items())
    print(f"wrote {out}/ (ROS 2 bag, MCAP storage; {summary.start_s:g} to {summary.end_s:g} s simulation time): {counts}")
    if depth is None:
        print(f"  no depth images: {Path(args.trial).parent / STEP_DEPTH_FILE} is missing (trials record it since "
              "this version; run the trial again)")
    print(f"  view: open {out / (out.name + '.mcap')} in Foxglove, or 'ros2 bag play {out}'")
    return 0


def _station_frames(data: dict, scene):
    """X_WS (the shelf in the world) and X_WB (the robot's base weld) as 4x4, and the trial's station."""
    from slax_drake.station.plant import base_pose, shelf_pose
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.station.scenario import station_for

    station = load_station_scenario(data.get("station") or station_for(data.get("config") or "sim_configs/sim_shelf.yaml"))
    return shelf_pose(station, scene.camera).GetAsMatrix4(), base_pose(station).GetAsMatrix4(), station


def run_check(args: argparse.Namespace) -> int:
    from slax_drake.errors import TrajectoryFileError
    from slax_drake.hardware.check import check_margin, check_trajectory
    from slax_drake.hardware.collision import CollisionWorld
    from slax_drake.hardware.trajectory_file import load_trajectory
    from slax_drake.io import write_text_atomic

    check_margin(args.margin)
    traj = load_trajectory(args.trajectory)
    if not traj.motions:
        raise TrajectoryFileError(f"{args.trajectory}: the file has no motion: nothing to check (and nothing to "
                                  "send to a robot)")
    world = None
    if not args.no_collision and args.collision_step > 0:
        from slax_drake.resources import check_memory

        count = sum(m.duration for m in traj.motions) / args.collision_step
        check_memory(count * BYTES_PER_CONFIGURATION, f"--collision-step {args.collision_step:g} s ({count:.3g} "
                     "configurations)", "use a longer step")
    if not args.no_collision:
        scene, station = _scene_and_station(traj, args.scene, args.station)
        world = CollisionWorld(station, scene)
    report = check_trajectory(traj, world, margin=args.margin, collision_step=args.collision_step)
    print(report.summary())
    if args.json:
        write_text_atomic(Path(args.json), json.dumps(_finite({
            "ok": report.ok, "checked": report.checked, "margins": report.margins,
            "violations": [v.__dict__ for v in report.violations]}), indent=1, allow_nan=False))
    return 0 if report.ok else 1


def _is_trial_record(path: str) -> bool:
    """Whether ``path`` is a JSON trial record of ``slax-drake trial`` (it holds ``executed_trajectory``)."""
    if not str(path).endswith(".json"):
        return False
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return False
    return isinstance(doc, dict) and "executed_trajectory" in doc


def _finite(x):
    """``x`` with every non-finite float (an unlimited joint's margin, a missing pose's offset) as None (JSON)."""
    import math

    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    return x


def run_replay(args: argparse.Namespace) -> int:
    from slax_drake.hardware.replay import compare_final_objects, replay
    from slax_drake.errors import TrajectoryFileError
    from slax_drake.hardware.trajectory_file import load_trajectory
    from slax_drake.io import write_text_atomic

    if _is_trial_record(args.trajectory):
        raise TrajectoryFileError(f"{args.trajectory} is a trial record, not an exported trajectory: "
                                  f"'slax-drake view-trial {args.trajectory}' draws its replay without simulating, "
                                  "'slax-drake export' makes the file this command plays")
    traj = load_trajectory(args.trajectory)
    scene, station = _scene_and_station(traj, args.scene, args.station)
    if scene is None:
        raise TrajectoryFileError(f"{args.trajectory} embeds no scene: pass --scene (export --write-scene writes one)")
    meshcat = None
    if args.meshcat or args.html:
        from pydrake.geometry import Meshcat

        meshcat = Meshcat()
        if args.meshcat:
            print(f"meshcat: {meshcat.web_url()}", flush=True)
    result = replay(traj, station, scene, meshcat=meshcat, progress=None)
    print(f"replayed {plural(len(traj.motions), 'motion')}: {result.sim_time:.2f} s simulated in {result.wall_s:.1f} s")
    recorded = traj.metadata.get("final_objects")
    diffs = compare_final_objects(result.final_objects, recorded) if recorded else {}
    for name, p in result.final_objects.items():
        line = f"  {name}: x {p['x']:+.4f} y {p['y']:+.4f} z {p['z']:+.4f} m, yaw {p['yaw']:+.3f} rad"
        if name in diffs:
            line += f"; {diffs[name]['xyz_m'] * 1000:.2f} mm from the trial's final pose"
        print(line)
    if args.html and result.html:
        Path(args.html).parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(Path(args.html), result.html)
        print(f"wrote {args.html}")
    if args.json:
        write_text_atomic(Path(args.json), json.dumps({"final_objects": result.final_objects, "difference": diffs,
                                                       "sim_time_s": result.sim_time}, indent=1))
    return 0


POLICY = "bluction-dar"  # plan-step's policy unless --policy or the trial of --from-trial names another


def run_plan_step(args: argparse.Namespace) -> int:
    from slax_drake.errors import PlanStepError
    from slax_drake.hardware.plan_step import plan_step_files
    from slax_drake.shelf.tool import parse_tool_rules

    frame_inputs = (args.depth, args.target_mask, args.joint_state)
    scenario, policy = args.scenario, args.policy or POLICY
    tool_rules = parse_tool_rules(args.tool_rule, "station") if args.tool_rule else None
    if args.from_trial is not None:
        from slax_drake.hardware.plan_step import inputs_from_trial

        if any(v is not None for v in frame_inputs):
            raise PlanStepError("--from-trial builds --depth, --target-mask and --joint-state: give one or the other")
        if args.step is None:
            raise PlanStepError("--from-trial needs --step N (the trial's decision, from 1)")
        out = Path(args.out)
        inputs = inputs_from_trial(args.from_trial, args.step, out.parent / f"{out.stem}_inputs")
        scenario = scenario or inputs.station
        frame_inputs = (str(inputs.depth), str(inputs.target_mask), str(inputs.joint_state))
        if args.history is None and inputs.history is not None:
            args.history = str(inputs.history)  # the objects the trial tracked, so they keep the trial's names
        if tool_rules is None:
            tool_rules = inputs.tool_rules  # the rules the trial planned with
        policy = args.policy or inputs.policy or POLICY  # the trial's unless told
        print(f"inputs of decision {args.step} (t = {inputs.time_s:.2f} s) of {args.from_trial}: "
              f"{', '.join(frame_inputs)}; station {scenario}; policy {policy}")
    else:
        if args.step is not None:
            raise PlanStepError("--step applies to --from-trial only")
        missing = [flag for flag, v in zip(("--depth", "--target-mask", "--joint-state"), frame_inputs) if v is None]
        if args.scenario is None:
            missing.insert(0, "--scenario")
        if missing:
            raise PlanStepError(f"missing {', '.join(missing)} (or give --from-trial DIR --step N)")
    from slax_drake.evaluation.trial import drake_info_silenced

    with drake_info_silenced():
        result = plan_step_files(scenario, *frame_inputs, args.out, history=args.history, policy=policy,
                                 tool_rules=tool_rules)
    t = result.timings
    vis = result.visibility or {}
    if vis.get("share") is not None:
        print(f"target: {vis['seen']} of the {vis['expected']} pixels its size covers are seen ({vis['share']:.0%}; "
              f"revealed from {vis['threshold']:.0%})")
    elif vis:
        print("target: not seen in the frame")
    if result.action is None:
        print(f"no action: {result.reason}; wrote {args.out} (no motion)")
        return 0
    a = result.action
    params = f"d={a['d']:+.3f} m" if a["type"] == "push" else f"dx={a['dx']:+.3f} m, to y={a['dz']:+.3f} m"
    motion = result.trajectory.motions[0]
    print(f"{a['type']} {a['object']} ({params}): motion {motion.duration:.2f} s, {plural(len(motion.times), 'point')}, "
          "checked (limits, jerk, continuity, collisions with the believed scene)")
    guarded = result.trajectory.metadata["plan_step"].get("guarded_push_in")
    if guarded:
        drag = (f" (a drag: over twice its {guarded['expected_resistance_n']:.1f} N of floor friction until the cup "
                f"has pushed in {guarded['rebase_after_m'] * 100:.0f} cm, then over a new baseline)"
                if guarded["expected_resistance_n"] > 0 else "")
        edge = (f"; a stop within its first {guarded['edge_retry_within_m'] * 100:.1f} cm is the board's front edge: "
                f"rise {guarded['edge_retry_rise_m'] * 100:.0f} cm and push in again, once"
                if guarded.get("edge_retry_within_m") else "")
        print(f"GUARDED: the push-in from {guarded['t_start_s']:.2f} to {guarded['t_end_s']:.2f} s places into space "
              f"the camera cannot see: run it as a guarded move that stops when the push meets more than "
              f"{guarded['stop_force_n']:.1f} N{drag}, then releases and backs out{edge} "
              "(metadata.plan_step.guarded_push_in)")
    watch = result.trajectory.metadata["plan_step"].get("edge_watch")
    if watch:
        print(f"EDGE: watch the push-in from {watch['t_start_s']:.2f} s (stop force {watch['stop_force_n']:.1f} N): a "
              f"stop within its first {watch['within_m'] * 100:.1f} cm is the board's front edge: rise "
              f"{watch['rise_m'] * 100:.0f} cm and push in again, once (metadata.plan_step.edge_watch)")
    from slax_drake.systems.drag_weigh import is_pull_record

    weigh = result.trajectory.metadata["plan_step"].get("weigh")
    if is_pull_record(weigh):
        limit = (f"over {weigh['max_friction_n']:.1f} N" if weigh["max_friction_n"] is not None
                 else "(no lever believed: never)")
        print(f"WEIGH: from {weigh['t_start_s']:.2f} to {weigh['t_end_s']:.2f} s the cup pulls its object out sliding: "
              f"measure the force resisting the pull from the joint efforts (baseline at {weigh['t_base_s']:.2f} s, "
              f"the free arm at rest) and at {weigh['t_decide_s']:.2f} s play the motion back to its start (suction "
              f"off at the seal) when its median is {limit}: sliding it across would twist it off the cup "
              "(metadata.plan_step.weigh)")
    elif weigh:
        print(f"WEIGH: at {weigh['t_s']:.2f} s the cup holds its object 1 cm up: weigh it from the joint efforts and "
              f"play the motion back to its start (suction off at the seal) when it weighs under "
              f"{weigh['min_weight_n']:.1f} N, hangs over {weigh['limit_nm']:.2f} N m off the cup or its lever is under "
              f"{weigh['free_hang_share'] * weigh['least_lever_m'] * 100:.1f} cm (metadata.plan_step.weigh)")
    steps = len(result.trajectory.metadata["plan_step"]["history"]["frames"]) - 1
    if steps:
        print(f"the policy's memory: {plural(steps, 'earlier step')} replayed in {t['replay_s']:.2f} s")
    print(f"perception {t['perception_s']:.3f} s, decision {t['decision_s']:.3f} s, planning and check "
          f"{t['planning_s']:.2f} s; wrote {args.out}")
    return 0


def run_check_action(args: argparse.Namespace) -> int:
    from slax_drake.errors import ActionSpecError
    from slax_drake.evaluation.trial import drake_info_silenced
    from slax_drake.hardware.check_action import check_action, check_all, table, verdict_png
    from slax_drake.io import write_bytes_atomic, write_text_atomic

    if args.png and not args.all:
        raise ActionSpecError("--png applies to --all only")
    scene, station, rules = args.scene, args.station, None
    if args.from_trial is not None:
        from slax_drake.hardware.plan_step import recorded_rules, trial_decision

        decision = trial_decision(args.from_trial, args.step)
        scene, station = decision.scene, args.station or decision.data.get("station") or None
        rules = recorded_rules(decision.data.get("tool_rules"), str(station or ""))
        print(f"the scene of {args.from_trial} at decision {decision.step} of {len(decision.decisions)} (the true "
              f"objects where the trial recorded them; the trial's station and rules)", flush=True)
    elif args.step is not None:
        raise ActionSpecError("--step applies to --from-trial only")
    with drake_info_silenced():
        if args.all:
            checker, checks = check_all(scene, station, progress=None, tool_rules=rules)
        else:
            checks = [check_action(scene, args.action, station, tool_rules=rules)]
    if args.all:
        print(table(checks), end="")
        if args.png:
            write_bytes_atomic(Path(args.png), verdict_png(checker, checks))
            print(f"wrote {args.png}")
    else:
        print(checks[0].line())
    if args.json:
        write_text_atomic(Path(args.json), json.dumps([
            {"action": c.action, "feasible": c.feasible, "stage": c.stage, "reason": c.reason,
             "duration_s": c.duration_s, "timings": c.timings} for c in checks], indent=1))
    return 0 if all(c.feasible for c in checks) or args.all else 1
