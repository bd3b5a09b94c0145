"""A Table I suction planned on the sim-shelf station and the checks every planned carry must pass, for the slow
planner tests (not library code)."""

from __future__ import annotations


def plan_table1_suction(objects: int, index: int, name: str, dx: float):
    """(checker, action, motion): the suction of object ``name`` by ``dx`` (m) that the station's action model offers
    on the initial state of Table I scene ``index`` at ``objects`` objects (the protocol's scene seeds), planned."""
    from slax_drake.config import load_scenario
    from slax_drake.evaluation.table1 import scene_seed
    from slax_drake.hardware.check_action import make_checker
    from slax_drake.scene.sampling import sample_scene

    scenario = load_scenario("sim_configs/table1.yaml")
    scene = sample_scene(scenario, objects, scene_seed(scenario.protocol.seed, objects, index),
                         target_size=tuple(scenario.target.sizes[0]))
    checker = make_checker(scene, "sim_configs/station_sim_shelf.yaml")
    action = next(a for a in checker.candidates().feasible
                  if a.name == name and a.kind == "suction" and abs(a.dx - dx) < 1e-9)
    return checker, action, checker.planner.plan(action, checker.scene)


def assert_motion_checks(checker, action, motion):
    """The motion is feasible, its trajectory passes the hardware checker (1 cm margin), every 10th configuration is
    collision free against the other objects, and the tool kept its straight segments within 5 mm; returns the
    planning world of the other objects it was checked in."""
    from slax_drake.hardware.check import check_trajectory
    from slax_drake.hardware.trajectory_file import ExportedTrajectory, Motion
    from slax_drake.planning.world import PlanningWorld

    assert motion.feasible, motion.reason
    traj = motion.trajectory
    report = check_trajectory(ExportedTrajectory([Motion(start_time=0.0, times=traj.times, q=traj.q, v=traj.v,
                                                         a=traj.a)]), margin=0.01)
    assert report.ok, report.summary()
    others = checker.scene.with_objects(tuple(o for o in checker.scene.objects if o.name != action.name))
    world = PlanningWorld(checker.planner.scenario, others)
    assert all(world.checker.CheckConfigsCollisionFree([world.full_q(q) for q in traj.q[::10]]))
    assert motion.max_deviation < 0.005
    return world
