"""Planning time per action (IK, collision checks, Ruckig timing) on sampled sim-shelf scenes.

For each scene, the action model's candidates are planned (the first push per object and direction and the
first suction per object, as a policy would try them); prints per-kind median and max wall time of the
planner's stages and the fraction of candidates with a feasible motion.

    python benchmarks/bench_planning.py --scenes 5 --objects 6
"""

import argparse
import collections
import os
import time

import numpy as np


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--scenes", type=int, default=5)
    parser.add_argument("--objects", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.shelf.actions import ActionModel
    from slax_drake.shelf.tool import tool_config
    from slax_drake.scene.sampling import sample_scene, shelf_of
    from slax_drake.station.scenario import load_station_scenario

    station = load_station_scenario()
    scenario = load_scenario(station.scene_config)
    tool = tool_config(scenario)
    planner = MotionPlanner(station, tool)
    rows = collections.defaultdict(list)
    outcomes = collections.Counter()
    durations = collections.defaultdict(list)
    for k in range(args.scenes):
        scene = sample_scene(scenario, args.objects, seed=args.seed + k)
        model = ActionModel(shelf_of(scenario), scene.camera.position, tool)
        seen = set()
        t0 = time.perf_counter()
        planner.world(scene)
        rows["world build"].append(time.perf_counter() - t0)
        for action in model.enumerate(scene.objects).feasible:
            key = (action.name, action.kind, getattr(action, "d", 0) > 0)
            if key in seen:
                continue
            seen.add(key)
            result = planner.plan(action, scene)
            t = result.timings
            rows[f"{action.kind} total"].append(t["total_s"] - t["world_s"])
            for stage in ("ik_s", "check_s", "timing_s"):
                rows[f"{action.kind} {stage[:-2]}"].append(t[stage])
            outcomes[(action.kind, result.feasible)] += 1
            if result.feasible:
                durations[action.kind].append(result.trajectory.duration)
    print(f"cpu threads available: {os.cpu_count()}; scenes {args.scenes} x {args.objects} objects")
    for name, values in rows.items():
        v = np.array(values)
        print(f"{name:>18}: median {np.median(v) * 1000:7.1f} ms   max {v.max() * 1000:7.1f} ms   (n={len(v)})")
    for kind in ("push", "suction"):
        ok, bad = outcomes[(kind, True)], outcomes[(kind, False)]
        dur = np.median(durations[kind]) if durations[kind] else float("nan")
        print(f"{kind}: {ok}/{ok + bad} candidates feasible; median motion duration {dur:.1f} s")


if __name__ == "__main__":
    main()
