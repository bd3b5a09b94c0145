"""Why the motion planner rejects a suction of one object of a Table I scene: planner variants and per-waypoint reach.

For the suction candidates of ``--object`` (optionally only those with ``--dx``) that the station's action model
offers on the initial state of Table I scene ``--index`` at ``--objects`` objects (the protocol's scene seeds, as in
``research/reach_rule.py``), prints the planner's verdict as shipped and under two variants that test the usual
suspects of a carry failure, each on a fresh planner:

- ``loose-hold``: the IK tolerances while the cup holds the object set to IK's defaults (0.5 mm, 0.01 rad)
  instead of ``HOLD_POSITION_TOLERANCE`` / ``HOLD_ANGLE_TOLERANCE`` (0.1 mm, 1 mrad);
- ``more-seeds``: 4x the random seeds of the seed library and 3x the re-anchorings.

Then, for the first rejected candidate, each waypoint of its first pull-out option: whether the planner's
first-waypoint search (:meth:`MotionPlanner.reaches`, the seed library, collision-free, no contact allowed) reaches
it, how many of ``--probe-seeds`` seeded random configurations give an IK solution (default tolerances), how many of
those are collision-free, and the bodies the colliding ones meet most often. A diagnostic, not a benchmark: the
variants are not planner settings.

    python research/diagnose_carry.py --objects 10 --index 0 --object object_9 --dx -0.05
"""

from __future__ import annotations

import argparse
import collections
import sys
import time

import numpy as np


def _plan_all(make_checker, scene, station, actions, patch):
    import slax_drake.planning.planner as planner_module

    saved = {k: getattr(planner_module, k) for k in patch}
    try:
        for k, v in patch.items():
            setattr(planner_module, k, v)
        checker = make_checker(scene, station)
        out = []
        for action in actions:
            t0 = time.perf_counter()
            result = checker.planner.plan(action, checker.scene)
            out.append((result, time.perf_counter() - t0))
        return out
    finally:
        for k, v in saved.items():
            setattr(planner_module, k, v)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="sim_configs/table1.yaml")
    parser.add_argument("--station", default="sim_configs/station_sim_shelf.yaml")
    parser.add_argument("--objects", type=int, required=True)
    parser.add_argument("--index", type=int, default=0, help="the protocol's scene index at that density")
    parser.add_argument("--object", required=True, help="the suctioned object's name, e.g. object_9")
    parser.add_argument("--dx", type=float, default=None, help="only the candidates with this dx (m)")
    parser.add_argument("--probe-seeds", type=int, default=30)
    args = parser.parse_args(argv)
    from pydrake.math import RigidTransform

    import slax_drake.planning.planner as planner_module
    from slax_drake.config import load_scenario
    from slax_drake.errors import UserError
    from slax_drake.evaluation.table1 import scene_seed
    from slax_drake.hardware.check_action import make_checker
    from slax_drake.planning.ik import solve_tool_pose
    from slax_drake.planning.waypoints import APPROACH_MARGIN, action_waypoints, pull_out_options
    from slax_drake.scene.sampling import sample_scene

    try:
        scenario = load_scenario(args.config)
        size = tuple(scenario.target.sizes[0])
        scene = sample_scene(scenario, args.objects, scene_seed(scenario.protocol.seed, args.objects, args.index),
                             target_size=size)
        checker = make_checker(scene, args.station)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    actions = [a for a in checker.candidates().feasible if a.name == args.object and a.kind == "suction"
               and (args.dx is None or abs(a.dx - args.dx) < 1e-9)]
    if not actions:
        print(f"error: no suction of {args.object} offered in that scene", file=sys.stderr)
        return 2
    variants = {
        "shipped": {},
        "loose-hold": {"HOLD_POSITION_TOLERANCE": 5e-4, "HOLD_ANGLE_TOLERANCE": 1e-2},
        "more-seeds": {"NUM_RANDOM_SEEDS": 4 * planner_module.NUM_RANDOM_SEEDS,
                       "MAX_REANCHORS": 3 * planner_module.MAX_REANCHORS},
    }
    results = {name: _plan_all(make_checker, scene, args.station, actions, patch) for name, patch in variants.items()}
    print(f"{args.objects} objects, scene {args.index}: {len(actions)} suction candidates of {args.object}")
    for i, action in enumerate(actions):
        print(f"  dx {action.dx:+.2f} dz {action.dz:+.3f} yaw {action.yaw:+.3f}:")
        for name in variants:
            result, dt = results[name][i]
            verdict = "planned" if result.feasible else result.reason.split(" [")[0][:110]
            print(f"    {name:11s} {dt:6.2f} s  {verdict}")
    rejected = [a for a, (r, _) in zip(actions, results["shipped"]) if not r.feasible]
    if not rejected:
        return 0
    action = rejected[0]
    planner, world_scene = checker.planner, checker.scene
    world = planner.world(world_scene)
    obj = next(o for o in world_scene.objects if o.name == action.name)
    pull = pull_out_options(action, obj, world_scene.shelf, world_scene.target, APPROACH_MARGIN)[0]
    lim = planner.limits
    lo = np.where(np.isfinite(lim.position_lower), lim.position_lower, -np.pi)
    hi = np.where(np.isfinite(lim.position_upper), lim.position_upper, np.pi)
    rng = np.random.default_rng(0)
    probes = []
    for _ in range(args.probe_seeds):
        s = rng.uniform(lo, hi)
        s[-1] = planner.q_observation[-1]
        probes.append(s)
    print(f"waypoints of dx {action.dx:+.2f} carried across at y = {pull:+.3f} (S, m); probe: {len(probes)} seeds")
    print(f"  {'waypoint':12s} {'x':>7s} {'y':>7s} {'z':>7s} {'reaches':>8s} {'IK':>4s} {'free':>5s}  most hit")
    for wp in action_waypoints(action, world_scene.objects, world_scene.shelf, planner.tool, pull_to=pull):
        reaches = planner.reaches(world_scene, wp)
        solved = free = 0
        hits = collections.Counter()
        world.allow_tool_contact(action.name, False)
        for s in probes:
            q = solve_tool_pose(world, wp.frame, RigidTransform(wp.X_SF), s, wp.shaft)
            if q is None:
                continue
            solved += 1
            if world.config_free(q):
                free += 1
            else:
                hits.update(world.colliding_bodies(q))
        x, y, z = wp.position
        top = ", ".join(f"{b} x{c}" for b, c in hits.most_common(3))
        print(f"  {wp.label:12s} {x:7.3f} {y:7.3f} {z:7.3f} {str(reaches):>8s} {solved:4d} {free:5d}  {top}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
