"""The planner's variants (approach margins, carrying depths) are tried on after a straight-segment failure:
a Table I suction whose first carrying depths fail and whose last one failed on the approach's straight segment
(the reason that used to end the search) is planned, and its trajectory passes the hardware checker's limits and
the planning world's collision check."""

import pytest

from slax_drake.planning.failures import FailureKind, PlanningFailure
from slax_drake.planning.planner import _may_differ


def test_straight_segment_failures_let_the_next_variant_be_tried():
    K = FailureKind
    assert _may_differ((PlanningFailure(K.LEAVES_STRAIGHT_SEGMENT, "approach", deviation=0.0423),), {"pull out"})
    assert _may_differ((PlanningFailure(K.STRAIGHT_SEGMENT_OUT_OF_REACH, "insert"),), {"pre-approach"})
    assert _may_differ((PlanningFailure(K.NO_IK_SOLUTION, "pull out"),), {"pull out"})
    assert not _may_differ((PlanningFailure(K.TOOL_COLLIDES, "insert", hits="wrist_roll_link"),), {"pre-approach"})


@pytest.mark.slow
def test_a_suction_that_failed_on_its_approach_segment_is_planned_and_checks():
    from table1_suction_plans import assert_motion_checks, plan_table1_suction

    assert_motion_checks(*plan_table1_suction(10, 1, "object_4", -0.3))
