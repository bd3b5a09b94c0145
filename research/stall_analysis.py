"""Where slax-belief's failed trials stall, and what could still reveal the target from there.

A stall is the first decision at which the policy's search finds no plan that reveals any of the belief's worlds
(its decision log's ``revealed`` is 0, after the widened beam): from then on the policy picks the move that brings
its worlds nearest to being revealed. For each chosen Table I trial (the benchmark's scene seeds, the registry's
slax-belief, the protocol's horizon) it prints the outcome and, when the trial stalled:

- ``truth``: the distance (m) from the true target to the nearest placement the belief still holds, and how many
  it holds (is the target where the policy thinks it may be?);
- ``oracle``: Oracle-P+S (the true scene, ``--oracle-seconds`` per search) from the shelf as it stood at the stall,
  with the actions left: revealed / no plan within the horizon / search cut by time;
- ``believed``: the same oracle on the policy's own shelf (its seen objects as estimated, the objects remembered
  hidden left out) with the true target: does the policy's model of the shelf hold a plan?
- with ``--variants``: the stalled decision searched again from a copy of the policy as it stood, with the
  corrections off (no return to an observed arrangement, no shuttle; exclusions kept), told where the target
  stands, both, and with twice the beam: the share of the belief the best plan reveals and its first move.

Then the counts, with the actions taken and the moves back chosen (against their object's last move: the trial
record's ``reversal_rule``) before a stall and from it on. A diagnostic, never a policy: the oracle and the told
target read the scene's hidden state.

``--census FOLDER``: no trial is run; the trial files of a ``slax-drake benchmark`` folder (``--policy``, default
slax-belief, which keeps a decision log) are read instead: per density, the trials that stalled, those revealed
after their stall, and the actions taken from the stall on. A ``--physics`` results folder (its ``physics.json``,
as ``docs/results`` keeps it) is read for its Drake trials instead, with the nothing-lost reveals, and what a
policy that stops at its stall (``stuck_select`` "stop", variant ``slax-belief-stall-stop``) would have done: it
decides as the policy did up to the stall, so its trials are these trials cut there.

    python research/stall_analysis.py --trials 4:0-19,6:0-19,8:0-19,10:0-19 --config sim_configs/table1_household.yaml \\
        --profile station --tool-rule max_drag_pull=42.412 ... [--observation camera [--full-resolution]]
        [--oracle-seconds 5] [--variants] [--seed 0]
    python research/stall_analysis.py --census RESULTS_FOLDER [--policy slax-belief]
    python research/stall_analysis.py --census docs/results/physics_belief_household_20580ad
"""

import argparse
import collections
import copy
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from belief_variants import parse_trials, tell_target  # noqa: E402

from slax_drake.config import load_scenario  # noqa: E402
from slax_drake.errors import UserError  # noqa: E402
from slax_drake.evaluation.table1 import protocol_scene, scene_seed  # noqa: E402
from slax_drake.policies.registry import make_policy  # noqa: E402
from slax_drake.shelf.simulator import CameraObserver, run_trial  # noqa: E402
from slax_drake.shelf.tool import parse_tool_rules  # noqa: E402

VARIANTS = ("corrections off", "target told", "told, corrections off", "beam x2")


class StallWatch:
    """Wraps a policy's ``decide`` (and ``placements``) for one trial: keeps a copy of the policy before each
    decision until the first stall, and at the stall the true shelf, the step, the policy's objects, the belief's
    placements and (``variants``) the stalled decision searched again from that copy under each of
    :data:`VARIANTS`."""

    def __init__(self, policy, variants: bool):
        self.policy, self.variants = policy, variants
        self.scene = None  # the true shelf of the current step (set by the observer or by run_trial's hook)
        self.step = 0
        self.stall = None  # dict once stalled
        self._placements = None
        self.moves_back = collections.Counter()  # chosen moves against their object's last move (reversal_rule)
        self._decide, self._place = policy.decide, policy.placements
        policy.decide, policy.placements = self.decide, self.placements

    def placements(self, obs):
        out = self._place(obs)
        self._placements = out
        return out

    def _copy(self):
        p = self.policy
        hooks = p.__dict__.pop("decide"), p.__dict__.pop("placements")
        try:
            return copy.deepcopy(p)
        finally:
            p.decide, p.placements = hooks

    def decide(self, obs):
        before = self._copy() if self.stall is None and self.variants else None
        decision = self._decide(obs)
        back = decision.best is not None and self.policy.reversal_rule(decision.best) is not None
        log = self.policy.decision_log[-1] if self.policy.decision_log else {}
        if self.stall is None and decision.best is not None and float(log.get("revealed", 1.0)) == 0.0:
            truth = self.scene.target.X_ST[:2, 3]
            placements = np.asarray(self._placements if self._placements is not None else np.zeros((0, 2)))
            gap = float(np.min(np.hypot(placements[:, 0] - truth[0], placements[:, 1] - truth[1]))) \
                if len(placements) else None
            self.stall = {"step": self.step, "scene": self.scene, "objects": tuple(self.policy._objects),
                          "truth_gap": gap, "placements": int(len(placements)), "variants": {}}
            if before is not None:
                for name in VARIANTS:
                    again = copy.deepcopy(before)
                    if "corrections off" in name:
                        again.corrected = False
                    if "told" in name:
                        tell_target(again, self.scene)
                    if name == "beam x2":
                        again.beam, again.widen_beam = 2 * again.beam, 2 * again.widen_beam
                    d = type(again).decide(again, obs)
                    revealed = float(again.decision_log[-1].get("revealed", 0.0)) if again.decision_log else 0.0
                    self.stall["variants"][name] = (revealed, d.best.describe() if d.best else d.stop_reason)
        if back:
            self.moves_back["from the stall on" if self.stall is not None else "before"] += 1
        self.step += 1
        return decision


class SceneTap:
    """An observer wrapper that records the true shelf it is shown (camera mode), for :class:`StallWatch`."""

    def __init__(self, observer, watch: StallWatch):
        self.observer, self.watch = observer, watch

    def __getattr__(self, name):
        return getattr(self.observer, name)

    def observe(self, scene):
        self.watch.scene = scene
        return self.observer.observe(scene)


class PrivilegedTap:
    """In privileged mode run_trial shows the policy the observation of the true shelf; this hook keeps the shelf
    for :class:`StallWatch` by wrapping :func:`slax_drake.shelf.simulator.observation_for`."""

    def __init__(self, watch: StallWatch):
        import slax_drake.shelf.simulator as simulator

        self.simulator, self.watch = simulator, watch
        self.original = simulator.observation_for

        def observation_for(policy, scene):
            watch.scene = scene
            return self.original(policy, scene)

        simulator.observation_for = observation_for

    def close(self):
        self.simulator.observation_for = self.original


def oracle_from(scenario, scene, left: int, density: int, rules: dict, profile: str, seconds: float):
    oracle = make_policy("oracle-p+s", scenario, horizon=left, profile=profile, tool_overrides=rules,
                         oracle_options={"seconds": seconds})
    return run_trial(scene, oracle, left, threshold=scenario.target.visibility_threshold,
                     suction_cost=scenario.protocol.suction_cost, density=density)


def census_physics(path: Path, policy: str) -> int:
    """``--census`` of a physics results folder's ``physics.json`` (``path``): the Drake trials' stalls (each
    record's ``stall``: [the step of the stall or None, the actions from it on]) and the same trials cut at their
    stall (see the module docstring)."""
    import json

    try:
        trials = [t for t in json.loads(path.read_text())["trials"] if t["policy"] == policy]
        records = [(int(t["density"]), t["stall"][0], int(t["stall"][1]), bool(t["drake_success"]),
                    bool(t["drake_clean_success"]), int(t["drake_steps"])) for t in trials]
    except (OSError, ValueError, KeyError, TypeError, IndexError) as e:
        print(f"error: {path}: unreadable physics record ({type(e).__name__}: {e})", file=sys.stderr)
        return 2
    if not records:
        print(f"error: {path}: no Drake trials of {policy}", file=sys.stderr)
        return 2
    rows = collections.defaultdict(collections.Counter)
    for density, stalled_at, after, success, clean, steps in records:
        stalled = stalled_at is not None
        for key in (density, "all"):
            row = rows[key]
            row["trials"] += 1
            row["revealed"] += success
            row["nothing lost"] += clean
            row["actions"] += steps
            row["stalled"] += stalled
            row["revealed after the stall"] += stalled and success
            row["nothing lost after the stall"] += stalled and clean
            row["actions from the stall on"] += after if stalled else 0
    print(f"{path} ({policy}, Drake): per density, trials / revealed / nothing lost / stalled / revealed after the "
          "stall (nothing lost) / actions / actions from the stall on; stopped at the stall: revealed / nothing lost "
          "/ actions")
    for key in sorted(rows, key=lambda k: (k == "all", k if k != "all" else 0)):
        r = rows[key]
        print(f"  {key}: {r['trials']} / {r['revealed']} / {r['nothing lost']} / {r['stalled']} / "
              f"{r['revealed after the stall']} ({r['nothing lost after the stall']}) / {r['actions']} / "
              f"{r['actions from the stall on']}; stopped: {r['revealed'] - r['revealed after the stall']} / "
              f"{r['nothing lost'] - r['nothing lost after the stall']} / "
              f"{r['actions'] - r['actions from the stall on']}")
    return 0


def census(folder: Path, policy: str) -> int:
    """``--census``: the stalls of a benchmark folder's trial files, or of a physics folder's ``physics.json``
    (see the module docstring)."""
    import json

    from slax_drake.evaluation.physics import stall_step

    if (folder / "physics.json").is_file():
        return census_physics(folder / "physics.json", policy)

    files = sorted((folder / "trials" / policy).glob("*.json"))
    if not files:
        print(f"error: --census: no trial files in {folder / 'trials' / policy}", file=sys.stderr)
        return 2
    rows = collections.defaultdict(collections.Counter)
    for path in files:
        try:
            trial = json.loads(path.read_text())
            log = trial["decision_log"]
            if isinstance(log, str):  # files written before the decision log was stored as a list
                import ast

                log = ast.literal_eval(log)
            density, steps, success = int(trial["density"]), int(trial["steps"]), trial["success"] in (True, "True")
        except (OSError, ValueError, SyntaxError, KeyError, TypeError) as e:
            print(f"error: {path}: unreadable trial file ({type(e).__name__}: {e})", file=sys.stderr)
            return 2
        stalled = stall_step(log)
        for key in (density, "all"):
            row = rows[key]
            row["trials"] += 1
            row["revealed"] += success
            row["actions"] += steps
            if stalled is not None:
                row["stalled"] += 1
                row["revealed after the stall"] += success
                row["actions from the stall on"] += steps - stalled
    print(f"{folder} ({policy}): per density, trials / revealed / stalled / revealed after the stall / actions / "
          "actions from the stall on")
    for key in sorted(rows, key=lambda k: (k == "all", k if k != "all" else 0)):
        r = rows[key]
        print(f"  {key}: {r['trials']} / {r['revealed']} / {r['stalled']} / {r['revealed after the stall']} / "
              f"{r['actions']} / {r['actions from the stall on']}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", help="DENSITY:FIRST-LAST,... (Table I scene indices)")
    ap.add_argument("--census", type=Path, metavar="FOLDER", help="read a benchmark folder's trial files instead")
    ap.add_argument("--policy", default="slax-belief", help="with --census: the policy's trial files")
    ap.add_argument("--config", default="sim_configs/table1_household.yaml")
    ap.add_argument("--profile", default="station")
    ap.add_argument("--tool-rule", action="append", default=[], metavar="FIELD=VALUE")
    ap.add_argument("--observation", choices=("privileged", "camera"), default="camera")
    ap.add_argument("--full-resolution", action="store_true",
                    help="camera frames ray-cast at the camera's resolution and resampled, as beside Drake")
    ap.add_argument("--oracle-seconds", type=float, default=5.0)
    ap.add_argument("--variants", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.census is not None:
        return census(args.census, args.policy)
    if args.trials is None:
        print("error: --trials or --census is required", file=sys.stderr)
        return 2
    try:
        trials = parse_trials(args.trials)
    except ValueError:
        print(f"error: --trials: expected DENSITY:FIRST-LAST,... (got {args.trials!r})", file=sys.stderr)
        return 2
    try:
        rules = parse_tool_rules(args.tool_rule, args.profile)
        scenario = load_scenario(args.config)
    except (UserError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    counts = collections.Counter()
    for density, index in trials:
        seed = scene_seed(args.seed, density, index)
        scene = protocol_scene(scenario, density, seed)
        horizon = scenario.protocol.horizon_per_object * density
        policy = make_policy("slax-belief", scenario, horizon=horizon, profile=args.profile, tool_overrides=rules)
        watch = StallWatch(policy, args.variants)
        observer, tap = None, None
        if args.observation == "camera":
            observer = SceneTap(CameraObserver(scene.shelf, scene.camera, tuple(scenario.target.sizes[0]),
                                               width=policy.observation_width,
                                               full_resolution=args.full_resolution), watch)
        else:
            tap = PrivilegedTap(watch)
        t0 = time.process_time()
        try:
            result = run_trial(scene, policy, horizon, threshold=scenario.target.visibility_threshold,
                               suction_cost=scenario.protocol.suction_cost, density=density, observer=observer)
        finally:
            if tap is not None:
                tap.close()
        line = f"{density:02d}_{index:04d} revealed={result.success} ending={result.reason!r} steps={result.steps}"
        counts["trials"] += 1
        counts["revealed"] += bool(result.success)
        counts["actions"] += result.steps
        counts["moves back before a stall"] += watch.moves_back["before"]
        counts["moves back from a stall on"] += watch.moves_back["from the stall on"]
        stall = watch.stall
        if stall is not None:
            counts["actions from a stall on"] += result.steps - stall["step"]
        if stall is not None:
            counts["stalled"] += 1
            counts["stalled, then revealed"] += bool(result.success)
            left = horizon - stall["step"]
            truth = oracle_from(scenario, stall["scene"], left, density, rules, args.profile, args.oracle_seconds)
            believed_scene = dataclasses.replace(
                stall["scene"], objects=tuple(o for o in stall["objects"] if not o.remembered))
            believed = oracle_from(scenario, believed_scene, left, density, rules, args.profile, args.oracle_seconds)
            gap = "-" if stall["truth_gap"] is None else f"{stall['truth_gap']:.3f}"
            line += (f" | stall at decision {stall['step']}, {left} actions left; truth {gap} m from the nearest of "
                     f"{stall['placements']} placements; oracle: {truth.reason} ({truth.steps}); on the policy's "
                     f"shelf: {believed.reason} ({believed.steps})")
            if not result.success:
                counts[f"failed stall, oracle: {truth.reason}"] += 1
                if truth.success:
                    counts[f"  ... and on the policy's shelf: {believed.reason}"] += 1
                for name, (revealed, first) in stall["variants"].items():
                    line += f"\n    {name}: reveals {revealed:.2f} of the belief, first {first}"
                    if truth.success:
                        counts[f"  ... {name} finds a revealing plan"] += revealed > 0
        else:
            counts["did not stall, failed"] += not result.success
        print(line + f" [cpu {time.process_time() - t0:.0f} s]", flush=True)
    print("counts:")
    for key, n in counts.items():
        print(f"  {key}: {n}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
