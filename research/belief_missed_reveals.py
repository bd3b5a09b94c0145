"""Why does slax-belief miss a reveal that Oracle-P+S makes in 1-3 actions? For chosen Table I trials (privileged
observation, ground-truth distributions, the benchmark's scene seeds) it replays slax-belief and, at each of its
decisions, asks the exact oracle (which knows the target) for its cheapest revealing plan from the true state there,
then looks that plan up in slax-belief's own search:

- is the true target's lattice node still in the belief (and its weight)?
- is the oracle's first move among slax-belief's first moves at all, and if not, what removed it: not enumerated on
  the seen objects (an unseen neighbour changes a push's reach), a blocked placement region, the corrections'
  exclusions, the "only the least risky placement that hides no world's target" rule (``aside``), or the
  ``placements_per_object`` cut?
- is the whole plan among the plans the beam looked at; its revealed mass R, expected cost G, R / G and value V
  (and R / G with no placement risk), against the chosen plan's;
- the share of the whole (weighted) belief, not just the sampled worlds, that the oracle's plan reveals;
- how many single moves from here reveal the true target, and how many of them slax-belief looks at.

Each decision gets a cause (:func:`classify`): "truth left the belief", "not a candidate", "ranked below",
"risk penalty", "oracle found no plan" or "other"; a trial's cause is its first decision's (the oracle's plan
from the scene as generated), and the counts over all its decisions are printed too. Prints Markdown.

    python research/belief_missed_reveals.py 6:29 10:9 [--policy slax-belief] [--options JSON] [--profile paper]
        [--seed 0] [--oracle-seconds 5] [--decisions N] [--config sim_configs/table1.yaml]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time

import numpy as np

CAUSES = ("truth left the belief", "not a candidate", "ranked below", "risk penalty", "oracle found no plan", "other")


@dataclasses.dataclass
class Probe:
    """What one decision of slax-belief looked like, measured against the oracle's plan from the true state."""

    step: int
    truth_kept: bool  # the lattice node nearest the true target centre is in the belief
    truth_near: int  # belief nodes within one grid step of the true centre (x and y)
    truth_weight: float  # that node's weight (1 unless outcome evidence changed it)
    oracle_plan: list | None  # the oracle's revealing plan from the true state (descriptions); None: none found
    oracle_status: str  # the oracle search's status ("optimal", "cut by time", ...)
    first_status: str  # "first level", or why the oracle's first move is not among slax-belief's first moves
    in_search: bool  # the oracle's whole plan is among the plans slax-belief's beam looked at
    plan_unseen: bool = False  # a move of the oracle's plan acts on an object slax-belief does not see
    oracle_r: float = 0.0  # its revealed mass R (share of sampled worlds, risk-weighted)
    oracle_g: float = 0.0  # its expected cost G
    oracle_v: float = 0.0  # its value V
    oracle_r_norisk: float = 0.0  # R with every placement risk 0
    oracle_risk: float = 0.0  # the placement risk of its first move (0 for a push)
    belief_share: float = 0.0  # the share of the whole weighted belief its arrangements reveal
    chosen_plan: list = dataclasses.field(default_factory=list)
    chosen_r: float = 0.0
    chosen_g: float = 0.0
    chosen_v: float = 0.0
    true_reveals: int = 0  # single moves on the seen objects that reveal the true target from here
    true_reveals_looked: int = 0  # ... of them among slax-belief's first moves (after its pruning)
    best_true_ratio: float = 0.0  # the best R / G among those looked at

    @property
    def oracle_ratio(self) -> float:
        return self.oracle_r / max(self.oracle_g, 1e-9)

    @property
    def oracle_ratio_norisk(self) -> float:
        return self.oracle_r_norisk / max(self.oracle_g, 1e-9)

    @property
    def chosen_ratio(self) -> float:
        return self.chosen_r / max(self.chosen_g, 1e-9)

    @property
    def would_win(self) -> bool:
        """The oracle's plan reveals some sampled world and its R / G is at least the chosen plan's: slax-belief's
        own rule would have taken it, had it looked at it."""
        return self.oracle_r > 0 and self.oracle_ratio >= self.chosen_ratio - 1e-9


def classify(p: Probe) -> tuple[str, str]:
    """(the cause, one of :data:`CAUSES`; a detail) for a decision that did not take the oracle's plan.

    In order: no oracle plan; the truth (and every node within a step of it) out of the belief; the oracle's plan
    not among slax-belief's candidate plans (its first move pruned, or a move on an object it does not see;
    detail: what removed it, and whether its R / G would have won); the plan not looked at by the beam although
    its R / G would win ("ranked below", by V, the beam's order); its R / G below the chosen plan's: "risk
    penalty" when it would rank above with no placement risk, else "ranked below"; "other" when it ranks at
    least as high and was looked at (a tie, or the chosen plan is the oracle's)."""
    if p.oracle_plan is None:
        return "oracle found no plan", ""
    if not p.truth_kept and p.truth_near == 0:
        return "truth left the belief", ""
    if p.first_status != "first level" or p.plan_unseen:
        what = p.first_status if p.first_status != "first level" else "a later move on an unseen object"
        return "not a candidate", what + ("; would win" if p.would_win else "")
    if p.would_win:
        if p.in_search or p.oracle_plan == p.chosen_plan[: len(p.oracle_plan)]:
            return "other", "looked at, ranks as high"
        return "ranked below", "by the beam's V, not looked at; would win"
    if p.oracle_r_norisk > 0 and p.oracle_ratio_norisk > p.chosen_ratio + 1e-9:
        return "risk penalty", ""
    return "ranked below", "less R / G" + (" (reveals no sampled world)" if p.oracle_r == 0 else "")


def cause_counts(causes: list) -> dict:
    """{cause: count} in the order of :data:`CAUSES`, the causes that occur only."""
    return {c: causes.count(c) for c in CAUSES if causes.count(c)}


def main_cause(causes: list) -> str:
    """The most frequent of ``causes`` but "oracle found no plan" (ties: the first in :data:`CAUSES`);
    "oracle found no plan" when there is no other."""
    counts = cause_counts([c for c in causes if c != "oracle found no plan"])
    if not counts:
        return "oracle found no plan"
    return max(counts, key=lambda c: (counts[c], -CAUSES.index(c)))


class SearchTap:
    """Wraps a BeliefSearch's methods so that each decision's search is kept: the worlds, the root node, the first
    moves (``cands``: after exclusions and blocked regions), the first level's nodes and every plan looked at."""

    def __init__(self, policy):
        self.policy = policy
        self.last: dict = {}
        expansions, beam_search, candidates = policy.expansions, policy.beam_search, policy.action_model_candidates

        def tapped_candidates(objects):
            out = candidates(objects)
            self.last = {"cands": list(out), "seen": []}
            return out

        def tapped_expansions(worlds, node, moves, remaining, counter):
            kids = expansions(worlds, node, moves, remaining, counter)
            if not node.plan:
                self.last.update(worlds=worlds, root=node, remaining=remaining, first=list(kids))
            return kids

        def tapped_beam_search(*args, **kwargs):
            nodes = beam_search(*args, **kwargs)
            self.last["seen"].extend(nodes)
            return nodes

        policy.action_model_candidates = tapped_candidates
        policy.expansions = tapped_expansions
        policy.beam_search = tapped_beam_search


def chain(policy, worlds, root, plan: list, remaining: int, risk: bool = True):
    """slax-belief's node for ``plan`` (actions) from ``root`` (:meth:`BeliefSearch.child` step by step); with
    ``risk`` False, every placement risk taken as 0."""
    import itertools

    from slax_drake.shelf.actions import apply_action

    counter = itertools.count(10 ** 9)
    saved = policy.placement_risk
    if not risk:
        policy.placement_risk = lambda objects, a: 0.0
    try:
        node = root
        for a in plan:
            node = policy.child(worlds, node, a, apply_action(node.objects, a), policy.move_cost(node.objects, a),
                                remaining, next(counter))
    finally:
        policy.placement_risk = saved
    return node


def first_move_status(policy, known, action, cands: list, first: list) -> str:
    """Why ``action`` (the oracle's first move) is, or is not, among the first moves slax-belief looked at."""
    from slax_drake.shelf.actions import Suction
    from slax_drake.policies.oracle_search import maximal_pushes_only

    text = action.describe()
    if text in {k.plan[0].describe() for k in first}:
        return "first level"
    if action.name not in {o.name for o in known}:
        return "object unseen"
    feasible = policy.action_model.enumerate(known, pushes=True, suctions=True).feasible
    if text not in {a.describe() for a in feasible}:
        return "not enumerated on the seen objects"
    if text not in {a.describe() for a in maximal_pushes_only(feasible)}:
        return "push not maximal on the seen objects"
    if isinstance(action, Suction) and not policy.placement_allowed(known, action):
        return "placement in a blocked region"
    if text not in {a.describe() for a in cands}:
        return "excluded (corrections)"
    if isinstance(action, Suction):
        from slax_drake.shelf.actions import apply_action

        moved = next(o for o in apply_action(known, action) if o.name == action.name)
        tap_worlds = policy.worlds
        if tap_worlds is not None and tap_worlds.mask(moved) is None:
            return "pruned: aside (hides no world's target, not the least risky)"
        return "pruned: placements_per_object"
    return "pruned (other)"


def belief_share(policy, template, plan: list, known) -> float:
    """The share of the whole weighted belief (every consistent lattice placement, not only the sampled worlds)
    whose target some arrangement along ``plan`` shows at v and no moved object overlaps."""
    from slax_drake.shelf.actions import apply_action
    from slax_drake.policies.hindsight import Worlds

    keys = sorted(policy.consistent_placements)
    if not keys:
        return 0.0
    centers = np.array(keys, dtype=float) * policy.grid_step
    weights = np.array([policy.placement_weight(k) for k in keys])
    worlds = Worlds(template, centers, policy.target_size(), policy.threshold)
    shown = np.zeros(len(keys), bool)
    blocked = np.zeros(len(keys), bool)
    objects = tuple(known)
    for a in plan:
        objects = apply_action(objects, a)
        blocked |= worlds.blocks(objects, a.name)
        shown |= worlds.revealed(objects) & ~blocked
    return float(weights[shown].sum() / weights.sum())


def true_single_reveals(policy, scene, known, first: list, threshold: float) -> tuple[int, int, float]:
    """(single moves on the seen objects that reveal the true target when executed on the true scene, how many of
    them are among slax-belief's first-level nodes, the best R / G among those)."""
    from slax_drake.shelf.simulator import execute
    from slax_drake.scene.sampling import target_visible_fraction

    by_text = {k.plan[0].describe(): k for k in first}
    count = looked = 0
    best = 0.0
    for a, _after, _c in policy.moves(known):
        after, _ = execute(scene, a, policy.action_model)
        if after is scene or target_visible_fraction(after) < threshold:
            continue
        count += 1
        k = by_text.get(a.describe())
        if k is not None:
            looked += 1
            best = max(best, k.revealed / max(k.g, 1e-9))
    return count, looked, best


def probe_decision(policy, tap: SearchTap, scene, step: int, oracle, remaining: int, threshold: float) -> Probe:
    """The :class:`Probe` of the decision slax-belief just made on ``scene`` (the true scene before its action)."""
    last = tap.last
    step_size = policy.grid_step
    truth = np.asarray(scene.target.X_ST[:2, 3], dtype=float)
    node_key = (int(round(truth[0] / step_size)), int(round(truth[1] / step_size)))
    keys = policy.consistent_placements
    near = sum(1 for k in keys if abs(k[0] * step_size - truth[0]) <= step_size + 1e-9
               and abs(k[1] * step_size - truth[1]) <= step_size + 1e-9)
    oracle.reset(scene)
    plan = oracle.search(scene, remaining)
    status = oracle.search_log[-1].get("status", "") if oracle.search_log else ""
    p = Probe(step=step, truth_kept=node_key in keys, truth_near=near,
              truth_weight=policy.placement_weight(node_key),
              oracle_plan=[a.describe() for a in plan] if plan else None, oracle_status=str(status),
              first_status="", in_search=False)
    log = policy.decision_log[-1] if policy.decision_log else {}
    p.chosen_plan = list(log.get("plan", []))
    if "root" not in last:
        p.first_status = "no search (no placements)"
        return p
    worlds, root, first = last["worlds"], last["root"], last["first"]
    seen = {tuple(a.describe() for a in k.plan): k for k in last["seen"]}
    best = seen.get(tuple(p.chosen_plan))
    if best is not None:
        p.chosen_r, p.chosen_g, p.chosen_v = best.revealed, best.g, best.value
    known = root.objects
    p.true_reveals, p.true_reveals_looked, p.best_true_ratio = true_single_reveals(policy, scene, known, first,
                                                                                   threshold)
    if not plan:
        return p
    p.first_status = first_move_status(policy, known, plan[0], last["cands"], first)
    if any(a.name not in {o.name for o in known} for a in plan):
        p.plan_unseen = True  # a move acts on an object slax-belief does not see: not evaluable in its search
        return p
    p.in_search = tuple(p.oracle_plan) in seen
    node = chain(policy, worlds, root, plan, last["remaining"])
    p.oracle_r, p.oracle_g, p.oracle_v = node.revealed, node.g, node.value
    p.oracle_r_norisk = chain(policy, worlds, root, plan, last["remaining"], risk=False).revealed
    p.oracle_risk = policy.placement_risk(known, plan[0])
    p.belief_share = belief_share(policy, policy.scene_template, plan, known)
    return p


def run(density: int, index: int, scenario, args) -> tuple[list[Probe], object]:
    """Replays the policy on Table I trial (density, index) with the benchmark's loop (the privileged observation,
    the first-order executor); returns the probes and the trial's outcome (revealed, actions)."""
    from slax_drake.evaluation.table1 import protocol_scene, scene_seed
    from slax_drake.policies.registry import make_policy
    from slax_drake.shelf.simulator import execute, observation_for
    from slax_drake.scene.sampling import target_visible_fraction

    threshold = scenario.target.visibility_threshold
    scene = protocol_scene(scenario, density, scene_seed(args.seed, density, index))
    horizon = scenario.protocol.horizon_per_object * density
    policy = make_policy(args.policy, scenario, horizon=horizon, profile=args.profile,
                         policy_options=json.loads(args.options))
    oracle = make_policy("oracle-p+s", scenario, horizon=horizon, profile=args.profile,
                         oracle_options={"seconds": args.oracle_seconds})
    tap = SearchTap(policy)
    policy.reset(scene)
    probes, actions = [], []
    for step in range(horizon):
        if target_visible_fraction(scene) >= threshold:
            break
        decision = policy.decide(observation_for(policy, scene))
        if decision.best is None:
            break
        if args.decisions is None or step < args.decisions:
            probes.append(probe_decision(policy, tap, scene, step, oracle, horizon - step, threshold))
        scene, _ = execute(scene, decision.best, policy.action_model)
        actions.append(decision.best.describe())
    return probes, (target_visible_fraction(scene) >= threshold, actions)


def fmt(x: float) -> str:
    return f"{x:.3f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trials", nargs="+", help="density:index")
    ap.add_argument("--policy", default="slax-belief")
    ap.add_argument("--options", default="{}", help="JSON: constructor options added to the registry's")
    ap.add_argument("--profile", default="paper")
    ap.add_argument("--seed", type=int, default=0, help="the protocol seed")
    ap.add_argument("--oracle-seconds", type=float, default=5.0, help="the oracle's search limit per decision")
    ap.add_argument("--decisions", type=int, default=None, help="probe only the first N decisions")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    args = ap.parse_args(argv)
    try:
        trials = [tuple(int(v) for v in spec.split(":")) for spec in args.trials]
        if any(len(t) != 2 for t in trials):
            raise ValueError
        options = json.loads(args.options)
        if not isinstance(options, dict):
            raise ValueError
    except ValueError:
        print(f"error: trials must be density:index pairs such as 10:9 and --options a JSON object (got "
              f"{' '.join(args.trials)} {args.options})", file=sys.stderr)
        return 2
    from slax_drake.config import load_scenario

    scenario = load_scenario(args.config)
    summary, details = [], []
    first_causes, main_causes, all_causes = [], [], []  # (cause, detail) per trial's first decision; ...
    t0 = time.process_time()
    for density, index in trials:
        probes, (revealed, actions) = run(density, index, scenario, args)
        name = f"{density:02d}_{index:04d}"
        causes = [classify(p) for p in probes]
        all_causes += causes
        first = probes[0] if probes else None
        cause, detail = causes[0] if causes else ("other", "no decision")
        first_causes.append((cause, detail))
        main = main_cause([c for c, _ in causes])
        main_causes.append(main)
        counts = ", ".join(f"{c}: {n}" for c, n in cause_counts([c for c, _ in causes]).items())
        if first is not None:
            summary.append(
                f"| {name} | {revealed} | {len(actions)} | {'; '.join(first.oracle_plan or ['-'])} | "
                f"{first.truth_kept} | {first.first_status} | {first.in_search} | {fmt(first.oracle_r)} / "
                f"{fmt(first.oracle_g)} = {fmt(first.oracle_ratio)} (no risk {fmt(first.oracle_ratio_norisk)}) | "
                f"{fmt(first.oracle_risk)} | {fmt(first.belief_share)} | {fmt(first.chosen_r)} / {fmt(first.chosen_g)} = "
                f"{fmt(first.chosen_ratio)}: {'; '.join(first.chosen_plan)} | {first.true_reveals_looked} / "
                f"{first.true_reveals} | **{cause}** {detail} | **{main}** ({counts}) |")
        for p, (c, d) in zip(probes, causes):
            details.append(
                f"| {name} | {p.step} | {p.truth_kept} ({p.truth_near}, w={p.truth_weight:g}) | "
                f"{'; '.join(p.oracle_plan or ['-'])} ({p.oracle_status}) | {p.first_status} | {p.in_search} | "
                f"{fmt(p.oracle_ratio)} ({fmt(p.oracle_ratio_norisk)}) | {fmt(p.oracle_risk)} | {fmt(p.belief_share)} | "
                f"{fmt(p.chosen_ratio)} | {'; '.join(p.chosen_plan)} | {p.true_reveals_looked} / {p.true_reveals} | "
                f"{c}{': ' + d if d else ''} |")
        print(f"# {name}: revealed={revealed} actions={len(actions)} first={cause} main={main} ({counts})",
              file=sys.stderr, flush=True)
    print(f"## slax-belief's missed reveals ({args.policy}, options {args.options}, profile {args.profile}, "
          f"seed {args.seed})\n")
    print("Per trial, at its first decision (the oracle's plan from the scene as generated). R / G: revealed mass "
          "over expected cost in slax-belief's own search; share: of the whole weighted belief that the oracle's "
          "plan reveals; 1-move reveals: looked at / existing; main cause: the most frequent over the trial's "
          "decisions where the oracle found a plan.\n")
    print("| trial | revealed | actions | oracle plan | truth in belief | oracle's first move | plan looked at | "
          "oracle R / G = R/G | risk | share | chosen R / G = R/G: plan | 1-move reveals | cause (first decision) | "
          "main cause (counts over all decisions) |")
    print("|" + "---|" * 14)
    print("\n".join(summary))
    print()
    print("Trials by the first decision's cause: " + ", ".join(
        f"{c}: {n}" for c, n in cause_counts([c for c, _ in first_causes]).items()))
    print("Trials by their main cause: " + ", ".join(f"{c}: {n}" for c, n in cause_counts(main_causes).items()))
    print("Decisions by cause and detail: " + ", ".join(
        f"{c}{' (' + d + ')' if d else ''}: {n}" for (c, d), n in sorted(
            ((k, all_causes.count(k)) for k in set(all_causes)), key=lambda e: (-e[1], e[0]))) + "\n")
    print("### Every decision\n")
    print("| trial | decision | truth kept (near, weight) | oracle plan (status) | oracle's first move | looked at | "
          "oracle R/G (no risk) | risk | share | chosen R/G | chosen plan | 1-move reveals | cause |")
    print("|" + "---|" * 13)
    print("\n".join(details))
    print(f"\n({len(trials)} trials, {time.process_time() - t0:.0f} CPU s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
