"""The action model's configuration, split in four: the tool's geometry, the action discretisation, the scene's
contact physics, and the rules; and the two named profiles of the rules.

A rule is one small class: its name (the ``--tool-rule`` key and the scenario's), its type, its value in each
profile, the check where it is small enough to live here (otherwise the docstring names the
:class:`~slax_drake.shelf.actions.ActionModel` method that applies it), and a docstring that says what it
refuses, which profile has it and why. A new rule is one class with the ``@register`` decorator.

The two profiles:

- ``paper``: the paper's first-order shelf simulator (FOSS) literally (Sec. III, VI-A): objects move exactly as
  commanded, never topple, one object per action; a push moves its object along x at most until the neighbour,
  never into space hidden behind other objects, with a blade as thin as the real one; a suction is any
  collision-free grasp on the camera-facing side with any collision-free placement. The Table I protocol
  (``sim_configs/table1.yaml``) runs it.
- ``station``: what our physical tool can do (the blade's 3.5 cm lane with the tube along its edge, the tube's
  way in and reach, placements kept out of hidden space); the Drake station's cup limits come on top from the
  station YAML's ``suction`` section. Drake trials and the station scenarios plan with it.

Lengths in metres, masses in kilograms, angles in degrees where the name says ``_deg``.
"""

from __future__ import annotations

import dataclasses
import math

from slax_drake.config import PROFILES  # ("paper", "station"): defined below the scenario, which names one


# --------------------------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class ToolGeometry:
    """The bluction tool's shape (m): the same in both profiles (the rules decide which parts must be free)."""

    blade_width: float = 0.065  # the blade's extent along the shelf's y (its face is normal to x)
    blade_height: float = 0.075
    cup_diameter: float = 0.03
    tube_diameter: float = 0.03
    lift_height: float = 0.02  # a suctioned object is lifted this much before it is pulled out
    push_contact_depth: float = 0.03  # the blade's tip goes at least this far past the object's front extreme


@dataclasses.dataclass(frozen=True)
class Discretisation:
    """How the continuous actions are sampled (m): push distances on a ``push_resolution`` lattice plus the
    maximal push (up to the neighbour), suction placements on a ``suction_resolution`` lattice around the object;
    ``cell`` is the path step and the hidden-space raster's cell (the resolutions are multiples of it)."""

    push_resolution: float = 0.05
    suction_resolution: float = 0.05
    min_push: float = 0.01
    cell: float = 0.005


@dataclasses.dataclass(frozen=True)
class ObjectPhysics:
    """The scene's contact physics, copied from the scenario (``objects.density``, ``objects.clearance``, the
    ``physics`` section's mass model): an object weighs its recorded mass, else what the mass model expects
    (:func:`slax_drake.scene.mass.object_mass`)."""

    object_density: float = 400.0  # kg/m^3, to weigh objects
    clearance: float = 0.002  # moved objects stop this far from neighbours and walls (m)
    mass_model: str = "density"  # or "household": an object without a recorded mass weighs its class's median
    box_masses: tuple = ()  # household classes ((largest volume L, lightest kg, heaviest kg), ...)
    cylinder_masses: tuple = ()


# --------------------------------------------------------------------------------------------------------------
class Rule:
    """One rule of the action model. Subclasses set the class attributes and write the docstring."""

    name: str
    type: type = float
    paper = None
    station = None
    choices: tuple | None = None

    def problem(self, value) -> str | None:
        """What makes ``value`` unusable for this rule, in one line, or None."""
        if self.choices is not None:
            return None if value in self.choices else f"must be one of {', '.join(map(repr, self.choices))}"
        if self.type is float and not value >= 0.0:
            return "must be non-negative"
        return None

    @property
    def doc(self) -> str:
        return " ".join((type(self).__doc__ or "").split())


RULES: dict[str, Rule] = {}


def register(cls):
    """Class decorator: one registration per rule (its ``name`` becomes a RuleSet field)."""
    rule = cls()
    if rule.name in RULES:
        raise ValueError(f"rule {rule.name!r} registered twice")
    RULES[rule.name] = rule
    return cls


# ---- pushes --------------------------------------------------------------------------------------------------
@register
class BladeGap(Rule):
    """The free width (m) beside the object that a push needs for the tool, from the object's front to the
    blade's tip (:meth:`ActionModel.push_swept_rects`). ``paper``: 1 mm, a blade as thin as the real one (the
    FOSS relaxed Huang et al.'s blade-width separation, Sec. VI-A). ``station``: 3.5 cm, the 3 cm tube runs
    along the blade's upper edge, centred on its plane."""

    name, paper, station = "blade_gap", 0.001, 0.035


@register
class TubePastBlade(Rule):
    """How far (m) past the blade's tip the gap must be free as well: the tube's end (the cup) reaches 2 cm past
    the blade's tip (0.42 - 0.40 m in the tool model). ``station`` only: the Drake planner found the cup inside
    an object standing just behind the blade's lane. ``paper``: 0, the FOSS has no tube."""

    name, paper, station = "tube_past_blade", 0.0, 0.02


@register
class ShaftLaneCheck(Rule):
    """The shaft's straight way in from outside the shelf to the blade's depth touches no object. Off in both
    profiles: the blade goes in edge first and turns in the gap; the Drake planner checks the arm itself."""

    name, type, paper, station = "shaft_lane_check", bool, False, False


@register
class PushTubeCheck(Rule):
    """The tube's straight way in to a push's blade touches no object taller than the tube's underside: the
    tube (``tube_diameter``) runs along the blade's upper edge, centred on the blade's plane, which the planner
    puts ``tube_diameter / 2 + TUBE_STANDOFF`` beside the pushed object's extreme x; from the opening to the
    blade's tip it passes where the tube passes on its way in (:meth:`ActionModel.push_tube_blocker`). Refused
    only where the corridor, narrowed and lowered by the planner's 4 mm deviation tolerance, still overlaps an
    object, so the planner could never plan it. ``station``: on, the Drake planner found the tube inside an
    object standing in front of the pushed one (3 of 41 offered pushes of six Table I scenes). ``paper``: off,
    the FOSS has no tube."""

    name, type, paper, station = "push_tube_check", bool, False, True


@register
class PushHiddenCheck(Rule):
    """A push never moves its object into space hidden from the camera by other objects (it stops at its edge;
    :func:`slax_drake.shelf.floor.free_push_cells`). Both profiles: the paper's own rule ("objects may not be
    pushed behind other objects, as to not risk collisions with obscured objects", Sec. VI-A). Off only as an
    ablation."""

    name, type, paper, station = "push_hidden_check", bool, True, True


@register
class PushHiddenExtent(Rule):
    """With ``push_hidden_check`` on: which cells the pushed object may not newly cover if hidden. "path" (both
    profiles): every cell it passes over on its way (it stops at the edge of hidden space). "end": only the
    cells it covers where it comes to rest, a second reading of the paper's "objects may not be pushed *behind*
    other objects" (Sec. VI-A) as a rule on where the object is left: it may cross hidden space on its way (the
    FOSS's "actions do not ... move multiple objects simultaneously", Sec. III, then says nothing unseen stands
    in the swept lane) but not stop in it. A reading measured by benchmarks/table1_ablation.py, not a profile's."""

    name, type, paper, station, choices = "push_hidden_extent", str, "path", "path", ("path", "end")


@register
class PushStop(Rule):
    """Where the longest push of an object stops before what stops it (a neighbour, the wall, the dragged blade
    meeting an object). "lattice" (both profiles): at the last step of ``cell`` (5 mm) that keeps ``clearance``
    (2 mm): 2-7 mm short of its stopper. "exact": at the exact distance (to 1 micrometre) at which it comes
    within ``clearance``; with ``clearance`` 0 (a ``--tool-rule clearance=0``), the object ends *against* its
    neighbour, a reading of the paper's "an object can only be pushed next to the closest object on its left or
    right" (Sec. V-C). Pushes stopped by hidden space or the arm's reach stay on the lattice (both are rasters).
    A reading measured by benchmarks/table1_ablation.py, not a profile's."""

    name, type, paper, station, choices = "push_stop", str, "lattice", "lattice", ("lattice", "exact")


@register
class PushTurn(Rule):
    """How a pushed box moves. "none" (both profiles): it translates by d along x, the paper's first-order model.
    "quasi-static": it turns as a box standing on its corners turns under the blade's flat face until a face lies
    flush against it (:mod:`slax_drake.shelf.pushing`; a box met at a corner, or along only the front of a deep
    side, turns 10-40 deg and shifts 1-3 cm along y over a 0.10 m push in the Drake station); the pushed box must
    end clear of the known objects and the walls and, with ``push_hidden_check``, newly cover no hidden cell where
    it ends; discs translate. The stations set it (``push_turn`` in the station YAML): the first-order translation
    matched 20 of 58 lone-box pushes in Drake, this model 50 (research/push_contact.py). The hidden-space check of
    the way there still follows the straight sweep."""

    name, type, paper, station, choices = "push_turn", str, "none", "none", ("none", "quasi-static")


@register
class HiddenSpace(Rule):
    """Which space counts as hidden, for the pushes' (and suction placements') hidden-space rule: "3d", a cell
    whose point ``hidden_probe_height`` above it is not seen by the camera (an unseen object at least that tall
    could stand there); "overhead", the 2D shadows of infinitely tall objects. Both profiles: "3d", since the
    visibility goal itself is 3D (with the camera 0.20 m high, low objects hide little)."""

    name, type, paper, station, choices = "hidden_space", str, "3d", "3d", ("overhead", "3d")


@register
class HiddenProbeHeight(Rule):
    """With ``hidden_space`` "3d": the height (m) of the point above a cell that must be seen for the cell to
    count as seen. Both profiles: 5 cm (an unseen object shorter than that hides nothing of a 6 cm target)."""

    name, paper, station = "hidden_probe_height", 0.05, 0.05


@register
class MinHiddenWidth(Rule):
    """Hidden space counts only where a disc this wide (m) fits in it, clear of known objects: the smallest
    object (0.06 m) contains such a disc, so narrower hidden slivers hold no unseen object. Both profiles."""

    name, paper, station = "min_hidden_width", 0.06, 0.06


# ---- suctions ------------------------------------------------------------------------------------------------
@register
class SuctionHiddenRule(Rule):
    """Which part of a suction must stay out of hidden space: "placement", the final placement; "path", the
    whole way in and out as well; "none", nothing (only collisions with known objects are checked); "guarded",
    a placement reaching into hidden space is admitted as a guarded move (:attr:`Suction.guarded`): the push in
    stops at the first contact and the object rests there (the shelf simulator stops it at the first unseen
    object along the way in; a drag's way out and across still stay out of hidden space). ``paper``: "none",
    the FOSS admits any collision-free placement. ``station``: "placement", the physical tool must not put an
    object down onto something it cannot see. "guarded" is a named variant of no profile; in a Drake trial the
    PlannerSystem stops the push in when the joint efforts show contact (:mod:`slax_drake.systems.guard`)."""

    name, type, paper, station, choices = ("suction_hidden_rule", str, "none", "placement",
                                           ("path", "placement", "none", "guarded"))


@register
class SuctionLift(Rule):
    """How the suctioned object leaves and re-enters: "over-lower", lifted over any object that leaves room for
    it under the shelf's top ("lifted... clear of the clutter"); "slight", lifted only ``lift_height``, passing
    over nothing. Both profiles: "over-lower"."""

    name, type, paper, station, choices = "suction_lift", str, "over-lower", "over-lower", ("slight", "over-lower")


@register
class CarryHiddenCheck(Rule):
    """A lifted object carried across inside the bay (the planner's shallower ways across, when the arm cannot
    carry it pulled all the way out) must not cross space the camera has not seen: the bounding box of its
    footprint, swept along x at that depth, meets no cell hidden by the other objects (the hidden space of
    ``hidden_space``, ``hidden_probe_height`` and ``min_hidden_width``). Read by the motion planner, which leaves
    such ways out (:func:`slax_drake.planning.waypoints.pull_out_options`), and by the action model's reach-map
    check of the ways across (:meth:`slax_drake.shelf.actions.ActionModel.carry_cup_ys`), so that both refuse
    the same carries. Behind an object's seen face stands its unseen depth, or an object never seen: in the Drake
    trial 10:9 of the Table II protocol a cylinder carried across 4 cm behind a box's estimated back, through the
    depth of it the camera had not seen, knocked it over (docs/research/physics.md). A drag's way out and across stays out of
    hidden space already. ``station``: on; ``paper``: off (no planner, no reach map)."""

    name, type, paper, station = "carry_hidden_check", bool, False, True


@register
class TubeApproachCheck(Rule):
    """The tube's straight way in to the cup's contact touches no object taller than the tube's underside: a
    contact the horizontal tube cannot reach is no "reachable point". ``station`` only: off, 70 of 168 initial
    candidates of six Table I scenes were suctions whose tube the Drake planner found inside another object.
    ``paper``: off, the FOSS admits any grasp on the camera-facing side."""

    name, type, paper, station = "tube_approach_check", bool, False, True


@register
class MaxSuctionDepth(Rule):
    """The deepest contact behind the shelf's opening that the cup reaches (m; the tube's length).
    ``station``: 0.40 m. ``paper``: unlimited, the FOSS admits any grasp on the camera-facing side."""

    name, paper, station = "max_suction_depth", math.inf, 0.40

    def refuses(self, value: float, contact_depth: float) -> bool:
        return contact_depth > value


@register
class MaxSuctionMass(Rule):
    """The heaviest object (kg) the cup may pick. Unlimited in both profiles (the FOSS's objects weigh nothing;
    the station's cup limit is the held moment, ``max_suction_moment``)."""

    name, paper, station = "max_suction_mass", math.inf, math.inf

    def refuses(self, value: float, mass: float) -> bool:
        return mass > value


@register
class MassQuantile(Rule):
    """Which mass the action model reckons an object with whose mass it does not know (a perceived hypothesis,
    not yet weighed), under the household mass model: the ``mass_quantile`` of its class's log-uniform
    distribution (:func:`slax_drake.scene.mass.quantile_mass`). Both profiles: 0.5, the median; higher plans
    lifts and sideways drags only for objects that are likely light enough (at 0.5 half of them weigh more
    than planned). No effect under the density model or on objects with a recorded or weighed mass."""

    name, paper, station = "mass_quantile", 0.5, 0.5

    def problem(self, value) -> str | None:
        return None if 0.0 <= value <= 1.0 else "must be between 0 and 1"


@register
class MinSealRadius(Rule):
    """A cylinder of smaller radius (m) curves more than the cup can seal on. ``station``: 1.5 cm (half the
    cup). ``paper``: 0, any camera-facing side is graspable."""

    name, paper, station = "min_seal_radius", 0.0, 0.015

    def refuses(self, value: float, radius: float) -> bool:
        return radius < value


@register
class MaxSuctionMoment(Rule):
    """The object's weight times the horizontal distance from the cup's contact to its centre (N m), at most.
    Unlimited in both profiles' defaults; the Drake station's cup sets it (``suction.max_held_moment`` in the
    station YAML: 0.4 N m, about 0.6 x the 42 N pull times the 15 mm cup radius; in 80 Drake trials of
    Bluction-DAR, 3 of 91 suctioned objects hanging less than 0.4 N m off the cup fell, and 31 of 71 heavier)."""

    name, paper, station = "max_suction_moment", math.inf, math.inf

    def refuses(self, value: float, moment: float) -> bool:
        return moment > value


@register
class DragGrasp(Rule):
    """An object the cup may not lift (its held moment over ``max_suction_moment``) is dragged instead: the cup
    seals low on the same face, pulls the object toward the camera sliding on the shelf floor until its front is
    ``DRAG_FRONT_MARGIN`` inside the opening, translates it by d_x and pushes it in to depth d_z, the object on the
    floor all the way (it passes over nothing; :meth:`ActionModel.drag_limits`). A drag is admitted when the pull it
    needs, ``drag_safety_factor`` x ``drag_friction`` x m g, is within the cup's pull ``max_drag_pull``, when it
    does not tip the object (the cup seals at most ``half base / (safety factor x mu)`` high, the base's half depth
    along the pull, and no lower than the tube allows), and when its swept footprint (out, across, in) keeps
    ``clearance`` from every known object and, unless ``suction_hidden_rule`` is "none", covers no hidden cell.
    ``station``: on (what a real cup on a heavy box does instead of lifting it); never chosen while
    ``max_suction_moment`` is unlimited. ``paper``: off, the FOSS lifts every object."""

    name, type, paper, station = "drag_grasp", bool, False, True


@register
class DragAfterWeighing(Rule):
    """A lift the arm weighed and put back as too heavy or not hanging free (its seal peeling) becomes, in the same
    action, the drag that puts the object where the lift would have (the same d_x and d_z), when the action model
    offers that drag on the arrangement the lift was chosen on with the object reckoned at its weighed mass
    (:meth:`ActionModel.drag_instead`): what a robot does that has just learned its load is too heavy to carry but
    not to slide. Off: the put-back ends the action and the next decision knows the mass. Both executors read it
    (the shelf simulator's camera mode and the Drake trial's planner system); privileged policies know the true
    masses and never lift what they must put back. ``station``: on (on the 80 physics-benchmark scenes in Drake 6 of
    27 put-backs dragged, actions as predicted 86 -> 88 %, the same scenes revealed; docs/research/weighing.md).
    ``paper``: off, the FOSS never weighs."""

    name, type, paper, station = "drag_after_weighing", bool, False, True


@register
class WeighDragPull(Rule):
    """A drag that slides its object across (d_x != 0) is weighed along its pull toward the opening: the floor's
    sliding friction, measured from the arm's joint efforts while the object slides out, takes the place of
    ``drag_friction`` x m g in the twist check (``max_drag_twist``), and a drag over the limit is pushed straight
    back and released where it was sealed, the object reckoned from then on with the mass that friction implies
    (:mod:`slax_drake.systems.drag_weigh`): what a robot does that can feel its load before it slides it sideways.
    Both executors read it (the Drake trial's planner system from the efforts; the shelf simulator with the true
    object's mass). Off in both profiles: on the 80 physics-benchmark scenes in Drake it cost one scene (38 against 39
    with nothing lost): the force read along the pull scatters by -25 to +160 % around the true friction, and the
    twist limit is not sharp enough for it (docs/research/weighing.md)."""

    name, type, paper, station = "weigh_drag_pull", bool, False, False


@register
class MaxDragPull(Rule):
    """The cup's pull (N) a drag may use: vacuum pressure x cup area. Unlimited in both profiles' defaults; the
    Drake station's cup sets it (``suction.vacuum_pressure`` and ``suction.cup_radius`` in the station YAML:
    60 kPa over a 15 mm radius, 42.4 N)."""

    name, paper, station = "max_drag_pull", math.inf, math.inf


@register
class MaxDragTwist(Rule):
    """The moment (N m) about the vertical through the cup's contact that a drag's
    translation along x may ask of the seal: sliding sideways, the floor's friction, ``drag_safety_factor`` x
    ``drag_friction`` x m g, acts at the object's centre, so it twists the object about the cup by that times the
    floor-plane distance from the contact to the centre (the held moment times mu'). Over this, only drags with
    d_x = 0 (pulled out and pushed back in) are admitted. Unlimited in both profiles' defaults; the Drake
    station's cup sets it: its lip moment, the pull times the cup's radius (42.4 N x 15 mm = 0.64 N m; in
    research/drag_hold.py 2 kg boxes 8 cm behind the contact, 0.69 N m without the safety factor, turned 35 deg
    while translated, 1.5 kg ones, 0.52 N m, did not)."""

    name, paper, station = "max_drag_twist", math.inf, math.inf


@register
class DragTwistFlatFactor(Rule):
    """How much more twist than ``max_drag_twist`` a drag sealed on a flat face (a box's) may ask of the seal: the
    cup's lip lies on a flat face all round and holds more than on a curved one. Measured in the Drake station
    (``research/drag_hold.py --shape box|cylinder --depth 0.16 --dx 0.10 --twist-limit 100``, 8 cm from the contact
    to the centre, heights 0.12 and 0.20 m): boxes slid across as predicted up to 0.78 N m asked (1.5 kg) and slipped
    round at 0.88 (1.7 kg); cylinders held 0.62 (1.2 kg) and slipped at 0.67 (1.3 kg): about 1.2 for a flat face.
    1.0 in both profiles (one limit for every face; ``docs/research/weighing.md``)."""

    name, paper, station = "drag_twist_flat_factor", 1.0, 1.0


def drag_twist_limit(rules, shape: str) -> float:
    """N m: the twist a drag of an object of ``shape`` ("box": a flat face to the cup; "cylinder": a curved one) may
    ask of the seal (``max_drag_twist``, times ``drag_twist_flat_factor`` for a box)."""
    return float(rules.max_drag_twist) * (float(rules.drag_twist_flat_factor) if shape == "box" else 1.0)


@register
class DragFriction(Rule):
    """The Coulomb friction coefficient between a dragged object and the shelf floor. Both profiles: 0.44, what
    the Drake station combines from the objects' 0.5 (``physics.object_friction``) and the shelf's 0.4 (Drake's
    2 mu1 mu2 / (mu1 + mu2))."""

    name, paper, station = "drag_friction", 0.44, 0.44


@register
class DragSafetyFactor(Rule):
    """The factor on ``drag_friction`` for a drag's limits (pull and tipping): static friction, the cup's seal
    and the floor vary. Both profiles: 1.5."""

    name, paper, station = "drag_safety_factor", 1.5, 1.5

    def problem(self, value) -> str | None:
        return None if value >= 1.0 else "must be at least 1"


@register
class MaxToolYawDeg(Rule):
    """How far (deg) the tool may turn about the shelf's z axis to meet a turned box face along its normal: the
    tube then comes in along the face's normal, turned by the face's angle clamped to this value and to what the
    side walls leave the tube at the opening (its axis from the contact out to the opening keeps a tube radius
    from the walls); the seal-angle rule (``max_seal_angle_deg``) applies to the angle left between the face's
    normal and the turned tube, and the tube's reach (``max_suction_depth``) is measured along it. ``station``:
    30 deg, with the 10 deg seal limit every box face up to 40 deg seals (a front face turns 45 deg at most); the
    planner checks the arm at the turned poses. ``paper``: 0, the FOSS's tube stays along the shelf's y (its seal
    angle is unlimited)."""

    name, paper, station = "max_tool_yaw_deg", 0.0, 30.0

    def problem(self, value) -> str | None:
        return None if 0.0 <= value <= 90.0 else "must lie in [0, 90]"


@register
class MaxSealAngleDeg(Rule):
    """A box face turned more than this (deg) from the tube's axis cannot be sealed; 90 admits every face (the
    tube's axis is the shelf's y, or turned by ``max_tool_yaw_deg`` toward the face's normal). Both profiles'
    defaults 90; the Drake station's cup sets it (``suction.max_seal_angle_deg``: 10; in 80 Drake trials with the
    tube along y, 3 of 117 suctions of faces turned 15-35 deg ended where the model put the object, 245 of 305
    under 10 deg did)."""

    name, paper, station = "max_seal_angle_deg", 90.0, 90.0

    def refuses(self, value: float, angle_deg: float) -> bool:
        return angle_deg > value


@register
class ReachMapRule(Rule):
    """The station's precomputed reach map (a JSON path, :mod:`slax_drake.shelf.reach`; "" for none): a push
    whose blade, inserted or at the push's end, and a suction with the tube along y whose cup at the seal, lies
    where the motion planner found no IK solution from the observation pose on the empty shelf (every grid node
    around it unreached) is refused before the planner tries. Conservative: only what the map shows unreachable
    all around; a turned suction is refused only where the map's turned-cup layers of both yaw nodes around its
    yaw refuse it (:meth:`slax_drake.shelf.reach.ReachMap.refuses_cup`; not checked without those layers). The map belongs to a station
    (the robot's placement): both profiles' value is "", and a Drake trial's station sets it (the station YAML's
    ``reach_map``, through ``station_tool_rules``)."""

    name, type, paper, station = "reach_map", str, "", ""

    def problem(self, value) -> str | None:
        if not value:
            return None
        from slax_drake.shelf.reach import reach_map_file

        return None if reach_map_file(value).is_file() else "no such reach map file"


# --------------------------------------------------------------------------------------------------------------
RuleSet = dataclasses.make_dataclass(
    "RuleSet", [(r.name, r.type, dataclasses.field(default=r.station)) for r in RULES.values()], frozen=True)
RuleSet.__doc__ = "The value of every registered rule (defaults: the station profile); see rule_set()."


def profile_values(profile: str) -> dict:
    """{rule name: value} of a named profile."""
    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r} (known: {', '.join(PROFILES)})")
    return {name: getattr(rule, profile) for name, rule in RULES.items()}


def rule_set(profile: str = "station", **overrides) -> RuleSet:
    """The rules of ``profile`` with single ``overrides`` ({rule name: value}) on top."""
    values = profile_values(profile)
    unknown = set(overrides) - set(values)
    if unknown:
        raise ValueError(f"unknown rule(s) {sorted(unknown)} (known: {', '.join(RULES)})")
    values.update(overrides)
    return RuleSet(**values)


def rules_problem(rules) -> str | None:
    """The first unusable rule value of ``rules`` in one line ("name = value: why"), or None."""
    for name, rule in RULES.items():
        value = getattr(rules, name)
        why = rule.problem(value)
        if why:
            return f"{name} = {value!r}: {why}"
    return None


def overrides_of(rules, profile: str) -> dict:
    """The entries of ``rules`` that differ from ``profile``'s values (what a result file records)."""
    base = profile_values(profile)
    return {k: getattr(rules, k) for k in RULES if getattr(rules, k) != base[k]}


SECTIONS = {"geometry": ToolGeometry, "grid": Discretisation, "physics": ObjectPhysics}


@dataclasses.dataclass(frozen=True)
class ToolConfig:
    """Everything the action model is configured with: geometry, discretisation, object physics and rules.

    ``ToolConfig.build(profile, **flat)`` routes flat keyword overrides (``blade_gap=0.05``, ``cell=0.01``,
    ``clearance=0.002``) to their section."""

    geometry: ToolGeometry = ToolGeometry()
    grid: Discretisation = Discretisation()
    physics: ObjectPhysics = ObjectPhysics()
    rules: RuleSet = RuleSet()
    profile: str = "station"

    @classmethod
    def build(cls, profile: str = "station", **flat) -> "ToolConfig":
        parts = {}
        for section, kind in SECTIONS.items():
            names = {f.name for f in dataclasses.fields(kind)}
            mine = {k: flat.pop(k) for k in list(flat) if k in names}
            parts[section] = kind(**mine)
        unknown = set(flat) - set(RULES)
        if unknown:
            raise ValueError(f"unknown tool field(s) {sorted(unknown)} (known: {', '.join(flat_field_names())})")
        return cls(rules=rule_set(profile, **flat), profile=profile, **parts)

    def value(self, name: str):
        """A field's value by its flat name (a rule, a geometry, discretisation or physics field)."""
        if name in RULES:
            return getattr(self.rules, name)
        for section, kind in SECTIONS.items():
            if name in {f.name for f in dataclasses.fields(kind)}:
                return getattr(getattr(self, section), name)
        raise KeyError(name)


def flat_field_names() -> list[str]:
    """Every flat name ToolConfig.build accepts: the rules first, then the other sections' fields."""
    return list(RULES) + [f.name for kind in SECTIONS.values() for f in dataclasses.fields(kind)]


POSITIVE_FIELDS = ("blade_width", "blade_height", "cup_diameter", "tube_diameter", "push_resolution",
                   "suction_resolution", "cell")


def tool_config_problem(tool: ToolConfig) -> str | None:
    """What makes ``tool`` unusable, in one line, or None: an unknown profile, an unusable rule value, a
    negative (or, for sizes and resolutions, zero) number, resolutions that are not multiples of ``cell``."""
    if tool.profile not in PROFILES:
        return f"profile = {tool.profile!r}: must be one of {', '.join(map(repr, PROFILES))}"
    problem = rules_problem(tool.rules)
    if problem:
        return problem
    for section in SECTIONS:
        part = getattr(tool, section)
        for f in dataclasses.fields(part):
            value = getattr(part, f.name)
            if isinstance(value, float) and not value >= (1e-12 if f.name in POSITIVE_FIELDS else 0.0):
                return f"{f.name} = {value!r}: must be {'positive' if f.name in POSITIVE_FIELDS else 'non-negative'}"
    for name in ("push_resolution", "suction_resolution"):
        ratio = getattr(tool.grid, name) / tool.grid.cell
        if abs(ratio - round(ratio)) > 1e-9:
            return f"{name} = {getattr(tool.grid, name)!r}: must be a multiple of cell = {tool.grid.cell!r}"
    return None


STRICT_RULES = dict(min_hidden_width=0.0, blade_gap=0.065, shaft_lane_check=True, tube_approach_check=True,
                    hidden_space="overhead", suction_lift="slight", suction_hidden_rule="path", max_suction_mass=2.0,
                    min_seal_radius=0.04)
"""The strictest variant of each rule (the blade turned flat in the gap, 2D shadows, ...), for
research/rule_ablation.py."""
