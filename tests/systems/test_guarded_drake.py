"""The guarded placement in the Drake station: a carried box pushed into hidden space stops on an object the robot
cannot see, sensed from the joint efforts alone, without toppling it; with nothing there it completes (the stop
logic on synthetic efforts: tests/systems/test_guard.py)."""

import pytest

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of

pytestmark = pytest.mark.slow


def _box(name, x, y, size, mass):
    return SceneObject(name, "box", size, planar_pose(x, y, size[2] / 2, 0.0), mass=mass)


@pytest.fixture(scope="module")
def planned(sim_scenario):
    """A 0.3 kg box at the front right suctioned straight back to y = +0.25 m, a guarded placement (the space behind
    it is hidden), planned in the believed scene (a wide box at the front left and the carried box)."""
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.shelf.actions import ActionModel
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.trial import station_tool_rules

    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    rules = {k: v for k, v in station_tool_rules(station).items() if k != "reach_map"}
    tool = tool_config(sim_scenario, "station", **{**rules, "suction_hidden_rule": "guarded"})
    wall = _box("object_0", -0.12, -0.15, (0.30, 0.06, 0.30), 0.3)
    carried = _box("object_1", 0.20, -0.10, (0.08, 0.08, 0.10), 0.3)
    believed = Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (wall, carried), None, 0)
    model = ActionModel(believed.shelf, believed.camera.position, tool)
    action = next(a for a in model.enumerate(believed.objects, pushes=False, only=("object_1",)).feasible
                  if a.guarded and a.grip == "lift" and abs(a.dx) < 1e-9 and abs(a.dz - 0.25) < 1e-9)
    planner = MotionPlanner(station, tool)
    motion = planner.plan(action, believed)
    assert motion.feasible, motion.reason
    return station, planner, believed, motion


def test_a_guarded_placement_stops_on_a_hidden_box_without_toppling_it(planned):
    from slax_drake.systems.motion_run import run_guarded_motion

    station, planner, believed, motion = planned
    hidden = _box("object_2", 0.20, 0.255, (0.08, 0.08, 0.10), 0.5)  # behind the carried box, at the back wall
    scene = Scene(believed.shelf, believed.camera, believed.objects + (hidden,), None, 0)
    poses, record = run_guarded_motion(station, scene, believed, motion, planner, ["object_1", "object_2"])
    assert record["stopped"] and record["peak_force_n"] > station.guarded_stop_force
    assert record["short_m"] > 0.05  # it met the hidden box 7 cm before the placement
    for name in ("object_1", "object_2"):
        assert poses[name]["tilt_deg"] < 20.0, name
    moved = ((poses["object_2"]["x"] - 0.20) ** 2 + (poses["object_2"]["y"] - 0.255) ** 2) ** 0.5
    assert moved < 0.02
    assert poses["object_1"]["y"] < 0.25 - 0.05  # the carried box rests where it stopped, short of d_z


def test_a_guarded_placement_with_nothing_in_the_way_completes(planned):
    from slax_drake.systems.motion_run import run_guarded_motion

    station, planner, believed, motion = planned
    poses, record = run_guarded_motion(station, believed, believed, motion, planner, ["object_1"])
    assert not record["stopped"] and record["peak_force_n"] < station.guarded_stop_force
    end = poses["object_1"]
    assert abs(end["y"] - motion.action.dz) < 0.01 and abs(end["x"] - 0.20) < 0.01
    assert end["tilt_deg"] < 20.0
