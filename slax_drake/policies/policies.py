"""Distribution-based search policies: DAR, DER-k, Bluction-DAR (paper Sec. V-C).

Each sees only the :class:`~slax_drake.shelf.simulator.PolicyObservation` (coarse depth and labels, the objects
seen, the 1D occupancy distribution P_t). It keeps the history encoding P'_t = min(P_t, P'_{t-1}) and scores a
hypothetical action by the distribution its model predicts for the observed objects moved as the action says
(:class:`~slax_drake.shelf.distribution.DistributionModel`), min-ed with P'_t:

- DAR: pushes only; the largest support reduction Delta r = r_t - r_{t+1}.
- DER-k: pushes only; a k-step lookahead (beam search, ``beam`` best partial sequences per depth) that takes
  the first action of the sequence with the least entropy of the predicted distribution after k steps.
- Bluction-DAR: pushes and suctions; a suction's reduction is weighted Delta r^s = psi Delta r (the paper's
  form, ``suction_weighting="paper"``) or Delta r / psi (``"cost"``, the variant ``bluction-dar-cost``).

The corrections (``corrected=True``, the registry's ``dar`` and ``bluction-dar``; ``dar-literal`` and
``bluction-dar-literal`` are the paper's text alone). The paper leaves implicit what any implementation needs when
the first-order model is wrong about the true shelf (:mod:`slax_drake.policies.trial_memory`):

1. an executed action that left the observation unchanged, or moved its object less than predicted, is excluded
   for the rest of the trial through the protocol's exclusion record, with its reason (a push that moved nothing
   excludes that object's pushes in that direction while it stands there: they all start with the same contact);
2. no candidate that would return the seen objects to an arrangement already observed in this trial;
3. no shuttle: a candidate that moves its object back against the last executed action on it
   (:meth:`~slax_drake.policies.trial_memory.TrialMemory.undoes`) is not taken unless it reveals space no earlier
   arrangement revealed: it uncovers at least ``shuttle_reveal`` (m) of width along x that the object covered in
   every arrangement observed so far (:meth:`~slax_drake.policies.trial_memory.TrialMemory.vacates_unseen`;
   ``shuttle_rule="sight"``: at least that width of shelf into which the camera would see deeper than in any
   observed arrangement, judged on every seen object, :mod:`slax_drake.policies.sight`). The
   predicted distribution is no judge here: it assumes the empty shelf behind a moved object, so on a shelf where
   another object stands behind it every move back and forth "reveals" the same columns again;
4. an action whose predicted support reduction is zero and that reveals no unseen space (the number of hidden
   target placements the distribution model counts does not drop) is not taken while another candidate reduces
   the support or reveals unseen space; among equal reductions, the one that reveals more unseen space first.

Ties are broken deterministically: the smaller support of the raw predicted distribution, then the cheaper
action, then the smaller displacement, then enumeration order. No policy draws random numbers, so a rollout
is a function of the scene alone.

Suction placements are many (a lattice per object). A policy first predicts the distribution with the object
removed; placements are then tried in order of how many still-possible columns their silhouette would cover
(``max_placements`` at most, stopping at one that loses nothing against removal).
"""

from __future__ import annotations

import math

import numpy as np

from slax_drake.shelf.actions import ActionModel, Push, Suction, apply_action
from slax_drake.shelf.distribution import DistributionModel, entropy, history_min, support
from slax_drake.policies.protocol import Decision, Exclusions, Reversal, Screened, read_only
from slax_drake.policies.trial_memory import Miss, TrialMemory


class DistributionPolicy:
    """Common machinery of the :class:`~slax_drake.policies.protocol.Policy` protocol for the policies that read a
    PolicyObservation: keep P'_t (``history``), record exclusions, predict candidates' distributions. A subclass
    implements ``rank(obs) -> Decision`` with ``self.history`` already updated for ``obs``."""

    name = "abstract"
    needs_true_scene = False
    use_pushes = True
    use_suctions = False
    SHUTTLE_RULES = ("width", "sight")  # the shuttle_rule values this policy can judge by

    def __init__(self, action_model: ActionModel, distribution: DistributionModel, psi: float = 1.3,
                 observation_width: int = 160, max_placements: int = 4, corrected: bool = False,
                 shuttle_reveal: float | None = 0.02, shuttle_last_resort: bool = False, shuttle_rule: str = "width",
                 shuttle_by_axis: bool = False):
        self.corrected = corrected  # the implementation's corrections (module docstring); False: the paper's text
        self.shuttle_reveal = shuttle_reveal  # m a shuttle must uncover never seen (correction 3); None: allowed
        # when the corrections leave no candidate, offer the ones screened out only as shuttles rather than stop
        self.shuttle_last_resort = shuttle_last_resort
        # what a shuttle must uncover to pass correction 3: "width", width its own footprint covered in every
        # observed arrangement (TrialMemory.vacates_unseen); "sight", width of shelf no observed arrangement let the
        # camera see as deep (slax_drake.policies.sight); "belief" (a policy with a belief: SHUTTLE_RULES), the width
        # rule or a place the belief still holds for the target shown (slax_drake.policies.belief)
        if shuttle_rule not in self.SHUTTLE_RULES:
            raise ValueError(f"shuttle_rule must be one of {', '.join(map(repr, self.SHUTTLE_RULES))} "
                             f"(got {shuttle_rule!r})")
        self.shuttle_rule = shuttle_rule
        self._view = None  # the DeepestView of this trial (shuttle_rule "sight"), made for the first frame's camera
        # correction 3 judges a move back against the object's last move, or with shuttle_by_axis its last move
        # along each axis (TrialMemory.by_axis: a move along y alone in between does not hide a cycle along x)
        self.memory = TrialMemory(by_axis=shuttle_by_axis)
        # camera mode: a suction that left its object where it stood excludes that object's suctions while it stands
        # there (slax-belief's option ``put_back_group``); False: only that action is excluded
        self.put_back_group = False
        # a suction that left its object where it stood excludes that object's suctions by the same dx, any
        # placement depth, while it stands there (slax-belief's option ``put_back_lane``)
        self.put_back_lane = False
        self._action_model = action_model
        self.distribution = distribution
        self.psi = psi
        self.observation_width = observation_width
        self.max_placements = max_placements
        self._history = None
        self._exclusions = Exclusions()
        self._objects = ()

    @property
    def action_model(self) -> ActionModel:
        return self._action_model

    @property
    def history(self):
        """P'_t, the history-encoded distribution after the last observation (read-only; None before it)."""
        return read_only(self._history)

    @property
    def exclusions(self) -> tuple:
        """(action, reason) for every candidate excluded this trial, in order."""
        return self._exclusions.records

    def reset(self, scene_or_observation=None) -> None:
        self._history = None
        self._exclusions = Exclusions()
        self._objects = ()
        self.memory.reset()
        self._view = None  # made again for the next trial's first frame (its camera)

    def decide(self, obs) -> Decision:
        self._history = history_min(obs.p1d, self._history)
        self._objects = obs.known
        self._exclusions.tolerant = getattr(obs, "belief", None) is not None  # camera mode: estimated poses
        self.memory.estimated = self._exclusions.tolerant
        if self.corrected and self.shuttle_rule == "sight" and self._view is None:
            from slax_drake.policies.sight import DeepestView, SightDepths

            self._view = DeepestView(SightDepths(obs.scene_template.camera, self.observation_width),
                                     self.memory.position_tolerance)
        if self.corrected:
            self.learn(obs)
        decision = self.rank(obs)
        if self.corrected and decision.best is not None:
            self.memory.propose(decision.best, obs.known)
        return decision

    def learn(self, obs) -> None:
        """Correction 1: the last proposed action, now executed, is excluded when ``obs`` shows that it did not move
        its object as predicted; ``obs``'s arrangement joins the observed ones (correction 2)."""
        failed = self.memory.outcome(obs.known)
        if failed is not None:
            proposal, how = failed
            unchanged = how.miss is Miss.UNCHANGED
            group = isinstance(proposal.action, Push) or (self.put_back_group and self._exclusions.tolerant)
            self._exclusions.add(proposal.action, f"executed: {how.message}", unchanged and group, proposal.before,
                                 lane=unchanged and self.put_back_lane)
        self.memory.observe(obs.known)
        if self._view is not None:
            self._view.observe(obs.known)

    def exclude(self, action, reason: str, whole_group: bool = False) -> None:
        self._exclusions.add(action, reason, whole_group, self._objects)
        self.memory.withdraw(action)

    def resume(self, history) -> None:
        """Continues a trial whose P'_{t-1} is ``history`` (a step planned by another process: plan-step)."""
        self._history = None if history is None else np.asarray(history, dtype=float).copy()

    def rank(self, obs) -> Decision:  # pragma: no cover - interface
        raise NotImplementedError

    # helpers ---------------------------------------------------------------------------------------------
    def predict(self, obs, objects) -> np.ndarray:
        """P(u) after the observed objects moved as ``objects`` says: in camera mode from the predicted image
        (``obs.belief``), else from the distribution model on the believed scene."""
        belief = getattr(obs, "belief", None)
        if belief is not None:
            return belief.predict(objects)
        return self.distribution.distribution(obs.scene_template.with_objects(objects))

    def candidates(self, objects, pushes=None, suctions=None):
        """The feasible actions on ``objects`` that have not been excluded, in enumeration order; with the
        corrections, also none that returns the objects to an arrangement observed in this trial."""
        c = self._action_model.enumerate(
            objects, pushes=self.use_pushes if pushes is None else pushes,
            suctions=self.use_suctions if suctions is None else suctions,
        )
        screened = self.screen(objects, c.feasible)
        allowed = [a for a, why in screened if why is None]
        if not allowed and self.shuttle_last_resort:
            allowed = [a for a, why in screened if why is Screened.SHUTTLE]
        return allowed

    def screen(self, objects, feasible, memory: TrialMemory | None = None) -> list:
        """``(action, why)`` for each of the action model's ``feasible`` candidates on ``objects``: ``why`` None for
        a candidate the policy may take, else the first correction that screens it out (:class:`Screened`):
        EXCLUDED (an exclusion of this trial: the motion planner rejected it or its group, or it failed when
        executed), BACK (correction 2) or SHUTTLE (correction 3: it reverses its object's last move and uncovers no
        new width). ``memory``: the trial memory to judge by (default: this trial's; a search passes
        the memory a plan would leave, :meth:`TrialMemory.after_plan`)."""
        memory = self.memory if memory is None else memory
        allowed = set(id(a) for a in self._exclusions.allowed(feasible, objects))
        out = [(a, None if id(a) in allowed else Screened.EXCLUDED) for a in feasible]
        if self.corrected and memory.observed:
            open_ = [a for a, why in out if why is None]
            back = {id(a) for a, seen in zip(open_, memory.leads_back(objects, open_)) if seen}
            out = [(a, Screened.BACK if id(a) in back else why) for a, why in out]
        if self.corrected and self.shuttle_reveal is not None and memory.moves:
            out = [(a, Screened.SHUTTLE if why is None and memory.undoes(objects, a)
                    and not self.reveals_new(objects, a, memory) else why) for a, why in out]
        return out

    def screened_counts(self, objects=None) -> dict:
        """{why: count} over the action model's feasible candidates on ``objects`` (default: the objects of the last
        decision, as the policy saw them) that this policy screens out
        (:meth:`screen`), for the record of a decision that found no action (plain text keys, the :class:`Screened`
        values); the policies that screen more (safe suctions, placement rules) add their own kinds."""
        import collections

        objects = self._objects if objects is None else tuple(objects)
        c = self._action_model.enumerate(objects, pushes=True, suctions=True)
        return dict(collections.Counter(str(why) for _, why in self.screen(objects, c.feasible) if why is not None))

    def reversal_rule(self, action, objects=None) -> Reversal | None:
        """How correction 3 judged ``action``, chosen on ``objects`` (default: those of the last decision), for the
        trial record: None when it does not move its object back against the last executed move on it (this trial's
        memory, on the estimated poses) or the policy applies no correction (the literal variants);
        :attr:`Reversal.UNCOVERS_NEW_WIDTH` when it does and passed the correction by uncovering at least
        ``shuttle_reveal`` m never seen; :attr:`Reversal.LET_THROUGH` when the correction screens it out as a shuttle
        and the policy took it all the same (the last resort, or slax-belief's move that clears more of a partly
        seen target); :attr:`Reversal.CORRECTION_OFF` when it does and the policy's no-shuttle correction is off
        (``shuttle_reveal`` None)."""
        objects = self._objects if objects is None else tuple(objects)
        if not (self.corrected and self.memory.undoes(objects, action)):
            return None
        if self.shuttle_reveal is None:
            return Reversal.CORRECTION_OFF
        return Reversal.UNCOVERS_NEW_WIDTH if self.reveals_new(objects, action) else Reversal.LET_THROUGH

    def reveals_new(self, objects, action, memory: TrialMemory | None = None) -> bool:
        """Whether ``action`` on ``objects`` reveals space no arrangement observed in this trial revealed (correction
        3), at least ``shuttle_reveal`` m of it: ``shuttle_rule`` "width", width (along x) that its object covered
        in every observed arrangement (of ``memory``, default this trial's); "sight", width of shelf the camera
        would see deeper into than in any observed arrangement (:class:`~slax_drake.policies.sight.DeepestView`,
        every seen object's footprint; the frames observed, whatever ``memory``)."""
        if self.shuttle_rule == "sight" and self._view is not None:
            return self._view.newly_shown(apply_action(tuple(objects), action)) >= self.shuttle_reveal
        memory = self.memory if memory is None else memory
        return memory.vacates_unseen(objects, action) >= self.shuttle_reveal

    def unseen_space(self, obs, objects) -> int | None:
        """The number of hidden target placements with the seen objects at ``objects`` (the distribution model's
        ``hidden_count``; None when the model has none, e.g. camera mode or the learned network)."""
        count = getattr(self.distribution, "hidden_count", None)
        if count is None or getattr(obs, "belief", None) is not None:
            return None
        return count(obs.scene_template.with_objects(objects))

    def action_cost(self, action) -> float:
        return 1.0 if isinstance(action, Push) else self.psi

    def ranked_suctions(self, obs, objects, history, suctions):
        """Groups suction candidates by object; yields (object name, removal distribution, placements ordered
        by how many still-possible columns the placed object's silhouette covers)."""
        cam = obs.scene_template.camera
        width = len(history)
        coarse = cam.with_resolution(width, max(1, int(round(cam.height * width / cam.width))))
        by_object: dict = {}
        for a in suctions:
            by_object.setdefault(a.name, []).append(a)
        for name, group in by_object.items():
            rest = tuple(o for o in objects if o.name != name)
            p_removed = self.predict(obs, rest)
            alive = np.minimum(p_removed, history) > 0
            obj = next(o for o in objects if o.name == name)
            corners = _box_corners(obj)
            ranked = []
            for order, a in enumerate(group):
                offset = np.array([a.dx, a.dz - obj.center[1], 0.0])
                u = coarse.project(corners + offset)[:, 0]
                lo, hi = int(max(0, math.floor(u.min()))), int(min(width - 1, math.ceil(u.max())))
                covered = int(alive[lo:hi + 1].sum()) if hi >= lo else 0
                ranked.append((covered, abs(a.dx) + abs(a.dz - obj.center[1]), order, a))
            ranked.sort(key=lambda r: r[:3])
            yield name, p_removed, [r[3] for r in ranked]


def _box_corners(obj) -> np.ndarray:
    sx, sy, sz = obj.size
    local = np.array([[x, y, z] for x in (-sx / 2, sx / 2) for y in (-sy / 2, sy / 2) for z in (-sz / 2, sz / 2)])
    return local @ obj.X_SO[:3, :3].T + obj.X_SO[:3, 3]


class DAR(DistributionPolicy):
    """Distribution Area Reduction: greedy support reduction (pushes; with suctions in Bluction-DAR)."""

    name = "dar"

    def suction_weight(self) -> float:
        return 1.0

    def rank(self, obs) -> Decision:
        h = self._history
        r_t = support(h)
        cands = self.candidates(obs.known)
        if not cands:
            return Decision.stop("no feasible action" if not (self.corrected and self.memory.observed) else
                                 "no feasible action that leads to an arrangement not yet observed")
        best, best_key = None, None
        order = 0
        ranked = []
        hidden_now = self.unseen_space(obs, obs.known) if self.corrected else None

        def consider(a, p):
            nonlocal best, best_key, order
            dr = r_t - support(np.minimum(p, h))
            weighted = dr * (self.suction_weight() if isinstance(a, Suction) else 1.0)
            disp = abs(a.d) if isinstance(a, Push) else abs(a.dx) + abs(a.dz)
            revealed = 0
            if hidden_now is not None:  # correction 4: the unseen space it reveals (lattice placements)
                revealed = hidden_now - self.unseen_space(obs, apply_action(obs.known, a))
            key = (-weighted, -revealed, support(p), self.action_cost(a), disp, order)
            order += 1
            ranked.append((key, a))
            if best_key is None or key < best_key:
                best, best_key = a, key
            return dr

        pushes = [a for a in cands if isinstance(a, Push)]
        suctions = [a for a in cands if isinstance(a, Suction)]
        for a in pushes:
            consider(a, self.predict(obs, apply_action(obs.known, a)))
        if suctions:
            w = self.suction_weight()
            for name, p_removed, placements in self.ranked_suctions(obs, obs.known, h, suctions):
                dr_removed = r_t - support(np.minimum(p_removed, h))
                if best_key is not None and -w * dr_removed > best_key[0]:
                    continue  # even removing the object outright would not beat the best action
                for a in placements[: self.max_placements]:
                    dr = consider(a, self.predict(obs, apply_action(obs.known, a)))
                    if dr >= dr_removed:
                        break
        ranked.sort(key=lambda r: r[0])
        if hidden_now is not None and ranked and (ranked[0][0][0] < 0 or ranked[0][0][1] < 0):
            # correction 4: something reduces the support or reveals unseen space; drop what does neither
            ranked = [r for r in ranked if r[0][0] < 0 or r[0][1] < 0]
        return Decision(tuple(a for _, a in ranked))


class BluctionDAR(DAR):
    """Bluction-DAR: DAR over pushes and suctions; suction reductions weighted by psi (paper) or 1/psi."""

    name = "bluction-dar"
    use_suctions = True

    def __init__(self, *args, suction_weighting: str = "paper", **kwargs):
        super().__init__(*args, **kwargs)
        if suction_weighting not in ("paper", "cost"):
            raise ValueError("suction_weighting must be 'paper' or 'cost'")
        self.suction_weighting = suction_weighting
        if suction_weighting == "cost":
            self.name = "bluction-dar-cost"

    def suction_weight(self) -> float:
        return self.psi if self.suction_weighting == "paper" else 1.0 / self.psi


class DER(DistributionPolicy):
    """DER-k: pushes only; beam-search lookahead of ``depth`` steps minimising the entropy of the predicted
    history-encoded distribution after the last step."""

    def __init__(self, *args, depth: int = 3, beam: int = 2, **kwargs):
        super().__init__(*args, **kwargs)
        self.depth = depth
        self.beam = beam
        self.name = f"der-{depth}"

    def rank(self, obs) -> Decision:
        """First actions ranked by the best leaf reached from each (the chosen one first), then the first actions
        that left the beam, by their one-step key."""
        level = [(None, obs.known, self._history)]
        best_leaf = None
        first_level, last_level = [], []
        for depth in range(self.depth):
            children = []
            for first, objects, hist in level:
                cands = self.candidates(objects)
                if depth == 0 and not cands:
                    return Decision.stop("no feasible action")
                for a in cands:
                    after = apply_action(objects, a)
                    p = self.predict(obs, after)
                    h2 = np.minimum(p, hist)
                    disp = abs(a.d)
                    key = (entropy(h2), support(h2), disp, len(children))
                    children.append((key, first or a, after, h2))
            if not children:
                break
            children.sort(key=lambda c: c[0])
            best_leaf = children[0]
            if depth == 0:
                first_level = children
            last_level = children
            level = [(c[1], c[2], c[3]) for c in children[: self.beam]]
        if best_leaf is None:
            return Decision.stop("no feasible action")
        ranked = [best_leaf[1]]
        for c in last_level + first_level:
            if c[1] not in ranked:
                ranked.append(c[1])
        return Decision(tuple(ranked))



class BluctionLookahead(DistributionPolicy):
    """Ours: Bluction-DAR with a two-step lookahead when no single action shrinks the support.

    Step one is Bluction-DAR's greedy choice (pushes and suctions, suction reductions weighted by psi as in
    the paper). When the best weighted reduction is not positive (every action leaves the support as it is,
    typically because the occluder cannot move until a neighbour makes room), the ``top_k`` first actions
    (ranked by the support of their raw predicted distribution, then cost) are each followed by every second
    action, and the first action of the pair with the largest support reduction per unit of action cost
    (pushes 1, suctions psi) is taken. A pair's second action is predicted on the objects after the first,
    min-ed with P'_t and the first prediction (the history encoding applied twice). Deterministic ties as in
    DAR; no random numbers."""

    name = "bluction-la2"
    use_suctions = True

    def __init__(self, *args, top_k: int = 2, **kwargs):
        kwargs.setdefault("max_placements", 6)
        super().__init__(*args, **kwargs)
        self.top_k = top_k
        self.visited = set()

    def _scored(self, obs, objects, h):
        """[(key, weighted reduction, action, predicted p, objects after)] for every candidate evaluated."""
        r_t = support(h)
        cands = self.candidates(objects)
        out = []
        for order, a in enumerate(c for c in cands if isinstance(c, Push)):
            after = apply_action(objects, a)
            p = self.predict(obs, after)
            dr = r_t - support(np.minimum(p, h))
            out.append(((-dr, support(p), 1.0, abs(a.d), order), dr, a, p, after))
        suctions = [c for c in cands if isinstance(c, Suction)]
        if suctions:
            for name, p_removed, placements in self.ranked_suctions(obs, objects, h, suctions):
                dr_removed = r_t - support(np.minimum(p_removed, h))
                for order, a in enumerate(placements[: self.max_placements]):
                    after = apply_action(objects, a)
                    p = self.predict(obs, after)
                    dr = r_t - support(np.minimum(p, h))
                    w = self.psi * dr
                    disp = abs(a.dx) + abs(a.dz - next(o for o in objects if o.name == a.name).center[1])
                    out.append(((-w, support(p), self.psi, disp, 10_000 + order), w, a, p, after))
                    if dr >= dr_removed:
                        break
        out.sort(key=lambda e: e[0])
        return out

    def reset(self, scene_or_observation=None) -> None:
        super().reset(scene_or_observation)
        self.visited = set()

    def rank(self, obs) -> Decision:
        """The chosen action first, then the other candidates evaluated at this step in their one-step order."""
        from slax_drake.scene.model import state_key

        h = self._history
        self.visited.add(state_key(obs.known))
        scored = self._scored(obs, obs.known, h)
        fresh = [e for e in scored if state_key(e[4]) not in self.visited]  # never undo a step: no cycles
        scored = fresh or scored
        if not scored:
            return Decision.stop("no feasible action")
        rest = [e[2] for e in scored]
        if scored[0][1] > 0:
            return Decision(tuple(rest))
        r_t = support(h)
        firsts = sorted(scored, key=lambda e: (e[0][1], e[0][2], e[0][3], e[0][4]))[: self.top_k]
        best, best_key = None, None
        for rank, (_, _, a1, p1, after1) in enumerate(firsts):
            h1 = np.minimum(p1, h)
            for key2, _, a2, p2, _ in self._scored(obs, after1, h1)[:1]:
                dr = r_t - support(np.minimum(p2, h1))
                cost = self.action_cost(a1) + self.action_cost(a2)
                k = (-dr / cost, cost, rank)
                if dr > 0 and (best_key is None or k < best_key):
                    best, best_key = a1, k
        if best is None:
            return Decision(tuple(rest))
        return Decision((best, *(a for a in rest if a != best)))
