"""Replay an exported trajectory open loop in the Drake station (what the hardware would be commanded to do).

:class:`ReplaySource` is a LeafSystem with the station's two command ports: ``desired_state`` (18: q and v of the
nine joints) and ``suction_command`` (1). Its timeline is the trial's: the initial positions held until the
first motion starts, each motion at its ``start_time`` (quintic Hermite interpolation of its points' positions,
velocities and accelerations: exact at the points), the last point of a motion held until the next one starts,
and the suction on while start + on <= t < start + off (the trial's own rule). :func:`replay` builds the station
with the scene's objects (no camera: it does not act on the physics), starts the robot at the initial positions,
simulates to the trajectory's end time and returns the final object poses (shelf frame S) and the commanded and
measured joint positions.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from slax_drake.hardware.interpolation import quintic_hermite
from slax_drake.hardware.trajectory_file import ExportedTrajectory


class ReplaySource(LeafSystem):
    """Commands of an exported trajectory as a function of time (module docstring)."""

    def __init__(self, traj: ExportedTrajectory):
        LeafSystem.__init__(self)
        self.traj = traj
        self.motions = traj.motions
        n = len(traj.joint_names)
        initial = traj.metadata.get("initial_positions")
        self.q_initial = np.asarray(initial, float) if initial is not None else (
            self.motions[0].q[0].copy() if self.motions else np.zeros(n))
        self._starts = np.array([m.start_time for m in self.motions])
        self.DeclareVectorOutputPort("desired_state", BasicVector(2 * n), self._calc_desired)
        self.DeclareVectorOutputPort("suction_command", BasicVector(1), self._calc_suction)

    def command(self, t: float) -> tuple[np.ndarray, np.ndarray, bool]:
        """(q, v, suction on) commanded at time t (s, trial clock)."""
        k = int(np.searchsorted(self._starts, t, side="right")) - 1
        n = len(self.q_initial)
        if k < 0:
            return self.q_initial.copy(), np.zeros(n), False
        m = self.motions[k]
        s = t - m.start_time
        if s >= m.duration:
            return m.q[-1].copy(), np.zeros(n), False
        q, v, _ = quintic_hermite(m.times, m.q, m.v, m.a, [s])
        on = False
        state = False
        for te, e_on in m.suction_events:  # events in time order: on at te <= s, off at te <= s
            if te <= s:
                state = e_on
        on = state
        return q[0], v[0], on

    def _calc_desired(self, context, output):
        q, v, _ = self.command(context.get_time())
        output.SetFromVector(np.concatenate([q, v]))

    def _calc_suction(self, context, output):
        output.SetAtIndex(0, 1.0 if self.command(context.get_time())[2] else 0.0)


@dataclasses.dataclass
class ReplayResult:
    final_objects: dict  # name -> {x, y, z, yaw, upright} in S (m, rad)
    sim_time: float
    wall_s: float
    times: np.ndarray  # s, the plant's steps logged (every ``log_period``)
    commanded: np.ndarray  # (N, 9)
    measured: np.ndarray  # (N, 9)
    html: str | None = None


def replay(traj: ExportedTrajectory, station, scene, meshcat=None, log_period: float = 0.01,
           end_time: float | None = None, progress: bool | None = False) -> ReplayResult:
    """Plays ``traj`` in ``MakeStation(station, scene)`` from t = 0 to ``end_time`` (default: the trajectory's).
    ``progress``: a progress bar of the simulated seconds on stderr (None: when stderr is a terminal)."""
    import time

    from pydrake.math import RigidTransform
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder
    from pydrake.systems.primitives import VectorLogSink

    from slax_drake.station import robot as robot_model
    from slax_drake.station.plant import shelf_pose
    from slax_drake.systems.station import MakeStation

    builder = DiagramBuilder()
    station_diagram = builder.AddNamedSystem("station", MakeStation(station, scene, meshcat=meshcat, camera=False))
    source = builder.AddNamedSystem("replay_source", ReplaySource(traj))
    builder.Connect(source.GetOutputPort("desired_state"), station_diagram.GetInputPort("desired_state"))
    builder.Connect(source.GetOutputPort("suction_command"), station_diagram.GetInputPort("suction_command"))
    n = len(traj.joint_names)
    measured_log = builder.AddNamedSystem("measured_log", VectorLogSink(2 * n, log_period))
    commanded_log = builder.AddNamedSystem("commanded_log", VectorLogSink(2 * n, log_period))
    builder.Connect(station_diagram.GetOutputPort("measured_state"), measured_log.get_input_port())
    builder.Connect(source.GetOutputPort("desired_state"), commanded_log.get_input_port())
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.set_target_realtime_rate(0.0)
    context = simulator.get_mutable_context()
    plant = station_diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyMutableContextFromRoot(context)
    robot = plant.GetModelInstanceByName(station.robot_model)
    q = plant.GetPositions(plant_context, robot).copy()
    names = list(robot_model.PLANNED_JOINTS)
    q_all = plant.GetPositions(plant_context).copy()
    for j, name in enumerate(names):
        q_all[plant.GetJointByName(name, robot).position_start()] = source.q_initial[j]
    plant.SetPositions(plant_context, q_all)
    del q
    t_end = traj.end_time if end_time is None else end_time
    if meshcat is not None:
        meshcat.StartRecording(frames_per_second=30.0)
    wall = time.perf_counter()
    simulator.Initialize()
    from tqdm import tqdm

    with tqdm(total=round(t_end, 1), desc="replaying", unit="sim s", disable=None if progress is None else not progress,
              leave=False, bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} simulated s") as bar:
        while context.get_time() < t_end:
            simulator.AdvanceTo(min(t_end, context.get_time() + 1.0))
            bar.update(round(context.get_time(), 1) - bar.n)
    wall = time.perf_counter() - wall
    html = None
    if meshcat is not None:
        meshcat.StopRecording()
        meshcat.PublishRecording()
        html = meshcat.StaticHtml()
    X_SW = shelf_pose(station, scene.camera).inverse()
    final = {}
    for obj in scene.objects:
        X = (X_SW @ plant.EvalBodyPoseInWorld(plant_context, plant.GetBodyByName(obj.name))).GetAsMatrix4()
        final[obj.name] = {"x": float(X[0, 3]), "y": float(X[1, 3]), "z": float(X[2, 3]),
                           "yaw": math.atan2(X[1, 0], X[0, 0]),
                           "upright": bool(abs(X[2, 2]) > math.cos(math.radians(20.0)))}
    m_log = measured_log.FindLog(context)
    c_log = commanded_log.FindLog(context)
    del RigidTransform
    return ReplayResult(final, context.get_time(), wall, m_log.sample_times(), c_log.data().T[:, :n],
                        m_log.data().T[:, :n], html)


def compare_final_objects(replayed: dict, recorded: dict) -> dict:
    """Per object: the planar distance (m) and the 3D distance (m) between replayed and recorded final poses."""
    out = {}
    for name, r in recorded.items():
        p = replayed.get(name)
        if p is None:
            continue
        dz = p["z"] - r["z"] if "z" in r else 0.0
        out[name] = {"xy_m": math.hypot(p["x"] - r["x"], p["y"] - r["y"]),
                     "xyz_m": math.sqrt((p["x"] - r["x"]) ** 2 + (p["y"] - r["y"]) ** 2 + dz ** 2)}
    return out
