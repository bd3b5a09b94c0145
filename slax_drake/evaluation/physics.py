"""The Table I protocol through full Drake trials, beside the fast first-order shelf simulator on the same scenes.

For every policy, density n and scene index, the scene seed is the shelf benchmark's
(``slax_drake.evaluation.table1.scene_seed(protocol_seed, n, index)``) and the target is the protocol's first
target size, so both simulators start from the very scene that ``slax-drake benchmark`` uses. Each scene runs

- in the shelf simulator (``slax_drake.shelf.simulator.run_trial``, H = horizon_per_object * n), and
- as a full Drake trial (``slax_drake.systems.trial.run_trial``: station, PlannerSystem, point-contact physics,
  suction) with the same policy, horizon and target.

Per action of the Drake trial, the action model's prediction (the action model applied to the poses observed before
the action) is compared with the physical outcome (the object's pose at the next decision): it *matches* when the
planar position is within ``MATCH_DISTANCE`` (2 cm) and the object's own turn is within ``MATCH_YAW`` (10 deg) of
the predicted one (none, but a box push's under the ``push_turn`` rule; a perceived hypothesis's yaw may name the
same box turned by 90 deg, so the turn is what is judged, :func:`action_matches`). Each mismatch is classified (:func:`mismatch_kind`:
dropped, toppled, seal never formed, slid, turned) and the report gives the match rate per action kind. Toppled
objects (z axis tilted more than 20 deg at the end) and dropped ones (centre outside the bay at the end) are
counted.

Each finished scene is written atomically as ``<out>/physics_trials/<policy>/<n>_<index>.json`` (so a stopped run
resumes; the settings are recorded in ``<out>/physics_settings.json`` and a run with other settings is refused);
when all are in, ``physics.json`` and ``physics.md`` are (re)written from those files. Scenes run as local
processes or Ray tasks (:mod:`slax_drake.backends`). The command line is ``slax-drake benchmark --physics``:

    slax-drake benchmark --physics --config sim_configs/table1.yaml --scenes-per-density 2 \\
        --policies bluction-dar --out results/physics_tiny
"""

from __future__ import annotations

import collections
import dataclasses
import json
import math
import time
from pathlib import Path

import numpy as np

from slax_drake.errors import PhysicsBenchmarkError
from slax_drake.io import figure_png, plural, write_bytes_atomic, write_text_atomic
from slax_drake.policies.protocol import Reversal
from slax_drake.policies.trial_memory import last_move_by_axis
from slax_drake.scene.mass import mass_model_words
from slax_drake.systems.drag_weigh import is_pull_record
from slax_drake.systems.guard import dragged_after_weighing
from slax_drake.systems.trial_summary import TARGET_MOVED

MATCH_DISTANCE = 0.02  # m, planar distance between predicted and physical final object position
MATCH_YAW = math.radians(10.0)  # rad



def drake_observation(sensor_noise: bool) -> str:
    """What the Drake trials' planner sees (slax_drake.systems.trial.build_trial, labels segmentation): recorded in
    the settings and said in the report, beside the shelf simulator's privileged observation."""
    return ("camera: rendered frames" + (" with the L515 depth-noise model" if sensor_noise else "")
            + ", the render's labels as segmentation, estimator hypotheses, P_t from the depth frame"
            + ("" if sensor_noise else ", no sensor noise"))


def trial_path(out: Path, policy: str, density: int, index: int) -> Path:
    return Path(out) / "physics_trials" / policy / f"{density:02d}_{index:04d}.json"


def is_stall(log: dict | None) -> bool:
    """Whether a policy's decision-log entry is a stall: its search found no plan revealing any place the target may
    stand (``revealed`` 0, not cut by the CPU cap), or it stopped there (``stalled``)."""
    return bool(log) and bool(log.get("stalled") or (not log.get("capped") and float(log.get("revealed", 1.0)) == 0.0))


def stall_step(decisions) -> int | None:
    """The index of the first decision in ``decisions`` (per step, the policy's decision-log entry it acted on or
    stopped at) that is a stall (:func:`is_stall`); None when there is none."""
    return next((k for k, log in enumerate(decisions) if is_stall(log)), None)


def stall_words(stalls: list) -> str:
    """A summary's ``stalls`` [stalled trials, of them revealed, actions from the stall on, all actions] in words."""
    return (f"{stalls[0]} trials, {stalls[1]} of them revealed the target after it; {stalls[2]} of the {stalls[3]} "
            f"executed actions came from a stall on.")


def action_matches(predicted: dict, outcome: dict | None, before: dict | None = None) -> bool | None:
    """Whether the physical outcome is within 2 cm and 10 deg of the action model's prediction (None: no outcome).

    With ``before`` (the true object's pose at the decision) the yaw test is the object's own turn, outcome less
    before: the first-order model never turns an object, and the prediction's yaw is the perceived hypothesis's,
    whose box axes may be the true object's turned by 90 or 180 deg (the same box). A push the quasi-static model
    predicted (``push_turn``) turns the object by the prediction's ``turn`` (rad): the test is the object's turn
    against it. Without ``before`` (records from before it was kept), the predicted yaw is compared directly."""
    if outcome is None:
        return None
    distance = math.hypot(outcome["x"] - predicted["x"], outcome["y"] - predicted["y"])
    reference = before["yaw"] + predicted.get("turn", 0.0) if before is not None else predicted["yaw"]
    dyaw = abs(math.remainder(outcome["yaw"] - reference, 2.0 * math.pi))
    return distance <= MATCH_DISTANCE and dyaw <= MATCH_YAW


def judge_action(action: dict, shelf_width: float, shelf_depth: float) -> tuple:
    """(matched, mismatch kind) of a physics record's action, judged again from its stored poses with the current
    rules (a file from before ``before`` was kept keeps its own verdict)."""
    if "before" not in action:
        return action["matched"], action.get("mismatch", "unclassified" if action["matched"] is False else None)
    matched = action_matches(action["predicted"], action["outcome"], action["before"])
    return matched, mismatch_kind({**action, "matched": matched}, shelf_width, shelf_depth)


SEAL_MOVE = 0.01  # m: a suctioned object that moved less than this (and turned < SEAL_TURN) was never sealed
SEAL_TURN = math.radians(5.0)  # rad
MISMATCH_KINDS = ("dropped", "toppled", "put back", "seal never formed", "slid", "turned")


def put_back_why(weighed: dict) -> str:
    """Why a weighed lift was put back (:func:`slax_drake.systems.guard.weigh_verdict`): its record's ``why``; a
    record that kept only the weight, the moment and the limit (a run of bda367b) gets the
    verdict those values give in the verdict's order (nothing held, too heavy), else "not hanging free", the only
    verdict left."""
    from slax_drake.systems.guard import MIN_HELD_WEIGHT, PutBack

    if "why" in weighed:
        return weighed["why"]
    if weighed["weight_n"] < MIN_HELD_WEIGHT:
        return PutBack.NOTHING_HELD.value
    return (PutBack.TOO_HEAVY if weighed["moment_nm"] > weighed["limit_nm"] else PutBack.NOT_HANGING_FREE).value


def mismatch_kind(action: dict, shelf_width: float, shelf_depth: float) -> str | None:
    """Why an executed action did not match its prediction (None when it matched or has no outcome), the first
    of: "dropped" (the object was lost at the next decision, its centre out of the bay), "toppled" (lost, inside
    the bay: tilted over 20 deg), "put back" (a lift the arm weighed at the cup and undid: too heavy, not hanging free or nothing held; a drag weighed along its pull and pushed back), "seal never formed" (a suction whose object moved less than ``SEAL_MOVE`` and
    turned less than ``SEAL_TURN`` from where it stood), "slid" (its planar position more than ``MATCH_DISTANCE``
    from the prediction), "turned" (its position within it, its yaw more than ``MATCH_YAW`` off). ``action``: a
    physics record's action (``matched``, ``outcome``, ``before``, ``lost_after``, ``type``)."""
    if action.get("matched") is not False:
        return None
    out, before = action["outcome"], action.get("before")
    if action.get("lost_after"):
        inside = abs(out["x"]) < shelf_width / 2 and abs(out["y"]) < shelf_depth / 2
        return "toppled" if inside else "dropped"
    if (action.get("weighed") or {}).get("put_back") and not dragged_after_weighing(action):
        return "put back"  # weighed at the lift and undone: lowered where it stood and released
    if action["type"] == "suction" and before is not None:
        moved = math.hypot(out["x"] - before["x"], out["y"] - before["y"])
        if moved < SEAL_MOVE and abs(math.remainder(out["yaw"] - before["yaw"], 2.0 * math.pi)) < SEAL_TURN:
            return "seal never formed"
    predicted = action["predicted"]
    if math.hypot(out["x"] - predicted["x"], out["y"] - predicted["y"]) > MATCH_DISTANCE:
        return "slid"
    return "turned"  # within MATCH_DISTANCE, so its yaw (its own turn, with ``before``) is off


def _run_scene(job) -> dict:
    """Runs one scene in both simulators (in whichever process the backend chose); returns its result file's
    content."""
    config, station, policy_name, density, index, seed, sleep, tool_rules, profile, sensor_noise, shelf_camera = job
    from slax_drake.config import load_scenario
    from slax_drake.policies.registry import make_policy
    from slax_drake.shelf.simulator import CameraObserver, run_trial as run_shelf_trial
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.evaluation.trial import TrialOptions, drake_info_silenced, run_trial

    scenario = load_scenario(config)
    opts = protocol_trial(TrialOptions(config=config, station=station, policy=policy_name, out=None, sleep=sleep,
                                       sensor_noise=sensor_noise,
                                       tool_rules=tool_rules, profile=profile), scenario, density, seed)
    scene = sample_scene(scenario, opts.objects, seed, target_size=opts.target_size)
    policy = make_policy(policy_name, scenario, perception="ground-truth", horizon=opts.horizon,
                         tool_overrides=tool_rules, profile=profile)
    observer = None
    if shelf_camera is not None:
        observer = CameraObserver(scene.shelf, scene.camera, opts.target_size, source="depth",
                                  width=policy.observation_width, segmentation=shelf_camera.segmentation,
                                  noise_seed=seed if shelf_camera.sensor_noise else None,
                                  full_resolution=shelf_camera.full_resolution)
    shelf = run_shelf_trial(scene, policy, opts.horizon, threshold=scenario.target.visibility_threshold,
                            suction_cost=scenario.protocol.suction_cost, density=density, observer=observer).to_dict()
    if hasattr(policy, "decision_log"):  # one decision per step in the shelf simulator
        shelf["stall_step"] = stall_step(policy.decision_log)
    t0 = time.perf_counter()
    with drake_info_silenced():
        d = run_trial(opts).data  # a simulation that blew up ends the trial "simulation diverged: ...", its actions kept
    actions = []
    for a in d["actions"]:
        params = {k: a[k] for k in ("d", "dx", "dz") if k in a}
        timings = (a.get("motion") or {}).get("timings", {})
        record = {"type": a["type"], "object": a["object"], **params,
                  **({"grip": a["grip"]} if "grip" in a else {}),
                  **({"reversal_rule": a["reversal_rule"]} if "reversal_rule" in a else {}), "predicted": a["predicted"],
                  "true_object": a.get("true_object"),  # the scene object the hypothesis was (the referee's)
                  "before": a.get("before"), "outcome": a["outcome"], "lost_after": a.get("lost_after"),
                  "matched": action_matches(a["predicted"], a["outcome"], a.get("before")),
                  "planning_s": a.get("planning_s"), "planning_cpu_s": a.get("planning_cpu_s"),
                  "rejected_before": len(a.get("rejected_before", [])),
                  # the candidates the motion planner refused before this action: what, why (FailureKind), where
                  "rejected": [{k: r.get(k) for k in ("action", "kind", "waypoint")}
                               for r in a.get("rejected_before", [])],
                  "motion_timings": {k: timings[k] for k in ("ik_s", "check_s", "timing_s") if k in timings}}
        if isinstance(a.get("weighed"), dict):  # a lift weighed at the cup: its moment, whether it was put back
            record["weighed"] = {k: a["weighed"][k] for k in ("weight_n", "moment_nm", "lever_m", "least_lever_m",
                                                               "limit_nm", "put_back", "why", "mass_kg",
                                                               "drag_after_weighing", "along", "friction_n",
                                                               "twist_nm")
                                 if k in a["weighed"]}
        if isinstance(a.get("guard"), dict):  # a guarded placement: whether it stopped on contact, where
            record["guard"] = {k: a["guard"][k] for k in ("stopped", "pushed_in_m", "short_m", "peak_force_n",
                                                          "threshold_n", "rebased", "edge_only") if k in a["guard"]}
            edge = a["guard"].get("edge_stop")
            if isinstance(edge, dict):  # stopped at the board's front edge first, then pushed in again higher
                record["guard"]["edge_stop"] = {k: edge[k] for k in ("pushed_in_m", "peak_force_n") if k in edge}
        record["mismatch"] = mismatch_kind(record, scenario.shelf.width, scenario.shelf.depth)
        actions.append(record)
    final = d["final_objects"]
    drake = {
        "success": d["success"], "result": d["result"], "steps": d["steps"], "cost": d["cost"],
        "visible_fraction": d["visible_fraction"], "sim_time_s": d["sim_time_s"], "wall_s": d["wall_s"],
        "total_s": round(time.perf_counter() - t0, 3), "real_time_factor": d["real_time_factor"],
        "actions": actions,
        "toppled": sorted(n for n, p in final.items() if not p["upright"]),
        "dropped": sorted(n for n, p in final.items() if not p["inside"]),
        "initial_objects": d["initial_objects"], "final_objects": final, "sleep": d.get("sleep", False),
        "target_moved_m": d.get("target_moved_m"),  # how far the trial's moves pushed the target (m)
    }
    logs = [step["decision_log"][-1] if step["decision_log"] else None
            for step in d.get("steps_log") or [] if "decision_log" in step]
    if logs:  # the policy keeps a decision log: the step at which its search stalled (None: it never did)
        drake["stall_step"] = stall_step(logs)
    last = (d.get("steps_log") or [{}])[-1]
    if last.get("reasons") is not None:  # ended with no action to execute: why, by stage and kind
        drake["end_reasons"] = last["reasons"]
        drake["end_rejected"] = [{"kind": r.get("kind"), "waypoint": r.get("waypoint")} for r in last.get("rejected", [])]
        if last.get("screened") is not None:  # the feasible candidates the policy's corrections screened out
            drake["end_screened"] = last["screened"]
    shelf_keep = {k: shelf[k] for k in ("success", "steps", "cost", "reason", "actions", "notes", "visible_fraction",
                                        "screened", "stall_step") if k in shelf}
    return {"policy": policy_name, "density": density, "index": index, "seed": seed, "shelf": shelf_keep,
            "drake": drake, "profile": profile, "tool_rules": tool_rules}


def protocol_trial(opts, scenario, density: int, seed: int):
    """``opts`` (TrialOptions) set to the protocol scene of ``density`` objects and scene seed ``seed`` of
    ``scenario`` (loaded from ``opts.config``): ``scenario.protocol.occluders(density)`` occluders (the Table I
    benchmark's scene), the protocol's first target size, H = horizon_per_object * density
    and, unless ``opts`` names a station, :func:`slax_drake.station.scenario.station_for`. The one definition of a protocol scene's Drake
    trial, shared by this benchmark and ``slax-drake trial --benchmark-scene``."""
    from slax_drake.station.scenario import station_for

    return dataclasses.replace(opts, objects=scenario.protocol.occluders(density), seed=seed,
                               target_size=tuple(float(v) for v in scenario.target.sizes[0]),
                               horizon=scenario.protocol.horizon_per_object * density,
                               station=opts.station or station_for(opts.config))


def run_physics_benchmark(config: str, policies, scenes_per_density: int, seed: int | None = None,
                          out: str | Path = "results/physics", workers: int = 1, densities=None,
                          station: str | None = None, sleep: bool = False, progress: bool = True,
                          tool_rules: dict | None = None, backend: str = "local",
                          ray_address: str | None = None, profile: str = "station",
                          sensor_noise: bool = False, shelf_camera=None) -> dict:
    """Runs the missing scenes (both simulators) and writes physics.json and physics.md; returns the summary, whose
    ``meta`` says how many scenes were kept from the folder and how many ran.

    ``config``: the protocol scenario YAML (e.g. sim_configs/table1.yaml); ``seed``: protocol seed (default the
    protocol's); ``densities``: default the protocol's; ``station``: default :func:`slax_drake.station.scenario.station_for`;
    ``profile``: the action model's rule profile for both simulators (default "station": the Drake station is the
    physical tool, whatever the protocol scenario's profile); ``tool_rules``: rule overrides of it for both
    simulators, on top of the station's cup limit
    (``trial.station_tool_rules``); ``backend``, ``workers``, ``ray_address``: where the scenes run
    (:func:`slax_drake.backends.run_tasks`); ``sensor_noise``: the L515 depth-noise model between the Drake
    trials' camera and their perception (seeded per scene); ``shelf_camera``: the shelf simulator's camera mode
    (slax_drake.evaluation.table1.CameraMode, the same frames' labels and noise as the Drake trials') or None
    (privileged: the objects as they are). The settings are recorded in the folder; a resumed run
    with other settings is refused before anything runs.
    """
    from tqdm import tqdm

    from slax_drake.backends import check_backend, run_tasks
    from slax_drake.config import load_scenario
    from slax_drake.evaluation.settings import (
        PHYSICS_SETTINGS_FILE, file_digest, protocol_settings, record_or_refuse,
    )
    from slax_drake.evaluation.table1 import scene_seed
    from slax_drake.policies.registry import POLICY_TABLE
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.trial import station_tool_rules

    scenario = load_scenario(config)
    policies = list(policies)
    if not policies:
        raise PhysicsBenchmarkError("no policies given")
    for p in policies:
        if p not in POLICY_TABLE:
            raise PhysicsBenchmarkError(f"unknown policy '{p}' (known: {', '.join(POLICY_TABLE)})")
        if POLICY_TABLE[p].load().needs_true_scene:
            raise PhysicsBenchmarkError(f"policy '{p}' cannot run in a Drake trial (an oracle needs the true scene)")
    if scenes_per_density < 1:
        raise PhysicsBenchmarkError("--scenes-per-density must be at least 1")
    check_backend(backend, workers, ray_address)
    seed = scenario.protocol.seed if seed is None else int(seed)
    densities = [int(n) for n in (densities or scenario.protocol.densities)]
    if any(n < 1 for n in densities):
        raise PhysicsBenchmarkError(f"--densities must be object counts of at least 1 (got {densities})")
    from slax_drake.evaluation.table1 import check_protocol_request
    from slax_drake.errors import BenchmarkError

    try:
        check_protocol_request(scenario, policies, densities)
    except BenchmarkError as e:
        raise PhysicsBenchmarkError(str(e)) from None
    if station is None:
        from slax_drake.station.scenario import station_for

        station = station_for(config)
    if not Path(station).is_file():
        raise PhysicsBenchmarkError(f"station file not found: {station}")
    out = Path(out)
    tool_rules = station_tool_rules(load_station_scenario(station), tool_rules, profile)
    settings = {**protocol_settings(scenario, config, seed, "ground-truth", tool_rules, policies, camera=shelf_camera,
                                    profile=profile),
                "drake_observation": drake_observation(sensor_noise),
                "station": str(station), "station_sha256": file_digest(station), "sleep": bool(sleep)}
    record_or_refuse(out, settings, has_results=any((out / "physics_trials").glob("*/*.json")),
                     name=PHYSICS_SETTINGS_FILE)
    all_jobs = [(config, station, p, n, i, scene_seed(seed, n, i), sleep, tool_rules, profile, sensor_noise,
                 shelf_camera)
                for p in policies for n in densities for i in range(scenes_per_density)]
    jobs = [j for j in all_jobs if not trial_path(out, j[2], j[3], j[4]).is_file()]
    # Scene index by scene index, densest first within each: a run stopped early holds the same number of scenes
    # of every density (and the long dense trials are spread over the run).
    jobs.sort(key=lambda j: (j[4], -j[3], j[2]))
    start = time.perf_counter()
    if jobs:
        with tqdm(total=len(jobs), desc="physics trials", unit="scene", disable=not progress) as bar:
            for job, result in run_tasks(_run_scene, jobs, workers=workers, backend=backend, ray_address=ray_address):
                write_text_atomic(trial_path(out, job[2], job[3], job[4]), json.dumps(result, indent=1, sort_keys=True))
                drake = result.get("drake", {})
                bar.set_postfix_str(f"last: {job[2]}, {job[3]} objects #{job[4]}, Drake "
                                    f"{'revealed' if drake.get('success') else drake.get('result', 'not revealed')}",
                                    refresh=False)
                bar.update(1)
    elapsed = time.perf_counter() - start
    trials = load_results(out, policies, densities, scenes_per_density)
    summary = summarise(trials, policies, densities, (scenario.shelf.width, scenario.shelf.depth))
    summary["meta"] = {"config": config, "station": station, "scenes_per_density": scenes_per_density,
                       "seed": seed, "densities": densities, "sleep": sleep, "sensor_noise": sensor_noise,
                       "workers": workers, "backend": backend, "mass_model": scenario.physics.mass_model,
                       "shelf_observation": "privileged" if shelf_camera is None else "camera",
                       **({"shelf_full_resolution": True} if shelf_camera is not None and shelf_camera.full_resolution
                          else {}),
                       "profile": profile, "tool_rules": tool_rules, "scenes_kept": len(all_jobs) - len(jobs), "scenes_run": len(jobs),
                       "wall_seconds_this_run": round(elapsed, 1), "match_distance_m": MATCH_DISTANCE,
                       "match_yaw_deg": math.degrees(MATCH_YAW)}
    write_text_atomic(out / "physics.json", json.dumps(summary, indent=1, sort_keys=True))
    write_text_atomic(out / "physics.md", markdown_table(summary))
    write_bytes_atomic(out / "physics.png", bar_chart_png(summary))
    return summary


def load_results(out: Path, policies, densities, scenes_per_density) -> list[dict]:
    results = []
    for p in policies:
        for n in densities:
            for i in range(scenes_per_density):
                path = trial_path(out, p, n, i)
                try:
                    r = json.loads(path.read_text())
                    _ = (r["shelf"]["success"], r["drake"]["success"], r["drake"]["actions"])
                except (OSError, json.JSONDecodeError, KeyError, TypeError) as e:
                    raise PhysicsBenchmarkError(f"{path}: unreadable result file ({e}); delete it to rerun that scene")
                for side in ("shelf", "drake"):
                    if not isinstance(r[side]["success"], bool):
                        raise PhysicsBenchmarkError(f"{path}: field '{side}.success' is {r[side]['success']!r}, not "
                                                    "true or false; delete the file to rerun that scene")
                if not isinstance(r["drake"]["actions"], list):
                    raise PhysicsBenchmarkError(f"{path}: field 'drake.actions' is not a list; delete the file to "
                                                "rerun that scene")
                results.append(r)
    return results


def _median(values):
    return float(np.median(values)) if values else None


def clean_success(drake: dict) -> bool:
    """Whether a physics record's Drake part revealed the target with nothing toppled or dropped (``toppled`` and
    ``dropped``: the lists of object names a trial record keeps, or the counts of a summary row)."""
    return bool(drake["success"] and not drake["toppled"] and not drake["dropped"])


def _stall_counts(recorded: list[dict]) -> dict:
    """``{"stalls": [...]}`` of the summary rows ``recorded`` (those whose records keep the policy's decision log):
    trials whose search stalled, of them revealed all the same, actions executed from the stall on, all actions
    executed; {} when there are none."""
    if not recorded:
        return {}
    stalled = [t for t in recorded if t["stall"][0] is not None]
    return {"stalls": [len(stalled), sum(t["drake_success"] for t in stalled), sum(t["stall"][1] for t in stalled),
                       sum(t["actions_executed"] for t in recorded)]}


def summarise(results: list[dict], policies, densities, shelf=(math.inf, math.inf)) -> dict:
    """Per policy and density key ("4", ..., "all"): shelf and Drake success rate and median steps (over
    successful trials), the fraction of Drake actions whose outcome matched the prediction (judged again from the
    stored poses, :func:`judge_action`; ``shelf``: the bay's width and depth, to tell dropped from toppled), toppled and
    dropped object counts, outcome agreement between the two simulators; plus one row per scene under ``trials``."""
    summary = {"policies": {}, "trials": []}
    for r in results:
        d = r["drake"]
        d = {**d, "actions": [dict(a, matched=m, mismatch=k) for a in d["actions"] for m, k in [judge_action(a, *shelf)]]}
        summary["trials"].append({
            "policy": r["policy"], "density": r["density"], "index": r["index"], "seed": r["seed"],
            "shelf_success": r["shelf"]["success"], "shelf_steps": r["shelf"]["steps"],
            "drake_success": d["success"], "drake_result": d["result"], "drake_steps": d["steps"],
            "drake_clean_success": clean_success(d),
            "actions_executed": len(d["actions"]),
            "matched_actions": sum(1 for a in d["actions"] if a["matched"]),
            "actions_with_outcome": sum(1 for a in d["actions"] if a["matched"] is not None),
            "toppled": len(d["toppled"]), "dropped": len(d["dropped"]), "real_time_factor": d["real_time_factor"],
            "drake_wall_s": d["wall_s"],
            "planning_s": [a["planning_s"] for a in d["actions"] if a.get("planning_s") is not None],
            "planning_cpu_s": [a["planning_cpu_s"] for a in d["actions"] if a.get("planning_cpu_s") is not None],
            "reversals": reversals(d["actions"]),
            "undoes": undoes(d["actions"]),
            "undo_rules": undo_rules(d["actions"]),
            "commanded_undoes": commanded_undoes(d["actions"]),
            "commanded_undo_rules": undo_rules(d["actions"], commanded=True),
            "axis_undoes": commanded_undoes(d["actions"], by_axis=True),
            "judged_by_kind": {kind: [sum(1 for a in d["actions"] if action_kind(a) == kind and a["matched"]),
                                      sum(1 for a in d["actions"] if action_kind(a) == kind and a["matched"] is not None)]
                               for kind in ACTION_KINDS},
            # a file written before mismatches were classified counts its mismatches as "unclassified"
            "mismatches": dict(collections.Counter(a["mismatch"] or "unclassified" for a in d["actions"]
                                                   if a["matched"] is False)),
            # an ending with no action executed: how many candidates the motion planner refused at that decision
            # (None: the trial ended otherwise, or its record predates end_rejected)
            "end_refused": len(d["end_rejected"]) if "end_rejected" in d else None,
            "guarded": [sum(1 for a in d["actions"] if "guard" in a and not a["guard"].get("edge_only")),
                        sum(1 for a in d["actions"] if (a.get("guard") or {}).get("stopped")),
                        sum(1 for a in d["actions"] if "edge_stop" in (a.get("guard") or {}))],
        })
        if "target_moved_m" in d:  # None: the simulation diverged (no final pose); absent: a record from before
            summary["trials"][-1]["target_moved_m"] = d["target_moved_m"]
        if "stall_step" in d:  # the policy's search stalled at this step (None: never); actions from it on
            stalled = d["stall_step"]
            summary["trials"][-1]["stall"] = [stalled, 0 if stalled is None else len(d["actions"][stalled:])]
        lifts = [a for a in d["actions"] if "weighed" in a and not is_pull_record(a["weighed"])]
        pulls = [a["weighed"] for a in d["actions"] if is_pull_record(a.get("weighed"))]
        if lifts:  # lifts weighed at the cup, how many were put back, and of those how many were then dragged to the
            # same placement (drag_after_weighing)
            summary["trials"][-1]["weighed"] = [len(lifts), sum(1 for a in lifts if a["weighed"].get("put_back")),
                                                sum(1 for a in lifts if dragged_after_weighing(a))]
            summary["trials"][-1]["put_back_why"] = dict(collections.Counter(
                put_back_why(a["weighed"]) for a in lifts if a["weighed"].get("put_back")))
        if pulls:  # sideways drags weighed along their pull (weigh_drag_pull): weighed (a friction measured),
            # pushed back
            summary["trials"][-1]["pulls"] = [sum(1 for w in pulls if w.get("friction_n") is not None),
                                              sum(1 for w in pulls if w.get("put_back"))]
    for p in policies:
        per = {}
        for key in [str(n) for n in densities] + ["all"]:
            sel = [t for t in summary["trials"] if t["policy"] == p and (key == "all" or t["density"] == int(key))]
            matched = sum(t["matched_actions"] for t in sel)
            judged = sum(t["actions_with_outcome"] for t in sel)
            no_motion_refused = [t.get("end_refused") for t in sel if _ending(t["drake_result"]) == "no feasible motion"]
            per[key] = {
                "trials": len(sel),
                "shelf_success_rate": round(sum(t["shelf_success"] for t in sel) / len(sel), 4) if sel else None,
                "drake_success_rate": round(sum(t["drake_success"] for t in sel) / len(sel), 4) if sel else None,
                "drake_clean_success_rate": round(sum(t["drake_clean_success"] for t in sel) / len(sel), 4)
                if sel else None,
                "drake_endings": dict(sorted(collections.Counter(_ending(t["drake_result"]) for t in sel).items())),
                # "no feasible motion" endings where the planner refused one candidate: the only one the action model
                # and the policy's corrections had left (None where the records do not say)
                "no_motion_one_left": None if None in no_motion_refused else no_motion_refused.count(1),
                # guarded placements executed, how many of them the guard stopped on contact, and how many lifted
                # push-ins (guarded or not) stopped at the board's front edge and went in again higher (before: 0)
                "guarded_placements": [sum(t.get("guarded", [0, 0])[0] for t in sel),
                                       sum(t.get("guarded", [0, 0])[1] for t in sel),
                                       sum((t.get("guarded", [0, 0]) + [0])[2] for t in sel)],
                # trials whose moves pushed the target TARGET_MOVED or farther, and of them revealed (None where the
                # records do not say)
                "target_moved": None if any("target_moved_m" not in t for t in sel) else [
                    sum(1 for t in sel if (t["target_moved_m"] or 0.0) >= TARGET_MOVED),
                    sum(1 for t in sel if (t["target_moved_m"] or 0.0) >= TARGET_MOVED and t["drake_success"])],
                **({"weighed_lifts": [sum(t["weighed"][0] for t in sel if "weighed" in t),
                                      sum(t["weighed"][1] for t in sel if "weighed" in t),
                                      sum(t["weighed"][2] for t in sel if len(t.get("weighed", ())) > 2)],
                    "put_back_why": dict(sorted(sum((collections.Counter(t.get("put_back_why", {})) for t in sel),
                                                    collections.Counter()).items()))}
                   if any("weighed" in t for t in sel) else {}),
                **({"weighed_pulls": [sum(t["pulls"][0] for t in sel if "pulls" in t),
                                      sum(t["pulls"][1] for t in sel if "pulls" in t)]}
                   if any("pulls" in t for t in sel) else {}),
                # trials whose search stalled, of them revealed all the same, actions executed from the stall on,
                # and all actions executed (where the records keep the policy's decision log)
                **_stall_counts([t for t in sel if "stall" in t]),
                "shelf_median_steps": _median([t["shelf_steps"] for t in sel if t["shelf_success"]]),
                "drake_median_steps": _median([t["drake_steps"] for t in sel if t["drake_success"]]),
                "same_outcome_rate": round(sum(t["shelf_success"] == t["drake_success"] for t in sel) / len(sel), 4)
                if sel else None,
                "actions_matched": matched, "actions_judged": judged,
                "match_rate": round(matched / judged, 4) if judged else None,
                "toppled": sum(t["toppled"] for t in sel), "dropped": sum(t["dropped"] for t in sel),
                "median_real_time_factor": _median([t["real_time_factor"] for t in sel
                                                    if t["real_time_factor"] is not None]),
                "planned_actions": sum(len(t["planning_s"]) for t in sel),
                **_planning_stats([s for t in sel for s in t["planning_s"]]),
                **_planning_stats([s for t in sel for s in t.get("planning_cpu_s", [])], "planning_cpu"),
                "reversals": sum(t["reversals"] for t in sel),
                "trials_with_reversal": sum(1 for t in sel if t["reversals"]),
                "trials_with_undo": sum(1 for t in sel if t.get("undoes")) if all("undoes" in t for t in sel) else None,
                "undo_rules": dict(sum((collections.Counter(t.get("undo_rules", {})) for t in sel),
                                       collections.Counter())),
                # the undos along an axis the action commands (not its object's drift): the shuttles proper
                "undoes_commanded": sum(t["commanded_undoes"] for t in sel),
                "trials_with_commanded_undo": sum(1 for t in sel if t["commanded_undoes"]),
                "commanded_undo_rules": dict(sum((collections.Counter(t["commanded_undo_rules"]) for t in sel),
                                                 collections.Counter())),
                # the same against the object's last move along each axis
                "undoes_by_axis": sum(t["axis_undoes"] for t in sel),
                "trials_with_axis_undo": sum(1 for t in sel if t["axis_undoes"]),
                "match_by_action": _match_by_action(sel),
                "mismatch_kinds": _mismatch_counts(sel),
            }
        summary["policies"][p] = per
    return summary


REVERSAL_MIN = 0.01  # m: both moves' components along the reversed axis exceed this (the no-shuttle rule's 1 cm)
SAME_PLACE = 0.02  # m: an action's object stood within this of where an earlier action left it (the same object)


def _reversed_axes(actions: list[dict], by_axis: bool = False):
    """Per executed action that moved an object back along x or y against the previous move of the same physical
    object (both components over :data:`REVERSAL_MIN`): (this action, that previous move, this move, the reversed
    axes' indices). ``by_axis``: against the object's last move along each axis (a move along the other axis alone
    in between keeps it: x +0.35 m, y -0.10 m, x -0.35 m reverses the first move).
    Judged from the true poses of the record (``before``, ``outcome``, m in S): an action's object is the one an
    earlier action left within :data:`SAME_PLACE` of where this one found it (the record's track names are the
    planner's and may change)."""
    last_moves = []  # (where the object was left (x, y), its displacement (dx, dy)), latest first
    for a in actions:
        before, after = a.get("before"), a.get("outcome")
        if before is None or after is None:
            continue
        move = (after["x"] - before["x"], after["y"] - before["y"])
        previous = next((m for (x, y), m in last_moves
                         if math.hypot(before["x"] - x, before["y"] - y) <= SAME_PLACE), None)
        if previous is not None:
            axes = [k for k, (p, c) in enumerate(zip(previous, move))
                    if p * c < 0 and abs(p) > REVERSAL_MIN and abs(c) > REVERSAL_MIN]
            if axes:
                yield a, previous, move, axes
        if by_axis and previous is not None:
            move = last_move_by_axis(previous, move, REVERSAL_MIN)
        last_moves.insert(0, ((after["x"], after["y"]), move))


def reversals(actions: list[dict]) -> int:
    """How many of a Drake trial's executed actions moved an object back along x or y against its previous move
    (:func:`_reversed_axes`): the shuttles the no-shuttle rule forbids, plus the ones it lets through because they
    uncover space no earlier arrangement did (most carry the object past where it stood)."""
    return sum(1 for _ in _reversed_axes(actions))


def _undo_actions(actions: list[dict], commanded: bool = False, by_axis: bool = False):
    """The actions of :func:`undoes`, in order; ``commanded``: only those that undo along an axis the action
    commands (:func:`commanded_axes`): a shuttle the policy chose, not a push along x that let its object drift back
    1-2 cm in y. ``by_axis``: judged against the object's last move along each axis (:func:`_reversed_axes`)."""
    for a, previous, move, axes in _reversed_axes(actions, by_axis):
        if commanded:
            axes = [k for k in axes if k in commanded_axes(a)]
        if any(abs(previous[k] + move[k]) <= abs(previous[k]) + REVERSAL_MIN for k in axes):
            yield a


def undoes(actions: list[dict]) -> int:
    """The reversals that undo the previous move: along a reversed axis the object ends no farther from where it
    stood before that move than the move took it (|previous + this| <= |previous|, within :data:`REVERSAL_MIN`):
    put back, or past by no more than the move; a reversal that carries it farther past is a relocation."""
    return sum(1 for _ in _undo_actions(actions))


def commanded_axes(action: dict) -> set[int]:
    """The axes of S (0: x, 1: y) along which ``action`` (a record) moves its object by command: a push along x by
    ``d``; a suction (lifted or dragged) along x by ``dx`` and along y by ``dz``, each when over
    :data:`REVERSAL_MIN`. A displacement along another axis is the object's drift (it slid or turned)."""
    if action.get("type") == "push":
        return {0}
    return {k for k, name in ((0, "dx"), (1, "dz")) if abs(action.get(name) or 0.0) > REVERSAL_MIN}


def commanded_undoes(actions: list[dict], by_axis: bool = False) -> int:
    """How many of :func:`undoes` reverse the previous move along an axis the action commands; ``by_axis``: the
    object's last move along that axis, a move along the other axis alone in between notwithstanding (the cycles
    through a third move that the previous-move count misses)."""
    return sum(1 for _ in _undo_actions(actions, commanded=True, by_axis=by_axis))


UNDO_RULES = (*(str(r) for r in Reversal), "not a move back by the estimate", "not recorded")


def undo_rules(actions: list[dict], commanded: bool = False) -> dict:
    """{how the policy's no-shuttle correction judged it: count} over the undos of :func:`undoes`, from each
    action's ``reversal_rule`` (:meth:`slax_drake.policies.policies.Policy.reversal_rule`): "uncovers new width"
    (it passed the correction by uncovering space never seen), "let through" (the correction screened it out and
    an exception took it), "not a move back by the estimate" (on the poses the policy estimated it did not reverse
    its object's last move: a tracking or estimation miss, or no correction applied) or "not recorded" (a record
    from before the field). ``commanded``: over :func:`commanded_undoes` only."""
    counts = collections.Counter()
    for a in _undo_actions(actions, commanded):
        rule = a["reversal_rule"] if "reversal_rule" in a else "not recorded"
        counts[rule or "not a move back by the estimate"] += 1
    return {k: counts[k] for k in UNDO_RULES if counts[k]}


ACTION_KINDS = ("push", "suction", "drag")  # "suction": lifted; "drag": slid on the floor (the drag grasp)


def action_kind(action: dict) -> str:
    """An action record's kind for the fidelity counts: "push", "suction" (lifted) or "drag" (a suction whose
    ``grip`` is "drag"; a record without ``grip`` was lifted)."""
    return "drag" if action["type"] == "suction" and action.get("grip") == "drag" else action["type"]


def _match_by_action(trials: list[dict]) -> dict:
    """{action kind: {"matched", "judged", "match_rate"}} over ``trials`` (summary rows)."""
    out = {}
    for kind in ACTION_KINDS:
        matched = sum(t["judged_by_kind"].get(kind, [0, 0])[0] for t in trials)
        judged = sum(t["judged_by_kind"].get(kind, [0, 0])[1] for t in trials)
        out[kind] = {"matched": matched, "judged": judged, "match_rate": round(matched / judged, 4) if judged else None}
    return out


def _mismatch_counts(trials: list[dict]) -> dict:
    """{mismatch kind: count} over ``trials``, every kind of MISMATCH_KINDS listed (0 when none)."""
    counts = collections.Counter()
    for t in trials:
        counts.update(t["mismatches"])
    return {**{k: counts.get(k, 0) for k in MISMATCH_KINDS}, **{k: v for k, v in counts.items() if k not in MISMATCH_KINDS}}


def _ending(result: str) -> str:
    """A Drake trial's result without its details ("simulation diverged: ..." -> "simulation diverged")."""
    return result.split(":")[0]


def planning_cell(e: dict) -> str:
    """"wall median / p90; CPU median / p90" (s) of a summary row's planning per executed action (the CPU part only
    where it was recorded)."""
    def secs(v):
        return "-" if v is None else f"{v:.2f}"

    cell = f"{secs(e.get('planning_median_s'))} / {secs(e.get('planning_p90_s'))}"
    if e.get("planning_cpu_median_s") is not None:
        cell += f"; CPU {secs(e['planning_cpu_median_s'])} / {secs(e.get('planning_cpu_p90_s'))}"
    return cell


def _planning_stats(seconds: list[float], name: str = "planning") -> dict:
    """Median and 90th percentile of the planning time per executed action (s), as ``{name}_median_s`` and
    ``{name}_p90_s`` (None without data): every candidate motion planned for that decision, the rejected ones first
    included (IK, collision checks, RRT, Ruckig). ``name``: "planning" (wall clock) or "planning_cpu" (the
    process's CPU time: what one core spends, whatever else shares the machine; None in a run from before it was
    recorded)."""
    if not seconds:
        return {f"{name}_median_s": None, f"{name}_p90_s": None}
    return {f"{name}_median_s": round(float(np.median(seconds)), 3),
            f"{name}_p90_s": round(float(np.percentile(seconds, 90)), 3)}


def markdown_table(summary: dict) -> str:
    def pct(v):
        return "-" if v is None else f"{100 * v:.0f} %"

    def num(v):
        return "-" if v is None else f"{v:.1f}"

    lines = ["| Policy | Objects | Scenes | Success (shelf sim) | Success (Drake) | Drake, nothing lost | Median steps (shelf sim) | "
             "Median steps (Drake) | Same outcome | Actions matching prediction | Toppled | Dropped | "
             "Real-time factor | Planning per action, median / p90 (s): wall; CPU |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for p, per in summary["policies"].items():
        for key, e in per.items():
            match = "-" if e["match_rate"] is None else \
                f"{100 * e['match_rate']:.0f} % ({e['actions_matched']}/{e['actions_judged']})"
            lines.append(f"| {p} | {'All' if key == 'all' else key} | {e['trials']} | {pct(e['shelf_success_rate'])} | "
                         f"{pct(e['drake_success_rate'])} | {pct(e.get('drake_clean_success_rate'))} | "
                         f"{num(e['shelf_median_steps'])} | "
                         f"{num(e['drake_median_steps'])} | {pct(e['same_outcome_rate'])} | {match} | "
                         f"{e['toppled']} | {e['dropped']} | {num(e['median_real_time_factor'])} | "
                         f"{planning_cell(e)} |")
    meta = summary.get("meta", {})
    lines += ["", f"{meta.get('scenes_per_density', '?')} scenes per density, protocol seed {meta.get('seed', '?')}, "
              f"the same scenes in both simulators: the shelf simulator "
              + ("with the objects seen as they are and ground-truth distributions (privileged)"
                 if meta.get("shelf_observation", "privileged") == "privileged" else
                 "with what its rendered camera sees (camera mode, the render's labels, the same noise model"
                 + ("; its frames rendered at the camera's resolution and resampled as the station's"
                    if meta.get("shelf_full_resolution") else "") + ")")
              + f", the Drake trials with what their camera sees "
              f"({drake_observation(bool(meta.get('sensor_noise')))}). "
              f"Steps over successful trials. "
              f"An action matches when the object's physical pose at the next decision is within "
              f"{100 * MATCH_DISTANCE:.0f} cm and {math.degrees(MATCH_YAW):.0f} deg of the action model's prediction"
              + (" (a box push's turned pose, push_turn quasi-static)"
                 if (meta.get("tool_rules") or {}).get("push_turn") == "quasi-static" else
                 " (the first-order model: a push translates)") + ". "
              f"Toppled/dropped: objects tilted > 20 deg / outside the bay at the end of the Drake trial; "
              f"nothing lost: a Drake success with no object toppled or dropped. "
              f"Planning per executed action: every candidate motion planned for that decision (rejected ones "
              f"included), one worker process each. "
              f"Object sleep {'on' if meta.get('sleep') else 'off'}. "
              f"Object masses: {mass_model_words(meta.get('mass_model'))}."
              + f" Action-model rules: the '{meta.get('profile', 'station')}' profile"
              + (f", with {', '.join(f'{k} = {v}' for k, v in meta['tool_rules'].items())}."
                 if meta.get("tool_rules") else ".")]
    for p, per in summary["policies"].items():
        endings = per.get("all", {}).get("drake_endings")
        if endings:
            lines += ["", f"{p}, Drake trial endings: " + ", ".join(f"{k} {v}" for k, v in endings.items()) + "."]
            one_left = per["all"].get("no_motion_one_left")
            if endings.get("no feasible motion") and one_left is not None:
                lines[-1] += (f" Of the {endings['no feasible motion']} trials ending \"no feasible motion\", {one_left} "
                              f"ended when the motion planner refused the one candidate the action model and the "
                              f"policy's corrections had left (the trial would have stopped at the next decision "
                              f"had the action model refused it too).")
        guarded = per.get("all", {}).get("guarded_placements")
        if guarded and guarded[0]:
            lines[-1] += (f" Guarded placements (a push-in into hidden space that stops on contact): {guarded[0]}, "
                          f"stopped on contact {guarded[1]}.")
        if guarded and len(guarded) > 2 and guarded[2]:
            lines[-1] += (f" Lifted push-ins stopped at the board's front edge and pushed in again higher: "
                          f"{guarded[2]}.")
        moved = per.get("all", {}).get("target_moved")
        if moved is not None and endings:
            lines[-1] += (f" The target pushed {100 * TARGET_MOVED:.0f} cm or more by a move that brushed it: "
                          + (f"{plural(moved[0], 'trial')}, {moved[1]} of them revealed (the target scored where it "
                             f"stands)." if moved[0] else "in no trial."))
        stalls = per.get("all", {}).get("stalls")
        if stalls and endings:  # on the endings' line
            lines[-1] += " Stalls (the first decision at which no plan of the policy's reveals anything): " + \
                stall_words(stalls)
        weighed = per.get("all", {}).get("weighed_lifts")
        if weighed and weighed[0]:
            why = per["all"].get("put_back_why") or {}
            lines[-1] += (f" Lifts weighed at the cup: {weighed[0]}, put back {weighed[1]}"
                          + (" (" + ", ".join(f"{k} {v}" for k, v in why.items()) + ")" if why else "")
                          + (f", {weighed[2]} of them then dragged to the same placement"
                             if len(weighed) > 2 and weighed[2] else "") + ".")
        pulls = per.get("all", {}).get("weighed_pulls")
        if pulls and pulls[0]:
            lines[-1] += (f" Sideways drags weighed along their pull: {pulls[0]}, pushed back as twisting off the cup "
                          f"{pulls[1]}.")
    lines += ["", "Physics fidelity per action kind (actions matching the prediction) and the mismatches by "
              "kind (dropped: lost out of the bay; toppled: lost inside it; put back: a lift the arm weighed and "
              "undid, or a drag it weighed along its pull and pushed back; seal never formed: a suction that left its "
              f"object within {100 * SEAL_MOVE:.0f} cm and {math.degrees(SEAL_TURN):.0f} deg of where it stood; slid: "
              f"more than {100 * MATCH_DISTANCE:.0f} cm from the prediction; turned: within it, yaw off):", "",
              "| Policy | Objects | Pushes matching | Suctions matching (lifted) | Drags matching | " + " | ".join(
                  k.capitalize() for k in MISMATCH_KINDS) + " | Other |",
              "|---|---|---|---|---|" + "---|" * (len(MISMATCH_KINDS) + 1)]
    for p, per in summary["policies"].items():
        for key, e in per.items():
            by = e.get("match_by_action", {})
            cells = [("-" if by.get(k, {}).get("match_rate") is None else
                      f"{100 * by[k]['match_rate']:.0f} % ({by[k]['matched']}/{by[k]['judged']})") for k in ACTION_KINDS]
            kinds = e.get("mismatch_kinds", {})
            other = sum(v for k, v in kinds.items() if k not in MISMATCH_KINDS)
            lines.append(f"| {p} | {'All' if key == 'all' else key} | " + " | ".join(cells) + " | "
                         + " | ".join(str(kinds.get(k, 0)) for k in MISMATCH_KINDS) + f" | {other} |")
    return "\n".join(lines) + "\n"


def bar_chart_png(summary: dict) -> bytes:
    """One row per policy: success per density in both simulators (Drake: every success, and those that lost no
    object), and the fraction of Drake actions that matched the prediction."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    policies = list(summary["policies"])
    fig, axes = plt.subplots(len(policies), 2, figsize=(11, 4 * len(policies)), squeeze=False,
                             gridspec_kw={"width_ratios": [3, 2]})
    series = (("shelf simulator", "shelf_success_rate", "#4c72b0"), ("Drake", "drake_success_rate", "#dd8452"),
              ("Drake, nothing lost", "drake_clean_success_rate", "#c44e52"))
    for (left, right), p in zip(axes, policies):
        per = summary["policies"][p]
        keys = list(per)
        x = np.arange(len(keys))
        labels = ["All" if k == "all" else f"{k} objects" for k in keys]
        for i, (name, field, color) in enumerate(series):
            left.bar(x + (i - 1) * 0.27, [100 * (per[k].get(field) or 0) for k in keys], 0.27, label=name, color=color)
        right.bar(x, [100 * (per[k]["match_rate"] or 0) for k in keys], 0.6, color="#55a868")
        for ax in (left, right):
            ax.set_xticks(x)
            ax.set_xticklabels(labels)
            ax.set_ylim(0, 105)
        left.set_title(f"{p}: success on the same scenes ({per['all']['trials']} scenes)")
        left.set_ylabel("success rate (%)")
        left.legend(fontsize=8)
        right.set_title("Drake actions matching the prediction")
        right.set_ylabel("within 2 cm and 10 deg (%)")
    fig.tight_layout()
    return figure_png(fig, 110)
