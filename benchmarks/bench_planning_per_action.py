"""Planning time per executed action, rejected candidates included, as a Drake trial's planner spends it.

For K scenes of N objects (``sample_scene`` on the station's scene config, seeds ``--seed``..``--seed``+K-1), the
policy (default bluction-dar) decides with privileged observation in the first-order shelf simulator, under the
rules a Drake trial plans with (the ``station`` profile with the station cup's limits and its reach map); each
decision's best candidate is planned from the observation pose, a rejected one handed back with
``policy.exclude`` (the whole group when the failure is early) and the policy decides again, exactly as
:class:`slax_drake.systems.planner.PlannerSystem` does; the feasible one is executed (``execute``). The time
charged to an executed action is every ``MotionPlanner.plan`` call of its decision (the policy's own deciding
time is not included). One MotionPlanner serves all scenes, as one trial's serves its decisions. Prints the
median, p90 and max over executed actions (wall clock; and the median and p90 of the process's CPU time, the
figure to read on a machine shared with other work), the counts of rejected candidates and the decisions that ended with
no feasible motion. Run it on one core for the figures of record:

    taskset -c 0 python benchmarks/bench_planning_per_action.py --scenes 5 --objects 6 --json out.json

``--observation camera`` decides as the physics benchmark's trials do: on the camera frame's hypotheses (the shelf
simulator's camera mode: the render's labels, the tracker's names), and plans against those believed objects, as the
PlannerSystem plans against its estimator's; the action is executed on the true object its hypothesis is. It is the
workload of the physics report's planning figures (boxes as deep as the camera leaves them, suctions of estimated
objects), without the physics.

``--no-keep-ik`` plans with ``MotionPlanner(keep_kinematic_ik=False)`` (IK kept within one planning world only).
The script runs against older checkouts too (PYTHONPATH=that checkout): the option is then ignored.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=5)
    parser.add_argument("--objects", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0, help="the first scene seed")
    parser.add_argument("--steps", type=int, default=6, help="at most this many executed actions per scene")
    parser.add_argument("--policy", default="bluction-dar")
    parser.add_argument("--observation", choices=("privileged", "camera"), default="privileged",
                        help="what the policy decides on and the planner plans against (default: privileged)")
    parser.add_argument("--no-keep-ik", action="store_true")
    parser.add_argument("--json", default=None, help="write every decision's figures here")
    args = parser.parse_args(argv)
    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.policies.registry import make_policy
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.shelf.simulator import CameraObserver, execute, observation_for, on_true_object
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.trial import station_tool_rules

    station = load_station_scenario()
    scenario = load_scenario(station.scene_config)
    rules = station_tool_rules(station, None, "station")
    tool = tool_config(scenario, "station", **rules)
    try:
        planner = MotionPlanner(station, tool, keep_kinematic_ik=not args.no_keep_ik)
        kept = not args.no_keep_ik
    except TypeError:  # a checkout without the option: IK kept within one planning world only
        planner, kept = MotionPlanner(station, tool), False
    per_action, per_action_cpu, decisions = [], [], []
    for k in range(args.scenes):
        scene = sample_scene(scenario, args.objects, seed=args.seed + k)
        policy = make_policy(args.policy, scenario, horizon=2 * args.objects, tool_overrides=rules,
                             profile="station")
        policy.reset(scene)
        observer = None
        if args.observation == "camera":
            observer = CameraObserver(scene.shelf, scene.camera, tuple(scenario.target.sizes[0]), source="depth",
                                      width=policy.observation_width, segmentation="labels")
            observer.start()
        for step in range(args.steps):
            names = None
            if observer is not None:
                obs, names = observer.observe(scene)
                planned_on = obs.scene_template.with_objects(obs.known)  # the PlannerSystem's believed scene
            else:
                obs, planned_on = observation_for(policy, scene), scene
            spent, cpu, rejected, kinds, motion = 0.0, 0.0, 0, [], None
            for _ in range(25):  # PlannerSystem's MAX_PLAN_ATTEMPTS
                action = policy.decide(obs).best
                if action is None:
                    break
                t0, c0 = time.perf_counter(), time.process_time()
                result = planner.plan(action, planned_on, q_start=planner.q_observation)
                spent += time.perf_counter() - t0
                cpu += time.process_time() - c0
                if result.feasible:
                    motion = result
                    break
                rejected += 1
                failure = getattr(result, "failure", None)
                kinds.append(failure.kind.value if failure is not None else "?")
                policy.exclude(action, result.reason, whole_group=bool(failure is not None and failure.early))
            decisions.append({"scene_seed": args.seed + k, "step": step, "planning_s": round(spent, 4), "planning_cpu_s": round(cpu, 4),
                              "rejected": rejected, "rejected_kinds": kinds,
                              "action": None if motion is None else action.describe()})
            if motion is None:
                break
            per_action.append(spent)
            per_action_cpu.append(cpu)
            if names is not None:  # camera: the hypothesis's true object is moved (a shelf segment moves nothing)
                observer.executed(action)
                if names.get(action.name) is None:
                    continue
                action = on_true_object(action, obs.known, scene, names[action.name])
            scene, _ = execute(scene, action, policy.action_model)
    v = np.array(per_action)
    ended = sum(1 for d in decisions if d["action"] is None and d["rejected"])
    summary = {"executed_actions": len(v), "median_s": round(float(np.median(v)), 3) if len(v) else None,
               "p90_s": round(float(np.percentile(v, 90)), 3) if len(v) else None,
               "max_s": round(float(v.max()), 3) if len(v) else None,
               "cpu_median_s": round(float(np.median(per_action_cpu)), 3) if len(v) else None,
               "cpu_p90_s": round(float(np.percentile(per_action_cpu, 90)), 3) if len(v) else None,
               "rejected_candidates": sum(d["rejected"] for d in decisions),
               "decisions_ending_no_feasible_motion": ended, "scenes": args.scenes, "objects": args.objects,
               "seed": args.seed, "policy": args.policy, "observation": args.observation,
               "keep_kinematic_ik": kept}
    print(json.dumps(summary))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"summary": summary, "decisions": decisions}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
