"""A full Drake trial's figures: real-time factor, planning time per action (IK, checks, Ruckig), decisions.

    python benchmarks/bench_trial.py                 # the default trial (3 objects, seed 7)
    python benchmarks/bench_trial.py --objects 6 --seed 2
    python benchmarks/bench_trial.py --sleep         # with object sleep (slax_drake/systems/sleep.py)

Prints the load average too: the real-time factor depends on what else runs on the machine.
"""

import argparse
import os

import numpy as np


def main():
    from slax_drake.evaluation.trial import DEFAULT_OBJECTS, DEFAULT_SEED, TrialOptions, run_trial

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--objects", type=int, default=DEFAULT_OBJECTS)
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED)
    parser.add_argument("--policy", default="bluction-dar")
    parser.add_argument("--sleep", action="store_true", help="lock resting objects out of the physics step")
    args = parser.parse_args()
    load_before = os.getloadavg()[0]
    d = run_trial(TrialOptions(objects=args.objects, seed=args.seed, policy=args.policy, sleep=args.sleep)).data
    print(f"{args.objects} objects, seed {args.seed}, {args.policy}, sleep {'on' if args.sleep else 'off'}: "
          f"success {d['success']} ({d['result']}), {d['steps']} actions, cost {d['cost']}")
    print(f"simulated {d['sim_time_s']:.1f} s in {d['wall_s']:.1f} s wall: real-time factor {d['real_time_factor']:.2f} "
          f"(setup {d['setup_s']:.1f} s); 1-min load average {load_before:.2f} before, {os.getloadavg()[0]:.2f} after "
          f"on {os.cpu_count()} cores")
    for a in d["actions"]:
        t = a["motion"]["timings"]
        print(f"  {a['type']:>7} {a['object']}: planning {t['total_s'] * 1000:.0f} ms (world {t['world_s'] * 1000:.0f}, "
              f"IK {t['ik_s'] * 1000:.0f} in {t['ik_solves']} solves, checks {t['check_s'] * 1000:.0f}, "
              f"Ruckig {t['timing_s'] * 1000:.0f}); policy decision {a['decision_s'] * 1000:.0f} ms; "
              f"motion {a['motion']['duration_s']:.1f} s; {len(a['rejected_before'])} rejected before")
    if d["actions"]:
        totals = np.array([a["motion"]["timings"]["total_s"] for a in d["actions"]])
        print(f"planning per executed action: median {np.median(totals) * 1000:.0f} ms, max {totals.max() * 1000:.0f} ms")


if __name__ == "__main__":
    main()
