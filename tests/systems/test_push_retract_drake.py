"""A push's retract in the Drake station leaves a light tall cylinder where the push put it. Pushed at its foot, a
thin cylinder leans onto the tool and moves less than d; a back-off of the push's gap alone left the tube touching it,
and the retract along S -y dragged it ~3 cm toward the opening (Table I household 8:8 and 10:13 at ba55d14, where
the next push knocked it off the board). The back-off now returns the tool toward the lane it came in by
(:func:`slax_drake.planning.waypoints.push_back_slack`)."""

import pytest

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("d", [+0.05, -0.05])
def test_a_pushed_tall_cylinder_is_not_dragged_toward_the_opening(d):
    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene, SceneObject, planar_pose
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.shelf.actions import ActionModel, Push
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.motion_run import run_motion
    from slax_drake.systems.trial import station_tool_rules

    scenario = load_scenario("sim_configs/table1_household.yaml")
    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    rules = {k: v for k, v in station_tool_rules(station).items() if k != "reach_map"}
    tool = tool_config(scenario, "station", **rules)
    y = -0.237  # its front 3.6 cm behind the opening (S y = -0.30)
    cylinder = SceneObject("object_0", "cylinder", (0.0626, 0.0626, 0.1785), planar_pose(0.0, y, 0.1785 / 2, 0.0),
                           mass=0.509)  # 10:13's object_8
    scene = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), (cylinder,), None, 0)
    push = next(a for a in ActionModel(scene.shelf, scene.camera.position, tool).enumerate(
        (cylinder,), suctions=False).feasible if isinstance(a, Push) and abs(a.d - d) < 1e-9)
    motion = MotionPlanner(station, tool).plan(push, scene)
    assert motion.feasible, motion.reason
    end = run_motion(station, scene, motion, cylinder.name, times=[])["end"]
    assert abs(end["y"] - y) < 0.01  # dragged 3.0 (d = +0.05) and 3.6 cm (-0.05) toward the opening before
    assert end["tilt_deg"] < 5.0
    assert 0.02 < (end["x"] - 0.0) * (1 if d > 0 else -1) < 0.07  # it was pushed (3.2 and 3.7 cm measured)
