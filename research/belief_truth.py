"""Does slax-belief keep the true target in its belief? For chosen Table I trials (privileged observation, ground-truth
distributions, the benchmark's scene seeds), prints per decision: the number of lattice placements still
consistent, whether the lattice node nearest to the true target centre is among them, how many consistent nodes lie
within one grid step of it (in x and in y), that node's weight, and the action chosen. Then, per trial, the first
decision at which the nearest node left the belief and the first at which every node within one step had left.

A belief that lost the target could never find it; one that kept it and still failed spent its actions badly.

    python research/belief_truth.py 10:9 6:29 [--profile paper] [--seed 0] [--config sim_configs/table1.yaml]
        [--quiet]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import run_trial


def truth_rows(policy, truth_xy: np.ndarray, decide):
    """Wraps ``decide`` so that each call appends (placements, nearest node kept, nodes within a step, weight,
    action) to the returned list."""
    rows = []
    step = policy.grid_step
    node = (int(round(truth_xy[0] / step)), int(round(truth_xy[1] / step)))

    def wrapped(obs):
        decision = decide(obs)
        keys = policy.consistent_placements
        near = sum(1 for k in keys if abs(k[0] * step - truth_xy[0]) <= step and abs(k[1] * step - truth_xy[1]) <= step)
        rows.append((len(keys), node in keys, near, policy.placement_weight(node),
                     decision.best.describe() if decision.best is not None else None))
        return decision

    return rows, wrapped


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trials", nargs="+", help="density:index")
    ap.add_argument("--profile", default="paper")
    ap.add_argument("--seed", type=int, default=0, help="the protocol seed")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    ap.add_argument("--quiet", action="store_true", help="one line per trial")
    args = ap.parse_args()
    scenario = load_scenario(args.config)
    try:
        trials = [tuple(int(v) for v in spec.split(":")) for spec in args.trials]
        if any(len(t) != 2 for t in trials):
            raise ValueError
    except ValueError:
        print(f"error: trials must be density:index pairs such as 10:9 (got {' '.join(args.trials)})", file=sys.stderr)
        return 2
    for density, index in trials:
        scene = protocol_scene(scenario, density, scene_seed(args.seed, density, index))
        horizon = scenario.protocol.horizon_per_object * density
        policy = make_policy("slax-belief", scenario, horizon=horizon, profile=args.profile)
        truth = np.asarray(scene.target.X_ST[:2, 3], dtype=float)
        rows, policy.decide = truth_rows(policy, truth, policy.decide)
        result = run_trial(scene, policy, horizon, threshold=scenario.target.visibility_threshold,
                           suction_cost=scenario.protocol.suction_cost, density=density)
        node_left = next((i for i, r in enumerate(rows) if not r[1]), None)
        all_left = next((i for i, r in enumerate(rows) if r[2] == 0), None)
        print(f"{density:02d}_{index:04d} revealed={result.success} steps={result.steps} target=({truth[0]:+.3f}, "
              f"{truth[1]:+.3f}) m nearest node left at decision {node_left}, every node within a step left at "
              f"{all_left}; placements {rows[0][0] if rows else 0} -> {rows[-1][0] if rows else 0}", flush=True)
        if not args.quiet:
            for i, (count, kept, near, weight, action) in enumerate(rows):
                print(f"  {i:2d} placements={count} nearest_kept={kept} within_step={near} weight={weight:g} "
                      f"action={action}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
