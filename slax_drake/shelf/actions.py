"""The bluction tool's action model: pushes with the blade and suction pick-and-place, in plain numpy.

Shared by the fast shelf simulator and (later) the Drake planner LeafSystem, so the two agree on which
actions exist. Everything is in the shelf frame S (x right, y into the shelf, z up; metres).

Push (q, d) (paper Sec. III-IV: "the robot inserts the flat face of the blade next to the object and then pushes
along the blade's surface normal"): the thin blade (faces normal to x, ``blade_width`` along y, ``blade_height``
tall) goes in beside the object's extreme x (its axis-aligned extent) on the side opposite the push, from the
object's front extreme to where its blade spans the point of the object at that extreme x (a rectangle's extreme
corner, a disc's point level with its centre; :meth:`ActionModel.blade_depth`), so that the blade meets the object
where the push begins. It needs a free gap
``blade_gap`` wide there, between the object and its neighbour or the wall (:meth:`ActionModel.push_swept_rects`;
default 3.5 cm: the 3 cm tube runs along the blade's upper edge, centred on its plane). q = (the centre of a
``blade_width`` lane beside the object, the blade tip's y, blade_height / 2), whatever the gap, as the planner
reads it. The blade then moves a signed distance d along x and the object translates with it (first order: no
rotation). The object stops ``clearance`` before a neighbour or a wall; the blade in its gap (dragged along)
must touch no other object; exactly one object moves; no cell the object newly covers may be hidden from the
camera by *another* object (:mod:`slax_drake.shelf.floor`; ``hidden_space``: "3d", default, the point
``hidden_probe_height`` above the cell is not seen, i.e. an unseen object at least that tall could stand there;
"overhead", the paper's 2D shadows of infinitely tall objects), counting only hidden space wide enough to hold an
unseen object (``min_hidden_width``: a disc of the smallest object's size fits in it, clear of known objects).

Suction (q, d_x, d_z): the cup (``cup_diameter``) seals on the camera-facing side: a box's side face whose
outward normal points most toward the camera (at least ``cup_diameter`` wide), or a cylinder's front (radius
at least ``min_seal_radius``), at the highest sealable point. The contact must lie within ``max_suction_depth``
of the opening (the tube's length) and the object must weigh at most ``max_suction_mass``. The object is
lifted, pulled straight out of the shelf, translated by d_x, and pushed straight in to depth y = d_z: those
paths must be collision free (``suction_lift``: "over-lower", default, the object is lifted over any object
that leaves room for it under the shelf's top, "lifted... clear of the clutter"; "slight", it is lifted only
``lift_height`` and passes over nothing); the placement must be collision free, inside the walls, and cover no
cell hidden from the camera by any known object, the object's own old shadow included, since nobody has seen
it yet (``suction_hidden_rule`` "placement", the station profile; "path": the whole way in and out too; "none",
the paper profile: no hidden-space rule for suctions).

Configuration (:mod:`slax_drake.shelf.rules`): the tool's geometry, the discretisation, the objects'
physics and the rules, each rule a small class with its value in the ``paper`` and ``station`` profiles
and a docstring saying what it refuses and why.

``enumerate`` lists a state's candidates with d discretised at ``push_resolution`` (the maximal push is always a
candidate) and placements on a ``suction_resolution`` lattice around the object, and returns every rejected
candidate with the reason.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import math

import numpy as np

from slax_drake.caches import memo
from slax_drake.shelf.pushing import push_pose
from slax_drake.shelf.rules import RULES, ToolConfig, ToolGeometry, drag_twist_limit, tool_config_problem
from slax_drake.shelf.floor import (
    NOT_FOUND, FloorGrid, band_crosses_hidden, column_extents, erode, first_hidden_row, free_push_cells,
    open_with_disc, push_end_hidden,
)
from slax_drake.shelf.reach import hold_height_span, load_reach_map
from slax_drake.scene import mass as scene_mass
from slax_drake.scene.footprint import Footprint, clear_of, footprints_clear, inside_shelf
from slax_drake.scene.model import SceneObject, Shelf

GRAVITY = 9.81  # m/s^2
FRONT_MARGIN = 0.05  # the lanes start this far outside the shelf's opening (m)
CONTACT_INSET = 0.01  # the blade's tip this far past the point where it meets the object (m)
BLADE_CONTACT_CLEARANCE = 1e-4  # the blade may pass this close to an object without touching it (m)
PAIR_CACHE_SIZE = 20_000  # entries of an ActionModel's cache of pairwise collision tests (ActionModel._pair)
GEOMETRY_CACHE_SIZE = 2_000  # objects in an ActionModel's identity cache (ActionModel.object_geometry)
REACH_MARGIN = 0.015  # m: the reach map refuses a tool position only when every grid node this near it is unreached
# Where the planner puts the blade for a push (slax_drake.planning.waypoints reads these): the tube's surface
# TUBE_STANDOFF beside the pushed object's extreme x (the blade's plane a tube radius farther), the blade's lower
# edge BLADE_LIFT above the support; the tube runs along the blade's upper edge, centred on its plane.
TUBE_STANDOFF = 0.004  # m
BLADE_LIFT = 0.008  # m
# A drag (the ``drag_grasp`` rule): the object is pulled until its front is DRAG_FRONT_MARGIN inside the opening
# (it stays on the floor); the cup seals no lower than DRAG_MIN_SEAL_Z above the floor (the horizontal tube, 3 cm
# thick, clears the floor by 1 cm).
DRAG_FRONT_MARGIN = 0.01  # m
DRAG_MIN_SEAL_Z = 0.025  # m
# A suction's motion as the planner makes it (slax_drake.planning.waypoints reads these; the reach map's hold
# layers are checked along it): the cup presses SEAL_PRESS into the face; the tool's tip is APPROACH_MARGINS in
# front of the opening before it enters (each margin tried in turn); the object is lifted LIFT, or LIFT_CLEARANCE
# above the tallest object its way crosses, pulled out until its back is OUT_MARGIN in front of the opening or
# carried across at shallower depths PULL_STEP apart, or pulled all the way out with the tool turned by
# CARRY_YAWS_DEG either way about the cup's vertical axis.
SEAL_PRESS = 0.001  # m
APPROACH_MARGINS = (0.05, 0.01)  # m
LIFT = 0.01  # m
LIFT_CLEARANCE = 0.01  # m
OUT_MARGIN = 0.01  # m
PULL_STEP = 0.04  # m
CARRY_YAWS_DEG = (30.0,)  # deg
# A turned suction's tube passes the side walls' front edges (at the opening), and the objects beside its way out
# where it puts its object down, with its surface at least this far from them (m): the planner's 2 mm collision
# padding, and how far the tube strays there between IK's tolerance on
# its direction (0.01 rad over the 0.3 m from the cup to the opening) and the joint-space segments. The boxes turned
# toward a wall of research/tube_wall.py: with none, 4 of 8 refused for the tube meeting the shelf; 6 mm, 1 of 6;
# 10 mm, none (the 3 refused by the left wall are out of the arm's reach).
TUBE_CLEARANCE = 0.010
TUBE_CHECK_SLACK = 0.004  # m: how far the planned tool may stray from its straight segment (the planner's
# DEVIATION_TOLERANCE); the push_tube_check corridor is narrowed and lowered by it, so it refuses only sure hits


@dataclasses.dataclass(frozen=True)
class Push:
    """Push object ``name`` by ``d`` metres along x with the blade starting at ``q`` (x, y, z). ``turns``: the
    object moves as the quasi-static model predicts (:func:`slax_drake.shelf.pushing.push_pose`, the
    ``push_turn`` rule) instead of translating by ``d``."""

    name: str
    q: tuple[float, float, float]
    d: float
    turns: bool = False

    kind = "push"

    def describe(self) -> str:
        return f"push {self.name} d={self.d:+.3f}"


@dataclasses.dataclass(frozen=True)
class Suction:
    """Suction object ``name`` at contact ``q``, translate it by ``dx`` and place it at depth y = ``dz``. ``yaw``
    (rad): the tool's turn about the shelf's z axis while it holds the object; the tube points into the shelf
    along (-sin yaw, cos yaw) in S (0: along +y), the cup meets the face along that axis (``max_tool_yaw_deg``)."""

    name: str
    q: tuple[float, float, float]
    dx: float
    dz: float
    yaw: float = 0.0
    drag: bool = False  # dragged on the shelf floor instead of lifted (the ``drag_grasp`` rule)
    guarded: bool = False  # the placement reaches into hidden space: pushed in until contact (``suction_hidden_rule``
    # "guarded"), so the object may rest short of d_z

    kind = "suction"

    def describe(self) -> str:
        turned = f" yaw={math.degrees(self.yaw):+.0f}deg" if self.yaw else ""
        return (f"suction {self.name} dx={self.dx:+.3f} dz={self.dz:+.3f}{turned}{' drag' if self.drag else ''}"
                f"{' guarded' if self.guarded else ''}")

    @property
    def grip(self) -> str:
        """"drag" when the object slides on the shelf floor all the way, else "lift"."""
        return "drag" if self.drag else "lift"

    @property
    def axis(self) -> np.ndarray:
        """The tube's axis into the shelf in the floor plane of S (unit (x, y))."""
        return np.array([-math.sin(self.yaw), math.cos(self.yaw)])


Action = Push | Suction


class RefusalKind(enum.Enum):
    """Why the action model refuses a candidate (the typed kind; :attr:`Rejected.reason` is its wording)."""

    NO_ROOM_FOR_BLADE = "no room for the blade"  # the blade does not fit between the object and the wall
    BLOCKED = "blocked by an object"  # the blade's lane, the tube's way in or the path out meets another object
    HIDDEN_SPACE = "hidden space"  # the motion would cross or end in space hidden from the camera
    NO_ROOM = "no room to move"  # the object is stopped at once, or a longer push would hit something
    NO_PLACEMENT = "no placement"  # no placement of a suctioned object fits or is collision-free
    TOO_HEAVY = "too heavy for the cup"  # the object's mass exceeds the cup's lift
    NO_FACE = "no face for the cup"  # the camera-facing side is too small or curved
    SEAL_ANGLE = "seal angle"  # the camera-facing side is turned too far from the tube
    SUCTION_MOMENT = "suction moment"  # the held weight's moment about the cup exceeds its limit
    TUBE_DEPTH = "beyond the tube"  # the face lies deeper than the tube reaches
    REACH_MAP = "out of the arm's reach (reach map)"  # the station's reach map says the arm cannot put the tool there


# What stops a push at once (the ``stopper`` of ActionModel._pushes), as a refusal kind; an object's name: NO_ROOM
_STOPPER_KIND = {"hidden space": RefusalKind.HIDDEN_SPACE, "the arm's reach": RefusalKind.REACH_MAP}


@dataclasses.dataclass(frozen=True)
class Rejected:
    """A candidate that was skipped: what it was and why. ``action_kind`` ("push" or "suction"), ``object_name``,
    ``direction`` (a push's side along the shelf's x: +1 or -1; 0 for a suction) and ``distance`` (the refused
    push distance in metres, signed along x, when one distance was refused; None when the whole direction or every
    placement was) say the same as ``what`` as values; ``kind`` (:class:`RefusalKind`) says why as a value."""

    what: str
    reason: str
    action_kind: str = ""
    object_name: str = ""
    direction: int = 0
    distance: float | None = None
    kind: RefusalKind | None = None

    def spec(self) -> str:
        """The refused candidate in the ``kind:object:value`` form of an action: ``push:OBJECT:+0.1000`` for one
        refused distance, ``push:OBJECT:+x`` (or ``-x``) for every push toward that side, ``suction:OBJECT:*:*``
        for every placement."""
        if self.action_kind == "push":
            value = f"{self.distance:+.4f}" if self.distance is not None else ("+x" if self.direction > 0 else "-x")
            return f"push:{self.object_name}:{value}"
        if self.action_kind == "suction":
            return f"suction:{self.object_name}:*:*"
        return self.what


@dataclasses.dataclass
class Candidates:
    feasible: list
    rejected: list


def object_mass(obj: SceneObject, density: float, physics=None, quantile: float = 0.5) -> float:
    """The object's mass (kg): its recorded mass, else what ``physics`` (ObjectPhysics) expects at ``quantile``
    of its class, else density x volume (:func:`slax_drake.scene.mass.object_mass`)."""
    return scene_mass.object_mass(obj, density, physics, quantile)


def weighed_mass(weight_n: float, moment_nm: float, lever: float) -> float:
    """The mass (kg) to reckon an object with once the cup has weighed it (``weight_n`` N hanging ``moment_nm`` N m
    off the cup): the action model reckons a held moment as mass x g x ``lever`` (m: the horizontal distance from
    the contact to the object's centre as believed), so at least the mass that makes that the weighed moment, and
    never less than the weighed weight's."""
    mass = max(weight_n, 0.0) / GRAVITY
    return max(mass, moment_nm / (GRAVITY * lever)) if lever > 0.0 else mass


def pushed(obj: SceneObject, action: Push) -> SceneObject:
    """``obj`` after the push ``action``: translated by d, or where the quasi-static model leaves it (``turns``)."""
    x, y = float(obj.center[0]), float(obj.center[1])
    if not action.turns or obj.shape == "cylinder":
        return obj.moved_to(x + action.d, y)
    tip = action.q[1]  # the blade spans the physical blade's length (the URDF's, as the planner's waypoints) back from it
    x, y, yaw = push_pose(Footprint.of(obj), 1.0 if action.d > 0 else -1.0, abs(action.d),
                          tip - ToolGeometry.blade_width, tip)
    return obj.moved_to(x, y, yaw)


def apply_action(objects: tuple[SceneObject, ...], action) -> tuple[SceneObject, ...]:
    """The objects after the action, exactly as the model says (no feasibility check)."""
    out = []
    for o in objects:
        if o.name == action.name:
            o = pushed(o, action) if isinstance(action, Push) else o.moved_to(float(o.center[0]) + action.dx, action.dz)
        out.append(o)
    return tuple(out)


def contact_lever(obj: SceneObject, contact_xy) -> float:
    """m: the floor-plane distance from a cup's contact ``contact_xy`` (S) to ``obj``'s centre, the lever of the
    object's weight off the cup (:meth:`ActionModel.held_moment`) and of the floor's friction on a drag."""
    return math.hypot(float(obj.center[0]) - float(contact_xy[0]), float(obj.center[1]) - float(contact_xy[1]))


class ActionModel:
    """Enumerates feasible pushes and suctions for a set of known objects (plus known immovable obstacles)."""

    def __init__(self, shelf: Shelf, eye_xy, tool: ToolConfig = ToolConfig()):
        problem = tool_config_problem(tool)
        if problem:
            raise ValueError(problem)
        self.shelf = shelf
        eye = np.asarray(eye_xy, dtype=float)
        self.eye_xy = eye[:2]
        self.eye_z = float(eye[2]) if len(eye) > 2 else None  # needed by hidden_space="3d"
        self.tool = tool
        self.grid = FloorGrid(shelf, tool.grid.cell)
        self.y_front = -shelf.depth / 2 - FRONT_MARGIN
        self._raster_cache: dict = {}
        self._push_rects_cache: dict = {}  # (footprint, sign) -> (tool rects, swept rects); the tool never changes
        self._pair_cache: dict = {}  # collision tests of one moved footprint against one other (see _pair)
        self._fp_ids: dict = {}  # footprint -> int (footprint_ids)
        self._geometry: dict = {}  # id(obj) -> (obj, ObjectGeometry) (object_geometry)
        self._lattices: dict = {}  # id(obj) -> (obj, SuctionLattice) (suction_lattice)
        self.reach = load_reach_map(tool.rules.reach_map) if tool.rules.reach_map else None  # the reach_map rule

    @property
    def eye(self) -> tuple:
        """The camera's position the model was built with (S, m): (x, y), or (x, y, z) when it has a height."""
        return tuple(self.eye_xy) if self.eye_z is None else (*self.eye_xy, self.eye_z)

    def with_tool(self, tool: ToolConfig) -> "ActionModel":
        """A model of the same shelf and camera planning with ``tool`` (another rule or clearance)."""
        return ActionModel(self.shelf, self.eye, tool)

    @property
    def placement_clearance(self) -> float:
        """How far (m) a suction's placement keeps from every other object: the scenario's clearance."""
        return self.tool.physics.clearance

    # ----------------------------------------------------------------------------------------------------
    def enumerate(self, objects, fixed=(), pushes: bool = True, suctions: bool = True, only=None) -> Candidates:
        """Candidates for moving each of ``objects`` (or only those named in ``only``); ``fixed`` are known
        obstacles that never move (the oracle's target). Returns feasible actions (deterministic order) and
        rejected ones with reasons."""
        objects = tuple(objects)
        ctx = _StateContext(self, objects, tuple(fixed))
        feasible, rejected = [], []
        for i in range(len(objects)):
            if only is not None and objects[i].name not in only:
                continue
            if pushes:
                for sign in (+1, -1):
                    self._pushes(ctx, i, sign, feasible, rejected)
            if suctions:
                self._suctions(ctx, i, feasible, rejected)
        return Candidates(feasible, rejected)

    def hidden_by_others(self, objects, name: str) -> np.ndarray:
        """Cells (ny, nx) of :attr:`grid` that ``objects`` other than the one named ``name`` hide from the camera,
        where an unseen object could stand: the hidden space the model's rules read for that object's moves."""
        objects = tuple(objects)
        return _StateContext(self, objects, ()).hidden_others([o.name for o in objects].index(name))

    def drag_instead(self, objects, lift: Suction, mass: float) -> tuple[Suction | None, str]:
        """(the drag, "") that puts the object of ``lift`` where ``lift`` would have (the same d_x and d_z), when this
        model offers it among ``objects`` (the arrangement ``lift`` was chosen on) with that object reckoned at
        ``mass`` (kg, what the arm weighed before putting it back; the ``drag_after_weighing`` rule); else (None, why
        not): the object still liftable at that mass, not to be dragged at all (the model's reason: too heavy to
        slide, it would tip, its way out blocked, ...), or no drag to that placement (on the floor the way the lift
        passed over an object or crossed hidden space, the placement in front of the drag's pull-out depth, or a
        guarded one, reaching into hidden space: left to the next decision, which sees the shelf again)."""
        weighed = tuple(dataclasses.replace(o, mass=float(mass)) if o.name == lift.name else o for o in objects)
        found = self.enumerate(weighed, pushes=False, only={lift.name})
        drags = [c for c in found.feasible if c.drag]
        same = [c for c in drags if abs(c.dx - lift.dx) < 1e-6 and abs(c.dz - lift.dz) < 1e-6]
        unguarded = [c for c in same if not c.guarded]
        if unguarded:
            return unguarded[0], ""
        if same:
            return None, "the drag to that placement reaches into hidden space (guarded)"
        if drags:
            return None, f"no drag to that placement ({len(drags)} to others)"
        if found.feasible:
            return None, f"still lifted at {mass:.2f} kg"
        return None, "no drag of it: " + ("; ".join(r.reason for r in found.rejected) or "no candidate")

    # ----------------------------------------------------------------------------------------------------
    def object_geometry(self, objects, rasters: bool = True, fixed=()) -> list["ObjectGeometry"]:
        """Each object's :class:`ObjectGeometry`, cached by identity (a search passes the same unmoved object
        instances in thousands of states; the cache holds them, so their ids are not reused while it lives). The
        footprint ids are small ints naming footprints (equal footprints, equal ids) for the keys of
        :meth:`_pair`: hashing ints is cheaper than hashing footprints at every test. One call names all objects
        of a state (``objects``, then ``fixed``): when the id table is full it is emptied first, with everything
        keyed by its ids, so no id of the returned list is stale. ``rasters``: ``objects`` with the footprint and
        shadow masks (:meth:`rasters`); ``fixed`` (objects the model never moves) always without."""
        named = [(obj, rasters) for obj in objects] + [(obj, False) for obj in fixed]
        if len(self._fp_ids) + len(named) > PAIR_CACHE_SIZE:
            self._fp_ids.clear()
            self._pair_cache.clear()
            self._geometry.clear()
        elif len(self._geometry) + len(named) > GEOMETRY_CACHE_SIZE:
            self._geometry.clear()
        out = []
        for obj, rasters in named:
            hit = self._geometry.get(id(obj))
            if hit is None or hit[0] is not obj or (rasters and hit[1].mask is None):
                fp = Footprint.of(obj)
                ex, ey = fp.extents()
                mask, shadow = self.rasters(obj, fp) if rasters else (None, None)
                hit = self._geometry[id(obj)] = (obj, ObjectGeometry(
                    fp, self._fp_ids.setdefault(fp, len(self._fp_ids)), mask, shadow,
                    (fp.x - ex, fp.x + ex, fp.y - ey, fp.y + ey)))
            out.append(hit[1])
        return out

    def _pair(self, key: tuple, compute):
        """``compute()``, cached under ``key``: a collision test of one object's motion against one other
        footprint. Such a test depends only on the two footprints, the direction and the tool (which never
        changes), and a search meets the same pairs in thousands of states, so the cache returns exactly what
        ``compute()`` would. The cache is emptied when it holds ``PAIR_CACHE_SIZE`` entries."""
        return memo(self._pair_cache, key, compute, PAIR_CACHE_SIZE)

    def _pushes(self, ctx, i, sign, feasible, rejected):
        t, shelf = self.tool, self.shelf
        obj, fp = ctx.objects[i], ctx.fps[i]
        ex, ey = fp.extents()
        x, y = fp.x, fp.y
        side = "left" if sign > 0 else "right"
        what = f"push {obj.name} {'+x' if sign > 0 else '-x'}"
        refused = functools.partial(Rejected, action_kind="push", object_name=obj.name, direction=sign)
        rects = self.push_swept_rects(fp, sign)
        lane_x = self.push_tool_rects(fp, sign)[0][0]
        gap_x = rects[0][0]
        if abs(gap_x) + rects[0][2] > shelf.width / 2 + 1e-9:
            rejected.append(refused(what, f"blade does not fit between {obj.name} and the {side} wall",
                                    kind=RefusalKind.NO_ROOM_FOR_BLADE))
            return
        y_lo = min([y - ey] + [r[1] - r[3] for r in rects]) - t.physics.clearance - 1e-6
        y_hi = max([y + ey] + [r[1] + r[3] for r in rects]) + t.physics.clearance + 1e-6
        band = ctx.others_in_band(i, 1, y_lo, y_hi)
        def lane_blocked(other: Footprint):
            """The index of the first of ``rects`` that meets ``other`` (None when none does)."""
            for k_r, (rx, ry, hx, hy) in enumerate(rects):
                if not clear_of("box", np.array([[rx, ry]]), 0.0, (hx, hy), other, BLADE_CONTACT_CLEARANCE)[0]:
                    return k_r
            return -1

        for j in band:
            k_r = self._pair(("lane", ctx.ids[i], sign, ctx.ids[j]), lambda: lane_blocked(ctx.all_fps[j]))
            if k_r >= 0:
                where = "gap" if k_r == 0 else "shaft's way in"
                rejected.append(refused(what, f"blade {where} {side} of {obj.name} blocked by {ctx.all_names[j]}",
                                        kind=RefusalKind.BLOCKED))
                return
        if t.rules.push_tube_check:
            blocker = self.push_tube_blocker(ctx, i, sign)
            if blocker is not None:
                rejected.append(refused(what, f"the tube's way in {side} of {obj.name} is blocked by {blocker}",
                                        kind=RefusalKind.BLOCKED))
                return
        n = int(math.ceil(shelf.width / t.grid.cell)) + 1
        k = np.arange(1, n + 1)
        xs = x + sign * k * t.grid.cell
        ok = np.abs(xs) + ex <= shelf.width / 2 - t.physics.clearance + 1e-12
        first_bad, stopper = _first_false(ok), "the wall"

        def first_step_hitting(other: Footprint) -> int:
            """The first step (index into k) at which the pushed footprint or the dragged tool meets ``other``."""
            centers = np.column_stack([xs, np.full(n, y)])
            clear = clear_of(fp.shape, centers, fp.yaw, (fp.half_x, fp.half_y), other, t.physics.clearance)
            for rx, ry, hx, hy in rects:
                tool = np.column_stack([rx + sign * k * t.grid.cell, np.full(n, ry)])
                clear &= clear_of("box", tool, 0.0, (hx, hy), other, BLADE_CONTACT_CLEARANCE)
            return _first_false(clear)

        for j in band:
            bad = self._pair(("sweep", ctx.ids[i], sign, ctx.ids[j]), lambda: first_step_hitting(ctx.all_fps[j]))
            if bad < first_bad:
                first_bad, stopper = bad, ctx.all_names[j]
        end_ok = None  # push_hidden_extent "end": per step 1..first_bad, whether the object may stop there
        if t.rules.push_hidden_check and t.rules.push_hidden_extent == "end":
            end_ok = ~push_end_hidden(ctx.masks[i], ctx.hidden_others(i), sign, first_bad)
            last_ok = int(np.flatnonzero(end_ok)[-1]) + 1 if end_ok.any() else 0
            if last_ok < first_bad:
                first_bad, stopper = last_ok, "hidden space"
                end_ok = end_ok[:first_bad]
        elif t.rules.push_hidden_check:
            r0, r1, hidden = ctx.hidden_others_near(i)
            hidden_cells = free_push_cells(ctx.masks[i][r0:r1], hidden, sign)
            if hidden_cells < first_bad:
                first_bad, stopper = hidden_cells, "hidden space"
        d_max = first_bad * t.grid.cell  # first_bad is the index of the first bad step: steps 0..first_bad-1 ok
        step = t.grid.push_resolution
        q = (lane_x, self.blade_depth(fp, sign), t.geometry.blade_height / 2)
        if self.reach is not None:
            layer = "push+x" if sign > 0 else "push-x"
            if self.reach.refuses(layer, q[0], q[1], REACH_MARGIN):
                rejected.append(refused(what, f"the arm cannot reach the blade beside {obj.name} at "
                                               f"({q[0]:+.2f}, {q[1]:+.2f}) m (reach map)",
                                        kind=RefusalKind.REACH_MAP))
                return
            k_reach = _first_false(np.array([not self.reach.refuses(layer, q[0] + sign * kk * t.grid.cell, q[1],
                                                                    REACH_MARGIN) for kk in range(1, first_bad + 1)],
                                           dtype=bool))
            if k_reach < first_bad:
                first_bad, stopper = k_reach, "the arm's reach"
                d_max = first_bad * t.grid.cell
        if t.rules.push_stop == "exact" and first_bad < n and stopper not in ("hidden space", "the arm's reach"):
            d_max = self._exact_stop(fp, sign, rects, [ctx.all_fps[j] for j in band], d_max, t.grid.cell)
        if d_max < t.grid.min_push - 1e-12:
            rejected.append(refused(what, f"no room: {obj.name} is stopped by {stopper} at once",
                                    kind=_STOPPER_KIND.get(stopper, RefusalKind.NO_ROOM)))
            return
        ds = list(np.arange(1, int(d_max / step + 1e-9) + 1) * step)
        if end_ok is not None:  # only the lattice distances at which the object may come to rest
            ds = [d for d in ds if end_ok[int(round(d / t.grid.cell)) - 1]]
        if not ds or d_max - ds[-1] > (1e-9 if t.rules.push_stop == "exact" else t.grid.cell / 2):
            ds.append(d_max)
        turns = t.rules.push_turn == "quasi-static" and fp.shape != "cylinder"
        for d in ds:
            push = Push(obj.name, q, round(float(sign * d), 6), turns=turns)
            if turns:  # the box turns on its way: where it ends must be clear of the walls and the known objects
                blocker = self._turned_end_blocker(ctx, i, push)
                if blocker is not None:
                    into, kind = blocker
                    rejected.append(refused(f"{what} by {d:.3f}", f"{obj.name} would turn into {into}",
                                            distance=push.d, kind=kind))
                    continue
            feasible.append(push)
        d = (int(d_max / step + 1e-9) + 1) * step
        if d < shelf.width:
            rejected.append(refused(f"{what} by {d:.3f}", f"{obj.name} would hit {stopper} after {d_max:.3f} m",
                                     distance=round(float(sign * d), 6),
                                     kind=_STOPPER_KIND.get(stopper, RefusalKind.NO_ROOM)))

    def _exact_stop(self, fp: Footprint, sign: int, rects, others, d_ok: float, step: float) -> float:
        """The longest push distance (m, floored to 1 micrometre) in [d_ok, d_ok + step) at which ``fp`` keeps
        ``clearance`` from ``others`` and the walls and the dragged tool ``rects`` touch none of ``others``
        (``push_stop`` "exact"): bisection, given that ``d_ok`` is clear and ``d_ok + step`` is not."""
        t, shelf = self.tool, self.shelf
        ex = fp.extents()[0]

        def clear(d: float) -> bool:
            x = fp.x + sign * d
            if abs(x) + ex > shelf.width / 2 - t.physics.clearance + 1e-12:
                return False
            centre = np.array([[x, fp.y]])
            for other in others:
                if not clear_of(fp.shape, centre, fp.yaw, (fp.half_x, fp.half_y), other, t.physics.clearance)[0]:
                    return False
                for rx, ry, hx, hy in rects:
                    if not clear_of("box", np.array([[rx + sign * d, ry]]), 0.0, (hx, hy), other,
                                    BLADE_CONTACT_CLEARANCE)[0]:
                        return False
            return True

        lo, hi = d_ok, d_ok + step
        while hi - lo > 1e-7:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if clear(mid) else (lo, mid)
        d = math.floor(lo * 1e6) / 1e6
        return d if d >= d_ok and clear(d) else d_ok

    # ----------------------------------------------------------------------------------------------------
    def _suctions(self, ctx, i, feasible, rejected):
        """Appends object i's feasible suctions (in lattice order: by column x', then depth y') to ``feasible``, or
        its reason to ``rejected``. What depends on the object alone comes from :meth:`suction_lattice`; the
        collision tests against each other object are pairwise masks of the lattice (cached per pair of
        footprints); the hidden-space rule reads the state's raster."""
        t = self.tool
        obj, fp = ctx.objects[i], ctx.fps[i]
        what = f"suction {obj.name}"
        refused = functools.partial(Rejected, action_kind="suction", object_name=obj.name)
        lat = self.suction_lattice(obj, fp, ctx.masks[i])
        if lat.refusal is not None:
            rejected.append(refused(what, lat.refusal, kind=lat.refusal_kind))
            return
        cz = lat.q[2]
        tube_r = t.geometry.tube_diameter / 2
        for j in (ctx.others(i) if t.rules.tube_approach_check else ()):
            if ctx.all_heights[j] <= cz - tube_r:
                continue  # the tube passes over it
            if not self._pair(("approach", ctx.ids[i], tuple(obj.size), ctx.ids[j]), lambda: bool(
                    clear_of("box", lat.corridor, lat.yaw, lat.corridor_half, ctx.all_fps[j],
                             BLADE_CONTACT_CLEARANCE)[0])):
                rejected.append(refused(what, f"tube approach to {obj.name} blocked by {ctx.all_names[j]}",
                                        kind=RefusalKind.BLOCKED))
                return
        ex = fp.extents()[0]
        drag = lat.drag  # on the floor all the way: every other object blocks it
        blocking = [j for j in ctx.others(i) if drag or not self.passes_over(obj, ctx.all_heights[j])]
        for j in ctx.others_in_band(i, 0, fp.x - ex - t.physics.clearance - 1e-6, fp.x + ex + t.physics.clearance + 1e-6):
            if j not in blocking:
                continue
            if not self._pair(("out", drag, ctx.ids[i], ctx.ids[j]), lambda: bool(clear_of(
                    fp.shape, lat.path_out, fp.yaw, (fp.half_x, fp.half_y), ctx.all_fps[j], t.physics.clearance).all())):
                rejected.append(refused(what, f"path out of the shelf blocked by {ctx.all_names[j]}",
                                        kind=RefusalKind.BLOCKED))
                return
        path_rule = t.rules.suction_hidden_rule == "path"
        if path_rule:
            hidden_o = ctx.hidden_others(i)
            if any(hidden_o[:r, c].any() for c, r in zip(lat.cols, lat.first_rows)):
                rejected.append(refused(what, "path out of the shelf crosses space hidden from the camera",
                                    kind=RefusalKind.HIDDEN_SPACE))
                return
        if lat.lattice_empty:
            rejected.append(refused(what, "no placement fits in the shelf", kind=RefusalKind.NO_PLACEMENT))
            return
        ok = lat.base.copy()
        for j in blocking:  # reachable on the way in past each object it cannot pass over
            ok &= self._pair(("in", drag, ctx.ids[i], ctx.ids[j]), lambda: self._reachable_past(lat, fp, ctx.all_fps[j]))
            if drag:
                ok &= self._pair(("across", ctx.ids[i], ctx.ids[j]), lambda: self._drag_across_clear(
                    lat, fp, ctx.all_fps[j]))
        for j in ctx.others(i):  # clear of each object it passes over, where it is put down
            if j not in blocking:
                ok &= self._pair(("placed", ctx.ids[i], ctx.ids[j]), lambda: self._placements_clear_of(
                    lat, fp, ctx.all_fps[j]))
        if t.rules.tube_approach_check and abs(lat.yaw) > 1e-9:
            # turned, the tube leaves the object's lane: where the object is put down, the tube's way out along its
            # axis must be clear of every object it cannot pass over, as its way in was
            for j in ctx.others(i):
                if ctx.all_heights[j] > cz - tube_r:
                    ok &= self._pair(("release tube", ctx.ids[i], tuple(obj.size), ctx.ids[j]),
                                     lambda: self._release_tube_clear(lat, obj, ctx.all_fps[j]))
        guarded = None  # (A, B) bool: placements reaching into hidden space, made as guarded moves
        if t.rules.suction_hidden_rule == "guarded" and ok.any():
            guarded = ~self._suction_hidden_ok(ctx, i, lat, False)
            if drag:
                ok &= self._drag_hidden_ok(ctx, i, lat, way_in=False)
            elif (ok & guarded).any():
                # a lifted guarded push-in stays at the lowest carry, where the guard senses what hides in its way:
                # one whose way in passes over a known object would be carried higher (the planner refuses it,
                # FailureKind.GUARDED_LIFTED), so only placements whose way in meets none of them are guarded moves
                low = np.ones_like(ok)
                for j in ctx.others(i):
                    if j not in blocking:
                        low &= self._pair(("in", False, ctx.ids[i], ctx.ids[j]), lambda: self._reachable_past(
                            lat, fp, ctx.all_fps[j]))
                if not (ok & ~(guarded & ~low)).any():
                    rejected.append(refused(what, f"every placement of {obj.name} reaching into hidden space "
                                                  f"passes over a known object on its way in (a guarded push-in "
                                                  f"must stay at the lowest carry)", kind=RefusalKind.HIDDEN_SPACE))
                    return
                ok &= ~(guarded & ~low)
        elif t.rules.suction_hidden_rule != "none" and ok.any():
            ok &= self._suction_hidden_ok(ctx, i, lat, path_rule)
            if drag and ok.any():
                ok &= self._drag_hidden_ok(ctx, i, lat)
        if self.reach is not None and ok.any() and abs(lat.yaw) < 1e-9 and not lat.drag:
            # the release layers were computed for a lifted carry's back-off and retract
            released = self._release_reachable(lat, obj)
            if not (ok & released).any():
                rejected.append(refused(what, f"the arm cannot back off and retract from any placement of "
                                              f"{obj.name} (reach map)", kind=RefusalKind.REACH_MAP))
                return
            ok &= released
        if self.reach is not None and self.reach.hold and ok.any():
            held = ~self._hold_refused(ctx, i, lat, obj, fp)
            if not (ok & held).any():
                rejected.append(refused(what, f"the arm cannot carry {obj.name} to any placement: its carry or its "
                                              f"lowered placement is out of reach (reach map)", kind=RefusalKind.REACH_MAP))
                return
            ok &= held
        a_index, b_index = np.nonzero(ok)
        if len(a_index) == 0:
            only_back = lat.drag and not lat.base[lat.a_all != 0].any()
            rejected.append(refused(what, f"no collision-free placement for {obj.name} in known free space" + (
                " (dragged straight out and back in only: a sideways drag would twist it off the cup)"
                if only_back else ""), kind=RefusalKind.NO_PLACEMENT))
            return
        if guarded is None:
            feasible.extend(lat.action(a, b) for a, b in zip(a_index.tolist(), b_index.tolist()))
        else:
            feasible.extend(dataclasses.replace(lat.action(a, b), guarded=True) if guarded[a, b] else lat.action(a, b)
                            for a, b in zip(a_index.tolist(), b_index.tolist()))

    def _release_reachable(self, lat: "SuctionLattice", obj: SceneObject) -> np.ndarray:
        """(A, B) bool: whether the reach map's release layers let the arm back off and retract from each
        placement of a yaw-0 suction (the cup's contact where it releases: moved by dx, and in by the placement's
        depth change); all True when the map has no release layers."""
        if "mask" in lat._release:
            return lat._release["mask"]
        ok = np.ones((len(lat.a_all), len(lat.b_all)), bool)
        lat._release["mask"] = ok  # it depends on the object and the map alone: kept with the object's lattice
        if not any(layer in self.reach.reach for layer in ("back off", "retract")):
            return ok
        cx, cy = float(lat.q[0]), float(lat.q[1])
        oy = float(obj.center[1])
        for a, dx in enumerate(np.asarray(lat.a_all, float) * lat.res):
            for b, y_placed in enumerate(lat.y_placed):
                ok[a, b] = not self.reach.refuses_release(cx + float(dx), cy + (float(y_placed) - oy), REACH_MARGIN)
        return ok

    def pre_approach_refused(self, cx: float, cy: float, cz: float, yaw: float) -> bool:
        """Whether the reach map's pre-approach layers refuse the first waypoint of a suction whose contact is
        (cx, cy, cz) (S, m) with the tool turned ``yaw`` (rad): the cup tip on the tube's axis in front of the
        opening, at each of ``APPROACH_MARGINS`` (the planner tries each); True only when every one is refused."""
        ax, ay = -math.sin(yaw), math.cos(yaw)
        for margin in APPROACH_MARGINS:
            y_pre = -self.shelf.depth / 2.0 - margin
            back = (cy - y_pre) / ay
            if not self.reach.refuses_approach(cx - back * ax, y_pre, cz, yaw, REACH_MARGIN):
                return False
        return True

    def carry_cup_ys(self, lat: "SuctionLattice", obj: SceneObject, fp: Footprint) -> list[tuple[float, float]]:
        """(cup y in S (m), turn of the tool about the cup's vertical axis (rad)) of every way the planner may carry
        the object of a lifted suction across (:func:`slax_drake.planning.waypoints.carry_options` at each of
        ``APPROACH_MARGINS``, none left out for the target): pulled all the way out (its back ``OUT_MARGIN`` in front
        of the opening, the cup at least the approach margin out), at shallower depths ``PULL_STEP`` apart while the
        cup is pulled at least ``PULL_STEP`` back from the contact, and all the way out turned by ``CARRY_YAWS_DEG``
        either way. A drag has one: the cup where the drag's pull leaves the object."""
        cy = float(lat.q[1])
        oy = float(obj.center[1])
        if lat.drag:
            return [(cy + (float(lat.y_pull) - oy) + SEAL_PRESS * math.cos(lat.yaw), 0.0)]
        y_open = -self.shelf.depth / 2.0
        ey = fp.extents()[1]
        y_out = cy + (y_open - ey - OUT_MARGIN - oy)
        options = []
        for margin in APPROACH_MARGINS:
            y_full = min(y_out, y_open - margin)
            options.append((y_full, 0.0))
            y = y_full + PULL_STEP
            while y <= cy - PULL_STEP + 1e-9:
                options.append((y, 0.0))
                y += PULL_STEP
            options.extend((y_full, sign * math.radians(d)) for d in CARRY_YAWS_DEG for sign in (1.0, -1.0))
        return list(dict.fromkeys((round(y, 9), w) for y, w in options))

    def _hold_refused(self, ctx, i: int, lat: "SuctionLattice", obj: SceneObject, fp: Footprint) -> np.ndarray:
        """(A, B) bool: placements of object i's suction whose motion the reach map's hold layers refuse: the cup
        lowered at the placement, or (a lifted carry) pushed in there, or every way across of
        :meth:`carry_cup_ys` refused at its pull-out or its translation. A lifted carry's cup is anywhere from
        ``LIFT`` above the seal to ``LIFT_CLEARANCE`` above the tallest other object near its way (any whose
        bounding box meets the box around every footprint the carried object may sweep); a drag's stays at the
        seal's height. What depends on the object alone is kept with its lattice."""
        pre = lat._hold.get("pre")
        if pre is None:
            pre = lat._hold["pre"] = self._hold_precompute(lat, obj, fp)
        cz = float(lat.q[2])
        refused = pre["lowered"].copy()
        if lat.drag:
            return refused | pre["carry_at_seal"]
        through_hidden = self._ways_through_hidden(ctx, i, pre, obj, fp)  # (A, O) or None
        # the tallest other object near each placement's way (A, B)
        ox, oy = float(obj.center[0]), float(obj.center[1])
        dxs, y_placed = pre["dxs"], lat.y_placed
        r = pre["sweep_radius"]
        x_lo, x_hi = ox + np.minimum(0.0, dxs) - r, ox + np.maximum(0.0, dxs) + r
        y_lo, y_hi = pre["y_far_centre"] - r, np.maximum(oy, y_placed) + r
        tallest = np.zeros((len(dxs), len(y_placed)))
        for j in ctx.others(i):
            other = ctx.all_fps[j]
            ejx, ejy = other.extents()
            near_x = (x_lo <= other.x + ejx) & (other.x - ejx <= x_hi)
            near_y = (y_lo <= other.y + ejy) & (other.y - ejy <= y_hi)
            tallest = np.maximum(tallest, float(ctx.all_heights[j]) * (near_x[:, None] & near_y[None, :]))
        z_top = cz + np.maximum(LIFT, np.where(tallest > 0.0, tallest + LIFT_CLEARANCE, 0.0))
        for zt in np.unique(np.round(z_top, 6)):
            span = hold_height_span(cz + LIFT, float(zt))
            if span is None:
                continue  # beyond the map's heights: not refused
            lo, hi = span[0], span[1] + 1
            sel = np.isclose(z_top, zt, atol=1e-6)
            pushed_in = pre["at_placement"][..., lo:hi].all(-1)  # (A, B)
            ways = pre["pull_out"][None, :, lo:hi].all(-1) | pre["translate"][:, :, lo:hi].all(-1)  # (A, O)
            if through_hidden is not None:
                ways = ways | through_hidden
            refused[sel] |= (pushed_in | ways.all(-1)[:, None])[sel]
        return refused

    def _ways_through_hidden(self, ctx, i: int, pre: dict, obj: SceneObject, fp: Footprint) -> np.ndarray | None:
        """(A, O) bool: the ways across of :meth:`carry_cup_ys` (O) on which object i, carried across by each
        placement's d_x (A), would cross space the other objects hide from the camera (the ``carry_hidden_check``
        rule: :func:`slax_drake.shelf.floor.band_crosses_hidden`); None when the rule is off. The planner leaves
        such ways out (:func:`slax_drake.planning.waypoints.pull_out_options`)."""
        if not self.tool.rules.carry_hidden_check:
            return None
        hidden = ctx.hidden_others(i)
        ex, ey = fp.extents()
        ox, oy = float(obj.center[0]), float(obj.center[1])
        dxs = pre["dxs"]
        x_lo, x_hi = ox + np.minimum(0.0, dxs) - ex, ox + np.maximum(0.0, dxs) + ex
        out = np.zeros((len(dxs), len(pre["way_ys"])), dtype=bool)
        for k, y_way in enumerate(pre["way_ys"]):
            y_centre = oy + (float(y_way) - pre["py"])
            out[:, k] = band_crosses_hidden(self.grid, hidden, y_centre - ey, y_centre + ey, x_lo, x_hi)
        return out

    def _hold_precompute(self, lat: "SuctionLattice", obj: SceneObject, fp: Footprint) -> dict:
        """The hold layers' verdicts (per height node, last axis) on the poses of object ``obj``'s suction that
        depend on it alone; see :meth:`_hold_refused`."""
        rmap = self.reach
        cx, cy, cz = (float(v) for v in lat.q)
        yaw = float(lat.yaw)
        px, py = cx - SEAL_PRESS * math.sin(yaw), cy + SEAL_PRESS * math.cos(yaw)
        oy = float(obj.center[1])
        dxs = np.asarray(lat.a_all, float) * lat.res
        x2 = px + dxs  # (A,) the cup's x across
        y_in = py + (np.asarray(lat.y_placed, float) - oy)  # (B,) the cup's y at each placement
        at_placement = rmap.hold_refusals(x2[:, None], y_in[None, :], yaw, REACH_MARGIN)  # (A, B, H)
        seal = hold_height_span(cz, cz)
        lowered = (np.zeros(at_placement.shape[:2], bool) if seal is None
                   else at_placement[..., seal[0]:seal[1] + 1].all(-1))
        ways = self.carry_cup_ys(lat, obj, fp)
        way_ys, turns = np.array([y for y, _ in ways]), np.array([w for _, w in ways])
        pull_out = np.zeros((len(ways), at_placement.shape[-1]), bool)  # (O, H)
        translate = np.zeros((len(x2), len(ways), at_placement.shape[-1]), bool)  # (A, O, H)
        for w in np.unique(turns):  # the ways of one turn of the tool together
            k = np.flatnonzero(turns == w)
            pull_out[k] = rmap.hold_refusals(np.full(len(k), px), way_ys[k], yaw + float(w), REACH_MARGIN)
            translate[:, k] = rmap.hold_refusals(x2[:, None], way_ys[k][None, :], yaw + float(w), REACH_MARGIN)
        pre = dict(dxs=dxs, lowered=lowered, at_placement=at_placement, pull_out=pull_out, translate=translate,
                   way_ys=way_ys, py=py)
        if lat.drag:  # one way, at the seal's height: pulled, dragged across, pushed in
            if seal is None:
                pre["carry_at_seal"] = np.zeros_like(lowered)
            else:
                s0, s1 = seal[0], seal[1] + 1
                across = pull_out[0, s0:s1].all() | translate[:, 0, s0:s1].all(-1)  # (A,)
                pre["carry_at_seal"] = across[:, None] | at_placement[..., s0:s1].all(-1)
            return pre
        ex, ey = fp.extents()
        pre["sweep_radius"] = math.hypot(float(obj.center[0]) - cx, oy - cy) + math.hypot(ex, ey)
        pre["y_far_centre"] = oy + (min(y for y, _ in ways) - py)
        return pre

    def suction_lattice(self, obj: SceneObject, fp: Footprint, mask: np.ndarray) -> "SuctionLattice":
        """Object ``obj``'s :class:`SuctionLattice` (``fp`` its footprint, ``mask`` its footprint mask on the
        floor raster), cached by the object's identity: it depends on the object and the tool alone, and a search
        passes the same unmoved object instances in thousands of states."""
        hit = self._lattices.get(id(obj))
        if hit is None or hit[0] is not obj:
            if len(self._lattices) >= GEOMETRY_CACHE_SIZE:
                self._lattices.clear()
            hit = self._lattices[id(obj)] = (obj, self._make_suction_lattice(obj, fp, mask))
        return hit[1]

    def _make_suction_lattice(self, obj: SceneObject, fp: Footprint, mask: np.ndarray) -> "SuctionLattice":
        t, shelf = self.tool, self.shelf
        mass = self.planning_mass(obj)
        if RULES["max_suction_mass"].refuses(t.rules.max_suction_mass, mass):
            return SuctionLattice.refused(f"{obj.name} weighs {mass:.2f} kg > {t.rules.max_suction_mass:.2f} kg",
                                          RefusalKind.TOO_HEAVY)
        contact = self.suction_contact(obj)
        if contact is None:
            return SuctionLattice.refused(f"{obj.name}'s camera-facing side is too small or curved for the cup",
                                          RefusalKind.NO_FACE)
        cx, cy, cz = contact
        yaw = self.tool_yaw(obj, (cx, cy))
        face = math.degrees(self.face_yaw(obj))
        angle = abs(face - math.degrees(yaw))
        if t.rules.max_seal_angle_deg >= 45.0:
            angle = 0.0  # a front face turns 45 deg at most (from y, and from a tube turned toward it): none refused
        if RULES["max_seal_angle_deg"].refuses(t.rules.max_seal_angle_deg, angle):
            turned = f" (the tool turns {abs(math.degrees(yaw)):.0f} deg)" if yaw else ""
            return SuctionLattice.refused(f"{obj.name}'s camera-facing side is turned {angle:.0f} deg from the "
                                          f"tube{turned} > {t.rules.max_seal_angle_deg:.0f} deg", RefusalKind.SEAL_ANGLE)
        moment = self.held_moment(obj, (cx, cy))
        drag, drag_across = False, True
        if RULES["max_suction_moment"].refuses(t.rules.max_suction_moment, moment):
            lifted = f"{obj.name}'s weight hangs {moment:.2f} N m off the cup > {t.rules.max_suction_moment:.2f} N m"
            if not t.rules.drag_grasp:
                return SuctionLattice.refused(lifted, RefusalKind.SUCTION_MOMENT)
            limits = self.drag_limits(obj, cz)
            if limits.refusal is not None:
                return SuctionLattice.refused(f"{lifted}, and no drag: {limits.refusal}", RefusalKind.SUCTION_MOMENT)
            drag, cz = True, limits.seal_z
            r = t.rules
            drag_across = r.drag_safety_factor * r.drag_friction * moment <= drag_twist_limit(r, obj.shape)
        if RULES["max_suction_depth"].refuses(t.rules.max_suction_depth, (cy - (-shelf.depth / 2)) / math.cos(yaw)):
            return SuctionLattice.refused(f"{obj.name}'s face is beyond the tube's reach", RefusalKind.TUBE_DEPTH)
        if self.reach is not None and self.reach.refuses_cup(cx, cy, cz, yaw, REACH_MARGIN):
            turned = f" turned {math.degrees(yaw):+.0f} deg" if yaw else ""
            return SuctionLattice.refused(f"the arm cannot reach the cup{turned} at {obj.name}'s face "
                                          f"({cx:+.2f}, {cy:+.2f}) m (reach map)", RefusalKind.REACH_MAP)
        if self.reach is not None and self.reach.approach and self.pre_approach_refused(cx, cy, cz, yaw):
            turned = f" turned {math.degrees(yaw):+.0f} deg" if yaw else ""
            return SuctionLattice.refused(f"the arm cannot hold the cup{turned} in front of the opening on its way to "
                                          f"{obj.name}'s face (reach map)", RefusalKind.REACH_MAP)
        # the tube's straight way in along its (turned) axis, from in front of the opening to the contact
        corridor, corridor_half = self.tube_corridor(np.array([cx]), cy, yaw)
        ex, ey = fp.extents()
        y_out = -shelf.depth / 2 - ey - t.grid.cell
        if drag:  # pulled along the floor until its front is DRAG_FRONT_MARGIN inside the opening
            y_out = min(fp.y, self.drag_pull_y(fp))
        n_out = int(math.ceil((fp.y - y_out) / t.grid.cell))
        path_out = np.column_stack([np.full(n_out, fp.x), fp.y - np.arange(1, n_out + 1) * t.grid.cell])
        if drag and n_out:
            path_out[-1, 1] = y_out
        cols, first_rows, last_rows = column_extents(mask)
        q = (float(cx), float(cy), float(cz))
        # Placements on a lattice around the object: x' = x + a res, y' = y + b res.
        res = t.grid.suction_resolution
        cells_per = int(round(res / t.grid.cell))
        x_lim = shelf.width / 2 - t.physics.clearance - ex
        y_lim = shelf.depth / 2 - t.physics.clearance - ey
        a_all = np.arange(int(math.floor((-x_lim - fp.x) / res + 1e-9)), int(math.floor((x_lim - fp.x) / res + 1e-9)) + 1)
        a_all = a_all[np.abs(fp.x + a_all * res) <= x_lim + 1e-12]
        b_all = np.arange(int(math.ceil((-y_lim - fp.y) / res - 1e-9)), int(math.floor((y_lim - fp.y) / res + 1e-9)) + 1)
        common = dict(q=q, yaw=yaw, corridor=corridor, corridor_half=corridor_half, path_out=path_out,
                      cols=cols, first_rows=first_rows, last_rows=last_rows, cells_per=cells_per, drag=drag,
                      y_pull=y_out)
        if len(a_all) == 0 or len(b_all) == 0:
            return SuctionLattice(refusal=None, lattice_empty=True, **common)
        # the way in: per column x', steps in from y_out to the deepest placement
        y_deep = fp.y + b_all[-1] * res
        n_in = int(math.ceil((y_deep - y_out) / t.grid.cell)) + 1
        steps = y_out + np.arange(n_in) * t.grid.cell
        steps[-1] = max(min(steps[-1], y_deep), y_out)
        xs = fp.x + a_all * res
        shifted_cols = cols[None, :] + a_all[:, None] * cells_per  # (A, C) raster columns of each placement column
        inside = (shifted_cols >= 0) & (shifted_cols < self.grid.nx)
        base = np.repeat(inside.any(axis=1)[:, None], len(b_all), axis=1)  # a column wholly off the raster: none
        base[(a_all == 0)[:, None] & (b_all == 0)[None, :]] = False  # not where it stands
        if drag:  # pushed in from the pull-out depth, never pulled farther out
            base &= (fp.y + b_all * res >= y_out - 1e-9)[None, :]
            if not drag_across:  # the seal would not hold the twist of a sideways slide: straight out and in only
                base &= (a_all == 0)[:, None]
        return SuctionLattice(refusal=None, lattice_empty=False, a_all=a_all, b_all=b_all, xs=xs,
                              y_placed=fp.y + b_all * res, steps=steps, shifted_cols=shifted_cols, inside=inside,
                              base=base, name=obj.name, res=res, **common)

    def planning_mass(self, obj: SceneObject) -> float:
        """The mass (kg) the model plans ``obj``'s suction with: its recorded (or weighed) mass, else its household
        class's ``mass_quantile`` (the rule), else the scenario's density x its volume (:func:`object_mass`)."""
        t = self.tool
        return object_mass(obj, t.physics.object_density, t.physics, t.rules.mass_quantile)

    def held_moment(self, obj: SceneObject, contact_xy) -> float:
        """N m: the moment ``obj``'s weight (:meth:`planning_mass`) hangs off a cup sealed at ``contact_xy`` (S,
        m): the weight times the horizontal distance from the contact to the object's centre."""
        return self.planning_mass(obj) * GRAVITY * contact_lever(obj, contact_xy)

    def drag_limits(self, obj: SceneObject, seal_z: float) -> "DragLimits":
        """The limits of dragging ``obj`` on the shelf floor (the ``drag_grasp`` rule), the cup sealing on its
        camera-facing side at most ``seal_z`` (m) high. With mu' = ``drag_safety_factor`` x ``drag_friction``:
        the pull, mu' m g (N), must be within ``max_drag_pull``; the object must not tip about its leading base
        edge: a horizontal pull F at height h tips it when F h > m g b, b the base's half depth along the pull, so
        the cup seals at most b / mu' high, b the least of the footprint's half extents along S x and y (the
        pull out and the push in run along y, the translation along x; a cylinder's radius); and the tube
        needs ``DRAG_MIN_SEAL_Z``. The seal height is the lower of ``seal_z`` and b / mu'."""
        r = self.tool.rules
        mu = r.drag_safety_factor * r.drag_friction
        mass = self.planning_mass(obj)
        pull = mu * mass * GRAVITY
        ex, ey = Footprint.of(obj).extents()
        b = min(ex, ey)
        z_tip = b / mu if mu > 0 else math.inf
        z = min(seal_z, z_tip)
        if pull > r.max_drag_pull:
            return DragLimits(f"{obj.name} needs a {pull:.1f} N pull to slide > the cup's {r.max_drag_pull:.1f} N",
                              pull, z_tip, z)
        if z < DRAG_MIN_SEAL_Z:
            return DragLimits(f"{obj.name} would tip (a pull above {z_tip * 100:.1f} cm tips it, the tube seals no "
                              f"lower than {DRAG_MIN_SEAL_Z * 100:.1f} cm)", pull, z_tip, z)
        return DragLimits(None, pull, z_tip, z)

    def drag_pull_y(self, fp: Footprint) -> float:
        """The y (S) of a dragged object's centre at the end of its pull toward the camera: its front
        ``DRAG_FRONT_MARGIN`` inside the opening."""
        return -self.shelf.depth / 2 + fp.extents()[1] + DRAG_FRONT_MARGIN

    def _drag_across_clear(self, lat: "SuctionLattice", fp: Footprint, other: Footprint) -> np.ndarray:
        """(A, B) bool: whether the dragged object, sliding along x at the pull-out depth from where it stands to
        each lattice column, keeps ``clearance`` from ``other``."""
        cell = self.tool.grid.cell
        lo, hi = min(float(lat.xs.min()), fp.x), max(float(lat.xs.max()), fp.x)
        n = int(math.ceil((hi - lo) / cell)) + 1
        xs = np.linspace(lo, hi, max(n, 2))
        clear = clear_of(fp.shape, np.column_stack([xs, np.full(len(xs), lat.y_pull)]), fp.yaw,
                         (fp.half_x, fp.half_y), other, self.tool.physics.clearance)
        ok = np.array([bool(clear[(xs >= min(fp.x, x) - 1e-9) & (xs <= max(fp.x, x) + 1e-9)].all()) for x in lat.xs])
        return np.repeat(ok[:, None], len(lat.y_placed), axis=1)

    def _drag_hidden_ok(self, ctx, i: int, lat: "SuctionLattice", way_in: bool = True) -> np.ndarray:
        """(A, B) bool: the drags of object i whose swept footprint (pulled out, across, and with ``way_in``
        pushed in; on the floor raster, the object's own mask shifted by whole cells, rounded outward) covers no
        cell hidden by others."""
        hidden = ctx.hidden_all & ~ctx.masks[i]
        rows, cols = np.nonzero(ctx.masks[i])
        ny, nx = hidden.shape
        cell = self.tool.grid.cell

        def hit(dr: int, dc: int) -> bool:
            r, c = rows + dr, cols + dc
            keep = (r >= 0) & (r < ny) & (c >= 0) & (c < nx)
            return bool(hidden[r[keep], c[keep]].any())

        out_rows = int(math.ceil((ctx.fps[i].y - lat.y_pull) / cell - 1e-9))
        ok = np.zeros((len(lat.xs), len(lat.y_placed)), dtype=bool)
        if any(hit(-k, 0) for k in range(out_rows + 1)):
            return ok
        for a_index, a in enumerate(lat.a_all.tolist()):
            dc_end = a * lat.cells_per
            step = 1 if dc_end >= 0 else -1
            if any(hit(-out_rows, dc) for dc in range(0, dc_end + step, step)):
                continue
            if not way_in:
                ok[a_index, :] = True
                continue
            for b_index, b in enumerate(lat.b_all.tolist()):
                dr_end = b * lat.cells_per
                ok[a_index, b_index] = not any(hit(dr, dc_end) for dr in range(-out_rows, dr_end + 1))
        return ok

    def _reachable_past(self, lat: "SuctionLattice", fp: Footprint, other: Footprint) -> np.ndarray:
        """(A, B) bool: whether the object (footprint ``fp``), going straight in at each lattice column, reaches the
        placement's depth before meeting ``other`` (an object it cannot pass over): the path test at every step of
        the way in, from outside the shelf to the deepest placement, keeping ``clearance``. Over several objects
        the AND of these masks is the test against all of them (the first step blocked by any is the least)."""
        n_in = len(lat.steps)
        centres = np.column_stack([np.repeat(lat.xs, n_in), np.tile(lat.steps, len(lat.xs))])
        clear = clear_of(fp.shape, centres, fp.yaw, (fp.half_x, fp.half_y), other,
                         self.tool.physics.clearance).reshape(len(lat.xs), n_in)
        first_bad = np.where(clear.all(axis=1), n_in, np.argmin(clear, axis=1))
        y_reach = np.where(first_bad >= n_in, np.inf,
                           np.where(first_bad == 0, -np.inf, lat.steps[np.maximum(first_bad - 1, 0)]))
        return lat.y_placed[None, :] <= y_reach[:, None] + 1e-9

    def tube_corridor(self, cups_x: np.ndarray, cup_y: float, yaw: float) -> tuple[np.ndarray, tuple[float, float]]:
        """The floor rectangle the tube covers on its axis, turned ``yaw`` (rad), from a cup at (x, ``cup_y``) (S,
        m) for each x of ``cups_x`` out to in front of the opening: (centres (K, 2), (half width, half length)) in
        the rectangle's own axes, turned by ``yaw``."""
        length = (cup_y - self.y_front) / math.cos(yaw)
        centres = np.column_stack([cups_x + math.sin(yaw) * length / 2,
                                   np.full(len(cups_x), cup_y - math.cos(yaw) * length / 2)])
        return centres, (self.tool.geometry.tube_diameter / 2, length / 2)

    def _release_tube_clear(self, lat: "SuctionLattice", obj: SceneObject, other: Footprint) -> np.ndarray:
        """(A, B) bool: whether the tube of a turned suction, where the object is put down at each lattice point
        (the contact moved with it), keeps ``TUBE_CLEARANCE`` from ``other`` on its axis from the cup out to in
        front of the opening (the approach's :meth:`tube_corridor`, moved to the placement)."""
        cx, cy = float(lat.q[0]), float(lat.q[1])
        cups_x = cx + np.asarray(lat.xs, float) - float(obj.center[0])
        out = np.ones((len(lat.xs), len(lat.y_placed)), bool)
        for b, y_placed in enumerate(lat.y_placed):
            centres, half = self.tube_corridor(cups_x, cy + float(y_placed) - float(obj.center[1]), lat.yaw)
            out[:, b] = clear_of("box", centres, lat.yaw, half, other, TUBE_CLEARANCE)
        return out

    def _placements_clear_of(self, lat: "SuctionLattice", fp: Footprint, other: Footprint) -> np.ndarray:
        """(A, B) bool: whether the object placed at each lattice point keeps :attr:`placement_clearance` from
        ``other``."""
        placed = np.column_stack([np.repeat(lat.xs, len(lat.y_placed)), np.tile(lat.y_placed, len(lat.xs))])
        return clear_of(fp.shape, placed, fp.yaw, (fp.half_x, fp.half_y), other,
                        self.placement_clearance).reshape(len(lat.xs), len(lat.y_placed))

    def _suction_hidden_ok(self, ctx, i: int, lat: "SuctionLattice", path_rule: bool) -> np.ndarray:
        """(A, B) bool: the lattice placements the hidden-space rule allows for object i. "path": the footprint,
        shifted to the column, advances from the front no further than the row before its first hidden cell (the
        placement's depth at most fp.y + that many cells); "placement": the shifted footprint at its placement
        covers no hidden cell (per column, a prefix count of hidden rows). Hidden space is the state's, object i's
        own cells excepted."""
        hidden_in = ctx.hidden_all & ~ctx.masks[i]
        cols_in = np.where(lat.inside, lat.shifted_cols, 0)  # (A, C), any valid column where outside (masked)
        if path_rule:
            first_h = first_hidden_row(hidden_in)
            adv = np.where(lat.inside, first_h[cols_in] - lat.last_rows[None, :] - 1, NOT_FOUND).min(axis=1)
            y_path = np.where(adv < NOT_FOUND // 2, ctx.fps[i].y + adv * self.tool.grid.cell, np.inf)
            return lat.y_placed[None, :] <= y_path[:, None] + 1e-9
        ny = self.grid.ny
        prefix = np.vstack([np.zeros((1, self.grid.nx), dtype=np.int32), np.cumsum(hidden_in, axis=0, dtype=np.int32)])
        shift = lat.b_all[None, :, None] * lat.cells_per  # (1, B, 1) rows
        r0 = np.clip(lat.first_rows[None, None, :] + shift, 0, ny)  # (1, B, C)
        r1 = np.clip(lat.last_rows[None, None, :] + shift + 1, 0, ny)
        c = cols_in[:, None, :]  # (A, 1, C)
        counts = np.where(lat.inside[:, None, :], prefix[r1, c] - prefix[r0, c], 0).sum(axis=2)  # (A, B)
        return counts == 0

    def _push_rects(self, fp: Footprint, sign: int):
        """(:meth:`push_tool_rects`, :meth:`push_swept_rects`) of ``fp``, cached by footprint and direction: they
        depend on nothing else (the tool is fixed), and a search asks for them thousands of times."""
        def compute():
            tool_rects = tuple(self._tool_rects(fp, sign))
            return tool_rects, tuple(self._swept_rects(tool_rects, sign))

        return memo(self._push_rects_cache, (fp, sign), compute, PAIR_CACHE_SIZE)

    def _turned_end_blocker(self, ctx, i: int, push: Push) -> tuple[str, "RefusalKind"] | None:
        """What the box of ``ctx.objects[i]``, turned where ``push`` leaves it, would meet, and the refusal's kind:
        a known object (within ``clearance``) or "the wall" (BLOCKED), or, under ``push_hidden_check``, "hidden
        space" (HIDDEN_SPACE: a cell it newly covers is hidden by the other objects, as the straight push's check
        reads it); None when nothing."""
        end = Footprint.of(pushed(ctx.objects[i], push))
        if not inside_shelf(end, self.shelf, self.tool.physics.clearance):
            return "the wall", RefusalKind.BLOCKED
        for j, other in enumerate(ctx.all_fps):
            if j != i and not footprints_clear(end, other, self.tool.physics.clearance):
                return ctx.all_names[j], RefusalKind.BLOCKED
        if self.tool.rules.push_hidden_check:
            newly = self.grid.footprint_mask(end) & ~ctx.masks[i]
            if (newly & ctx.hidden_others(i)).any():
                return "hidden space", RefusalKind.HIDDEN_SPACE
        return None

    def push_tool_rects(self, fp: Footprint, sign: int) -> list[tuple[float, float, float, float]]:
        """The tool's outline when inserted to push ``fp`` toward ``sign`` x: (centre x, centre y, half x,
        half y) of the blade in the gap beside the object and of the shaft's way in (see :meth:`_tool_rects`)."""
        return list(self._push_rects(fp, sign)[0])

    def _tool_rects(self, fp: Footprint, sign: int) -> list[tuple[float, float, float, float]]:
        """The tool's outline when inserted to push ``fp`` toward ``sign`` x: (centre x, centre y, half x,
        half y) of the blade in the gap beside the object (``blade_width`` along x, from the object's front
        extreme to the blade's depth) and of the shaft's way in (``tube_diameter`` wide, from outside the
        shelf to the blade's depth; the blade goes in edge first and turns in the gap)."""
        t = self.tool
        ex, ey = fp.extents()
        edge = fp.x - ex if sign > 0 else fp.x + ex
        blade_x = edge - sign * t.geometry.blade_width / 2  # q's x: the lane centre, whatever blade_gap is
        y_tip = self.blade_depth(fp, sign)
        y_face = fp.y - ey
        blade = (blade_x, (y_face + y_tip) / 2, t.geometry.blade_width / 2, max(1e-4, (y_tip - y_face) / 2))
        shaft = (blade_x, (self.y_front + y_tip) / 2, t.geometry.tube_diameter / 2, (y_tip - self.y_front) / 2)
        return [blade, shaft]

    def rasters(self, obj: SceneObject, fp: Footprint):
        """(footprint mask, shadow mask) of an object, cached by its shape and pose (searches revisit them)."""
        key = (obj.name, obj.shape, tuple(obj.size), round(fp.x, 6), round(fp.y, 6), round(fp.yaw, 6))
        hit = self._raster_cache.get(key)
        if hit is not None:
            return hit
        grid, t = self.grid, self.tool
        if t.rules.hidden_space == "3d" and self.eye_z is not None:
            shadow = grid.shadow_mask(fp, self.eye_xy, obj.size[2], self.eye_z, t.rules.hidden_probe_height)
        else:
            shadow = grid.shadow_mask(fp, self.eye_xy)
        if len(self._raster_cache) >= 1500:
            self._raster_cache.clear()
        self._raster_cache[key] = (grid.footprint_mask(fp), shadow)
        return self._raster_cache[key]

    def push_tube_corridor(self, fp: Footprint, sign: int) -> tuple[float, float, float, float, float] | None:
        """Where the tube surely passes on its straight way in to push ``fp`` toward ``sign`` x: (centre x,
        centre y, half x, half y) of the floor rectangle its axis sweeps from the opening to the blade's tip at
        the blade's plane (``TUBE_STANDOFF`` + a tube radius beside the object's extreme x, where the planner puts
        it), ``tube_diameter`` wide, narrowed by ``TUBE_CHECK_SLACK`` on every side; and the height (m) above
        which an object surely meets the tube (its underside, on the blade's upper edge, plus the slack)."""
        t = self.tool
        ex, _ = fp.extents()
        tube_r = t.geometry.tube_diameter / 2
        plane_x = (fp.x - ex - tube_r - TUBE_STANDOFF) if sign > 0 else (fp.x + ex + tube_r + TUBE_STANDOFF)
        y0 = -self.shelf.depth / 2 + TUBE_CHECK_SLACK
        y1 = self.blade_depth(fp, sign) - TUBE_CHECK_SLACK
        if tube_r <= TUBE_CHECK_SLACK or y1 <= y0:
            return None
        underside = BLADE_LIFT + t.geometry.blade_height - tube_r
        return plane_x, (y0 + y1) / 2, tube_r - TUBE_CHECK_SLACK, (y1 - y0) / 2, underside + TUBE_CHECK_SLACK

    def push_tube_blocker(self, ctx, i: int, sign: int) -> str | None:
        """The name of an object that the tube surely meets on its way in to push object i toward ``sign`` x
        (one taller than :meth:`push_tube_corridor`'s height whose footprint overlaps its rectangle), or None."""
        corridor = self.push_tube_corridor(ctx.fps[i], sign)
        if corridor is None:
            return None
        cx, cy, hx, hy, height = corridor
        for j in ctx.others(i):
            if ctx.all_heights[j] > height and not self._pair(("tube", ctx.ids[i], sign, ctx.ids[j]), lambda: bool(
                    clear_of("box", np.array([[cx, cy]]), 0.0, (hx, hy), ctx.all_fps[j], 0.0)[0])):
                return ctx.all_names[j]
        return None

    def push_swept_rects(self, fp: Footprint, sign: int) -> list[tuple[float, float, float, float]]:
        """The parts of :meth:`push_tool_rects` the model requires to be free (and drags along the push):
        the blade in the gap, with the tube's end ``tube_past_blade`` beyond its tip, plus the shaft's way in
        when ``shaft_lane_check`` is on."""
        return list(self._push_rects(fp, sign)[1])

    def _swept_rects(self, tool_rects, sign: int) -> list[tuple[float, float, float, float]]:
        t = self.tool
        blade, shaft = tool_rects
        edge = blade[0] + sign * t.geometry.blade_width / 2
        y_face, y_end = blade[1] - blade[3], blade[1] + blade[3] + t.rules.tube_past_blade
        gap = (edge - sign * t.rules.blade_gap / 2, (y_face + y_end) / 2, t.rules.blade_gap / 2, (y_end - y_face) / 2)
        return [gap, shaft] if t.rules.shaft_lane_check else [gap]

    def passes_over(self, lifted: SceneObject, obstacle_height: float) -> bool:
        """Whether the suctioned object, lifted, passes over an obstacle ``obstacle_height`` tall: never for
        ``suction_lift="slight"``; for ``"over-lower"`` when the object lifted ``lift_height`` above the
        obstacle still fits under the shelf's top (clearance to spare)."""
        if self.tool.rules.suction_lift == "slight":
            return False
        t = self.tool
        return obstacle_height + t.geometry.lift_height + lifted.size[2] + t.physics.clearance <= self.shelf.height

    def blade_depth(self, fp: Footprint, sign: int) -> float:
        """How deep the blade goes to push ``fp`` toward ``sign`` x (y of its tip, S): ``CONTACT_INSET`` past the
        object's point at its extreme x on the blade's side (a rectangle's extreme corner, the front one of two
        tied corners; a disc's point level with its centre), so that the blade, ``blade_width`` along y, meets
        the object at that point; and at least ``push_contact_depth`` past the object's front extreme. (A blade
        only 3 cm past the front of a turned box or a disc meets it late or not at all.)"""
        if fp.shape == "cylinder":
            y_contact = fp.y
        else:
            corners = fp.corners()
            reach = -sign * corners[:, 0]  # pushing +x, the blade stands at the object's least x
            y_contact = float(corners[reach >= reach.max() - 1e-9, 1].min())
        return max(fp.y - fp.extents()[1] + self.tool.geometry.push_contact_depth, y_contact + CONTACT_INSET)

    def suction_contact(self, obj: SceneObject):
        """Where the cup seals on the object's camera-facing side (x, y, z), or None when it cannot."""
        t = self.tool
        cup_r = t.geometry.cup_diameter / 2
        h = obj.size[2]
        if h < t.geometry.cup_diameter:
            return None
        z = max(cup_r, h - cup_r - 0.005)
        cx, cy = float(obj.center[0]), float(obj.center[1])
        if obj.shape == "cylinder":
            r = obj.size[0] / 2
            if RULES["min_seal_radius"].refuses(t.rules.min_seal_radius, r):
                return None
            return cx, cy - r, z
        normal, half_w, dist = _front_face(obj)
        if 2 * half_w < t.geometry.cup_diameter:
            return None
        p = np.array([cx, cy]) + normal * dist
        return float(p[0]), float(p[1]), z

    @staticmethod
    def seal_angle_deg(obj: SceneObject) -> float:
        """The angle (deg) between the shelf's y and the normal of the face the cup seals on: 0 for a cylinder
        (sealed where its front faces the tube), at most 45 for a box."""
        return abs(math.degrees(ActionModel.face_yaw(obj)))

    @staticmethod
    def face_yaw(obj: SceneObject) -> float:
        """The tool yaw (rad, about S z) that brings the tube along the inward normal of the face the cup seals
        on: the face's outward normal is (sin yaw, -cos yaw); 0 for a cylinder; in [-pi/4, pi/4] for a box."""
        if obj.shape == "cylinder":
            return 0.0
        normal = _front_face(obj)[0]
        return math.atan2(float(normal[0]), -float(normal[1]))

    def tool_yaw(self, obj: SceneObject, contact_xy) -> float:
        """The tool's yaw (rad) for a suction of ``obj`` at ``contact_xy`` (S): the face's yaw clamped to
        ``max_tool_yaw_deg`` and to the turns whose tube, on its axis from the contact out through the opening,
        passes the side walls' front edges with ``TUBE_CLEARANCE`` to spare (0 when the contact itself is
        that close to a wall)."""
        limit = math.radians(self.tool.rules.max_tool_yaw_deg)
        if limit == 0.0:
            return 0.0
        yaw = min(limit, max(-limit, self.face_yaw(obj)))
        cx, cy = float(contact_xy[0]), float(contact_xy[1])
        depth = cy + self.shelf.depth / 2  # behind the opening
        half_width = self.shelf.width / 2
        reach = self.tool.geometry.tube_diameter / 2 + TUBE_CLEARANCE  # from the axis to an edge, at least
        if depth <= 1e-9 or abs(cx) >= half_width - reach:
            return 0.0
        # The axis leaves along (sin yaw, -cos yaw); its distance from the right wall's edge (half_width, opening)
        # is (half_width - cx) cos yaw - depth sin yaw = R cos(yaw + phi), from the left one's (half_width + cx)
        # cos yaw + depth sin yaw = R' cos(yaw - phi'): each at least ``reach`` bounds the turn.
        right, left = half_width - cx, half_width + cx
        hi = math.acos(reach / math.hypot(right, depth)) - math.atan2(depth, right)
        lo = math.atan2(depth, left) - math.acos(reach / math.hypot(left, depth))
        return min(hi, max(lo, yaw))


def _front_face(obj: SceneObject):
    """(outward normal in the floor plane, half width, distance from the centre) of the box face whose normal
    points most toward the opening (-y)."""
    c, s = math.cos(obj.yaw), math.sin(obj.yaw)
    faces = [
        (np.array([c, s]), obj.size[1] / 2, obj.size[0] / 2),
        (np.array([-c, -s]), obj.size[1] / 2, obj.size[0] / 2),
        (np.array([-s, c]), obj.size[0] / 2, obj.size[1] / 2),
        (np.array([s, -c]), obj.size[0] / 2, obj.size[1] / 2),
    ]
    return min(faces, key=lambda f: f[0][1])


@dataclasses.dataclass(frozen=True)
class DragLimits:
    """What :meth:`ActionModel.drag_limits` finds: ``refusal`` (why the object cannot be dragged, or None), the
    pull the drag needs with the safety factor (N), the highest seal that does not tip it (m above the floor),
    and the seal height a drag uses (m)."""

    refusal: str | None
    pull: float
    tip_z: float
    seal_z: float


@dataclasses.dataclass(frozen=True)
class ObjectGeometry:
    """What the action model derives from one object's pose (:meth:`ActionModel.object_geometry`): its
    footprint, the footprint's id (keys of ``ActionModel._pair``), footprint and shadow masks on the floor
    raster (None when not asked for) and the footprint's axis-aligned box (x_lo, x_hi, y_lo, y_hi; S, m)."""

    fp: Footprint
    id: int
    mask: np.ndarray | None
    shadow: np.ndarray | None
    aabb: tuple[float, float, float, float]


@dataclasses.dataclass(frozen=True)
class SuctionLattice:
    """What the suctions of one object depend on alone (its pose, the shelf and the tool;
    :meth:`ActionModel.suction_lattice`). Shelf frame S, metres; A lattice columns x' = x + a res (``a_all``),
    B depths y' = y + b res (``b_all``), C raster columns of the object's footprint.

    ``refusal``: why a rule on the object alone refuses every suction of it (None: none does; ``refusal_kind`` the
    same as a :class:`RefusalKind`). Else ``q`` the cup's
    contact (x, y, z), ``yaw`` the tool's yaw (rad), ``corridor`` (1, 2) and ``corridor_half`` the tube's way in as a
    turned box, ``path_out`` (n_out, 2) the centres of the way straight out of the shelf, ``cols``, ``first_rows``,
    ``last_rows`` (C,) the footprint's raster columns and their first and last rows, ``cells_per`` raster cells per
    lattice step; ``lattice_empty`` when no placement fits in the shelf. Else also ``xs`` (A,) and ``y_placed`` (B,)
    the placements' x and y, ``steps`` the y of each step of the way in (from outside the shelf to the deepest
    placement), ``shifted_cols`` and ``inside`` (A, C) the footprint's columns at each placement column and whether
    they lie on the raster, ``base`` (A, B) the placements before any test against other objects (not where the
    object stands, not in a column wholly off the raster), ``name`` the object's and ``res`` the lattice step;
    :meth:`action` the :class:`Suction` to a lattice point (made on first use and kept)."""

    refusal: str | None
    refusal_kind: "RefusalKind | None" = None  # the refusal's kind (None when there is none)
    lattice_empty: bool = True
    q: tuple = ()
    yaw: float = 0.0
    corridor: np.ndarray | None = None
    corridor_half: tuple = ()
    path_out: np.ndarray | None = None
    cols: np.ndarray | None = None
    first_rows: np.ndarray | None = None
    last_rows: np.ndarray | None = None
    cells_per: int = 0
    a_all: np.ndarray | None = None
    b_all: np.ndarray | None = None
    xs: np.ndarray | None = None
    y_placed: np.ndarray | None = None
    steps: np.ndarray | None = None
    shifted_cols: np.ndarray | None = None
    inside: np.ndarray | None = None
    base: np.ndarray | None = None
    name: str = ""
    res: float = 0.0
    drag: bool = False
    y_pull: float = 0.0
    _actions: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)
    _release: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)  # _release_reachable's mask
    _hold: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)  # _hold_precompute's verdicts

    @classmethod
    def refused(cls, reason: str, kind: "RefusalKind") -> "SuctionLattice":
        return cls(refusal=reason, refusal_kind=kind)

    def action(self, a_index: int, b_index: int) -> Suction:
        """The suction that places the object at lattice point (a_all[a_index], b_all[b_index])."""
        hit = self._actions.get((a_index, b_index))
        if hit is None:
            a = self.a_all[a_index]
            hit = self._actions[(a_index, b_index)] = Suction(
                self.name, self.q, round(float(a * self.res), 6), round(float(self.y_placed[b_index]), 6),
                round(float(self.yaw), 6), self.drag)
        return hit


class _StateContext:
    """Per-state precomputation: footprints, masks, shadows."""

    def __init__(self, model: ActionModel, objects, fixed):
        self.objects = objects
        self.all_objs = objects + fixed
        geometry = model.object_geometry(objects, fixed=fixed)  # one call: the ids of one table
        self.fps = [g.fp for g in geometry[:len(objects)]]
        self.all_fps = [g.fp for g in geometry]
        self.ids = [g.id for g in geometry]  # keys of ActionModel._pair
        self.all_names = [o.name for o in self.all_objs]
        self.all_heights = [o.size[2] for o in self.all_objs]
        grid = model.grid
        self.masks = [g.mask for g in geometry[:len(objects)]]
        shadows = [g.shadow for g in geometry[:len(objects)]]
        self.shadows = shadows
        self.aabbs = np.array([g.aabb for g in geometry]).reshape(-1, 4)
        self._shape = (grid.ny, grid.nx)
        self._radius_cells = int(math.floor(model.tool.rules.min_hidden_width / 2 / grid.cell + 1e-9))
        # cells under known objects hold no unseen object (only with min_hidden_width > 0, the strict
        # variant keeps the overhead shadows whole)
        self.occupied = _union(self.masks, self._shape) if self.masks and self._radius_cells > 0 else None
        self._hidden_all = None
        self._n = len(self.all_objs)
        self._hidden_others: dict = {}
        self._hidden_others_near: dict = {}

    @property
    def hidden_all(self) -> np.ndarray:
        """The hidden space as all objects make it (computed on first use: only suctions read it)."""
        if self._hidden_all is None:
            self._hidden_all = self._open(erode(_union(self.shadows, self._shape)))
        return self._hidden_all

    def others(self, i):
        return [j for j in range(self._n) if j != i]

    def others_in_band(self, i, axis: int, lo: float, hi: float):
        """Others whose bounding box meets the band lo <= x (axis 0) or y (axis 1) <= hi: the only ones a
        motion confined to that band can touch (an exact pre-filter)."""
        a = self.aabbs
        near = (a[:, 2 * axis + 1] >= lo) & (a[:, 2 * axis] <= hi)
        return [j for j in range(self._n) if j != i and near[j]]

    def _open(self, mask: np.ndarray, r0: int = 0) -> np.ndarray:
        """Hidden space where an unseen object could stand: free of known objects, a disc
        ``min_hidden_width`` wide fits (unchanged when min_hidden_width is 0). ``mask``: the raster's rows from
        ``r0`` on (all of them by default)."""
        if self._radius_cells <= 0:
            return mask
        free = mask & ~self.occupied[r0:r0 + len(mask)] if self.occupied is not None else mask
        return open_with_disc(free, self._radius_cells)

    def hidden_others_near(self, i) -> tuple[int, int, np.ndarray]:
        """(r0, r1, rows r0 .. r1 - 1 of :meth:`hidden_others`), the rows of object i's footprint mask with a
        margin, computed on those rows alone (the pushes read only the rows the object covers). Exact: the
        one-cell erosion and the opening by a disc of r cells see the window's edge only 2 r + 1 rows into it,
        and the margin is 2 r + 2 rows (none at the raster's own edges, which behave as before)."""
        hit = self._hidden_others_near.get(i)
        if hit is None:
            ny = self._shape[0]
            rows = np.flatnonzero(self.masks[i].any(axis=1))
            if len(rows) == 0:
                r0, r1 = 0, ny
            else:
                pad = 2 * self._radius_cells + 2
                r0, r1 = max(0, int(rows[0]) - pad), min(ny, int(rows[-1]) + 1 + pad)
            others = [s[r0:r1] for j, s in enumerate(self.shadows) if j != i]
            hit = self._hidden_others_near[i] = (r0, r1, self._open(erode(_union(others, (r1 - r0, self._shape[1]))), r0))
        return hit

    def hidden_others(self, i) -> np.ndarray:
        """The hidden space as the other objects make it (cached per object: both push directions read it)."""
        hit = self._hidden_others.get(i)
        if hit is None:
            others = [s for j, s in enumerate(self.shadows) if j != i]
            hit = self._hidden_others[i] = self._open(erode(_union(others, self._shape)))
        return hit


def _union(masks, shape) -> np.ndarray:
    """The cells (bool ``shape``) in any of ``masks``."""
    out = np.zeros(shape, dtype=bool)
    for m in masks:
        out |= m
    return out


def _first_false(ok: np.ndarray) -> int:
    """Index of the first False (len(ok) when all are True)."""
    bad = np.flatnonzero(~ok)
    return int(bad[0]) if len(bad) else len(ok)
