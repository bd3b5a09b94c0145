"""What a distribution policy remembers of its own trial: the arrangements it has observed and the action it last
proposed, so that it can tell an action that failed from one that went as predicted.

The paper's DAR and Bluction-DAR (Sec. V-C) keep only the history encoding P'_t. An implementation needs more,
because the first-order model can be wrong about the true shelf (an unseen object stops a push; a placement is put
back): without a memory, the greedy choice repeats an action that changed nothing, or undoes the last action and
redoes it, until the horizon. :class:`TrialMemory` holds the two facts the corrections use:

- the arrangements observed so far (the seen objects' planar poses), compared within ``position_tolerance`` (m)
  and ``yaw_tolerance`` (rad), by name and, when the names differ (camera-mode hypotheses are renamed per frame),
  by matching shapes and poses; an object seen in one arrangement and hidden in the other does not count (the
  objects seen in both decide), and neither does a remembered one (``SceneObject.remembered``: hidden now, held
  where it was last estimated, an estimate that moves when a glimpse of the object updates it although nothing
  moved the object: a Table II trial in Drake cycled one object through the same four poses for 14 actions while
  a remembered neighbour's estimate, 6.8 cm off, made each return look new). On estimated poses (``estimated``,
  camera mode) only the objects the robot acted on since the earlier arrangement was observed decide, and the one
  the candidate moves: an object no action touched stands where it stood, and its estimate moves with what hides
  it (a neighbour's partly seen box, 1.2 cm off, let another Drake trial return to an arrangement). An object
  pushed along by an action on its neighbour is not seen as moved then;
- the last proposed action, the objects it was chosen on and the pose the action model predicts for its object.
  :meth:`outcome` compares that prediction with the next observation: "moved nothing" (the object stands where
  it stood), "moved less than predicted" (it moved, but stands more than ``position_tolerance`` short of or away
  from the predicted pose; or, for a move predicted shorter than twice the tolerance, such as a 1 cm push, it moved
  less than ``SMALL_MOVE_SHARE`` of it along its direction), or None (as predicted, or the object is no longer seen and
  nothing can be said);
- per object, the planar displacement (m) of the last executed action on it (as observed; as commanded when the
  object is hidden after it), so that :meth:`undoes` can tell a candidate that moves the object back (a shuttle).
  With ``by_axis`` each axis keeps the last move along it: a move along y alone (a suction pulling the object
  forward) leaves the last move along x in place, so that moving the object back along x after it is still a
  move back (x +0.35, then y -0.10, then x -0.35 is a cycle too).

Names are the observation's: true names in privileged mode, the tracker's stable names in camera mode
(:mod:`slax_drake.perception.tracking`), so an object keeps its name across frames.

All positions are in the shelf frame S (x right, y into the shelf; metres).
"""

from __future__ import annotations

import dataclasses
import enum
import math

import numpy as np

from slax_drake.scene.model import box_yaw_difference
from slax_drake.shelf.actions import apply_action


# A move predicted shorter than twice the position tolerance failed when the object moved less than this share of
# it along the predicted direction (TrialMemory._small_move_outcome)
SMALL_MOVE_SHARE = 0.5


class Miss(enum.Enum):
    """How an executed action failed to move its object as predicted."""

    UNCHANGED = "unchanged"  # the observation did not change: the action moved nothing
    SHORT = "short"  # the object moved less than predicted
    ELSEWHERE = "elsewhere"  # the object moved, but stands away from the predicted pose


@dataclasses.dataclass(frozen=True)
class Failed:
    """An executed action that did not move its object as predicted: ``miss``, and (for ``SHORT`` and
    ``ELSEWHERE``) how far it moved (``moved``, m), how far it was predicted to move (``predicted``, m) and how far
    it stands from the predicted pose (``off``, m)."""

    miss: Miss
    moved: float = 0.0
    predicted: float = 0.0
    off: float = 0.0

    @property
    def message(self) -> str:
        """The failure in words, as trial logs record it."""
        if self.miss is Miss.UNCHANGED:
            return "the observation did not change: the action moved nothing"
        if self.miss is Miss.SHORT:
            return f"moved its object {self.moved:.3f} m where {self.predicted:.3f} m was predicted"
        return f"its object stands {self.off:.3f} m from the predicted pose"


@dataclasses.dataclass(frozen=True)
class Proposal:
    """The action a policy proposed last, the objects it decided on, and its object's predicted pose (x, y)."""

    action: object
    before: tuple
    predicted_xy: tuple[float, float]
    before_xy: tuple[float, float]


class TrialMemory:
    """See the module docstring. ``reset`` at the start of a trial; ``observe(objects)`` once per observation;
    ``propose(action, objects)`` when a decision names its best candidate; ``withdraw()`` when that candidate is
    excluded before execution."""

    def __init__(self, position_tolerance: float = 0.01, yaw_tolerance: float = 0.05, by_axis: bool = False):
        self.position_tolerance = position_tolerance
        self.yaw_tolerance = yaw_tolerance
        self.by_axis = by_axis  # each axis keeps the last move along it (module docstring)
        self.estimated = False  # set by a policy deciding on estimated poses (camera mode): module docstring
        self.reset()

    def reset(self) -> None:
        self.observed: list[tuple] = []
        self.executed: list[str] = []  # the objects of the executed actions, in order
        self.observed_after: list[int] = []  # per observed arrangement: how many actions were executed before it
        self.proposal: Proposal | None = None
        self.moves: dict[str, tuple[float, float]] = {}  # object name -> its last executed displacement (m)

    def record_move(self, name: str, d: tuple[float, float]) -> None:
        """``d`` (m, along x and y of S) is the last executed move of object ``name``; with ``by_axis`` only along
        the axes it moves over ``position_tolerance``, the last move along the other axis kept."""
        d = (float(d[0]), float(d[1]))
        last = self.moves.get(name)
        if self.by_axis and last is not None:
            d = last_move_by_axis(last, d, self.position_tolerance)
        self.moves[name] = d

    def undoes(self, objects, action) -> bool:
        """Whether ``action`` on ``objects`` moves its object back against the last executed action on it (with
        ``by_axis``, the last along each axis): along x or along y, both that move and this one's commanded
        displacement exceed ``position_tolerance`` (m) and point opposite ways (e.g. dx -0.05 then +0.10, whatever
        either did along y)."""
        last = self.moves.get(action.name)
        if last is None:
            return False
        obj = next((o for o in objects if o.name == action.name), None)
        if obj is None:
            return False
        moved = apply_action((obj,), action)[0]
        now = (float(moved.center[0] - obj.center[0]), float(moved.center[1] - obj.center[1]))
        tol = self.position_tolerance
        return any(abs(a) > tol and abs(b) > tol and a * b < 0 for a, b in zip(last, now))

    def vacates_unseen(self, objects, action) -> float:
        """The width (m) of the space ``action`` on ``objects`` uncovers along x that its object covered in every
        arrangement observed so far (where it was seen): space behind it no earlier arrangement showed. Judged on
        the footprints' x extents (the camera looks along y)."""
        obj = next((o for o in objects if o.name == action.name), None)
        if obj is None:
            return 0.0
        moved = apply_action((obj,), action)[0]
        now, new = _x_extent(obj), _x_extent(moved)
        always = now
        for seen in self.observed:
            other = next((o for o in seen if o.name == action.name), None)
            if other is None:
                continue
            lo, hi = _x_extent(other)
            always = (max(always[0], lo), min(always[1], hi))
        if always[1] <= always[0]:
            return 0.0
        # the part of ``always`` that the object leaves: ``always`` minus the new extent
        left = max(0.0, min(always[1], new[0]) - always[0])
        right = max(0.0, always[1] - max(always[0], new[1]))
        return left + right

    def after_plan(self, objects, plan) -> "TrialMemory":
        """A new memory holding what this one would after ``plan`` (actions) executed from ``objects`` exactly as
        the action model predicts: each arrangement along it observed, each action's displacement its object's last
        move. For a search that looks at what the corrections would leave at a plan's end; this one is unchanged."""
        out = TrialMemory(self.position_tolerance, self.yaw_tolerance, self.by_axis)
        out.estimated = self.estimated
        out.observed, out.moves = list(self.observed), dict(self.moves)
        out.executed, out.observed_after = list(self.executed), list(self.observed_after)
        state = tuple(objects)
        for a in plan:
            before = next((o for o in state if o.name == a.name), None)
            state = apply_action(state, a)
            if before is not None:
                after = next(o for o in state if o.name == a.name)
                d = (float(after.center[0] - before.center[0]), float(after.center[1] - before.center[1]))
                if math.hypot(*d) > self.position_tolerance:
                    out.record_move(a.name, d)
            out.executed.append(a.name)
            out.observe(state)
        return out

    # ---- arrangements -------------------------------------------------------------------------------------------
    def observe(self, objects) -> None:
        """Adds ``objects`` to the observed arrangements, each one as observed: an arrangement within the tolerances
        of the last one is kept too (only an identical one is not), so that tolerances do not chain. Were it
        dropped as "the same", an object moved by just under ``position_tolerance`` (a 1 cm push) would be
        remembered at its earlier pose only, and a later move back to where it stands now, 1.005 cm from that pose,
        would pass the no-return correction."""
        objects = seen_objects(objects)
        if not self.observed or not _identical(objects, self.observed[-1]):
            self.observed.append(objects)
            self.observed_after.append(len(self.executed))

    def acted_since(self, j: int) -> set | None:
        """On estimated poses, the names of the objects acted on since observed arrangement ``j`` (the only ones,
        with the candidate's object, that decide whether an arrangement returns to it); None on true poses (every
        object decides)."""
        if not self.estimated:
            return None
        return set(self.executed[self.observed_after[j]:])

    def seen_before(self, objects, moved: str | None = None) -> bool:
        """Whether ``objects`` (an arrangement an action on object ``moved`` would lead to) equals one already
        observed."""
        objects = tuple(objects)
        for j, seen in enumerate(self.observed):
            acted = self.acted_since(j)
            if acted is not None and moved is not None:
                acted.add(moved)
            if self.same_arrangement(objects, seen, acted):
                return True
        return False

    def leads_back(self, objects, actions) -> list[bool]:
        """Per action, whether it leads back to an observed arrangement: ``seen_before(apply_action(objects, a))``
        for each of ``actions``, without building every arrangement. An action moves one object and keeps the
        names, so against an observed arrangement that shares names with ``objects``, the unmoved objects' match
        is worked out once and only the moved object is compared per action; otherwise (no shared name, repeated
        names) the arrangement is built and compared whole."""
        objects = seen_objects(objects)
        names = [o.name for o in objects]
        out = [False] * len(actions)
        if len(set(names)) != len(names):
            return [self.seen_before(apply_action(objects, a), a.name) for a in actions]
        index = {name: k for k, name in enumerate(names)}
        moved: dict = {}  # action index -> the moved object, made once

        def moved_object(k):
            if k not in moved:
                a = actions[k]
                moved[k] = apply_action((objects[index[a.name]],), a)[0] if a.name in index else None
            return moved[k]

        for j, seen in enumerate(self.observed):
            seen = seen_objects(seen)
            pending = [k for k, found in enumerate(out) if not found]
            if not pending:
                break
            acted = self.acted_since(j)
            by_name = {o.name: o for o in seen}
            shared = [name for name in names if name in by_name]
            if not objects or not seen or not shared or len(by_name) != len(seen):
                for k in pending:  # the general comparison (it does not depend on the names matching)
                    out[k] = self.same_arrangement(apply_action(objects, actions[k]), seen,
                                                   None if acted is None else acted | {actions[k].name})
                continue
            ours_small = len(objects) <= len(seen)  # same_arrangement compares the smaller one's objects first
            if ours_small:
                differ = {n for n in shared if not self._close(objects[index[n]], by_name[n])}
            else:
                mine = {o.name: o for o in objects}
                differ = {o.name for o in seen if o.name in mine and not self._close(o, mine[o.name])}
            if acted is not None:  # estimated poses: an object no action touched since does not decide
                differ &= acted
            for k in pending:
                name = actions[k].name
                if name not in index:  # an action on none of the objects leaves them as they are
                    out[k] = self.same_arrangement(objects, seen, acted)
                    continue
                if differ - {name}:
                    continue  # an object the action leaves in place stands elsewhere there
                if name not in by_name:
                    out[k] = True  # the moved object is not in the observed arrangement: the others all match
                    continue
                after = moved_object(k)
                out[k] = self._close(after, by_name[name]) if ours_small else self._close(by_name[name], after)
        return out

    def _close(self, a, b) -> bool:
        if a.shape != b.shape:
            return False
        dx = float(a.center[0] - b.center[0])
        dy = float(a.center[1] - b.center[1])
        if math.hypot(dx, dy) > self.position_tolerance:
            return False
        if a.shape == "cylinder":
            return True
        return same_box_turn(a, b, self.yaw_tolerance)

    def same_arrangement(self, a: tuple, b: tuple, only: set | None = None) -> bool:
        """Whether ``a`` and ``b`` show the same shelf. When they share names: every object seen in both stands in
        both at the same pose (an object seen in only one of them is hidden in the other, and a hidden object is
        never acted on, so it has not moved); with ``only``, every such object named in it (the others are taken to
        stand where they stood: :meth:`acted_since`). Otherwise (camera-mode hypotheses may be renamed per frame): the
        smaller arrangement's objects each stand where one of the other's stands, by shape and pose, one-to-one.
        Two empty arrangements are the same; an empty one and another are not. Remembered objects do not count
        (:func:`seen_objects`)."""
        a, b = seen_objects(a), seen_objects(b)
        if len(a) > len(b):
            a, b = b, a
        if not a:
            return not b
        by_name = {o.name: o for o in b}
        common = [o for o in a if o.name in by_name]
        if common:
            return all(self._close(o, by_name[o.name]) for o in common if only is None or o.name in only)
        free = list(b)
        for o in a:
            match = next((k for k, other in enumerate(free) if self._close(o, other)), None)
            if match is None:
                return False
            free.pop(match)
        return True

    # ---- the last action's outcome ------------------------------------------------------------------------------
    def propose(self, action, objects) -> None:
        objects = tuple(objects)
        obj = next((o for o in objects if o.name == action.name), None)
        if obj is None:
            self.proposal = None
            return
        moved = next(o for o in apply_action(objects, action) if o.name == action.name)
        self.proposal = Proposal(action, objects, (float(moved.center[0]), float(moved.center[1])),
                                 (float(obj.center[0]), float(obj.center[1])))

    def withdraw(self, action) -> None:
        if self.proposal is not None and self.proposal.action == action:
            self.proposal = None

    def outcome(self, objects) -> tuple[Proposal, Failed] | None:
        """(the proposal, how it failed) when the observation ``objects`` shows that the last proposed action did
        not move its object as predicted; None otherwise. Forgets the proposal either way."""
        p, self.proposal = self.proposal, None
        if p is None:
            return None
        self.executed.append(p.action.name)
        tol = self.position_tolerance
        predicted = math.dist(p.predicted_xy, p.before_xy)
        now = next((o for o in objects if o.name == p.action.name), None)
        if now is None:
            self.record_move(p.action.name, (p.predicted_xy[0] - p.before_xy[0], p.predicted_xy[1] - p.before_xy[1]))
        else:
            d = (float(now.center[0]) - p.before_xy[0], float(now.center[1]) - p.before_xy[1])
            if math.hypot(*d) > tol:
                self.record_move(p.action.name, d)
        if predicted <= tol:  # a move the tolerance cannot tell apart: judged along its own direction
            return self._small_move_outcome(p, now, predicted)
        if now is None and self.same_arrangement(tuple(objects), p.before):
            return p, Failed(Miss.UNCHANGED)
        if now is None:
            return None
        xy = (float(now.center[0]), float(now.center[1]))
        if math.dist(xy, p.predicted_xy) <= tol:  # as predicted, unless a move under twice the tolerance fell short
            return self._small_move_outcome(p, now, predicted)
        if math.dist(xy, p.before_xy) <= tol:
            return p, Failed(Miss.UNCHANGED)
        moved, off = math.dist(xy, p.before_xy), math.dist(xy, p.predicted_xy)
        return p, Failed(Miss.SHORT if moved < predicted else Miss.ELSEWHERE, moved, predicted, off)

    @staticmethod
    def _small_move_outcome(p: Proposal, now, predicted: float) -> tuple[Proposal, Failed] | None:
        """The outcome of a proposal whose object stands within ``position_tolerance`` of where it stood or of
        where it was predicted: failed ("moved less than predicted") when the object, seen now, moved less than
        ``SMALL_MOVE_SHARE`` of the predicted distance along the predicted direction. That can happen only to a
        move predicted shorter than twice the tolerance (a push of 1 cm, which an object that did not move at all
        stands within the tolerance of); judged by the tolerance alone such pushes could never fail, and a push
        blocked by a wall or a neighbour was repeated: a Drake trial (Table II 12:1) pushed one box 1 cm 13 times,
        0.6 mm each time. An object seen in both frames and moved by the robot has an estimate steady to a
        millimetre or so (untouched objects between decisions of Drake trials: median 0, 90th percentile 0.6 mm),
        so half of a 1 cm move is told apart."""
        if now is None or now.remembered or predicted <= 0.0:
            return None
        px, py = p.predicted_xy[0] - p.before_xy[0], p.predicted_xy[1] - p.before_xy[1]  # the predicted move
        dx, dy = float(now.center[0]) - p.before_xy[0], float(now.center[1]) - p.before_xy[1]  # the observed one
        if dx * px + dy * py >= SMALL_MOVE_SHARE * predicted * predicted:  # along the predicted direction, x predicted
            return None
        return p, Failed(Miss.SHORT, math.hypot(dx, dy), predicted, math.hypot(px - dx, py - dy))


def same_box_turn(a, b, tolerance: float) -> bool:
    """Whether boxes ``a`` and ``b`` stand turned alike, within ``tolerance`` (rad): a box turned by pi stands the
    same, and so does one described with its x and y sizes swapped and turned a quarter more (the estimator names a
    box either way from frame to frame: a Drake trial's 0.13 x 0.07 m box read yaw 0.01 and, two frames later, 1.56
    with its sizes swapped, and a return onto an observed pose looked turned)."""
    if abs(box_yaw_difference(a.yaw, b.yaw)) <= tolerance:
        return True
    (ax, ay), (bx, by) = a.size[:2], b.size[:2]
    if abs(ax - by) + abs(ay - bx) > abs(ax - bx) + abs(ay - by):
        return False  # the sizes match as they stand: a quarter turn is another footprint
    return abs(box_yaw_difference(a.yaw, b.yaw + math.pi / 2)) <= tolerance


def seen_objects(objects) -> tuple:
    """``objects`` less the remembered ones (hidden now, held where they were last estimated): what an arrangement
    is compared by."""
    return tuple(o for o in objects if not o.remembered)


def _identical(a: tuple, b: tuple) -> bool:
    """Whether two arrangements hold the same objects (names and shapes) at exactly the same poses."""
    return len(a) == len(b) and all(p.name == q.name and p.shape == q.shape and np.array_equal(p.X_SO, q.X_SO)
                                    for p, q in zip(a, b))


def last_move_by_axis(last: tuple[float, float], move: tuple[float, float], tolerance: float) -> tuple:
    """An object's last move along each axis of S (m) after ``move``: ``move``'s component where it exceeds
    ``tolerance``, else ``last``'s (a move along y alone keeps the last move along x)."""
    return tuple(now if abs(now) > tolerance else before for before, now in zip(last, move))


def _x_extent(o) -> tuple[float, float]:
    """(x_min, x_max) of ``o``'s footprint in S (m)."""
    from slax_drake.scene.footprint import Footprint

    fp = Footprint.of(o)
    ex, _ = fp.extents()
    return fp.x - ex, fp.x + ex
