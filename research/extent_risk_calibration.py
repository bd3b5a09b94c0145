"""How well slax-belief's ``extent_risk`` tells a failing first move from one that goes as planned, in camera mode:
runs chosen Table I trials with today's slax-belief (the risk computed for every first move but given no weight,
so the trials take the default's actions), and counts the executed actions by kind and by how many of the
:data:`~slax_drake.policies.extents.EXTENT_DRAWS` joint draws of the seen objects' extents made them fail (the
decision log's ``extent_draws_failed``), with how many of them did not go as planned in the shelf simulator (put
back, stopped early, blocked: a simulator note).

    python research/extent_risk_calibration.py --trials 10:0-14 [--profile paper] [--seed 0]
        [--config sim_configs/table1.yaml]

The trials are the benchmark's (`slax-drake benchmark`: the same scene seed per protocol seed, density and index;
label segmentation, ground-truth distributions).
"""

import argparse
import collections
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import UserError
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.policies.extents import EXTENT_DRAWS
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import CameraObserver, run_trial, split_note

sys.path.insert(0, str(Path(__file__).resolve().parent))
from belief_variants import parse_trials  # noqa: E402  (the research scripts' shared helpers)

WEIGHTLESS = 1e-9  # the extent_risk factor that computes the risk without moving any choice


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
    try:
        scenario = load_scenario(args.config)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    size = tuple(scenario.target.sizes[0])
    counts = collections.defaultdict(lambda: [0, 0])  # (kind, failing draws) -> [actions, not as planned]
    for density, index in trials:
        seed = scene_seed(args.seed, density, index)
        scene = protocol_scene(scenario, density, seed)
        horizon = scenario.protocol.horizon_per_object * density
        policy = make_policy("slax-belief", scenario, horizon=horizon, profile=args.profile,
                             policy_options={"extent_risk": WEIGHTLESS})
        observer = CameraObserver(scene.shelf, scene.camera, size, width=policy.observation_width)
        result = run_trial(scene, policy, horizon, threshold=scenario.target.visibility_threshold,
                           suction_cost=scenario.protocol.suction_cost, density=density, observer=observer)
        noted = {split_note(note)[0] for note in result.notes}  # the steps whose action did not go as planned
        for step, (action, log) in enumerate(zip(result.actions, policy.decision_log), start=1):
            if "extent_draws_failed" not in log:  # no search at that decision (no placement left)
                continue
            entry = counts[(action.split()[0], log["extent_draws_failed"])]
            entry[0] += 1
            entry[1] += step in noted
    print(f"{'kind':<8} {'failing draws':>13} {'actions':>8} {'not as planned':>15}")
    for (kind, failing), (n, bad) in sorted(counts.items()):
        print(f"{kind:<8} {f'{failing} of {EXTENT_DRAWS}':>13} {n:>8} {bad:>8} ({bad / n:.0%})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
