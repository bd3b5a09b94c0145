"""The way back to the observation pose clears the moved object where the action leaves it, not where it stood.

The case: Table I household scene 10:7 at its fourth decision (the camera's hypotheses, S, m). slax-belief carries
track_7 (a 0.16 m tall box) 5 cm left and 5 cm toward the opening; the way back planned around the box where it
had stood swept through it where it stood now and knocked it off the shelf in the Drake trial (replayed with
`slax-drake trial --from-benchmark docs/results/physics_belief_household_8f5e6b4 --benchmark-scene 10:7`)."""

import numpy as np
import pytest

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of

pytestmark = pytest.mark.slow  # plans a motion

HYPOTHESES = {
    "track_2": ("box", (0.0793, 0.1555, 0.1916), -0.15229, -0.13753, 0.91106),
    "track_8": ("box", (0.06, 0.1605, 0.1037), -0.09967, 0.04934, 0.0),
    "track_3": ("box", (0.1418, 0.188, 0.1829), 0.17882, -0.17798, 1.53938),
    "track_4": ("cylinder", (0.1313, 0.1313, 0.1866), 0.08273, 0.21138, 0.0),
    "track_5": ("box", (0.0973, 0.0758, 0.1538), -0.23254, -0.23916, 0.28274),
    "track_7": ("box", (0.0773, 0.1241, 0.1563), 0.01444, -0.19904, 1.4207),
}


def test_the_way_back_clears_the_carried_object_where_it_was_placed(monkeypatch):
    from slax_drake.config import load_scenario
    from slax_drake.planning import planner as planner_module
    from slax_drake.shelf.actions import Suction
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.scenario import load_station_scenario, station_for
    from slax_drake.systems.trial import station_tool_rules

    config = "sim_configs/table1_household.yaml"
    scenario = load_scenario(config)
    station = load_station_scenario(station_for(config))
    tool = tool_config(scenario, "station", **station_tool_rules(station))
    believed = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), tuple(
        SceneObject(name, shape, size, planar_pose(x, y, size[2] / 2, yaw))
        for name, (shape, size, x, y, yaw) in HYPOTHESES.items()), None, 0)
    action = Suction("track_7", (0.00866, -0.23727, 0.13625), -0.05, -0.249045, -0.150098)
    obj, X_placed = planner_module.placed_pose(action, believed)
    assert obj.name == "track_7" and np.allclose(X_placed[:3, 3], [0.01444 - 0.05, -0.249045, 0.1563 / 2])

    def way_back_clear(motion, world):
        """Whether every segment after the retract is free with track_7 where the action left it."""
        t_retract = dict(motion.waypoint_times)["retract"]
        traj = motion.trajectory
        k = int(np.argmin(np.abs(traj.times - t_retract)))
        world.place(obj, X_placed)
        try:
            return all(world.edge_free(a, b) for a, b in zip(traj.q[k:-1:5], traj.q[k + 5::5]))
        finally:
            world.unplace()

    planner = planner_module.MotionPlanner(station, tool)
    motion = planner.plan(action, believed)
    assert motion.feasible, motion.reason
    assert way_back_clear(motion, planner.world(believed))
    # planned with the box where it stood (the code before), the way back meets it where it stands now
    monkeypatch.setattr(planner_module, "placed_pose", lambda action, scene: None)
    before = planner_module.MotionPlanner(station, tool)
    old = before.plan(action, believed)
    assert old.feasible, old.reason
    assert not way_back_clear(old, before.world(believed))
