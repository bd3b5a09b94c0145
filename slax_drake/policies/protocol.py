"""The one interface every search policy implements, the oracles included: :class:`Policy`.

A trial drives a policy the same way in the fast shelf simulator (:func:`slax_drake.shelf.simulator.run_trial`)
and in the Drake planner system (:class:`slax_drake.systems.planner.PlannerSystem`):

1. ``reset(scene_or_observation)`` once at the start of a trial: the policy forgets everything of the last trial
   (its history, its plan, its exclusions).
2. Per step, ``decide(observation) -> Decision``: the candidate actions ranked best first, or none and a stop
   reason. ``observation`` is what the policy reads: an :class:`~slax_drake.shelf.simulator.PolicyObservation` for
   the distribution policies, the true :class:`~slax_drake.scene.model.Scene` for the policies that declare
   ``needs_true_scene`` (the oracles, which cannot run on a robot). ``decide`` is called once per step
   (a policy may keep a plan across steps), and again on the same observation after ``exclude``.
3. When the planner cannot execute the best candidate, ``exclude(action, reason)``, then ``decide`` again on the
   same observation: the policy re-ranks without it. An excluded action is never proposed again in this trial;
   with ``whole_group=True`` (the tool could not even reach the object) no action of its group (pushes of that
   object in that direction, or suctions of that object) is proposed again while that object stands where it
   stood. ``exclusions`` lists them with their reasons.

The action model (tool, discretisation, rules) is given at construction (``action_model``, read-only); nothing
else is swapped in while a policy decides. A new policy is one class implementing this protocol and one line in
the table of :mod:`slax_drake.policies.registry`.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from typing import Protocol, runtime_checkable

import numpy as np

from slax_drake.scene.model import box_yaw_difference
from slax_drake.shelf.actions import Push


class Screened(enum.StrEnum):
    """Why a policy screens out a candidate the action model finds feasible (``screen`` of the corrected
    policies, counted per kind in the record of a decision that found no action). A ``StrEnum``: it compares equal
    to its text and is written as its text in JSON records."""

    EXCLUDED = "excluded"  # an exclusion of this trial: the planner rejected it or its group, or it failed
    BACK = "back to an observed arrangement"  # correction 2
    SHUTTLE = "shuttle"  # correction 3: it reverses its object's last move and uncovers no new width
    PLACEMENT_NOT_ALLOWED = "placement not allowed"  # slax-hindsight/-belief: its placement overlaps a blocked box


class StopReason(enum.StrEnum):
    """A policy's stop reason that a trial acts on (``Decision.stop_reason``); a ``StrEnum``: it compares equal to
    its text and is written as its text in records."""

    NO_REVEALING_PLAN = "no plan reveals the target"  # slax-belief's stuck_select "stop": no plan reveals anything


NO_REVEALING_PLAN = StopReason.NO_REVEALING_PLAN  # the Drake trial ends with it as its result


class Reversal(enum.StrEnum):
    """How correction 3 judged an executed action that moves its object back against its last move (the trial
    record's ``reversal_rule``; None when it is not such a move)."""

    UNCOVERS_NEW_WIDTH = "uncovers new width"  # it passed the correction: it reveals space never seen
    LET_THROUGH = "let through"  # screened out as a shuttle and taken all the same (a last resort or an exception)
    CORRECTION_OFF = "correction off"  # a move back of a policy whose no-shuttle correction is off (shuttle_reveal None)


@dataclasses.dataclass(frozen=True)
class Decision:
    """A policy's answer for one step: ``candidates`` ranked best first (``Push``/``Suction``), and when there is
    none, ``stop_reason`` (e.g. "no feasible action", "search budget")."""

    candidates: tuple = ()
    stop_reason: str | None = None

    @property
    def best(self):
        """The best candidate, or None when the policy stops."""
        return self.candidates[0] if self.candidates else None

    @classmethod
    def stop(cls, reason: str) -> "Decision":
        return cls((), reason)


@runtime_checkable
class Policy(Protocol):
    """See the module docstring. Attributes: ``name`` (the registry name), ``needs_true_scene`` (True: ``decide``
    takes the true Scene; False: a PolicyObservation), ``action_model`` (the ActionModel it enumerates with),
    ``distribution`` (the model of the 1D distribution P_t its observations carry; None when it reads the true
    scene), ``observation_width`` (px of the coarse observation it reads)."""

    name: str
    needs_true_scene: bool

    def reset(self, scene_or_observation) -> None: ...

    def decide(self, observation) -> Decision: ...

    def exclude(self, action, reason: str, whole_group: bool = False) -> None: ...

    @property
    def history(self): ...

    @property
    def exclusions(self) -> tuple: ...


def action_group(action) -> tuple:
    """The group an early planning failure excludes: the pushes of one object in one direction, or the suctions of
    one object."""
    if isinstance(action, Push):
        return ("push", action.name, action.d > 0)
    return ("suction", action.name)


def suction_lane(action) -> tuple | None:
    """The suctions of one object to one x (the same ``dx``, any placement depth ``dz``) for ``action``, a suction;
    None for a push. A suction that leaves its object where it stood failed before its placement depth mattered:
    its way out was blocked, its object did not fit between the walls at that x, or the way in at that x was
    blocked before the object was inside the bay (put back); every suction of that object to that x fails alike
    while it and its neighbours stand where they stood (the exclusion holds while the object stands there: a
    neighbour moved since may have cleared the lane)."""
    if isinstance(action, Push):
        return None
    return ("suction lane", action.name, round(float(action.dx), 6), bool(getattr(action, "drag", False)))


def _pose_keys(objects) -> dict:
    """Per object name in ``objects``, its planar pose as :func:`~slax_drake.scene.model.state_key` rounds it."""
    from slax_drake.scene.model import state_key

    return {k[0]: k for k in state_key(tuple(objects))}


def _pose_key(name: str, objects) -> tuple | None:
    """Object ``name``'s planar pose in ``objects`` (:func:`_pose_keys`), None when it is not among them."""
    return _pose_keys(objects).get(name)


class Exclusions:
    """The candidates a planner could not execute during one trial, with their reasons (what ``exclude`` records).

    Single actions are excluded for the rest of the trial (an action names its absolute contact point, so it is
    specific to where its object stood); a group (see :func:`action_group`) is excluded while its object stands at
    the pose it had when the group was excluded (``objects``: the objects the policy last decided on).

    A suction's lane (:func:`suction_lane`: the same object and dx, any dz) is excluded the same way as a group,
    while its object stands where it stood (``lane=True`` in :meth:`add`).

    ``tolerant`` (set by a policy deciding on a camera frame): estimated poses differ from frame to frame by the
    estimate's noise, and so do the contact points and placements the actions name, so exact comparison never
    matches again (a push blocked at once was repeated to the horizon). Then an action is also excluded when an
    excluded one names the same object, kind and displacement (a push's d; a suction's dx, and its placement dz
    within ``position_tolerance``) while its object stands within ``position_tolerance`` (m) and
    ``yaw_tolerance`` (rad) of where it stood then, and a group or lane while its object stands so near its pose
    then."""

    def __init__(self, position_tolerance: float = 0.01, yaw_tolerance: float = 0.05):
        self._records: list[tuple] = []
        self._actions: set = set()
        self._groups: set = set()  # (action_group or suction_lane key, the object's pose then)
        self._near: list[tuple] = []  # (action, its excluded group keys, the object's pose then): tolerant comparison
        self.tolerant = False
        self.position_tolerance = position_tolerance
        self.yaw_tolerance = yaw_tolerance

    def add(self, action, reason: str, whole_group: bool, objects, lane: bool = False) -> None:
        """Excludes ``action`` (``objects``: the state it was decided on); with ``whole_group`` its group
        (:func:`action_group`), with ``lane`` (a suction) its lane (:func:`suction_lane`), while its object stands
        where it stands in ``objects``."""
        self._records.append((action, reason))
        self._actions.add(action)
        pose = _pose_key(action.name, objects)
        keys = tuple(k for k in ((action_group(action) if whole_group else None),
                                 (suction_lane(action) if lane else None)) if k is not None)
        self._groups.update((k, pose) for k in keys)
        if pose is not None:
            self._near.append((action, keys, pose))

    def allowed(self, actions, objects) -> list:
        """``actions`` less the excluded ones (``objects``: the state they were enumerated in)."""
        if not self._actions:
            return list(actions)
        keep = [a for a in actions if a not in self._actions]
        poses = _pose_keys(objects)  # per object name, computed once for every candidate
        if self._groups:
            keep = [a for a in keep if (action_group(a), poses.get(a.name)) not in self._groups
                    and (suction_lane(a), poses.get(a.name)) not in self._groups]
        if self.tolerant and self._near:
            keep = [a for a in keep if not self._near_excluded(a, poses.get(a.name))]
        return keep

    def _near_excluded(self, action, pose: tuple | None) -> bool:
        """Whether ``action``, its object standing at ``pose`` (:func:`_pose_key`), is excluded within the
        tolerances."""
        if pose is None:
            return False
        own = (action_group(action), suction_lane(action))  # the groups it belongs to
        for excluded, keys, then in self._near:
            if excluded.name != action.name or not self._same_place(pose, then):
                continue
            if own[0] in keys or own[1] in keys:
                return True
            if _same_move(excluded, action, self.position_tolerance):
                return True
        return False

    def _same_place(self, a: tuple, b: tuple) -> bool:
        """Two poses (name, x, y, yaw) of :func:`_pose_key` within the tolerances (a box turned by pi is the same)."""
        if math.hypot(a[1] - b[1], a[2] - b[2]) > self.position_tolerance:
            return False
        return abs(box_yaw_difference(a[3], b[3])) <= self.yaw_tolerance

    @property
    def records(self) -> tuple:
        return tuple(self._records)

    def __len__(self) -> int:
        return len(self._records)


def _same_move(a, b, tolerance: float) -> bool:
    """Whether actions ``a`` and ``b`` (of one object) move it alike: pushes by the same d; suctions by the same
    dx to placements dz within ``tolerance`` (m)."""
    if isinstance(a, Push) or isinstance(b, Push):
        return isinstance(a, Push) and isinstance(b, Push) and abs(a.d - b.d) < 1e-9
    return abs(a.dx - b.dx) < 1e-9 and abs(a.dz - b.dz) <= tolerance


def read_only(array):
    """A read-only view of ``array`` (None stays None): what the ``history`` property hands out."""
    if array is None:
        return None
    view = np.asarray(array).view()
    view.flags.writeable = False
    return view
