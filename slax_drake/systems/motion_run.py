"""One planned motion executed open loop in the Drake station, for tests and benchmarks of single actions.

:func:`run_motion` builds the station with the scene's objects (no camera), feeds the motion's joint trajectory
(``desired_state``) and suction schedule (``suction_command``) from t = 0, starting at the observation pose, and
returns the manipulated object's pose in the shelf frame S at the requested times and at the end (the motion's
end plus ``settle`` seconds).
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem


class MotionSource(LeafSystem):
    """``desired_state`` (q, v of the planned joints) and ``suction_command`` of a PlannedMotion, by time."""

    def __init__(self, motion):
        LeafSystem.__init__(self)
        self.motion = motion
        n = len(motion.trajectory.names)
        self.DeclareVectorOutputPort("desired_state", BasicVector(2 * n), self._state)
        self.DeclareVectorOutputPort("suction_command", BasicVector(1), self._suction)

    def _state(self, context, out):
        q, v = self.motion.trajectory.value(context.get_time())
        out.SetFromVector(np.concatenate([q, v]))

    def _suction(self, context, out):
        out.SetAtIndex(0, 1.0 if self.motion.suction_at(context.get_time()) else 0.0)


def run_motion(station_scenario, scene, motion, name: str, times=(), settle: float = 1.0) -> dict:
    """{time or "end": {"x", "y", "z", "yaw", "tilt_deg"}} of object ``name`` (S; m, rad, deg from upright) while
    ``motion`` runs in the station on ``scene``."""
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder

    from slax_drake.station.plant import shelf_pose
    from slax_drake.systems.station import MakeStation

    builder = DiagramBuilder()
    station = builder.AddSystem(MakeStation(station_scenario, scene, camera=False))
    source = builder.AddSystem(MotionSource(motion))
    builder.Connect(source.GetOutputPort("desired_state"), station.GetInputPort("desired_state"))
    builder.Connect(source.GetOutputPort("suction_command"), station.GetInputPort("suction_command"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    plant = station.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    X_SW = shelf_pose(station_scenario, scene.camera).inverse()
    body = plant.GetBodyByName(name)

    def pose():
        X = (X_SW @ plant.EvalBodyPoseInWorld(plant_context, body)).GetAsMatrix4()
        return {"x": float(X[0, 3]), "y": float(X[1, 3]), "z": float(X[2, 3]), "yaw": math.atan2(X[1, 0], X[0, 0]),
                "tilt_deg": math.degrees(math.acos(min(1.0, abs(float(X[2, 2])))))}

    out = {}
    for t in sorted(times):
        simulator.AdvanceTo(t)
        out[t] = pose()
    simulator.AdvanceTo(motion.trajectory.duration + settle)
    out["end"] = pose()
    return out
