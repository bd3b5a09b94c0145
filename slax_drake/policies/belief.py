"""slax-belief (ours): a belief-space beam search over short plans, choosing the plan that reveals the most
probability mass of the target's placement per unit of expected cost.

With a privileged observation and a known shelf, the only unknown that matters is where the target stands: a
placement in the hidden region. The belief is the set of lattice placements consistent with every observation of
the trial (:meth:`~slax_drake.policies.hindsight.Hindsight.placements`: clear of the seen objects, hidden at the
first observation, seen less than v at each later one), uniform, as the scene generator draws the target. A plan
(a sequence of actions on the seen objects) reveals a placement when some arrangement along it shows a target
there at v. ``samples`` placements (stratified, seeded with the scene seed and the step: :meth:`Hindsight.draw`)
stand for the belief (the worlds); they are kept from one decision to the next while at least half of them stay
consistent (the consistent ones are a rejection sample of the updated belief), then drawn anew.

Why not greedy: revealing the hidden region usually needs several objects moved first, one in front of the
other, and the first of those moves reveals little. ``slax-hindsight`` scores a world only 0 (seen), 1 (one
object away) or F (more), so a first move that brings a world from three objects away to two earns nothing, and
it wanders between small reveals. Here every world keeps a graded distance h_w: the fewest seen objects whose
removal would show its target (0, 1, 2 exactly; from 3 on the count of a greedy cover), from per-object
occlusion masks of the target's surface points (:class:`~slax_drake.policies.hindsight.Worlds`, packed as bits).

A plan a_1..a_d has an expected cost G = sum_k c(a_k) P(not revealed before step k) (c = 1 for a push, psi for a
suction), a revealed mass R (the share of worlds some arrangement along it shows, each reveal weighted by the
probability that the plan's suctions so far were placed as planned), and a value
V = G + sum_w [w not revealed] h_w(s_d) / K (``failure_cost`` for a world farther than the actions left when
``horizon`` is given). The horizon H (actions per trial) is the protocol's, passed by the registry as the
oracles get it: the experimenter fixes it before the trial, so it is not knowledge of the scene's content. The
paper's distribution policies (DAR, DER-3, Bluction-DAR) have no use for it (they are greedy and stop only at H);
ours plans to it. Note that Table I's H = 2n also tells the object count n; this policy uses H only as the actions
left. The beam (``beam`` arrangements per depth, duplicates merged) is ranked by V; the plan
taken is the one with the largest R / G among all plans looked at (the classic search rule: look first where
probability per cost is highest), by V when none reveals anything. The search goes ``depth`` actions deep, and
on to ``max_depth`` while no plan reveals anything.

Moves: the oracles' coarse action set (each object pushed each way up to its neighbour; suction placements on the
action model's lattice, the ``placements_per_object`` best per object and state by their value; of the placements
where the object hides no world's target, only the least risky one). The first move is one of the policy's own
candidates (Bluction-DAR's corrections: exclusions, no return to an observed arrangement). In the paper profile a
suction may place its object in hidden space, where an unseen object may stop it: its chance of failing is taken
as ``hidden_risk`` times the share of hidden placements in its placement box (widened by half the target), and a
placement that was put back or stopped short marks its box blocked for the rest of the trial.

What the trial has shown (three fields of :class:`BeliefOptions`; ``evidence="none"``,
``remember_objects=False`` and ``widen_beam=0`` turn them off):

- ``remember_objects``: an object seen earlier and hidden now, that the robot has not moved since, is kept among
  the seen objects where it stood (:meth:`with_remembered`; in the first-order world nothing moves unless the
  robot moves it). Without it the planner would place objects onto an object that a move had just hidden.
- ``evidence="outcome"``: the outcome of each executed action updates the belief
  (:meth:`condition_on_outcome`). A robot sees, at the next observation, whether the object it moved ended where
  it was commanded to; the policy replays the action with the first-order executor for a target at each
  possible placement. An action that went as the seen objects predict proves that no target stood in its way
  (those placements leave the belief); one stopped by something unseen makes the placements that would have
  stopped it exactly there ``block_weight`` times likelier (an unseen object other than the target may have done
  it: Table I scenes of 8-10 objects hide about two), and those that would have stopped a push earlier impossible.
  The worlds are then drawn from the weighted belief (:meth:`draw`). The policy never reads the target's pose or
  the simulator's notes: only the next observation of the object it moved.
- ``widen_beam``: when no plan of the beam reveals anything within ``max_depth`` actions, the search runs once
  more with a beam of ``widen_beam`` (``decision_log`` records ``widened``): a small first move that makes room
  for a suction (a push of 2 cm) ranks low by V and falls out of a narrow beam.

``stuck_select``: the rule when no plan of either search reveals anything. "value" (the default) takes the plan of
least V; since every action adds to G while the distances rarely fall, that is nearly always a single cheap move
that changes nothing. "progress" takes the plan whose end is nearest to revealing, the least V - G (the worlds'
distances, lost and failed worlds, the suctions' risk), whatever it costs, ties by V; the rest of that plan stays
in the next decision's beam; every other decision is unchanged.

``stuck_undo`` (variant ``slax-belief-stuck-undo``): when no plan of either search reveals anything, the moves the
corrections screened out only as a return to an observed arrangement or as a shuttle start plans of a widened search
too (:meth:`undo_plans`), and the best of those plans is taken when one reveals part of the belief. Under the Drake
station's rules a first move that revealed nothing often leaves only moves back (an object pushed across its
neighbour's tool lane), and the worlds an arrangement revealed are gone from the belief, so a move back whose plan
reveals what the belief still holds is no cycle.

``blocked_rule`` (what a failed placement's box refuses; "risk" is the default since 2026-12-06, "box" before it,
the registry's ``slax-belief-box``). A placement put back or stopped short marks its placement box blocked
(:meth:`note_outcome`); "box" refuses every later placement, of any object, that overlaps such a box, for the rest
of the trial. But what stopped it stands somewhere
along the way in, not necessarily in that box, and only in space the camera has not seen. "hidden": an overlap
refuses only where it meets space still hidden (a possible target placement's footprint;
:meth:`holds_hidden_space`); "risk": nothing is refused, and a placement overlapping a blocked region in hidden
space fails with ``blocked_risk`` more (:meth:`placement_risk`), so the reveals after it count for less. Unlike a
refusal, a risk lets a move that reveals much outrank the cheap moves left; an identical failed action is still
excluded by the corrections.

Camera mode (the observation is a frame: ``known`` holds the estimator's hypotheses, named ``track_<k>`` by the
object tracker, never true objects). The observer's hypotheses assume the least depth an object can have, so an action may run into an
object the frame showed, reaching beyond its hypothesis, into an object seen before and hidden now, or beyond the
walls. The options below address these; all but ``seen_target``, ``uncover_seen`` and ``camera_memory`` are off
in the registry's ``slax-belief``; ``slax-belief-camera-depth`` sets ``camera_depth``, ``camera_memory`` and
``camera_outcome_tolerance`` and turns ``seen_target`` off:

- ``camera_depth`` (m): the hypotheses are estimated again from the frame assuming each at least this deep behind
  its visible surfaces (:meth:`with_camera_hypotheses`; the estimator's ``DepthPrior(rule="fixed")``, shortened at
  the walls and the other hypotheses); the actions are checked and replayed on them;
- ``maybe_occupied``: the target's placements are judged against the observer's (shallow) hypotheses, so a
  placement in the part of a hypothesis that only the assumed depth fills stays possible, at this weight
  (:meth:`placements`); with ``camera_depth`` alone such placements are excluded;
- ``camera_memory``: :meth:`with_remembered` in camera mode, the tracker's hidden objects (without a tracker, a
  hypothesis matched across frames by where it stands: segment ids are not kept by a real segmentation),
  remembered as ``remembered_<name>``, an obstacle the policy takes no action on (:meth:`remembered_in_frame`);
- ``camera_outcome_tolerance`` (m): the outcome evidence and the placement check compare estimated poses, within
  this tolerance rather than the 3 mm (5 mm) that exact poses allow;
- ``camera_extents`` (a share in [0, 1]): as ``camera_depth``, but each hypothesis's unseen edges lie that share
  of the way from what the frame shows to the farthest it allows (the estimator's extent range: the walls, the
  neighbours' observed footprints, space seen empty, the largest object; ``DepthPrior(rule="range")``), so an
  object with little room behind it is assumed shallow and one with room deep;
- ``seen_target``: when the frame shows part of the target, its placement is known up to its size: the belief
  keeps only the placements whose target holds every seen target point (:meth:`placements`; ``decision_log``
  records ``target_seen``), so every world is the partly seen target and the search clears what still hides it
  (on by default; ``slax-belief-no-seen-target`` turns it off). When none of the placements consistent with the
  earlier observations holds the seen points, those possible now are collapsed. ``unseen_risk`` (measured, off):
  after the collapse the suctions' risk of meeting something unseen reads the space never seen
  (:meth:`hidden_space`), not the target's few placements;
- ``uncover_seen`` (read only while the belief is collapsed onto a partly seen target): a move that uncovers part
  of it (its object hides fewer of the worlds' target points after it) is a first move even where the no-return
  and no-shuttle corrections refuse it (:meth:`uncovering_moves`; ``decision_log`` records ``uncovering``): an
  object carried in front of the target by an earlier action must be allowed back.
- ``aim_visible``: no action on a hypothesis whose segment shows no disc of the cup's diameter (a sliver of an
  object seen above or beside a nearer one: a move planned on it moves the whole object); it stays an obstacle
  (:meth:`unaimable`);
- ``deepen_failed``: an object whose suction placement failed is estimated, for the rest of the trial, with the
  range prior at its farthest (:meth:`with_camera_hypotheses`).
- ``extent_prior`` and ``extent_risk`` (the extents drawn with the target's placement; both off, measured in
  docs/research/uncertain-extents.md): a placement inside a seen object's extent range weighs the chance that the
  object does not reach it (:func:`~slax_drake.policies.extents.extent_free_weights`); a first move is scored by
  the share of joint draws of the seen objects' extents in which it fails (:meth:`first_move_extent_risk`).

The privileged path does not read any of them. The measurements behind each option's default are in the
research note docs/research/slax_belief.md.

The first action of the chosen plan is taken; the next decision searches again on the new observation, the rest
of the last plan kept in the beam at every depth (so it is kept unless a better one is found). Deterministic: no
random number is drawn but from the seeded generator, and ties keep enumeration order. ``seconds`` caps a
decision's CPU time (checked per expanded node: the search stops and takes the best plan so far; ``decision_log``
records ``capped``); a result that no decision's cap bound does not depend on the machine.
"""

from __future__ import annotations

import dataclasses
import functools
import time

import numpy as np

from slax_drake.shelf.actions import Push, Suction, apply_action
from slax_drake.policies.belief_options import DEFAULT_BELIEF_OPTIONS, BeliefOptions
from slax_drake.policies.extents import EXTENT_DRAW, EXTENT_DRAWS, extent_free_weights
from slax_drake.policies.hindsight import Hindsight, Worlds
from slax_drake.policies.oracle_search import maximal_pushes_only
from slax_drake.policies.protocol import NO_REVEALING_PLAN, Decision, Screened
from slax_drake.policies.trial_memory import TrialMemory
from slax_drake.scene.model import state_key


EXPLAIN_SHARES = (0.25, 0.5, 0.75, 1.0)  # explain_failed: the shares of an extent range tried, least first
REMEMBERED = "remembered_"  # camera mode: the name prefix of a remembered hypothesis (SceneObject.remembered)


def _planar_distance(a, b) -> float:
    """The distance (m) between two objects' centres in the shelf's floor plane."""
    return float(np.hypot(*(np.asarray(a.center[:2], dtype=float) - np.asarray(b.center[:2], dtype=float))))


class _NoActionsOnRemembered:
    """The policy's action model, enumerating no action on a remembered hypothesis (``remembered``: the camera
    shows no segment of it to act on) nor on one named in ``unaimable`` (``aim_visible``: the camera shows too
    little of it to aim the tool at); it stays an obstacle. Everything else is the wrapped model's. Privileged
    observations name no object so: there it is the wrapped model."""

    def __init__(self, model):
        self._model = model
        self.unaimable: frozenset = frozenset()

    def __getattr__(self, name):
        if name == "_model":  # not set yet (e.g. while unpickling)
            raise AttributeError(name)
        return getattr(self._model, name)

    def enumerate(self, objects, fixed=(), pushes: bool = True, suctions: bool = True, only=None):
        objects = tuple(objects)
        if only is None and any(o.remembered or o.name in self.unaimable for o in objects):
            only = {o.name for o in objects if not o.remembered and o.name not in self.unaimable}
        return self._model.enumerate(objects, fixed, pushes, suctions, only)


class _Node:
    """One plan in the beam: its arrangement, actions, accumulated expected cost ``g``, the worlds not yet revealed
    (``alive``, bool (K,)), the terminal value of the worlds lost to a blocked action (``lost``), its value V, the
    revealed mass R (``revealed``) and the probability that its suctions so far went as planned (``prob``)."""

    __slots__ = ("objects", "plan", "g", "alive", "lost", "value", "order", "revealed", "prob", "mass")

    def __init__(self, objects, plan, g, alive, lost, value, order, revealed=0.0, prob=1.0):
        self.objects, self.plan, self.g, self.alive, self.lost = objects, plan, g, alive, lost
        self.value, self.order, self.revealed, self.prob = value, order, revealed, prob
        self.mass = None  # the share of worlds alive, set by the first child (``alive`` is fixed by then)


class BeliefSearch(Hindsight):
    """See the module docstring. ``options``: how it searches (:class:`BeliefOptions`, every field documented
    there); ``horizon``: actions per trial (None: unknown; the registry passes the protocol's H). Other keyword
    arguments are :class:`~slax_drake.policies.hindsight.Hindsight`'s (``grid_step`` (m), ``threshold`` (v; the
    registry passes the scenario's), ...)."""

    name = "slax-belief"
    uses_horizon = True  # the registry passes the protocol's H (see the module docstring)
    SHUTTLE_RULES = ("width", "sight", "belief")  # "belief": reveals_new reads the worlds still alive

    def __init__(self, *args, options: BeliefOptions = DEFAULT_BELIEF_OPTIONS, horizon: int | None = None, **kwargs):
        o = options
        super().__init__(*args, samples=o.samples, seconds=o.seconds, failure_cost=o.failure_cost, safe_suctions=False,
                         shuttle_last_resort=o.shuttle_last_resort, shuttle_rule=o.shuttle_rule,
                         shuttle_reveal=o.shuttle_reveal, shuttle_by_axis=o.shuttle_by_axis, **kwargs)
        self.options = o
        self.put_back_group = o.put_back_group  # camera mode: a suction put back excludes its object's suctions
        self.put_back_lane = o.put_back_lane  # a suction that moved nothing excludes its object's suctions by its dx
        self._hidden_centers = None  # the target's possible placements at this decision (x, y; m)
        self._risk_by_box: dict = {}  # placement box -> its placement_risk, for this decision's hidden centres
        self._risk_cache: dict = {}  # (id(object), action) -> (the object, its placement_risk), this decision
        self.depth = o.depth
        self.max_depth = max(o.depth, o.max_depth)  # deeper while no plan of ``depth`` reveals anything
        self.beam = o.beam
        self.placements_per_object = o.placements_per_object
        self.horizon = horizon
        self._plan: list = []  # the rest of the last decision's plan
        self._expected = None  # the arrangement that plan expects next
        self._distance_cache: dict = {}
        self._worlds = None  # the worlds (PackedWorlds) of this trial, kept while enough stay consistent
        self._n_worlds = 0  # how many of them are consistent at this decision
        self.hidden_risk = o.hidden_risk
        self.select = o.select
        self._blocked: list = []  # boxes (x_lo, x_hi, y_lo, y_hi) where a placement failed: an unseen obstacle
        self.deepen_failed = o.deepen_failed  # camera mode: an object whose placement failed is assumed deepest
        self._deepened: dict = {}  # camera mode: name -> the share of its extent range it is assumed at
        self.explain_failed = o.explain_failed  # camera mode: what a put-back teaches about the extents
        self._explained = None  # (name, share) the last put-back was explained by, for this decision's log
        self._share_cache = (None, {})  # (the frame, share -> its hypotheses at that share): _estimate_at
        self.extent_prior = o.extent_prior  # camera mode: placements weighed by the seen objects' extent ranges
        self._extent_weights: dict = {}  # lattice key -> the chance no seen object's unseen extent reaches it
        self.extent_risk = float(o.extent_risk)  # camera mode: a first move's risk from the unseen extents
        self._extent_belief = None  # camera mode with extent_risk: this decision's ObservedBelief
        self._extent_cache: dict = {}  # action -> the extent draws it fails in, this decision (first moves only)
        self._extent_draws = None  # (seen names, this decision's joint draws of their extents): extent_draws
        self._last = None  # (the suction taken last, the pose it predicts for its object)
        self.evidence = o.evidence
        self.block_weight = float(o.block_weight)
        self._weights: dict = {}  # lattice key -> the placement's weight in the belief (1 when absent)
        self._executed = None  # (the action taken last, the seen objects it was planned on)
        self._template = None  # the observation's scene template (shelf, camera) at this decision
        self.evidence_log: list = []  # per executed action: how its outcome changed the belief
        self.remember_objects = o.remember_objects
        self.widen_beam = o.widen_beam  # the beam of a second search when the first reveals nothing (0: none)
        self._remembered: dict = {}  # name -> the object as last believed (seen, or remembered), last decision
        self.camera_depth = o.camera_depth  # camera mode: the hypotheses' assumed unseen depth (None: as observed)
        self.camera_extents = o.camera_extents  # camera mode: unseen edges' share of their extent range (None: off)
        self.seen_target = o.seen_target  # camera mode: a partly seen target collapses the belief onto it
        self.uncover_seen = o.uncover_seen  # ... and a move uncovering it passes the no-return/no-shuttle corrections
        self._target_seen_now = False  # this decision's placements were collapsed onto a partly seen target
        self.unseen_risk = o.unseen_risk  # ... and the placement risk then reads the space never seen
        self._unseen_keys = None  # after a collapse: lattice keys of the space never seen (placement risk reads it)
        self.camera_memory = o.camera_memory  # camera mode: remember hidden hypotheses (matched across frames)
        self.camera_outcome_tolerance = float(o.camera_outcome_tolerance)  # m, outcome evidence on estimated poses
        self._action_model = _NoActionsOnRemembered(self._action_model)
        self._camera_mode = False  # the last observation was a camera frame's
        self.maybe_occupied = o.maybe_occupied  # camera mode: the weight of a placement in a hypothesis' assumed depth
        self._as_observed: dict = {}  # camera mode with camera_depth: name -> the observer's hypothesis (least depth)
        self._maybe: frozenset = frozenset()  # lattice keys of the placements weighed by maybe_occupied now
        self.aim_visible = o.aim_visible  # camera mode: no action on a hypothesis too little seen to aim the tool at
        self.stuck_select = o.stuck_select  # the rule when no plan looked at reveals anything (module docstring)
        self.blocked_rule = o.blocked_rule  # which placements a failed placement's box refuses (placement_allowed)
        self.blocked_risk = float(o.blocked_risk)  # blocked_rule="risk": the failure chance a blocked box adds
        self.dead_end = o.dead_end  # what a plan ending where no move is left costs ("ignore", "model", ...)
        self.stuck_undo = o.stuck_undo  # stuck: moves back screened by the corrections start plans too (undo_plans)
        self._root_worlds = None  # shuttle_rule "belief": (arrangement, worlds, alive) of the decision being made

    def reset(self, scene_or_observation=None) -> None:
        super().reset(scene_or_observation)
        self._plan, self._expected = [], None
        self._blocked, self._last = [], None
        self._deepened, self._explained, self._share_cache = {}, None, (None, {})
        self._worlds, self._distance_cache, self._n_worlds = None, {}, 0
        self._weights, self._executed, self.evidence_log = {}, None, []
        self._remembered = {}
        self._as_observed, self._maybe = {}, frozenset()
        self._unseen_keys = None
        self._extent_weights = {}

    @property
    def worlds(self) -> "PackedWorlds | None":
        """The sampled worlds of the last decision (None before the first one or after the belief was redrawn)."""
        return self._worlds

    @property
    def scene_template(self):
        """The last observation's scene template (shelf and camera, the seen objects; None before a decision)."""
        return self._template

    def placement_weight(self, key: tuple[int, int]) -> float:
        """The weight in the belief of the target placement with lattice key ``key`` (1 unless an action's outcome
        made it likelier; see :meth:`condition_on_outcome`)."""
        return float(self._weights.get(key, 1.0))

    def worlds_for(self, template, placements: np.ndarray, seed: int):
        """(the worlds, (K,) bool: those still consistent with every observation). The worlds drawn at the first
        decision are kept while at least half of ``samples`` of them stay consistent: the consistent ones are a
        sample of the belief (the prior conditioned on what was seen, by rejection), and keeping them keeps the
        plan's values and the occlusion masks from one decision to the next. Then ``samples`` are drawn anew
        from the consistent placements."""
        step = self.grid_step
        if self._worlds is not None:
            keys = np.round(self._worlds.worlds.centers / step).astype(int)
            consistent = np.array([(int(i), int(j)) in self._consistent for i, j in keys], dtype=bool)
            if consistent.sum() >= min(len(placements), max(1, self.samples // 2)):
                return self._worlds, consistent
        self._worlds = PackedWorlds(Worlds(template, self.draw(placements, seed), self.target_size(), self.threshold))
        self._distance_cache = {}
        return self._worlds, np.ones(self._worlds.count, bool)

    # ---- suctions ------------------------------------------------------------------------------------------------
    def placement_box(self, objects, a) -> tuple:
        """The footprint box (x_lo, x_hi, y_lo, y_hi; m) of suction ``a``'s object where ``a`` places it."""
        from slax_drake.scene.footprint import Footprint

        fp = Footprint.of(next(o for o in objects if o.name == a.name))
        ex, ey = fp.extents()
        x = fp.x + a.dx
        return x - ex, x + ex, a.dz - ey, a.dz + ey

    def note_outcome(self, known) -> None:
        """When the last suction did not leave its object where it predicted (put back, or stopped early by
        something unseen), its placement box joins the blocked regions: no later placement overlaps one."""
        if self._last is None:
            return
        (x_lo, x_hi, y_lo, y_hi), name = self._last
        self._last = None
        obj = next((o for o in known if o.name == name), None)
        if obj is None:
            return
        x, y = float(obj.center[0]), float(obj.center[1])
        limit = max(0.005, self.camera_outcome_tolerance) if self._camera_mode else 0.005  # estimated poses: noisier
        if abs(x - (x_lo + x_hi) / 2) > limit or abs(y - (y_lo + y_hi) / 2) > limit:
            self._blocked.append((x_lo, x_hi, y_lo, y_hi))
            if self._camera_mode and self.deepen_failed:
                self._deepened[name] = 1.0

    # ---- objects seen before and hidden now ---------------------------------------------------------------------
    def decide(self, obs) -> Decision:
        self._camera_mode = getattr(obs, "belief", None) is not None
        if self._camera_mode and self.explain_failed != "none":
            self.explain_put_back(obs)
        self._action_model.unaimable = self.unaimable(obs) if self._camera_mode and self.aim_visible else frozenset()
        return super().decide(self.with_remembered(self.with_camera_hypotheses(obs)))

    def unaimable(self, obs) -> frozenset:
        """Camera mode: the names of the hypotheses whose segment shows no disc of the cup's diameter (its size in
        pixels at the segment's median depth, ``cup_diameter * fx / z``) inside the segment's mask, closed by one
        pixel to bridge dropped returns (``aim_visible``)."""
        import cv2

        frame = obs.belief.observation
        cup = self.action_model.tool.geometry.cup_diameter
        out = set()
        for h in obs.belief.hypotheses:
            mask = frame.segmentation == h.segment_id
            z = frame.depth[mask & (frame.depth > 0)]
            if len(z) == 0:
                out.add(h.object.name)
                continue
            diameter = max(1, int(round(cup * frame.camera.fx / float(np.median(z)))))
            closed = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
            disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (diameter, diameter))
            if not cv2.erode(closed, disc, borderValue=0).any():
                out.add(h.object.name)
        return frozenset(out)

    def with_camera_hypotheses(self, obs):
        """Camera mode (``obs.belief`` set) with ``camera_depth``: ``obs`` with its hypotheses estimated again from
        the same frame, each assumed at least ``camera_depth`` deep behind its visible surfaces (the estimator's
        ``DepthPrior(rule="fixed")``, shortened at the walls and the other hypotheses as every prior is). The
        observer's hypotheses assume the least depth an object can have (0.06 m), so a move planned on them can
        run the moved object, or another one, into the unseen rest of a seen object. ``camera_extents``: likewise
        with the range prior. ``deepen_failed``: the objects whose placement failed earlier in the trial are
        estimated with the range prior at its farthest (the rest as above). Privileged observation, or none of the
        three: ``obs`` unchanged."""
        belief = getattr(obs, "belief", None)
        self._as_observed = {}
        deepened = belief is not None and any(h.object.name in self._deepened for h in belief.hypotheses)
        if belief is None or (self.camera_depth is None and self.camera_extents is None and not deepened):
            return obs
        self._as_observed = {o.name: o for o in obs.known}
        from slax_drake.perception.belief import ObservedBelief
        from slax_drake.perception.estimator import DepthPrior, EstimatorConfig, estimate_objects

        names = {h.segment_id: h.object.name for h in belief.hypotheses}  # the tracker's names, when it runs
        if self.camera_extents is not None:
            prior = DepthPrior(rule="range", fraction=float(self.camera_extents))
        elif self.camera_depth is not None:
            prior = DepthPrior(rule="fixed", fixed=float(self.camera_depth))
        else:
            prior = None  # the observer's hypotheses, but for the deepened ones below
        hypotheses = (list(belief.hypotheses) if prior is None
                      else estimate_objects(belief.observation, belief.shelf, EstimatorConfig(prior=prior)))
        if deepened:  # the objects whose placement failed, at the share of their extent range assumed for them
            hypotheses = [self._estimate_at(belief, self._deepened[names[h.segment_id]]).get(h.segment_id, h)
                          if names.get(h.segment_id) in self._deepened else h for h in hypotheses]
        hypotheses = [dataclasses.replace(h, object=dataclasses.replace(h.object, name=names[h.segment_id]))
                      if h.segment_id in names else h for h in hypotheses]
        deeper = ObservedBelief(belief.observation, belief.shelf, belief.source, background=belief.background,
                                hypotheses=hypotheses, p1d=belief.p1d, remembered=belief.remembered)
        known = deeper.known
        return dataclasses.replace(obs, known=known, scene_template=obs.scene_template.with_objects(known),
                                   belief=deeper)

    def _estimate_at(self, belief, share: float) -> dict:
        """segment id -> the hypothesis of ``belief``'s frame estimated with every unseen edge ``share`` of the way
        along its extent range (``DepthPrior(rule="range", fraction=share)``); cached per share for the frame of
        this decision (:meth:`explain_put_back` and :meth:`with_camera_hypotheses` read the same frame)."""
        from slax_drake.perception.estimator import DepthPrior, EstimatorConfig, estimate_objects

        frame, by_share = self._share_cache
        if frame is not belief.observation:
            frame, by_share = belief.observation, {}
            self._share_cache = (frame, by_share)
        if share not in by_share:
            by_share[share] = {h.segment_id: h for h in estimate_objects(
                frame, belief.shelf, EstimatorConfig(prior=DepthPrior(rule="range", fraction=share)))}
        return by_share[share]

    def explain_put_back(self, obs) -> None:
        """Camera mode with ``explain_failed``: when the last action was a suction and this frame shows its object
        where it stood (put back), the least share of an extent range (:data:`EXPLAIN_SHARES`) at which the action
        model puts it back too, on the objects the suction was planned on with that one object estimated again from
        this frame at that share, is assumed for that object from then on (the carried object first; "any": then
        each other seen object, in frame order). An object already assumed at a share is tried only at larger
        ones. Nothing changes when no share of any suspect explains the put-back (its cause is not in the frame)."""
        from slax_drake.shelf.simulator import execute

        self._explained = None
        if self._executed is None or not isinstance(self._executed[0], Suction):
            return
        a, before = self._executed
        start = next((o for o in before if o.name == a.name), None)
        now = next((o for o in obs.known if o.name == a.name), None)
        if start is None or now is None:
            return
        limit = max(0.005, self.camera_outcome_tolerance)
        if _planar_distance(now, start) > limit:
            return  # it moved: placed, or stopped short
        belief = obs.belief
        segment_of = {h.object.name: h.segment_id for h in belief.hypotheses}
        suspects = [a.name] + ([n for n in segment_of if n != a.name] if self.explain_failed == "any" else [])
        suspects = [n for n in suspects if n in segment_of]
        for share in EXPLAIN_SHARES:
            estimates = None
            for name in suspects:
                if self._deepened.get(name, 0.0) >= share:
                    continue
                estimates = estimates if estimates is not None else self._estimate_at(belief, share)
                h = estimates.get(segment_of[name])
                if h is None:
                    continue
                wider = dataclasses.replace(h.object, name=name)
                objects = tuple(wider if o.name == name else o for o in before)
                after, _ = execute(self._template.with_objects(objects), a, self.action_model)
                carried = wider if name == a.name else start
                if _planar_distance(after.object_named(a.name), carried) <= 1e-6:  # put back on these objects too
                    self._deepened[name] = share
                    self._explained = (name, share)
                    return

    def first_move_extent_risk(self, objects, a) -> float:
        """``extent_risk``: the chance that first move ``a``, planned on ``objects`` (this frame's hypotheses and the
        remembered ones), does not go as planned because the objects the frame shows reach farther than their
        hypotheses: ``a`` is executed (:func:`~slax_drake.shelf.simulator.execute`) in each of this decision's
        joint draws of the seen objects' extents (:meth:`extent_draws`; a suction's placement depth follows its
        object's centre, as the shelf simulator executes it on the true object), and the share of draws in which it
        does not go as planned (put back, stopped early, blocked), times ``extent_risk``, is the risk. The count of
        failing draws is cached per action for this decision (``decision_log`` records the taken move's)."""
        failed = self._extent_cache.get(a)
        if failed is None:
            from slax_drake.shelf.simulator import execute, on_true_object

            failed = 0
            seen, draws = self.extent_draws()
            if a.name in seen:
                for grown in draws:
                    scene = self._template.with_objects(tuple(grown.get(o.name, o) for o in objects))
                    _, note = execute(scene, on_true_object(a, objects, scene, a.name), self.action_model)
                    failed += bool(note)
            self._extent_cache[a] = failed
        return min(1.0, self.extent_risk * failed / EXTENT_DRAWS)

    def extent_draws(self) -> tuple[frozenset, list[dict]]:
        """``extent_risk``: (the names of this frame's seen objects, this decision's :data:`EXTENT_DRAWS` joint draws
        of their extents). Each draw gives every seen object a share of its extent range (:data:`EXTENT_DRAW`'s
        probabilities, independent per object; a generator seeded with the scene seed and the step) and holds, by
        name, the objects it grows: the hypothesis estimated again at that share. Drawn once per decision."""
        if self._extent_draws is None:
            belief = self._extent_belief
            seed = self._template.seed if self._template.seed is not None else 0
            rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, self._step, 7])
            levels, probs = zip(*EXTENT_DRAW)
            hypotheses = belief.hypotheses
            picks = rng.choice(len(levels), size=(EXTENT_DRAWS, len(hypotheses)), p=np.array(probs) / sum(probs))
            draws = []
            for row in picks:
                grown = {}
                for h, k in zip(hypotheses, row):
                    estimate = self._estimate_at(belief, levels[k]).get(h.segment_id) if levels[k] > 0 else None
                    if estimate is not None:
                        grown[h.object.name] = dataclasses.replace(estimate.object, name=h.object.name)
                draws.append(grown)
            self._extent_draws = (frozenset(h.object.name for h in hypotheses), draws)
        return self._extent_draws

    def with_remembered(self, obs):
        """``obs`` with the objects seen earlier in this trial and hidden now added to ``known`` (and to the scene
        template), where they were last believed to stand (``remember_objects``; in camera mode only with
        ``camera_memory``, :meth:`remembered_in_frame`).

        In the paper's first-order world nothing moves but the object the robot moves, so an object that the
        robot did not touch since it was seen still stands there when another one, moved in front of it, hides
        it. Forgetting it (the observation lists only what is seen now) makes the planner place objects onto it
        (a placement put back) and believe the target may stand where it stands. The object the last action moved
        is not remembered when it ends hidden: where it stopped is not known."""
        if not self.remember_objects:
            return obs
        camera = getattr(obs, "belief", None) is not None
        if camera and not self.camera_memory:
            return obs
        moved = self._executed[0].name if self._executed is not None else None
        if camera:
            kept = self.remembered_in_frame(obs, moved)
        else:
            seen = {o.name for o in obs.known}
            kept = tuple(o for name, o in sorted(self._remembered.items()) if name not in seen and name != moved)
        known = tuple(obs.known) + kept
        self._remembered = {o.name: o for o in known}
        if not kept:
            return obs
        return dataclasses.replace(obs, known=known, scene_template=obs.scene_template.with_objects(known))

    def remembered_in_frame(self, obs, moved: str | None) -> tuple:
        """Camera mode: the hypotheses of the last decision (seen then, or remembered) that stand for an object
        hidden now, flagged ``remembered`` and named ``remembered_<k>`` (:data:`REMEMBERED`; the policy takes no
        action on them: it sees no segment to act on).

        When the observation comes with a tracker's hidden objects (``obs.belief.remembered``,
        :class:`~slax_drake.perception.tracking.ObjectTracker`), those are the remembered ones, but the one the
        last action moved (``moved``). Otherwise (no tracker): a segment's id says nothing across frames (a real
        segmentation renumbers them), so a hypothesis is matched by where it stands: it is the object of a
        hypothesis of this frame when their footprints overlap (more than ``overlap_share`` of the smaller one);
        the hypothesis the last action moved is not remembered (where it ended is what this frame shows, or
        unknown). An unmatched one is kept unless this frame contradicts it: the frame sees past it (deeper than
        its surface by ``see_through`` m) on more than half of the pixels where it would show, were it alone on
        the shelf."""
        from slax_drake.scene.footprint import Footprint
        from slax_drake.scene.raycast import SceneRaycaster

        tracked = getattr(obs.belief, "remembered", None)
        if tracked is not None:  # the tracker's hidden objects: matched across frames, contradicted ones dropped
            names = {o.name for o in obs.known}
            return tuple(dataclasses.replace(o, name=f"{REMEMBERED}{o.name}", remembered=True) for o in tracked
                         if o.name != moved and f"{REMEMBERED}{o.name}" not in names)
        overlap_share, see_through = 0.2, 0.01
        frame = obs.belief.observation
        now = [Footprint.of(o).polygon() for o in obs.known]
        kept = []
        for name, o in sorted(self._remembered.items()):
            if name == moved:
                continue
            poly = Footprint.of(o).polygon()
            if any(poly.intersection(q).area > overlap_share * min(poly.area, q.area) for q in now):
                continue  # seen now: this frame's hypothesis stands for it
            depth, labels = SceneRaycaster(obs.scene_template.with_objects((o,))).render(frame.camera)
            pixels = labels == 1
            if pixels.any():
                beyond = (frame.depth[pixels] > depth[pixels] + see_through).mean()
                if beyond > 0.5:
                    continue  # the frame shows the space where it was believed: it is not there
            kept.append(o)
        names = {o.name for o in obs.known}
        out = []
        for k, o in enumerate(kept):
            label = o.name if o.remembered else f"{REMEMBERED}{o.name}"
            while label in names:
                label = f"{REMEMBERED}{k}_{label}"
            names.add(label)
            out.append(o if label == o.name else dataclasses.replace(o, name=label, remembered=True))
        return tuple(out)

    def placements(self, obs) -> np.ndarray:
        """:meth:`Hindsight.placements`; in camera mode with ``camera_depth`` and ``maybe_occupied``, judged against
        the observer's hypotheses (each as deep as the frame shows, at least the smallest object depth) rather than
        the deeper ones the actions are checked against: a placement in the part of a hypothesis that only the
        assumed depth fills is possible, with weight ``maybe_occupied`` in the worlds' draw (:meth:`draw`)."""
        shallow = self._as_observed
        if self.maybe_occupied is None or not shallow:
            self._maybe = frozenset()
            return self.with_extent_weights(obs, self.on_seen_target(obs, super().placements(obs)))
        from slax_drake.scene.footprint import Footprint, clear_of

        objects = tuple(shallow.get(o.name, o) for o in obs.known)
        out = super().placements(dataclasses.replace(obs, known=objects,
                                                     scene_template=obs.scene_template.with_objects(objects)))
        half = (self.target_size()[0] / 2, self.target_size()[1] / 2)
        inside = np.zeros(len(out), bool)
        for o in obs.known:
            if o.name in shallow and len(out):
                inside |= ~clear_of("box", out, 0.0, half, Footprint.of(o), 0.0)
        self._maybe = frozenset(self.lattice_keys(out[inside]))
        return self.on_seen_target(obs, out)

    def with_extent_weights(self, obs, placements: np.ndarray) -> np.ndarray:
        """``placements`` unchanged; camera mode with ``extent_prior``: their weights in the draw
        (:meth:`draw`) set to the chance that no seen object's unseen extent reaches them
        (:func:`extent_free_weights` over this frame's hypotheses' extent ranges)."""
        belief = getattr(obs, "belief", None)
        if not self.extent_prior or belief is None:
            return placements
        extents = [h.uncertainty.extent for h in belief.hypotheses if h.uncertainty.extent is not None]
        size = self.target_size()
        w = extent_free_weights(placements, (size[0] / 2, size[1] / 2), extents)
        self._extent_weights = dict(zip(self.lattice_keys(placements), (float(v) for v in w)))
        return placements

    def on_seen_target(self, obs, placements: np.ndarray) -> np.ndarray:
        """Camera mode with ``seen_target``: when the frame's target mask shows part of the target, the placements
        (K, 2; m) whose target (its known size, any yaw: within its half diagonal plus half a lattice step and
        5 mm of its centre, in x-y) holds at least 95 % of the seen target points, back-projected into S; the
        belief keeps only these from now on. When none of ``placements`` (those consistent with every observation
        so far) holds them, the placements possible now (clear of the seen objects, seen less than v past them:
        :func:`~slax_drake.policies.hindsight.possible_placements`) are collapsed instead: the seen points are
        direct evidence, the earlier observations' consistency is the model's (a hypothesis narrower than its
        object makes the true placement look partly seen at the first observation, where a wholly hidden target
        is required). Unchanged when nothing of the target shows, in privileged mode, or when no placement holds
        the points (the estimate is off: the belief is not emptied on it)."""
        belief = getattr(obs, "belief", None)
        self._target_seen_now = False
        if not self.seen_target or belief is None or not len(placements):
            return placements
        frame = belief.observation
        mask = frame.target_mask & (frame.depth > 0)
        if not mask.any():
            return placements
        from slax_drake.perception.segmentation import back_project

        points = back_project(np.where(mask, frame.depth, 0.0).astype(np.float32), frame.camera)[mask][:, :2]
        size = self.target_size()
        reach = float(np.hypot(size[0] / 2, size[1] / 2)) + self.grid_step / 2 + 0.005

        def holding(centers: np.ndarray) -> np.ndarray:
            d = np.hypot(centers[:, None, 0] - points[None, :, 0], centers[:, None, 1] - points[None, :, 1])
            return centers[(d <= reach).mean(axis=1) >= 0.95]

        kept = holding(placements)
        if not len(kept):
            from slax_drake.policies.hindsight import possible_placements

            now = possible_placements(obs.scene_template.with_objects(obs.known), size, self.grid_step,
                                      self.threshold)
            kept = holding(now) if len(now) else now
        if not len(kept):
            return placements
        if self.unseen_risk and self._unseen_keys is None:  # the hidden space so far, before the collapse
            self._unseen_keys = set(self.lattice_keys(placements))
        self._consistent = set(self.lattice_keys(kept))
        self._target_seen_now = True
        return kept

    def hidden_space(self, obs, placements: np.ndarray) -> np.ndarray:
        """(K, 2; m) the lattice placements standing for the space never seen since the trial began, where an
        unseen object may stand (what :meth:`placement_risk` and :meth:`holds_hidden_space` read): the target's
        possible ``placements``; with ``unseen_risk``, once a partly seen target collapsed the belief
        (:meth:`on_seen_target`), the belief before the collapse, less every placement a later frame shows (a target
        there seen at v past the seen objects: :func:`~slax_drake.policies.hindsight.possible_placements`): the
        collapsed belief makes every placement away from the target look safe, into space other unseen objects may
        hold."""
        if self._unseen_keys is None:
            return placements
        from slax_drake.policies.hindsight import possible_placements

        now = possible_placements(obs.scene_template.with_objects(obs.known), self.target_size(), self.grid_step,
                                  self.threshold)
        self._unseen_keys &= set(self.lattice_keys(now))
        return np.array(sorted(self._unseen_keys), dtype=float).reshape(-1, 2) * self.grid_step

    # ---- what an executed action's outcome says about the target ---------------------------------------------
    def condition_on_outcome(self, known) -> None:
        """Updates the belief with the outcome of the action taken last (``evidence="outcome"``).

        A robot knows where it commanded an object and sees where the object ended (the next observation: the
        object moved less than commanded, or not at all); it does not know what stopped it. For every placement c
        still possible, the action is replayed with the first-order executor on the objects seen before it (plus
        any seen only now, where they stand now) and a target at c, giving the pose the object would have ended
        at (the simulator's own rule: a push or a placement stops before the first obstacle; a blocked blade or
        way out leaves it in place). Then, against the pose observed now:
        - the outcome is what the seen objects alone predict: a target at c that would have stopped the object
          cannot be there (removed from the belief; certain);
        - something unseen stopped it: a target at c that would have stopped it exactly there explains the
          outcome, and its weight is multiplied by ``block_weight`` (the odds of the target against a wholly
          hidden object there: at 8-10 objects Table I scenes hide about two objects besides the target, so the
          target is not certain); a target at c that would have stopped a push earlier than observed cannot be
          there (removed); the others keep their weight.
        The worlds are drawn anew from the weighted belief when a weight changed (:meth:`draw`)."""
        executed, self._executed = self._executed, None
        if executed is None or self.evidence != "outcome" or not self._consistent:
            return
        from slax_drake.shelf.simulator import execute
        from slax_drake.scene.model import Target, planar_pose

        a, before = executed
        now = {o.name: o for o in known}
        if a.name not in now:
            return
        names = {o.name for o in before}
        objects = tuple(before) + tuple(o for o in known if o.name not in names)
        template = self._template
        size = self.target_size()

        def end_of(scene) -> np.ndarray:
            after, _ = execute(scene, a, self.action_model)
            return np.asarray(after.object_named(a.name).center[:2], dtype=float)

        start = np.asarray(next(o for o in before if o.name == a.name).center[:2], dtype=float)
        seen = np.asarray(now[a.name].center[:2], dtype=float)
        alone = end_of(template.with_objects(objects))
        tol = self.camera_outcome_tolerance if self._camera_mode else 0.003
        keys = sorted(self._consistent)
        centers = np.array(keys, dtype=float).reshape(-1, 2) * self.grid_step
        near = self._near_action(objects, a, centers)
        removed = explained = 0
        certain = bool(np.linalg.norm(seen - alone) <= tol)
        for key, c, close in zip(keys, centers, near):
            if not close:
                continue
            target = Target(size, planar_pose(float(c[0]), float(c[1]), size[2] / 2.0, 0.0))
            end = end_of(dataclasses.replace(template, objects=objects, target=target))
            if np.linalg.norm(end - seen) <= tol:
                if not certain and np.linalg.norm(end - alone) > tol:
                    self._weights[key] = self._weights.get(key, 1.0) * self.block_weight
                    explained += 1
                continue
            if np.linalg.norm(end - alone) <= tol:
                continue  # the target there would not have touched it: unseen something else stopped it
            if certain or (isinstance(a, Push) and np.linalg.norm(end - start) < np.linalg.norm(seen - start) - tol):
                self._consistent.discard(key)
                removed += 1
        planned = np.asarray(apply_action(before, a)[[o.name for o in before].index(a.name)].center[:2], dtype=float)
        self.evidence_log.append({"step": self._step, "action": a.describe(), "stopped": not certain,
                                  "removed": removed, "explained": explained,
                                  "as_planned": bool(np.linalg.norm(seen - planned) <= tol),
                                  "seen_objects_predict": bool(np.linalg.norm(alone - planned) <= tol)})
        if explained:
            self._worlds = None  # drawn anew from the weighted belief

    def _near_action(self, objects, a, centers: np.ndarray) -> np.ndarray:
        """(K,) bool: the target placements that could touch action ``a``'s object, blade or ways out and in (a box
        around the object's whole travel, widened by the target, the blade and the clearances); the others cannot
        change its outcome."""
        from slax_drake.scene.footprint import Footprint

        fp = Footprint.of(next(o for o in objects if o.name == a.name))
        ex, ey = fp.extents()
        pad = max(self.target_size()[:2]) / 2 + 0.06
        if isinstance(a, Push):
            boxes = [(min(fp.x, fp.x + a.d) - ex, max(fp.x, fp.x + a.d) + ex, fp.y - ey, fp.y + ey)]
        else:
            front = -self._template.shelf.depth / 2
            boxes = [(fp.x - ex, fp.x + ex, front, fp.y + ey), (fp.x + a.dx - ex, fp.x + a.dx + ex, front, a.dz + ey)]
        near = np.zeros(len(centers), bool)
        for x_lo, x_hi, y_lo, y_hi in boxes:
            near |= ((centers[:, 0] >= x_lo - pad) & (centers[:, 0] <= x_hi + pad)
                     & (centers[:, 1] >= y_lo - pad) & (centers[:, 1] <= y_hi + pad))
        return near

    def draw(self, placements: np.ndarray, seed: int) -> np.ndarray:
        """``samples`` placements: :meth:`Hindsight.draw` (stratified, uniform) while every weight is 1; else one
        per stratum of equal weight along x (then y), by the same seeded generator (systematic sampling of the
        weighted belief, which :meth:`condition_on_outcome` and, in camera mode, :meth:`placements` set)."""
        keys = self.lattice_keys(placements)
        w = np.array([self._weights.get(k, 1.0) * (self.maybe_occupied if k in self._maybe else 1.0)
                      * self._extent_weights.get(k, 1.0) for k in keys])
        if not len(w) or np.all(w == 1.0):
            return super().draw(placements, seed)
        rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, self._step])
        order = np.lexsort((placements[:, 1], placements[:, 0]))
        cum = np.cumsum(w[order])
        k = min(self.samples, len(placements))
        u = (np.arange(k) + rng.random(k)) / k * cum[-1]
        picks = order[np.minimum(np.searchsorted(cum, u, side="right"), len(order) - 1)]
        return placements[picks]

    def placement_allowed(self, objects, a) -> bool:
        """Whether suction ``a``'s placement may be planned: its box overlaps no blocked region (a box where an
        earlier placement failed: :meth:`note_outcome`). ``blocked_rule="hidden"``: it may overlap one where the
        overlap holds no space that is hidden now (:meth:`holds_hidden_space`); ``"risk"``: every placement may be
        planned, one whose overlap holds hidden space with a higher risk of failing (:meth:`blocked_overlaps`)."""
        if not self._blocked or self.blocked_rule == "risk":
            return True
        b = self.placement_box(objects, a)
        if self.blocked_rule == "box":
            return not self._blocked_intersections(b)
        return self.blocked_overlaps(b) == 0

    def _blocked_intersections(self, box: tuple) -> list:
        """The intersections (x_lo, x_hi, y_lo, y_hi; m) of the box with each blocked region it overlaps (open
        intervals: touching is no overlap)."""
        return [(max(box[0], r[0]), min(box[1], r[1]), max(box[2], r[2]), min(box[3], r[3])) for r in self._blocked
                if box[0] < r[1] and r[0] < box[1] and box[2] < r[3] and r[2] < box[3]]

    def blocked_overlaps(self, box: tuple) -> int:
        """How many blocked regions the placement box (x_lo, x_hi, y_lo, y_hi; m) overlaps in space still hidden
        (:meth:`holds_hidden_space`)."""
        return sum(self.holds_hidden_space(part) for part in self._blocked_intersections(box))

    def holds_hidden_space(self, box: tuple) -> bool:
        """Whether the box (x_lo, x_hi, y_lo, y_hi; m) meets the footprint of a target placement the belief still
        holds (:attr:`_hidden_centers`, this decision's): space never seen since the trial began, where an unseen
        obstacle may stand. What stopped a placement was unseen, so it stands in such space: where the camera has
        seen a blocked box (at the failure, or since), nothing unseen stops a placement. An approximation: a
        hidden gap narrower than the target holds no placement, and a placement the outcome evidence removed (the
        target cannot stand there) is taken as free of other objects too."""
        centers = self._hidden_centers
        if centers is None or not len(centers):
            return False
        hx, hy = self.target_size()[0] / 2, self.target_size()[1] / 2
        x_lo, x_hi, y_lo, y_hi = box
        return bool(np.any((centers[:, 0] > x_lo - hx) & (centers[:, 0] < x_hi + hx)
                           & (centers[:, 1] > y_lo - hy) & (centers[:, 1] < y_hi + hy)))

    def moves(self, objects) -> list:
        """(action, objects after, cost) of every move from ``objects`` on the seen objects: each object pushed each
        way up to its neighbour, and every suction placement of the profile but those overlapping a blocked region
        (the enumeration cached per arrangement for the trial); the cost is :meth:`move_cost`'s (a placement's risk
        of meeting something unseen is not a cost: :meth:`child` weighs the reveals after it by
        :meth:`placement_risk`)."""
        key = state_key(objects)
        hit = self._moves.get(key)
        if hit is None:
            found = maximal_pushes_only(self.action_model.enumerate(objects, pushes=True, suctions=True).feasible)
            hit = self._moves[key] = [(a, apply_action(objects, a)) for a in found]
        return [(a, after, self.move_cost(objects, a)) for a, after in hit
                if not isinstance(a, Suction) or self.placement_allowed(objects, a)]

    def move_cost(self, objects, a) -> float:
        """1 for a push, psi for a suction."""
        return self.cost(a)

    def placement_risk(self, objects, a) -> float:
        """The probability that suction ``a`` does not place its object as planned: ``hidden_risk`` times the share
        of its placement box, widened by half the target, where the target could stand now (hidden space, where an
        unseen object may stand too); 0 for a push (the profile never pushes into hidden space). With
        ``blocked_rule="risk"``, each blocked region its box overlaps in space still hidden multiplies its chance
        of success by 1 - ``blocked_risk``."""
        centers = self._hidden_centers
        if not isinstance(a, Suction) or not self.hidden_risk or centers is None or not len(centers):
            return 0.0
        obj = next(o for o in objects if o.name == a.name)
        hit = self._risk_cache.get((id(obj), a))  # cached per decision (the hidden centres are the decision's)
        if hit is None:
            box = self.placement_box((obj,), a)
            risk = self._risk_by_box.get(box)
            if risk is None:
                risk = self.box_risk(box, centers)
                if self.blocked_rule == "risk" and self._blocked:
                    risk = 1.0 - (1.0 - risk) * (1.0 - self.blocked_risk) ** self.blocked_overlaps(box)
                self._risk_by_box[box] = risk
            hit = self._risk_cache[(id(obj), a)] = (obj, risk)  # the object keeps its id alive
        return hit[1]

    def box_risk(self, box: tuple, centers: np.ndarray) -> float:
        """:meth:`placement_risk` of a placement box (x_lo, x_hi, y_lo, y_hi; m) among the target's possible
        placements ``centers`` (K, 2)."""
        x_lo, x_hi, y_lo, y_hi = box
        hx, hy = self.target_size()[0] / 2, self.target_size()[1] / 2
        x_lo, x_hi, y_lo, y_hi = x_lo - hx, x_hi + hx, y_lo - hy, y_hi + hy
        inside = ((centers[:, 0] >= x_lo) & (centers[:, 0] <= x_hi) & (centers[:, 1] >= y_lo) & (centers[:, 1] <= y_hi))
        cells = max(1.0, (x_hi - x_lo) * (y_hi - y_lo) / self.grid_step ** 2)
        return self.hidden_risk * min(1.0, 2.0 * inside.sum() / cells)

    # ---- per-world distances -----------------------------------------------------------------------------------
    def distances(self, worlds: "PackedWorlds", objects) -> np.ndarray:
        """(K,) float: per world, the fewest objects of ``objects`` whose removal shows its target at v (0, 1, 2
        exactly; from 3 on, the count a greedy cover removes, an upper bound; ``failure_cost`` for a world whose
        target the empty shelf does not show). Cached per tuple of objects (by identity: the search reuses the
        arrangement tuples of :meth:`moves`); :meth:`prefetch_distances` computes many at once."""
        key = tuple(map(id, objects))
        hit = self._distance_cache.get(key)
        if hit is None:
            self.prefetch_distances(worlds, [objects])
            hit = self._distance_cache[key]
        return hit[1]

    def prefetch_distances(self, worlds: "PackedWorlds", arrangements) -> None:
        """Computes and caches :meth:`distances` of every arrangement of ``arrangements`` not cached yet, all in
        one :meth:`world_distances` call per object count: the arrangements' worlds side by side as columns (every
        quantity is computed column by column, so this is exactly the one-by-one result, in far fewer numpy
        calls). An object hiding nothing in any world gets a zero mask row marked ``absent``."""
        cache = self._distance_cache
        todo: dict = {}  # object count -> {key: objects}
        for objects in arrangements:
            key = tuple(map(id, objects))
            if key not in cache:
                todo.setdefault(len(key), {})[key] = objects
        k, w = worlds.shown.shape  # worlds, words per world
        zero = np.zeros((k, w), np.uint64)
        for n, items in todo.items():
            per = [[worlds.mask(o) for o in objects] for objects in items.values()]  # J lists of n masks or None
            j = len(per)
            masks = np.array([[zero if m is None else m for m in ms] for ms in per], dtype=np.uint64).reshape(j, n, k, w)
            masks = masks.transpose(1, 0, 2, 3).reshape(n, j * k, w)  # column j * K + k: world k of arrangement j
            absent = np.repeat(np.array([[m is None for m in ms] for ms in per], bool).reshape(j, n).T, k, axis=1)
            d = self.world_distances(masks, absent, np.tile(worlds.shown, (j, 1)), np.tile(worlds.need, j),
                                     np.tile(worlds.n_shown, j)).reshape(j, k)
            for row, (key, objects) in zip(d, items.items()):
                cache[key] = (tuple(objects), row)  # the objects keep their ids alive

    def world_distances(self, masks: np.ndarray, absent: np.ndarray, shown: np.ndarray, need: np.ndarray,
                        n_shown: np.ndarray) -> np.ndarray:
        """(C,) :meth:`distances` of C world columns: ``masks`` (n, C, W) uint64 the target points each object
        hides (in the arrangement's order), ``absent`` (n, C) bool the rows of objects that hide nothing in any
        world of their arrangement (zero masks; never counted as a removal), ``shown`` (C, W) the points the empty
        shelf shows, ``need`` (C,) how many must be seen (v times ``n_shown``), ``n_shown`` (C,). Column by
        column: a column's value depends on that column alone."""
        c = len(shown)
        at1, at2, at3 = _at_least(masks, 3)
        seen = _popcount(shown & ~at1)  # (C,) points seen past all objects
        d = np.full(c, 3.0)
        only = _popcount(masks & (at1 & ~at2))  # (n, C) points hidden by that object alone
        one = (seen + only >= need).any(axis=0)
        two = np.zeros(c, bool)
        ask = ~one & (seen < need)  # the columns whose count of two decides something
        if len(masks) > 1 and ask.any():
            i, j = _pairs(len(masks))
            m, s, o = masks[:, ask], seen[ask], only[:, ask]
            both = _popcount(m[i] & m[j] & (at2[ask] & ~at3[ask]))  # (pairs, C') hidden by exactly that pair
            two[ask] = (s + o[i] + o[j] + both >= need[ask]).any(axis=0)
        rest = ask & ~two
        if rest.any():
            d[rest] = np.maximum(3.0, self.greedy_removals(masks[:, rest], shown[rest], need[rest], known_above=2,
                                                           absent=absent[:, rest]))
        d = np.where(one, 1.0, np.where(two, 2.0, d))
        d = np.where(seen >= need, 0.0, d)
        return np.where(n_shown > 0, d, self.failure_cost)

    @staticmethod
    def greedy_removals(masks: np.ndarray, shown: np.ndarray, need: np.ndarray, known_above: int = 0,
                        absent: np.ndarray | None = None) -> np.ndarray:
        """(K,) per world, how many objects a greedy cover removes until its target is seen at v (each time the
        object whose removal shows the most of it, the first such on a tie; an upper bound on the fewest;
        ``len(masks) + 1`` when even removing all does not show it). ``masks`` (n, K, W) packed per object,
        ``shown`` (K, W), ``need`` (K,). ``known_above``: the caller knows that no world's target is shown by
        removing this many objects or fewer (:meth:`world_distances` passes 2), so the check is skipped for those
        counts; the picks are made all the same. ``absent`` (n, K) bool: rows standing for no object (zero masks,
        never picked). Worlds leave the arrays as they are done."""
        n, k = masks.shape[0], masks.shape[1]
        present = masks.copy()  # the masks of the objects not removed yet (a removed one's are zeroed)
        removed = np.zeros((n, k), bool) if absent is None else absent.copy()
        out = np.full(k, float(n + 1))
        worlds = np.arange(k)  # the worlds the arrays' columns stand for
        for step in range(n + 1):
            at1, at2 = _at_least(present, 2)
            if step > known_above or step == n:
                done = _popcount(shown & ~at1) >= need
                out[worlds[done]] = step
                if done.all():
                    break
                if done.any():
                    keep = ~done
                    present, removed, shown, need, worlds = present[:, keep], removed[:, keep], shown[keep], \
                        need[keep], worlds[keep]
                    at1, at2 = at1[keep], at2[keep]
            if step == n:
                break
            gain = _popcount(present & (at1 & ~at2))  # (n, K) shown by removing that one next
            gain[removed] = -1
            pick = gain.argmax(axis=0)
            columns = np.arange(len(worlds))
            removed[pick, columns] = True
            present[pick, columns] = 0
        return out

    # ---- search --------------------------------------------------------------------------------------------------
    def child(self, worlds, node: _Node, a, after, c: float, remaining: int, order: int) -> _Node:
        if node.mass is None:
            node.mass = node.alive.sum() / self._n_worlds  # the share of worlds not revealed yet
        g = node.g + c * node.mass
        d_before = self.distances(worlds, node.objects)
        alive, lost = node.alive, node.lost
        if isinstance(a, Suction):
            blocked = worlds.blocks(after, a.name) & alive
            if blocked.any():
                lost = lost + float(((d_before + c) * blocked).sum()) / self._n_worlds
                alive = alive & ~blocked
        prob = node.prob * (1.0 - self.placement_risk(node.objects, a))
        if not node.plan and self._extent_belief is not None:
            prob *= 1.0 - self.first_move_extent_risk(node.objects, a)
        d = self.distances(worlds, after)
        shown = alive & (d == 0)
        alive = alive & ~shown
        left = remaining - len(node.plan) - 1
        h = np.where(d > left, self.failure_cost, d)
        n = self._n_worlds
        n_shown = float(shown.sum())
        value = g + lost + float((h * alive).sum()) / n + (1.0 - prob) * n_shown / n
        revealed = node.revealed + prob * n_shown / n
        return _Node(after, node.plan + (a,), g, alive, lost, value, order, revealed, prob)

    def expansions(self, worlds, node: _Node, moves, remaining: int, counter) -> list:
        """The children of ``node`` over ``moves`` ((action, objects after, cost)): every push, and each object's
        ``placements_per_object`` best suctions (of the placements where the object hides no world's target, only
        the least risky one is looked at: they lead to the same value but for the risk)."""
        kids = []
        best_suctions: dict = {}
        aside: dict = {}  # per object, the placement that hides no world's target with the least risk
        looked = []  # the moves looked at, in order (the aside ones after them)
        for a, after, c in moves:
            if isinstance(a, Suction):
                moved = next(o for o in after if o.name == a.name)
                if worlds.mask(moved) is None:  # such placements differ only in their risk: keep one
                    risk = self.placement_risk(node.objects, a)
                    if a.name not in aside or risk < aside[a.name][0]:
                        aside[a.name] = (risk, a, after, c)
                    continue
            looked.append((a, after, c))
        looked += [(a, after, c) for _, a, after, c in aside.values()]  # suctions only
        self.prefetch_distances(worlds, [node.objects] + [after for _, after, _ in looked])
        for a, after, c in looked:
            kid = self.child(worlds, node, a, after, c, remaining, next(counter))
            if isinstance(a, Push):
                kids.append(kid)
            else:
                best_suctions.setdefault(a.name, []).append(kid)
        for group in best_suctions.values():
            group.sort(key=lambda k: (k.value, k.order))
            kids.extend(group[: self.placements_per_object])
        return kids

    def screened_counts(self, objects=None) -> dict:
        """The base policy's screening counts, plus :attr:`Screened.PLACEMENT_NOT_ALLOWED` for the suctions it lets
        through whose placement overlaps a blocked region (:meth:`placement_allowed`)."""
        counts = super().screened_counts(objects)
        objects = self._objects if objects is None else tuple(objects)
        blocked = sum(1 for a in super(Hindsight, self).candidates(objects, True, True)
                      if isinstance(a, Suction) and not self.placement_allowed(objects, a))
        if blocked:
            counts[str(Screened.PLACEMENT_NOT_ALLOWED)] = blocked
        return counts

    def reveals_new(self, objects, action, memory: TrialMemory | None = None) -> bool:
        """Correction 3's test (:meth:`Policy.reveals_new`). ``shuttle_rule`` "belief": the width rule, or, for a
        first move of the decision being made (``objects`` its arrangement, ``memory`` this trial's), the
        arrangement after ``action`` shows the target in at least one of the belief's worlds still alive (a
        world is alive only while no frame of this trial showed its place: the move shows space no earlier
        arrangement showed). Moves later in a plan (another ``memory`` or arrangement) are judged by width."""
        if self.shuttle_rule != "belief":
            return super().reveals_new(objects, action, memory)
        memory = self.memory if memory is None else memory
        width = memory.vacates_unseen(objects, action) >= self.shuttle_reveal
        root = self._root_worlds
        objects = tuple(objects)
        if width or memory is not self.memory or root is None or len(objects) != len(root[0]) \
                or not all(a is b for a, b in zip(objects, root[0])):
            return width
        _, worlds, alive = root
        if not alive.any():
            return False
        after = apply_action(objects, action)
        return bool((alive & (self.distances(worlds, after) == 0)).any())

    def action_model_candidates(self, objects) -> list:
        """The first moves: the policy's candidates (every suction of the profile; exclusions and no return
        applied), less the placements overlapping a blocked region."""
        base = super(Hindsight, self).candidates(objects, True, True)
        return [a for a in base if not isinstance(a, Suction) or self.placement_allowed(objects, a)]

    def uncovering_moves(self, worlds, known, alive: np.ndarray, cands: list) -> list:
        """With the belief collapsed onto a partly seen target (``seen_target`` and ``uncover_seen``): the feasible
        moves not among ``cands`` (refused by the no-return or no-shuttle correction; a failed action's exclusion
        and a blocked placement box still apply) whose object hides part of the ``alive`` worlds' targets and after
        which the arrangement hides fewer of their points than the current one and than every arrangement observed
        in this trial: the moves that clear more of the seen target than was ever cleared. The corrections keep a
        distribution policy from shuttling an object between arrangements that reveal nothing new; here every
        world is the seen target, so clearing more of it than before is progress, while a move back to where the
        target was hidden as much as now is not (without that test an object in front of the target was pushed
        right then carried left, each move clearing more than the arrangement before it, until the horizon).

        An observed arrangement holds the objects seen then; an object not seen then counts where it stands now
        (only acted-on objects move)."""
        found = maximal_pushes_only(self._action_model.enumerate(known, pushes=True, suctions=True).feasible)
        allowed = self._exclusions.allowed(found, known)
        taken = set(cands)
        alive_rows = np.flatnonzero(alive)
        if not len(alive_rows):
            return []
        def masked(obj):
            m = worlds.mask(obj)
            return None if m is None else m[alive_rows]

        def hidden_by(masks) -> int:
            """Points of the alive worlds' targets that the objects of ``masks`` (None: hides none) hide together."""
            union = None
            for m in masks:
                if m is not None:
                    union = m if union is None else union | m
            return 0 if union is None else int(_popcount(union).sum())

        now = {o.name: masked(o) for o in known}  # each object's hidden points where it stands now

        def filled(arrangement):
            """The masks of an observed arrangement, an object not seen then where it stands now."""
            then = {o.name: masked(o) for o in arrangement}
            return list(then.values()) + [m for name, m in now.items() if name not in then]

        least = min([hidden_by(now.values())] + [hidden_by(filled(seen)) for seen in self.memory.observed])
        others: dict = {}  # name -> the union of every other object's mask now, as a one-element list
        out = []
        for a in allowed:
            if a in taken or (isinstance(a, Suction) and not self.placement_allowed(known, a)):
                continue
            if now[a.name] is None:
                continue  # its object hides nothing of the seen target
            if a.name not in others:
                rest = [m for name, m in now.items() if name != a.name and m is not None]
                others[a.name] = [np.bitwise_or.reduce(rest)] if rest else []
            moved = next(o for o in apply_action(known, a) if o.name == a.name)
            if hidden_by(others[a.name] + [masked(moved)]) < least:
                out.append(a)
        return out

    def rank(self, obs) -> Decision:
        import itertools

        t0 = time.process_time()
        self._step += 1
        known = tuple(obs.known)
        self._template = obs.scene_template
        self.note_outcome(known)
        self.condition_on_outcome(known)
        # this decision's placements first: placement_allowed may read them (blocked_rule="hidden")
        placements = self.placements(obs)
        self._hidden_centers = self.hidden_space(obs, placements)
        self._risk_by_box, self._risk_cache = {}, {}
        self._extent_belief = getattr(obs, "belief", None) if self.extent_risk > 0 else None
        self._extent_cache, self._extent_draws = {}, None
        template = obs.scene_template
        seed = template.seed if template.seed is not None else 0
        worlds = consistent = self._root_worlds = None
        if len(placements):  # before the first moves are screened: shuttle_rule "belief" reads them (reveals_new)
            worlds, consistent = self.worlds_for(template, placements, seed)
            if self.shuttle_rule == "belief":
                self._root_worlds = (known, worlds, consistent & (self.distances(worlds, known) > 0))
        cands = maximal_pushes_only(self.action_model_candidates(known))
        if not cands:
            return Decision.stop("no feasible action")
        log = {"placements": int(len(placements)), "samples": 0, "expanded": 0, "capped": False}
        if self._explained is not None:
            log["put_back_explained"] = {"object": self._explained[0], "share": self._explained[1]}
            self._explained = None
        if self._target_seen_now:
            log["target_seen"] = True  # the placements were collapsed onto a partly seen target (seen_target)
        self.decision_log.append(log)
        if not len(placements):
            return Decision(tuple(cands))
        self._n_worlds = int(consistent.sum())
        log["samples"] = self._n_worlds
        remaining = self.horizon - (self._step - 1) if self.horizon is not None else 10 ** 6
        counter = itertools.count()
        self._root_objects = known  # the arrangement the plans start from (dead_end_cost)
        self._node_moves = {}  # id(node) -> (node, its plan_moves), this decision's (expansion and dead_end_cost)
        root = _Node(known, (), 0.0, np.ones(worlds.count, bool), 0.0, 0.0, -1)
        d0 = self.distances(worlds, known)
        root.alive = consistent & (d0 > 0)
        if self._target_seen_now and self.uncover_seen:
            extra = self.uncovering_moves(worlds, known, root.alive, cands)
            if extra:
                log["uncovering"] = len(extra)  # first moves the corrections refused, let through (seen_target)
                cands = cands + extra
        level = self.expansions(worlds, root, [(a, apply_action(known, a), self.move_cost(known, a)) for a in cands],
                                remaining, counter)
        # the rest of the last plan, when this is the arrangement it expected: kept in the beam at every depth
        kept: dict = {}
        if self._plan and self._expected == state_key(known) and self._plan[0] in cands:
            node = root
            for i, a in enumerate(self._plan[: self.depth]):
                after = apply_action(node.objects, a)
                c = self.move_cost(node.objects, a)
                node = kept[i + 1] = self.child(worlds, node, a, after, c, remaining, next(counter))
        first_level = list(level)
        seen_nodes = self.beam_search(worlds, first_level, kept, remaining, counter, log, t0, self.beam)
        if self.widen_beam > self.beam and not log["capped"] and not any(k.revealed > 0 for k in seen_nodes):
            log["widened"] = True  # nothing revealed within max_depth: once more with a wider beam
            seen_nodes += self.beam_search(worlds, first_level, kept, remaining, counter, log, t0, self.widen_beam)
        if self.stuck_undo and not log["capped"] and not any(k.revealed > 0 for k in seen_nodes):
            undo = self.undo_plans(worlds, root, cands, remaining, counter, log, t0)
            if undo:
                seen_nodes = undo
                first_level = [k for k in undo if len(k.plan) == 1]
        if self.stuck_select == "stop" and not log["capped"] and not any(k.revealed > 0 for k in seen_nodes):
            log["stalled"] = True  # no plan looked at reveals anything: stop rather than move on
            log["seconds"] = round(time.process_time() - t0, 3)
            self._plan = []
            return Decision.stop(NO_REVEALING_PLAN)
        if self.select == "ratio" and any(k.revealed > 0 for k in seen_nodes):
            # the most revealed mass per expected cost, R / (G + dead end); ties: the lesser V, the earlier plan
            best = self.least(seen_nodes, lambda k, extra: (-k.revealed / max(k.g + extra, 1e-9), k.value, k.order),
                              log)
        elif self.stuck_select == "progress" and log.get("widened"):
            # no plan reveals anything, even widened: the plan that ends nearest to revealing (least V - G)
            best = self.least(seen_nodes, lambda k, extra: (k.value - k.g + extra, k.value, len(k.plan), k.order),
                              log)
        else:
            best = self.least(seen_nodes, lambda k, extra: (k.value + extra, len(k.plan), k.order), log)
        log["revealed"] = round(best.revealed, 4)
        log["value"] = round(best.value, 4)
        log["expected_cost"] = round(best.g, 4)  # G of the chosen plan
        log["plan"] = [a.describe() for a in best.plan]
        log["seconds"] = round(time.process_time() - t0, 3)
        first = best.plan[0]
        if self._extent_belief is not None:  # the taken move's (extent_risk)
            failed = self._extent_cache.get(first, 0)
            log["extent_draws_failed"] = failed
            log["extent_risk"] = round(min(1.0, self.extent_risk * failed / EXTENT_DRAWS), 4)
        if isinstance(first, Suction):
            self._last = (self.placement_box(known, first), first.name)
        self._executed = (first, known)
        self._plan = list(best.plan[1:])
        self._expected = state_key(apply_action(known, first))
        ranked = sorted(first_level, key=lambda k: (k.value, k.order))
        rest = [k.plan[0] for k in ranked if k.plan[0] != first]
        rest += [a for a in cands if a != first and a not in rest]
        return Decision((first, *rest))

    def undo_plans(self, worlds, root: _Node, cands: list, remaining: int, counter, log: dict, t0: float) -> list:
        """``stuck_undo``: every plan looked at (a widened beam) from the feasible moves the corrections screened out
        only as a return to an observed arrangement or as a shuttle (a failed action's exclusion and a blocked
        placement still apply), when one of them reveals part of the belief; else []. ``log["undo"]``: how many
        such first moves were looked at."""
        taken = set(cands)
        moves = [m for m in self.moves(root.objects) if m[0] not in taken]
        if not moves:
            return []
        why = dict(self.screen(root.objects, [a for a, _, _ in moves]))
        moves = [m for m in moves if why.get(m[0]) in (Screened.BACK, Screened.SHUTTLE)]
        if not moves:
            return []
        log["undo"] = len(moves)
        first_level = self.expansions(worlds, root, moves, remaining, counter)
        nodes = self.beam_search(worlds, first_level, {}, remaining, counter, log, t0, self.widen_beam)
        return nodes if any(k.revealed > 0 for k in nodes) else []

    def plan_moves(self, node: _Node) -> list:
        """The moves the search looks at from ``node``: :meth:`moves`, and with ``dead_end`` "corrections" only
        those the corrections would leave after its plan (:meth:`screen` on :meth:`TrialMemory.after_plan`; a
        shuttle is left only with ``shuttle_last_resort``), as the policy itself would screen them when it got
        there."""
        moves = self.moves(node.objects)
        if moves and node.plan and self.dead_end == "corrections":
            hit = self._node_moves.get(id(node))
            if hit is not None:
                return hit[1]
            memory = self.memory.after_plan(self._root_objects, node.plan)
            left = {None, Screened.SHUTTLE} if self.shuttle_last_resort else {None}
            moves = [m for m, (_, why) in zip(moves, self.screen(node.objects, [a for a, _, _ in moves], memory))
                     if why in left]
            self._node_moves[id(node)] = (node, moves)  # the node kept alive: its id stays its own
        return moves

    def dead_end_cost(self, node: _Node, log: dict | None = None) -> float:
        """``dead_end``: ``failure_cost`` times the share of worlds ``node`` leaves alive when the search could not
        go on from its arrangement (:meth:`plan_moves` finds none), else 0. Counted in ``log["dead_ends"]``."""
        if self.dead_end == "ignore" or not node.alive.any() or not self._n_worlds or self.plan_moves(node):
            return 0.0
        if log is not None:
            log["dead_ends"] = log.get("dead_ends", 0) + 1
        return self.failure_cost * float(node.alive.sum()) / self._n_worlds

    def least(self, nodes: list, key, log: dict) -> _Node:
        """The node of least ``key(node, extra)`` (a tuple whose first element does not decrease as ``extra``
        grows), ``extra`` its :meth:`dead_end_cost` with ``dead_end``, else 0. Evaluated lazily: nodes in order of
        ``key(node, 0)``, a lower bound of their own key, until the next one's exceeds the best found (each
        evaluation may enumerate and screen the moves of an arrangement not yet expanded)."""
        if self.dead_end == "ignore":
            return min(nodes, key=lambda k: key(k, 0.0))
        best, best_key = None, None
        for k in sorted(nodes, key=lambda k: key(k, 0.0)):
            if best is not None and key(k, 0.0)[0] > best_key[0]:
                break
            k_key = key(k, self.dead_end_cost(k, log))
            if best is None or k_key < best_key:
                best, best_key = k, k_key
        return best

    def beam_search(self, worlds, first_level: list, kept: dict, remaining: int, counter, log: dict, t0: float,
                    beam_width: int) -> list:
        """Every plan looked at (duplicates merged per depth) by a beam of ``beam_width`` from the first moves
        ``first_level``, ``kept`` (depth -> node: the rest of the last plan) kept in the beam, to ``depth``
        actions, on to ``max_depth`` while no plan reveals anything; stops at the CPU cap (``log["capped"]``)."""
        level = list(first_level)
        seen_nodes = []  # every plan looked at (after merging duplicates)
        for depth in range(1, self.max_depth + 1):
            merged: dict = {}
            for k in level + ([kept[depth]] if depth in kept else []):
                key = state_key(k.objects)
                old = merged.get(key)
                if old is None or (k.value, k.order) < (old.value, old.order):
                    merged[key] = k
            level = sorted(merged.values(), key=lambda k: (k.value, k.order))
            seen_nodes.extend(level)
            level = [k for k in level if k.alive.any()]
            beam = level[: beam_width]
            if depth in kept and kept[depth].alive.any() and all(k is not kept[depth] for k in beam):
                if merged.get(state_key(kept[depth].objects)) is kept[depth]:
                    beam.append(kept[depth])
            level = beam
            log["expanded"] += len(level)
            if not level or depth >= self.max_depth or \
                    (depth >= self.depth and any(k.revealed > 0 for k in seen_nodes)):
                break
            if time.process_time() - t0 > self.seconds:
                log["capped"] = True
                break
            nxt = []
            for i, k in enumerate(level):
                if i and time.process_time() - t0 > self.seconds:
                    log["capped"] = True  # the nodes looked at so far make the next level
                    break
                nxt.extend(self.expansions(worlds, k, self.plan_moves(k), remaining, counter))
            level = nxt
        return seen_nodes


@functools.lru_cache(maxsize=64)
def _pairs(n: int):
    """The index pairs i < j of ``n`` objects (np.triu_indices, cached)."""
    return np.triu_indices(n, 1)


def _popcount(words: np.ndarray) -> np.ndarray:
    """Set bits per row of packed words: (..., W) uint64 -> (...) int64. The W words are added one by one: a numpy
    sum over a short last axis costs several times more than W additions."""
    counts = np.bitwise_count(words)
    total = counts[..., 0].astype(np.int64)
    for w in range(1, counts.shape[-1]):
        total += counts[..., w]
    return total


def _at_least(masks: np.ndarray, levels: int) -> list:
    """[bits set in at least 1, ..., at least ``levels`` (at most 3) of the packed ``masks`` (n, ..., W) uint64],
    each (..., W), bit by bit. A bit is set in at least two of masks[:i + 1] when it is set in masks[i] and in one
    of masks[:i], and in at least three when it is set in masks[i] and in two of masks[:i]: OR-accumulated
    prefixes along the first axis, a fixed number of array operations whatever n."""
    zeros = np.zeros(masks.shape[1:], np.uint64)
    if not len(masks):
        return [zeros] * levels
    one = np.bitwise_or.accumulate(masks, axis=0)  # one[i]: set in at least one of masks[:i + 1]
    out = [one[-1]]
    if levels >= 2:
        two = np.bitwise_or.accumulate(masks[1:] & one[:-1], axis=0) if len(masks) > 1 else zeros[None]
        out.append(two[-1])  # two[i]: set in at least two of masks[:i + 2]
        if levels >= 3:
            out.append(np.bitwise_or.reduce(masks[2:] & two[:-1], axis=0) if len(masks) > 2 else zeros)
    return out


class PackedWorlds:
    """:class:`~slax_drake.policies.hindsight.Worlds` with each world's target points packed as bits (uint64 words),
    and each object's occlusion masks cached by the object itself and by its name, footprint and size, so that an
    equal object rebuilt by another plan reuses them."""

    def __init__(self, worlds: Worlds):
        self.worlds = worlds
        self.count = worlds.count
        self.n_shown = worlds.n_shown
        self.need = worlds.threshold * worlds.n_shown - 1e-9
        self.shown = self.pack(worlds.shown)
        self._masks: dict = {}  # id(object) -> (the object, kept alive; its mask or None)
        self._masks_by_pose: dict = {}  # (name, Footprint, size) of the object -> its mask or None
        self._blocks: dict = {}  # Footprint of an object -> (K,) bool, the worlds whose target it overlaps
        self._blocks_by_id: dict = {}  # id(object) -> (the object, its entry of _blocks)
        from shapely.geometry import MultiPoint

        hx, hy = worlds.size[0] / 2, worlds.size[1] / 2
        corners = [(x + sx * hx, y + sy * hy) for x, y in worlds.centers for sx in (-1, 1) for sy in (-1, 1)]
        # every eye-to-target segment of every world projects inside this hull: an object clear of it hides nothing
        self.hull = _ConvexRegion(MultiPoint([tuple(worlds.eye[:2])] + corners).convex_hull)

    @staticmethod
    def pack(bits: np.ndarray) -> np.ndarray:
        """(K, P) bool -> (K, W) uint64."""
        k, p = bits.shape
        w = max(1, -(-p // 64))
        padded = np.zeros((k, w * 64), bool)
        padded[:, :p] = bits
        return np.packbits(padded, axis=1).view(np.uint64)

    def mask(self, obj):
        """(K, W) the points of each world's target that ``obj`` alone hides; None when it hides none."""
        hit = self._masks.get(id(obj))
        if hit is None:
            from slax_drake.scene.footprint import Footprint

            fp = Footprint.of(obj)
            key = (obj.name, fp, tuple(obj.size))  # exact: what the hull test and the mask depend on
            if key in self._masks_by_pose:
                m = self._masks_by_pose[key]
            else:
                ex, ey = fp.extents()
                m = None
                if self.hull.may_meet_box(fp.x - ex, fp.x + ex, fp.y - ey, fp.y + ey):
                    hidden = self.worlds.hidden_by(obj)
                    m = self.pack(hidden) if hidden.any() else None
                self._masks_by_pose[key] = m
            hit = self._masks[id(obj)] = (obj, m)
        return hit[1]

    def blocks(self, objects, name: str) -> np.ndarray:
        """(K,) bool: :meth:`Worlds.blocks` (the object ``name`` of ``objects`` overlaps the target of each world),
        cached by the object's footprint (all it depends on). Not to be modified."""
        obj = next(o for o in objects if o.name == name)
        hit = self._blocks_by_id.get(id(obj))
        if hit is None:
            from slax_drake.scene.footprint import Footprint

            key = Footprint.of(obj)
            blocks = self._blocks.get(key)
            if blocks is None:
                blocks = self._blocks[key] = self.worlds.blocks(objects, name)
            hit = self._blocks_by_id[id(obj)] = (obj, blocks)  # the object keeps its id alive
        return hit[1]


class _ConvexRegion:
    """A convex polygon of the shelf plane (x, y; m) as half-planes, for a fast test whether an axis-aligned box may
    meet it (the separating-axis test of a box against a convex polygon: the box's two axes and the polygon's edge
    normals). Conservative: a box within ``slack`` (m) of the polygon counts as meeting it; a caller may only use a
    "no" to skip work whose result would be empty anyway."""

    def __init__(self, polygon, slack: float = 1e-9):
        self.slack = slack
        if polygon.geom_type != "Polygon" or polygon.area <= 0.0:
            self.lo, self.hi = tuple(polygon.bounds[:2]), tuple(polygon.bounds[2:])
            self.edges = []  # a degenerate hull (a point or a segment): its bounding box only
            return
        from shapely.geometry.polygon import orient

        ring = np.asarray(orient(polygon, 1.0).exterior.coords)  # counter-clockwise, closed
        edges = np.diff(ring, axis=0)
        normals = np.column_stack([edges[:, 1], -edges[:, 0]])  # (m, 2) outward for a CCW ring
        offsets = np.einsum("ij,ij->i", normals, ring[:-1]) + slack * np.linalg.norm(normals, axis=1)
        # per edge (normal x, normal y, offset): a point p is inside (or within slack of) it when normal . p <= offset
        self.edges = [(float(nx), float(ny), float(c)) for (nx, ny), c in zip(normals, offsets)]
        self.lo, self.hi = tuple(map(float, ring.min(axis=0))), tuple(map(float, ring.max(axis=0)))

    def may_meet_box(self, x_lo: float, x_hi: float, y_lo: float, y_hi: float) -> bool:
        """False only when the box [x_lo, x_hi] x [y_lo, y_hi] lies farther than ``slack`` outside the polygon."""
        e = self.slack
        if x_lo > self.hi[0] + e or x_hi < self.lo[0] - e or y_lo > self.hi[1] + e or y_hi < self.lo[1] - e:
            return False
        for nx, ny, offset in self.edges:  # a few edges: plain floats beat numpy's per-call overhead
            nearest = (nx * x_lo if nx > 0 else nx * x_hi) + (ny * y_lo if ny > 0 else ny * y_hi)  # the box's least
            if nearest > offset:
                return False
        return True
