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
    from slax_drake.config import load_scenario
    from slax_drake.evaluation.table1 import scene_seed
    from slax_drake.hardware.check import check_trajectory
    from slax_drake.hardware.check_action import make_checker
    from slax_drake.hardware.trajectory_file import ExportedTrajectory, Motion
    from slax_drake.planning.world import PlanningWorld
    from slax_drake.scene.sampling import sample_scene

    scenario = load_scenario("sim_configs/table1.yaml")
    scene = sample_scene(scenario, 10, scene_seed(scenario.protocol.seed, 10, 1),
                         target_size=tuple(scenario.target.sizes[0]))
    checker = make_checker(scene, "sim_configs/station_sim_shelf.yaml")
    action = next(a for a in checker.candidates().feasible
                  if a.name == "object_4" and a.kind == "suction" and abs(a.dx + 0.3) < 1e-9)
    motion = checker.planner.plan(action, checker.scene)
    assert motion.feasible, motion.reason
    traj = motion.trajectory
    report = check_trajectory(ExportedTrajectory([Motion(start_time=0.0, times=traj.times, q=traj.q, v=traj.v,
                                                         a=traj.a)]), margin=0.01)
    assert report.ok, report.summary()
    others = checker.scene.with_objects(tuple(o for o in checker.scene.objects if o.name != action.name))
    world = PlanningWorld(checker.planner.scenario, others)
    assert all(world.checker.CheckConfigsCollisionFree([world.full_q(q) for q in traj.q[::10]]))
    assert motion.max_deviation < 0.005
