"""Typed planning failures: each kind's message is the text trial files record, and the planner's decisions (try
the next variant, exclude the action's whole group) follow the kind and the waypoint, not the wording."""

import pytest

from slax_drake.planning.failures import RETURN, FailureKind, PlanningFailure, distinct, joined_message
from slax_drake.planning.planner import MARGIN_DEPENDENT, MARGIN_DEPENDENT_KINDS, PULL_DEPENDENT, _may_differ
from slax_drake.policies.trial_memory import Failed, Miss

K = FailureKind

MESSAGES = [
    (PlanningFailure(K.NO_IK_SOLUTION, "lift"), "lift: tool pose out of reach (no IK solution)"),
    (PlanningFailure(K.FIRST_OUT_OF_REACH, "pre-approach", seeds=16),
     "pre-approach: tool pose out of reach (no IK solution; 16 seeds)"),
    (PlanningFailure(K.FIRST_OUT_OF_REACH, "pre-approach", seeds=16, collides=True),
     "pre-approach: tool pose out of reach (every solution collides; 16 seeds)"),
    (PlanningFailure(K.EVERY_SOLUTION_COLLIDES, "seal", hits="shelf::top, object_2"),
     "seal: every IK solution collides: shelf::top, object_2"),
    (PlanningFailure(K.TOOL_COLLIDES, "insert", hits="wrist_roll_link (environment)"),
     "insert: the tool collides at its pose: wrist_roll_link (environment)"),
    (PlanningFailure(K.TOOL_COLLIDES, "insert", hits="tool_shaft_link with shelf::top"),
     "insert: the tool collides at its pose: tool_shaft_link with shelf::top"),
    (PlanningFailure(K.LEAVES_STRAIGHT_SEGMENT, "approach", deviation=0.04234),
     "approach: the tool leaves its straight segment by 42.3 mm"),
    (PlanningFailure(K.STRAIGHT_SEGMENT_OUT_OF_REACH, "insert"), "insert: a point of the straight segment is out of reach"),
    (PlanningFailure(K.NO_WAY_FROM_START, "pre-approach"), "pre-approach: no collision-free way from the start"),
    (PlanningFailure(K.NO_WAY_BACK), "no collision-free way back to the observation pose"),
    (PlanningFailure(K.SEGMENT_COLLIDES, "retract"), "segment to retract collides"),
    (PlanningFailure(K.SEGMENT_COLLIDES, "retract", hits="upperarm_roll_link with object_2"),
     "segment to retract collides: upperarm_roll_link with object_2"),
    (PlanningFailure(K.SEGMENT_COLLIDES, RETURN), "segment to the return to the observation pose collides"),
    (PlanningFailure(K.CARRIED_COLLIDES, "pull out", hits="object_3, the shelf", carried="object_1"),
     "segment to pull out: the carried object_1 collides with object_3, the shelf"),
    (PlanningFailure(K.JOINT_LIMIT, hits="wrist_flex_joint", margin=0.02),
     "wrist_flex_joint comes within 0.02 of its position limit"),
    (PlanningFailure(K.GUARDED_LIFTED, "push in", deviation=0.18),
     "push in: a guarded push-in carried 18.0 cm above the floor would lower the object onto what it cannot see"),
]


@pytest.mark.parametrize("failure, message", MESSAGES)
def test_the_message_is_made_from_the_kind(failure, message):
    assert failure.message == message


def test_every_kind_has_a_message():
    assert {f.kind for f, _ in MESSAGES} == set(FailureKind)


def test_one_variants_failures_are_joined_once_each():
    a, b = PlanningFailure(K.SEGMENT_COLLIDES, "lift"), PlanningFailure(K.NO_WAY_BACK)
    assert distinct((a, b, a)) == (a, b)
    assert joined_message((a, b, a)) == "segment to lift collides; no collision-free way back to the observation pose"
    assert joined_message((a,)) == a.message


# (failure, early: the whole group is excluded, margin-dependent, pull-dependent)
DECISIONS = [
    (PlanningFailure(K.FIRST_OUT_OF_REACH, "pre-approach", seeds=16), True, True, False),
    (PlanningFailure(K.NO_WAY_FROM_START, "pre-approach"), True, True, False),
    (PlanningFailure(K.SEGMENT_COLLIDES, "pre-approach"), True, True, False),
    (PlanningFailure(K.TOOL_COLLIDES, "insert", hits="gripper_link"), True, False, False),
    (PlanningFailure(K.SEGMENT_COLLIDES, "insert"), True, False, False),
    (PlanningFailure(K.NO_IK_SOLUTION, "approach"), True, False, False),
    (PlanningFailure(K.EVERY_SOLUTION_COLLIDES, "seal", hits="object_2"), True, False, False),
    # the segment arriving at the seal already touches the object: not the whole group
    (PlanningFailure(K.SEGMENT_COLLIDES, "seal"), False, False, False),
    (PlanningFailure(K.NO_IK_SOLUTION, "push"), False, False, False),
    (PlanningFailure(K.CARRIED_COLLIDES, "translate", hits="object_3", carried="object_1"), False, False, True),
    (PlanningFailure(K.NO_IK_SOLUTION, "lift"), False, False, True),
    (PlanningFailure(K.SEGMENT_COLLIDES, "lower"), False, False, True),
    (PlanningFailure(K.EVERY_SOLUTION_COLLIDES, "retract", hits="shelf"), False, True, False),
    (PlanningFailure(K.SEGMENT_COLLIDES, "retract"), False, True, False),
    (PlanningFailure(K.NO_WAY_BACK), False, True, False),
    (PlanningFailure(K.SEGMENT_COLLIDES, RETURN), False, False, False),
    (PlanningFailure(K.JOINT_LIMIT, hits="torso_lift_joint", margin=0.02), False, False, False),
    (PlanningFailure(K.GUARDED_LIFTED, "push in", deviation=0.18), False, False, True),
]


@pytest.mark.parametrize("failure, early, margin, pull", DECISIONS)
def test_each_kind_decides_retry_and_group_exclusion(failure, early, margin, pull):
    assert failure.early is early
    assert _may_differ((failure,), MARGIN_DEPENDENT, MARGIN_DEPENDENT_KINDS) is margin
    assert _may_differ((failure,), PULL_DEPENDENT) is pull


@pytest.mark.parametrize("kind", [K.LEAVES_STRAIGHT_SEGMENT, K.STRAIGHT_SEGMENT_OUT_OF_REACH])
def test_a_straight_segment_failure_of_any_first_solution_lets_the_next_variant_be_tried(kind):
    lead = PlanningFailure(K.SEGMENT_COLLIDES, "push")
    assert not _may_differ((lead,), MARGIN_DEPENDENT, MARGIN_DEPENDENT_KINDS)
    straight = PlanningFailure(kind, "push")
    assert straight.straight_segment and not lead.straight_segment
    assert _may_differ((lead, straight), MARGIN_DEPENDENT, MARGIN_DEPENDENT_KINDS)
    assert _may_differ((lead, straight), PULL_DEPENDENT)


def test_only_the_first_solutions_failure_names_the_waypoint():
    first, second = PlanningFailure(K.SEGMENT_COLLIDES, "push"), PlanningFailure(K.SEGMENT_COLLIDES, "retract")
    assert not _may_differ((first, second), MARGIN_DEPENDENT, MARGIN_DEPENDENT_KINDS)
    assert _may_differ((second, first), MARGIN_DEPENDENT, MARGIN_DEPENDENT_KINDS)


@pytest.mark.parametrize("failed, message", [
    (Failed(Miss.UNCHANGED), "the observation did not change: the action moved nothing"),
    (Failed(Miss.SHORT, moved=0.04, predicted=0.1, off=0.06), "moved its object 0.040 m where 0.100 m was predicted"),
    (Failed(Miss.ELSEWHERE, moved=0.1, predicted=0.1, off=0.031), "its object stands 0.031 m from the predicted pose"),
])
def test_an_executed_actions_miss_is_typed_and_its_message_made_from_it(failed, message):
    assert failed.message == message


def test_a_variant_that_reached_the_object_leads_so_the_group_is_not_ruled_out():
    """A suction whose first carry variants failed at the translate and whose last failed at the approach (a
    replayed 6-object scene, seed 0 of Table I): the approach is not what rules it out, so the reported failure is
    the last late one and the policy excludes this action only, not the object's other placements."""
    from slax_drake.planning.failures import lead_last

    translate = [PlanningFailure(FailureKind.NO_IK_SOLUTION, "translate")]
    lower = [PlanningFailure(FailureKind.NO_IK_SOLUTION, "lower")]
    approach = [PlanningFailure(FailureKind.SEGMENT_COLLIDES, "approach", hits="a with b")]
    ordered = lead_last([("y = -0.48", translate), ("y = -0.36", lower), ("turned", approach)])
    assert ordered[-1] == ("y = -0.36", lower) and not ordered[-1][1][0].early
    assert [w for w, _ in ordered] == ["y = -0.48", "turned", "y = -0.36"]
    # every variant failed before the tool reached the object: the last one leads and the whole group goes
    only_early = lead_last([("m 5 cm", approach), ("m 2 cm", [PlanningFailure(FailureKind.NO_IK_SOLUTION, "insert")])])
    assert only_early[-1][0] == "m 2 cm" and only_early[-1][1][0].early
