"""What a distribution policy remembers of its own trial: the arrangements it has observed and the action it last
proposed, so that it can tell an action that failed from one that went as predicted (issue 19 item 3).

The paper's DAR and Bluction-DAR (Sec. V-C) keep only the history encoding P'_t. An implementation needs more,
because the first-order model can be wrong about the true shelf (an unseen object stops a push; a placement is put
back): without a memory, the greedy choice repeats an action that changed nothing, or undoes the last action and
redoes it, until the horizon. :class:`TrialMemory` holds the two facts the corrections use:

- the arrangements observed so far (the seen objects' planar poses), compared within ``position_tolerance`` (m)
  and ``yaw_tolerance`` (rad), by name and, when the names differ (camera-mode hypotheses are renamed per frame),
  by matching shapes and poses; an object seen in one arrangement and hidden in the other does not count (the
  objects seen in both decide);
- the last proposed action, the objects it was chosen on and the pose the action model predicts for its object.
  :meth:`outcome` compares that prediction with the next observation: "moved nothing" (the object stands where
  it stood), "moved less than predicted" (it moved, but stands more than ``position_tolerance`` short of or away
  from the predicted pose), or None (as predicted, or the object is no longer seen and nothing can be said).

All positions are in the shelf frame S (x right, y into the shelf; metres).
"""

from __future__ import annotations

import dataclasses
import math

from slax_drake.policies.actions import apply_action


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

    def __init__(self, position_tolerance: float = 0.01, yaw_tolerance: float = 0.05):
        self.position_tolerance = position_tolerance
        self.yaw_tolerance = yaw_tolerance
        self.reset()

    def reset(self) -> None:
        self.observed: list[tuple] = []
        self.proposal: Proposal | None = None

    # ---- arrangements -------------------------------------------------------------------------------------------
    def observe(self, objects) -> None:
        objects = tuple(objects)
        if not any(self.same_arrangement(objects, seen) for seen in self.observed[-1:]):
            self.observed.append(objects)

    def seen_before(self, objects) -> bool:
        """Whether ``objects`` (an arrangement an action would lead to) equals one already observed."""
        return any(self.same_arrangement(tuple(objects), seen) for seen in self.observed)

    def _close(self, a, b) -> bool:
        if a.shape != b.shape:
            return False
        dx = float(a.center[0] - b.center[0])
        dy = float(a.center[1] - b.center[1])
        if math.hypot(dx, dy) > self.position_tolerance:
            return False
        if a.shape == "cylinder":
            return True
        dyaw = (float(a.yaw) - float(b.yaw) + math.pi / 2) % math.pi - math.pi / 2  # a box turned by pi is the same
        return abs(dyaw) <= self.yaw_tolerance

    def same_arrangement(self, a: tuple, b: tuple) -> bool:
        """Whether ``a`` and ``b`` show the same shelf. When they share names: every object seen in both stands in
        both at the same pose (an object seen in only one of them is hidden in the other, and a hidden object is
        never acted on, so it has not moved). Otherwise (camera-mode hypotheses may be renamed per frame): the
        smaller arrangement's objects each stand where one of the other's stands, by shape and pose, one-to-one.
        Two empty arrangements are the same; an empty one and another are not."""
        if len(a) > len(b):
            a, b = b, a
        if not a:
            return not b
        by_name = {o.name: o for o in b}
        common = [o for o in a if o.name in by_name]
        if common:
            return all(self._close(o, by_name[o.name]) for o in common)
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

    def outcome(self, objects) -> tuple[Proposal, str] | None:
        """(the proposal, why it failed) when the observation ``objects`` shows that the last proposed action did
        not move its object as predicted; None otherwise. Forgets the proposal either way."""
        p, self.proposal = self.proposal, None
        if p is None:
            return None
        tol = self.position_tolerance
        predicted = math.dist(p.predicted_xy, p.before_xy)
        if predicted <= tol:
            return None  # too small a move to tell from the observation
        now = next((o for o in objects if o.name == p.action.name), None)
        if now is None and self.same_arrangement(tuple(objects), p.before):
            return p, "the observation did not change: the action moved nothing"
        if now is None:
            return None
        xy = (float(now.center[0]), float(now.center[1]))
        if math.dist(xy, p.predicted_xy) <= tol:
            return None
        if math.dist(xy, p.before_xy) <= tol:
            return p, "the observation did not change: the action moved nothing"
        return p, (f"moved its object {math.dist(xy, p.before_xy):.3f} m where {predicted:.3f} m was predicted"
                   if math.dist(xy, p.before_xy) < predicted else
                   f"its object stands {math.dist(xy, p.predicted_xy):.3f} m from the predicted pose")
