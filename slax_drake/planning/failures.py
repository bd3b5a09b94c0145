"""Why the motion planner rejects an action, as typed values.

A :class:`PlanningFailure` is one reason a planning variant failed: its :class:`FailureKind`, the waypoint it
names (by its label, see :class:`slax_drake.planning.waypoints.ToolWaypoint`; for a joint segment, the waypoint the
segment arrives at) and what it met. Decisions rest on these fields, never on the wording of the message:

- :attr:`PlanningFailure.straight_segment`: a straight tool segment could not be kept; another carrying depth or
  approach margin changes the IK solutions the chain takes, so the planner tries its next variant;
- :meth:`PlanningFailure.names_any`: the failure names one of the given waypoints (e.g. the ones in front of the
  opening, which a smaller approach margin moves);
- :attr:`PlanningFailure.early`: it happens before the tool reaches the object, so no action
  of the same group (pushes of the object in that direction, or its suctions) can run from here (``EARLY_WAYPOINTS``,
  and for joint segments ``EARLY_SEGMENTS``).

:attr:`PlanningFailure.message` is the text written to logs and trial files; :func:`joined_message` joins the
failures of one variant (one per first IK solution tried) as the planner reports them.
"""

from __future__ import annotations

import dataclasses
import enum

# The waypoints before the tool reaches the object, and the joint segments arriving at them: a failure there rules
# out the action's whole group. (The segment arriving at the seal already touches the object: not early.)
EARLY_WAYPOINTS = frozenset({"pre-approach", "insert", "approach", "seal"})
EARLY_SEGMENTS = frozenset({"pre-approach", "insert", "approach"})
# The label of the last joint segment (from the action's last waypoint back to the observation pose)
RETURN = "the return to the observation pose"


class FailureKind(enum.Enum):
    """What made a planning variant fail."""

    NO_IK_SOLUTION = "no IK solution"  # the waypoint's tool pose has no IK solution from the guesses
    FIRST_OUT_OF_REACH = "first waypoint out of reach"  # no usable IK solution of the first waypoint from any seed
    EVERY_SOLUTION_COLLIDES = "every solution collides"  # each IK solution of the waypoint collides
    TOOL_COLLIDES = "tool collides"  # the tool itself meets the environment at the waypoint's pose
    LEAVES_STRAIGHT_SEGMENT = "leaves straight segment"  # the tool leaves the Cartesian segment to the waypoint
    STRAIGHT_SEGMENT_OUT_OF_REACH = "straight segment out of reach"  # a point of the segment has no IK solution
    NO_WAY_FROM_START = "no way from start"  # no collision-free way from the start to the first waypoint
    NO_WAY_BACK = "no way back"  # no collision-free way from the last waypoint back to the observation pose
    SEGMENT_COLLIDES = "segment collides"  # a checked joint segment collides
    CARRIED_COLLIDES = "carried object collides"  # the carried object collides on a joint segment
    JOINT_LIMIT = "joint limit"  # the timed trajectory comes within the IK limit margin of a joint's limit
    GUARDED_LIFTED = "guarded push-in lifted"  # a guarded placement's push-in is carried higher than LIFT: it
    # would pass over what it cannot see and lower the object onto it, where the guard (which senses the push) is blind


STRAIGHT_SEGMENT_KINDS = frozenset({FailureKind.LEAVES_STRAIGHT_SEGMENT, FailureKind.STRAIGHT_SEGMENT_OUT_OF_REACH})


@dataclasses.dataclass(frozen=True)
class PlanningFailure:
    """One reason a planning variant failed.

    ``waypoint``: the label of the waypoint it names ("" for :attr:`FailureKind.NO_WAY_BACK` and
    :attr:`FailureKind.JOINT_LIMIT`; for joint segments the waypoint the segment arrives at, or :data:`RETURN`).
    ``hits``: what it met (colliding pairs or bodies, the carried object's obstacles; "X (environment)" for a tool that meets the
    environment with no colliding pair named; for :attr:`FailureKind.JOINT_LIMIT` the joint).
    ``carried``: the carried object's name (:attr:`FailureKind.CARRIED_COLLIDES`). ``deviation``: how far the tool
    leaves its segment (m; for :attr:`FailureKind.GUARDED_LIFTED` the carried object's height above the floor). ``margin``: the joint-limit margin (rad or m). ``seeds``: the number of IK seeds tried
    (:attr:`FailureKind.FIRST_OUT_OF_REACH`); ``collides``: whether those seeds' solutions all collided rather than
    none existing. ``tool``: whether a body rigid with the tool is among what collided
    (:attr:`FailureKind.SEGMENT_COLLIDES`; the planner's near-miss variant reads it).
    """

    kind: FailureKind
    waypoint: str = ""
    hits: str = ""
    carried: str = ""
    deviation: float = 0.0
    margin: float = 0.0
    seeds: int = 0
    collides: bool = False
    tool: bool = False

    @property
    def segment(self) -> bool:
        """Whether it names a joint segment (arriving at ``waypoint``) rather than the waypoint itself."""
        return self.kind in (FailureKind.SEGMENT_COLLIDES, FailureKind.CARRIED_COLLIDES)

    @property
    def straight_segment(self) -> bool:
        """A straight tool segment could not be kept (the IK solutions at its ends lie on different branches)."""
        return self.kind in STRAIGHT_SEGMENT_KINDS

    @property
    def early(self) -> bool:
        """It happens before the tool reaches the object: no action of the same group can run from here."""
        return self.waypoint in (EARLY_SEGMENTS if self.segment else EARLY_WAYPOINTS)

    def names_any(self, waypoints) -> bool:
        """Whether it names one of ``waypoints`` (labels; a joint segment names the waypoint it arrives at)."""
        return self.waypoint in waypoints

    @property
    def message(self) -> str:
        """The failure in words, as logs and trial files record it."""
        k, w = self.kind, self.waypoint
        if k is FailureKind.NO_IK_SOLUTION:
            return f"{w}: tool pose out of reach (no IK solution)"
        if k is FailureKind.FIRST_OUT_OF_REACH:
            what = "every solution collides" if self.collides else "no IK solution"
            return f"{w}: tool pose out of reach ({what}; {self.seeds} seeds)"
        if k is FailureKind.EVERY_SOLUTION_COLLIDES:
            return f"{w}: every IK solution collides: {self.hits}"
        if k is FailureKind.TOOL_COLLIDES:
            return f"{w}: the tool collides at its pose: {self.hits}"
        if k is FailureKind.LEAVES_STRAIGHT_SEGMENT:
            return f"{w}: the tool leaves its straight segment by {self.deviation * 1000:.1f} mm"
        if k is FailureKind.STRAIGHT_SEGMENT_OUT_OF_REACH:
            return f"{w}: a point of the straight segment is out of reach"
        if k is FailureKind.NO_WAY_FROM_START:
            return f"{w}: no collision-free way from the start"
        if k is FailureKind.NO_WAY_BACK:
            return "no collision-free way back to the observation pose"
        if k is FailureKind.SEGMENT_COLLIDES:
            return f"segment to {w} collides" + (f": {self.hits}" if self.hits else "")
        if k is FailureKind.CARRIED_COLLIDES:
            return f"segment to {w}: the carried {self.carried} collides with {self.hits}"
        if k is FailureKind.JOINT_LIMIT:
            return f"{self.hits} comes within {self.margin} of its position limit"
        if k is FailureKind.GUARDED_LIFTED:
            return (f"{w}: a guarded push-in carried {self.deviation * 100:.1f} cm above the floor would lower the object "
                    "onto what it cannot see")
        raise AssertionError(k)


def distinct(failures) -> tuple:
    """The failures whose messages differ, in order (the first of each message)."""
    seen, out = set(), []
    for f in failures:
        if f.message not in seen:
            seen.add(f.message)
            out.append(f)
    return tuple(out)


def joined_message(failures) -> str:
    """The message of one variant's failures (one per first IK solution tried): the distinct ones, "; "-joined."""
    return "; ".join(f.message for f in distinct(failures))


def lead_last(variants: list) -> list:
    """The failed variants of one action, ``[(where, [PlanningFailure, ...]), ...]`` in the order tried, reordered so
    that the one to report leads at the end: the last variant, unless one got past the approach (its first failure
    not :attr:`PlanningFailure.early`), then the last such one. A group-wide (early) failure must hold for every
    variant: when one variant reached the object, the approach is not what rules the action out, and the other
    actions of its group (the object's other placements, say) may still run."""
    late = [i for i, (_, failures) in enumerate(variants) if not failures[0].early]
    lead = late[-1] if late else len(variants) - 1
    return variants[:lead] + variants[lead + 1:] + [variants[lead]]
