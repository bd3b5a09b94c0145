"""How well slax-belief's ``extent_risk`` tells a failing first move from one that goes as planned, in camera mode:
runs chosen Table I trials with today's slax-belief (the risk computed for every first move but given no weight,
so the trials take the default's actions), and counts the executed actions by kind and by how many of the
:data:`~slax_drake.policies.extents.EXTENT_DRAWS` joint draws of the seen objects' extents made them fail, with how
many of them did not go as planned in the shelf simulator (put back, stopped early, blocked: a simulator note).

    python research/extent_risk_calibration.py --trials 10:0-14 [--profile paper] [--seed 0]
        [--config sim_configs/table1.yaml]

The trials are the benchmark's (`slax-drake benchmark`: the same scene seed per protocol seed, density and index;
label segmentation, ground-truth distributions).
"""

import argparse
import collections
import re
import sys

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.extents import EXTENT_DRAWS
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import CameraObserver, run_trial

WEIGHTLESS = 1e-9  # the extent_risk factor that computes the risk without moving any choice


def parse_trials(text: str) -> list[tuple[int, int]]:
    """"10:0-9,8:3" -> [(10, 0), ..., (10, 9), (8, 3)]."""
    out = []
    for part in text.split(","):
        density, _, indices = part.partition(":")
        lo, _, hi = indices.partition("-")
        out += [(int(density), i) for i in range(int(lo), int(hi or lo) + 1)]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", required=True, help="density:index or density:first-last, comma separated")
    ap.add_argument("--profile", default="paper")
    ap.add_argument("--seed", type=int, default=0, help="the protocol seed")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    args = ap.parse_args(argv)
    try:
        trials = parse_trials(args.trials)
    except ValueError:
        print(f"error: --trials: density:index pairs such as 10:0-14 (got {args.trials})", file=sys.stderr)
        return 2
    scenario = load_scenario(args.config)
    size = tuple(scenario.target.sizes[0])
    counts = collections.defaultdict(lambda: [0, 0])  # (kind, failing draws) -> [actions, not as planned]
    for density, index in trials:
        seed = scene_seed(args.seed, density, index)
        scene = protocol_scene(scenario, density, seed)
        horizon = scenario.protocol.horizon_per_object * density
        policy = make_policy("slax-belief", scenario, horizon=horizon, profile=args.profile,
                             policy_options={"extent_risk": WEIGHTLESS})
        draws_failed = watch_first_moves(policy)
        observer = CameraObserver(scene.shelf, scene.camera, size, width=policy.observation_width)
        result = run_trial(scene, policy, horizon, threshold=scenario.target.visibility_threshold,
                           suction_cost=scenario.protocol.suction_cost, density=density, observer=observer)
        noted = {int(m.group(1)) for note in result.notes for m in [re.match(r"step (\d+):", note)] if m}
        for step, (action, failing) in enumerate(zip(result.actions, draws_failed), start=1):
            entry = counts[(action.split()[0], failing)]
            entry[0] += 1
            entry[1] += step in noted
    print(f"{'kind':<8} {'failing draws':>13} {'actions':>8} {'not as planned':>15}")
    for (kind, failing), (n, bad) in sorted(counts.items()):
        print(f"{kind:<8} {f'{failing} of {EXTENT_DRAWS}':>13} {n:>8} {bad:>8} ({bad / n:.0%})")
    return 0


def watch_first_moves(policy) -> list[int]:
    """Wraps ``policy.decide`` so that each decision appends to the returned list how many joint draws made its
    first move fail (read from the policy's per-decision cache)."""
    out = []
    decide = policy.decide

    def watched(obs):
        decision = decide(obs)
        if decision.candidates:
            risk = policy._extent_cache.get(decision.candidates[0], 0.0)
            out.append(int(round(risk / WEIGHTLESS * EXTENT_DRAWS)))
        return decision

    policy.decide = watched
    return out


if __name__ == "__main__":
    raise SystemExit(main())
