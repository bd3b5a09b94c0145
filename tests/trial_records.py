"""Hand-made trial records for the hardware tests (no test here): Ruckig-timed motions around the observation pose.

``fake_trial()`` returns a dict shaped like trial.json (``executed_trajectory`` every 10 ms, ``actions`` with
``motion.duration_s`` and ``suction_intervals``, ``steps_log`` decision times, config, objects and seed), built
from the planner's Ruckig timing (the test data only: the checker under test never calls it).
"""

from __future__ import annotations

import numpy as np

from slax_drake.planning.timing import time_waypoints
from slax_drake.planning.trajectory import JointTrajectory
from slax_drake.station.plant import station_joint_limits
from slax_drake.station.robot import PLANNED_JOINTS
from slax_drake.station.scenario import DEFAULT_STATION, load_station_scenario, observation_positions

# The arm swung right (pan at its limit) and folded back at the elbow: the forearm, wrist and tool lie inside the
# torso column (models/fetch_bluction.urdf's torso_lift_link: column + shoulder mount) by 35 to 127 mm. (The pose
# the planner once reached in 'slax-drake trial --objects 2 --seed 7', inside the former whole-bounding-box torso,
# is in front of the refined column.)
FOLDED_INTO_TORSO = [0.192, 1.6, -0.5961, -1.4248, -2.25, -2.5026, 1.0495, -0.8012, 0.0]


def q_observation() -> np.ndarray:
    return observation_positions(load_station_scenario("sim_configs/station_sim_shelf.yaml"))


def fake_trial(objects: int = 2, seed: int = 3) -> dict:
    lim = station_joint_limits(load_station_scenario(DEFAULT_STATION))
    q0 = q_observation()
    q0[PLANNED_JOINTS.index("torso_lift_joint")] = 0.0107  # the suction motion dips 7 mm: 3.7 mm above the limit
    delta = np.array([0.01, 0.05, -0.04, 0.05, 0.06, -0.05, 0.04, 0.1, 0.3])
    motions = [
        ("push", time_waypoints(PLANNED_JOINTS, [q0, q0 + delta, q0], lim.velocity,
                                lim.acceleration, lim.jerk), []),
        ("suction", time_waypoints(PLANNED_JOINTS, [q0, q0 - 0.7 * delta, q0], lim.velocity, lim.acceleration, lim.jerk),
         None),
    ]
    traj = JointTrajectory.hold(PLANNED_JOINTS, q0, 0.5)
    actions, steps_log = [], []
    for k, (kind, m, suction) in enumerate(motions):
        t_start = float(traj.times[-1])
        duration = m.duration
        if suction is None:
            suction = [[round(0.3 * duration, 3), round(0.7 * duration, 3)]]
        traj = traj.then(m)
        traj = traj.then(JointTrajectory.hold(PLANNED_JOINTS, traj.q[-1], 0.6))
        action = {"type": kind, "object": "object_0", "q": [0, 0], "motion": {"duration_s": round(duration, 3),
                                                                               "suction_intervals": suction}}
        action.update({"d": 0.05} if kind == "push" else {"dx": 0.0, "dz": -0.1})
        actions.append(action)
        steps_log.append({"step": k, "time": round(t_start, 4), "action": action, "lost": [], "poses_before": None})
    return {"config": "sim_configs/sim_shelf.yaml", "station": "sim_configs/station_sim_shelf.yaml",
            "objects": objects, "seed": seed, "policy": "test", "actions": actions, "steps_log": steps_log,
            "initial_objects": None, "final_objects": None, "executed_trajectory": traj.to_dict(stride=10),
            "full_trajectory": traj}
