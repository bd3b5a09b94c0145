"""The planner's variants (approach margins, carrying depths) are tried on after a straight-segment failure:
a Table I suction whose first carrying depths fail and whose last one failed on the approach's straight segment
(the reason that used to end the search) is planned, and its trajectory passes the hardware checker's limits and
the planning world's collision check."""

import pytest

from slax_drake.planning.planner import STRAIGHT_SEGMENT_FAILURES, _may_differ


def test_straight_segment_failures_let_the_next_variant_be_tried():
    assert _may_differ("approach: the tool leaves its straight segment by 42.3 mm", ("pull out",))
    assert _may_differ("insert: a point of the straight segment is out of reach", ("pre-approach",))
    assert _may_differ("pull out: tool pose out of reach (no IK solution)", ("pull out",))
    assert not _may_differ("insert: the tool collides at its pose: wrist_roll_link (environment)", ("pre-approach",))
    assert len(STRAIGHT_SEGMENT_FAILURES) == 2


@pytest.mark.slow
def test_a_suction_that_failed_on_its_approach_segment_is_planned_and_checks():
    from table1_suction_plans import assert_motion_checks, plan_table1_suction

    assert_motion_checks(*plan_table1_suction(10, 1, "object_4", -0.3))
