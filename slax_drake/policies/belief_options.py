"""The options of slax-belief (:class:`slax_drake.policies.belief.BeliefSearch`) as one frozen dataclass.

Plain data (no heavy imports): the policy registry builds its named variants from :data:`DEFAULT_BELIEF_OPTIONS`
with ``dataclasses.replace``. Lengths are in metres, times in seconds of CPU time. The horizon (the protocol's
actions per trial) and the visibility threshold v are not options of the policy: the registry passes the
scenario's.
"""

from __future__ import annotations

import dataclasses

SELECT_RULES = ("ratio", "value")
EVIDENCE_RULES = ("outcome", "none")
STUCK_RULES = ("value", "progress", "stop")
BLOCKED_RULES = ("box", "hidden", "risk")
DEAD_END_RULES = ("ignore", "model", "corrections")
EXPLAIN_RULES = ("none", "carried", "any")


@dataclasses.dataclass(frozen=True)
class BeliefOptions:
    """How slax-belief searches; the defaults are the registry's ``slax-belief``. A ValueError names a field whose
    value it cannot take."""

    samples: int = 64
    """Worlds (target placements drawn from the belief) that stand for the belief."""
    depth: int = 3
    """Actions per plan searched."""
    max_depth: int = 5
    """Actions per plan searched while no plan of ``depth`` actions reveals anything (at least ``depth``)."""
    beam: int = 6
    """Arrangements kept per depth of the beam search (duplicates merged)."""
    placements_per_object: int = 2
    """Suction placements kept per object and state, the best by their value."""
    failure_cost: float = 10.0
    """Cost (actions) of a world farther from being revealed than the actions left."""
    seconds: float = 30.0
    """CPU time per decision; past it the search stops and takes the best plan so far."""
    hidden_risk: float = 1.0
    """The chance a suction placed in hidden space fails, per share of hidden placements in its placement box."""
    select: str = "ratio"
    """The plan taken: "ratio", the most revealed mass per expected cost; "value", the least value V."""
    evidence: str = "outcome"
    """"outcome": each executed action's outcome updates the belief; "none": only what the camera shows."""
    block_weight: float = 8.0
    """How much likelier a placement that would have stopped a stopped action exactly there becomes (> 0)."""
    remember_objects: bool = True
    """An object seen earlier, hidden now and not moved since is kept among the seen objects where it stood."""
    widen_beam: int = 12
    """The beam of a second search when the first reveals nothing (0: no second search)."""
    stuck_select: str = "value"
    """The plan taken when no plan looked at reveals anything (the search stalls): "value" (least V) or "progress"
    (least V - G); "stop": none, the policy stops with :data:`~slax_drake.policies.protocol.NO_REVEALING_PLAN`
    (a plan cut by the CPU cap is not a stall). Under the Drake station's rules the stalled search reveals the
    target in 1 of 41 trials and takes half of all actions and three quarters of the moves back; in the paper
    profile it reveals in 12 of 62 (docs/research/physics.md, "Where the failed trials stall")."""
    blocked_rule: str = "risk"
    """What the box of a placement that was put back or stopped short refuses: "box", every later placement
    overlapping it (the default until 2026-12-06); "hidden", only those overlapping it in hidden space; "risk", none,
    but those overlapping it in hidden space fail with ``blocked_risk`` more. Through the camera a placement mostly
    fails on the estimates, not on an unseen object, and "box" then refuses the neighbourhood for the rest of the
    trial (docs/research/physics.md, "A failed placement as a risk, not a refusal")."""
    blocked_risk: float = 0.5
    """``blocked_rule`` "risk": the failure chance a blocked box adds, in [0, 1]."""
    camera_depth: float | None = None
    """Camera mode: the hypotheses are estimated again assuming each at least this deep (m) behind its visible
    surfaces (None: as the observer estimated them)."""
    camera_memory: bool = True
    """Camera mode: the objects seen earlier in the trial and hidden now (the object tracker's hidden tracks, where
    they were last estimated; the one the last action moved excepted) are obstacles the actions are checked
    against, and the target cannot stand where they stand. The default since 2026-12-06 (at 2100fd5, before it, 34 %
    of the put-backs in the camera-mode Table I run at 10 objects ran into such an object;
    docs/research/observation-modes.md, "What the put-backs ran into")."""
    camera_outcome_tolerance: float = 0.003
    """Camera mode: the tolerance (m, > 0) of the outcome evidence and the placement check on estimated poses."""
    maybe_occupied: float | None = None
    """Camera mode with ``camera_depth``: the weight, in (0, 1], of a target placement inside a hypothesis' assumed
    depth (None: such placements are excluded)."""
    camera_extents: float | None = None
    """Camera mode: the hypotheses are estimated again with each unseen edge this share, in [0, 1], of the way from
    what the frame shows to the farthest it allows (the estimator's extent range; ``DepthPrior(rule="range")``);
    None: as the observer estimated them. Takes precedence over ``camera_depth``."""
    seen_target: bool = True
    """Camera mode: when the frame shows part of the target, the belief keeps only the placements whose target
    would hold every seen target point (the target's known size), however few pixels show (False: the frame's
    target mask is not read; the default before a partly seen target was finished)."""
    uncover_seen: bool = True
    """Camera mode with ``seen_target``, while the belief is collapsed onto a partly seen target: a move that
    uncovers part of it (its object hides fewer of the worlds' target points after it than before) is a first move
    even where the no-return and no-shuttle corrections refuse it (an excluded failed action stays excluded)."""
    unseen_risk: bool = False
    """Camera mode with ``seen_target``, once the belief collapsed onto a partly seen target: the suctions' risk of
    meeting something unseen reads the space never seen (the belief before the collapse, less what later frames
    show) rather than the collapsed belief, whose few placements make every placement away from the target look
    safe. Measured, not the default (docs/research/slax_belief.md, "A partly seen target")."""
    aim_visible: bool = False
    """Camera mode: no action is planned on a hypothesis whose segment shows no patch the tool could be aimed at
    (a disc of the cup's diameter, at the segment's depth, inside its mask with dropped returns closed); it stays an
    obstacle. A sliver of an object seen above or beside a nearer one is a hypothesis of its own, far smaller than
    the object: a move planned on it moves the whole object (:meth:`BeliefSearch.unaimable`)."""
    deepen_failed: bool = False
    """Camera mode: an object whose suction placement failed (put back, or stopped early) is assumed, from then on
    for the trial, as deep and wide as the frame allows (its extent range's farthest edges, the estimator's
    ``DepthPrior(rule="range", fraction=1)``) rather than the least depth: its unseen part is the likeliest cause,
    and a deeper object's failed placement box covers the neighbouring placements that fail alike."""
    explain_failed: str = "none"
    """Camera mode: what a suction put back (the next frame shows its object where it stood) teaches about the
    extents. "carried": the carried object is assumed, for the rest of the trial, the least share of its extent
    range (:data:`~slax_drake.policies.belief.EXPLAIN_SHARES`; the estimator's ``DepthPrior(rule="range")``) at
    which the put-back follows on the objects the suction was planned on (the action model puts it back too);
    "any": the same, the carried object first, else the least share of any one other seen object that explains it;
    "none" (the default): the extents stay as the frame shows them. No share explains a put-back whose cause is not
    in the frame (an object never seen): nothing changes then. ``deepen_failed`` goes to the farthest at once,
    whatever the cause."""
    extent_prior: bool = False
    """Camera mode: the target's placements are drawn jointly with the seen objects' unseen extents. A placement
    whose target footprint lies inside a seen object's extent range (beyond what the frame shows of it: the walls,
    the neighbours, space seen empty and the largest object bound it) weighs the chance that the object does not
    reach it: 1 - the tail probability (:data:`~slax_drake.policies.extents.EXTENT_SHARE_TAIL`) of the least share
    of the range at which the grown object meets the target, multiplied over the objects. Without it such a
    placement weighs as much as one in space seen empty around it, and the worlds hidden in the unseen part of an
    object draw plans that can never reveal them."""
    extent_risk: float = 0.0
    """Camera mode: a first move is scored by the chance that the unseen extents of the objects the frame shows make
    it fail: the share of joint draws of every seen object's extent (each object at a share of its extent range
    drawn from where true edges lie in their ranges, :data:`~slax_drake.policies.extents.EXTENT_DRAW`) in which the
    move, executed by the shelf simulator's first-order executor, does not go as planned (put back, stopped early,
    blocked), times this factor (0: off; 1: the draws' share as it is). The reveals after it count for that much
    less, as after a suction's ``hidden_risk``."""
    put_back_group: bool = False
    """Camera mode: a suction that left its object where it stood (put back, or its way out blocked) excludes every
    suction of that object while it stands there (within the tolerant exclusions' 1 cm / 0.05 rad), as a push
    that moved nothing excludes that object's pushes in its direction. On a camera frame such a failure mostly means
    the object reaches beyond its hypothesis (a mostly hidden object is wider or deeper than its visible part), so
    its other placements fail alike: of 263 later suctions of an object put back in the camera-mode Table I run,
    176 failed again (privileged: 6 of 43)."""
    put_back_lane: bool = False
    """A suction that left its object where it stood excludes every suction of that object by the same dx, whatever
    its placement depth dz, while the object stands there (within the exclusions' tolerances in camera mode;
    :func:`~slax_drake.policies.protocol.suction_lane`); without it only the same dx with a dz within 1 cm. Such a
    suction failed before its depth mattered: its way out was blocked, the object did not fit between the walls at
    that x, or the way in at that x was blocked before the object was inside the bay (put back), and its other
    depths fail alike. In the camera-mode Table I run at 2100fd5, 166 of the 498 put-backs at 10 objects repeated
    an earlier put-back's object and dx, the object unmoved since."""
    shuttle_rule: str = "width"
    """What a move back against its object's last move must uncover to pass the no-shuttle correction (at least
    0.02 m of it): "width", width its own footprint covered in every arrangement observed in the trial; "sight",
    width of shelf into which the camera would see deeper than in any observed arrangement, judged on every seen
    object's footprint (:mod:`slax_drake.policies.sight`): the space behind an object moved far away was shown
    when it stood elsewhere, and the space behind another object it stood in front of never was. "belief": the
    width rule, or, for a first move, the arrangement after it shows the target in at least one of the belief's
    worlds still alive (:meth:`BeliefSearch.reveals_new`): a world is alive only while no frame of the trial has
    shown its place, so the move reveals space no earlier arrangement revealed, in the one sense the search
    values (a move back later in a plan is judged by width)."""
    shuttle_reveal: float | None = 0.02
    """The width (m) of space never revealed that a move back against its object's last move must uncover to pass
    the no-shuttle correction (issue 27's rule); None: the correction is off (the variant
    ``slax-belief-no-shuttle-rule``, which measures what the rule costs; it executes moves back the rule forbids)."""
    shuttle_by_axis: bool = False
    """The no-shuttle correction judges a move back against its object's last move along each axis, not its last
    move (:attr:`TrialMemory.by_axis`): x +0.35, then y -0.10, then x -0.35 is a move back too. Without it a move
    along y alone in between lets an object cycle along x (measured in Drake: docs/research/physics.md)."""
    dead_end: str = "corrections"
    """What a plan that ends where the search could not go on costs. "ignore": nothing. "model": a plan whose last
    arrangement leaves no move at all (the action model allows none there) loses the worlds it has not revealed,
    each at ``failure_cost``, in the rule that picks the plan (R / (G + failure_cost x the share of worlds left)
    under ``select`` "ratio"; V plus the same otherwise). "corrections": the same where every move left there
    would be screened out by the corrections as they would stand after the plan (excluded, back to an arrangement
    observed or passed on the way, a shuttle; :meth:`TrialMemory.after_plan`). Without it a one-move plan that
    reveals much and leaves the shelf locked (the object pushed behind a neighbour that now blocks every tool
    path, or every object moved toward one wall) outranks plans that reveal a little less and keep the search
    going. The default since 2026-12-06 (before: "ignore")."""
    stuck_undo: bool = False
    """When no plan from the moves the corrections allow reveals anything, even widened: the moves screened out only
    as a return to an observed arrangement or as a shuttle are looked at as first moves too, and a plan starting
    with one is taken when it reveals part of the belief (:meth:`BeliefSearch.undo_plans`; ``decision_log``
    records ``undo``). The corrections keep a policy from moving objects back and forth between arrangements that
    reveal nothing new; a move back whose plan goes on to reveal worlds the belief still holds is not such a cycle
    (the worlds an earlier arrangement revealed are gone from the belief), and without it a first move that revealed
    nothing and blocked the others (an object pushed across the lane of its neighbour's tool) ends the trial with
    no action left."""
    shuttle_last_resort: bool = False
    """When the corrections screen out every feasible candidate and some only as shuttles (a move back against the
    object's last move that uncovers no new width), those shuttles are offered rather than stopping with no action
    (the correction is kept whenever anything else is left)."""

    def __post_init__(self):
        if self.select not in SELECT_RULES:
            raise ValueError("select must be 'ratio' or 'value'")
        if self.evidence not in EVIDENCE_RULES:
            raise ValueError("evidence must be 'outcome' or 'none'")
        if not self.block_weight > 0:
            raise ValueError(f"block_weight must be positive (got {self.block_weight!r})")
        w = self.widen_beam
        if isinstance(w, bool) or not isinstance(w, int) or w < 0:
            raise ValueError(f"widen_beam must be a whole number, 0 or more (got {w!r})")
        if self.camera_depth is not None and not 0 < self.camera_depth:
            raise ValueError(f"camera_depth must be a positive depth in metres or None (got {self.camera_depth!r})")
        if not self.camera_outcome_tolerance > 0:
            raise ValueError(f"camera_outcome_tolerance must be positive (got {self.camera_outcome_tolerance!r})")
        if self.maybe_occupied is not None and not 0 < self.maybe_occupied <= 1:
            raise ValueError(f"maybe_occupied must be in (0, 1] or None (got {self.maybe_occupied!r})")
        if self.camera_extents is not None and not 0 <= self.camera_extents <= 1:
            raise ValueError(f"camera_extents must be in [0, 1] or None (got {self.camera_extents!r})")
        if self.stuck_select not in STUCK_RULES:
            raise ValueError("stuck_select must be 'value', 'progress' or 'stop'")
        if self.explain_failed not in EXPLAIN_RULES:
            raise ValueError("explain_failed must be 'none', 'carried' or 'any'")
        if self.blocked_rule not in BLOCKED_RULES:
            raise ValueError("blocked_rule must be 'box', 'hidden' or 'risk'")
        if self.shuttle_rule not in ("width", "sight", "belief"):
            raise ValueError("shuttle_rule must be 'width', 'sight' or 'belief'")
        if self.shuttle_reveal is not None and not self.shuttle_reveal >= 0:
            raise ValueError(f"shuttle_reveal must be a width in metres, 0 or more, or None (got {self.shuttle_reveal!r})")
        if self.dead_end not in DEAD_END_RULES:
            raise ValueError("dead_end must be 'ignore', 'model' or 'corrections'")
        if not 0 <= self.extent_risk:
            raise ValueError(f"extent_risk must be a factor, 0 or more (got {self.extent_risk!r})")
        if not 0 <= self.blocked_risk <= 1:
            raise ValueError(f"blocked_risk must be in [0, 1] (got {self.blocked_risk!r})")

    def changed(self) -> dict:
        """The fields that differ from the defaults (what a results folder's settings record of this variant)."""
        default = type(self)()
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if getattr(self, f.name) != getattr(default, f.name)}


DEFAULT_BELIEF_OPTIONS = BeliefOptions()
