"""Sleeping objects: resting scene objects far from anything that moves are locked out of the physics step.

Most of a station step is spent building and solving the contact problem of objects that only rest on the
board. ``ObjectSleep`` locks the floating joint of such an object (Drake's ``Joint.Lock``: the discrete solver
drops its six velocities and treats it as fixed, its velocities are set to zero) and unlocks it as soon as
something could touch it. With 10 objects at rest this made the station about 2x faster (see
benchmarks/bench_station.py). In full trials with 2-3 objects it made the trial slower instead (the Python
monitor runs every step; `python benchmarks/bench_trial.py [--sleep]`), so ``slax-drake trial`` uses it only with
``--sleep``; the outcome was the same (same actions, final poses within 0.03 mm on the 2-object seed-7 trial).

Rules, checked every ``check_period`` seconds of simulated time from a Simulator monitor:

- An object is *still* when its translational speed is below ``linear_speed`` and its angular speed below
  ``angular_speed``. *Active* bodies are the robot's (always: it may start moving at any step) and the awake
  objects that are not still.
- An awake object that has been still for ``still_time`` falls asleep unless an active body's collision geometry
  lies within ``wake_distance`` of one of its own.
- A sleeping object wakes when an active body's geometry comes within ``wake_distance``.
- Both tests use ``wake_distance`` plus the distance the fastest active body could cover in two check periods
  (a bound on the speed of any point of its geometry: |v| + |w| * reach from the body origin), so a fast arm
  wakes objects earlier instead of running into a sleeping one.

Cost of the approximation: a sleeping object is immovable until woken; one that a body reaches faster than the
speed bound foresees (accelerating hard within one check period) would meet a fixed object for up to one period;
a sleeping object does not feel an external force other than contact (gravity is balanced by the board anyway).

Usage: ``ObjectSleep(station).install(simulator)`` (one per Simulator; it replaces the simulator's monitor). The
bookkeeping (how long each object has been still) lives in this object, not in the Context: reset it with
``reset()`` when the context is reset or rewound.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np


@dataclasses.dataclass(frozen=True)
class SleepParameters:
    """Thresholds of ``ObjectSleep`` (SI units; see the module docstring)."""

    linear_speed: float = 2e-3  # m/s
    angular_speed: float = 2e-2  # rad/s
    still_time: float = 0.1  # s
    wake_distance: float = 0.05  # m
    check_period: float = 0.02  # s


class ObjectSleep:
    """Locks resting objects of a station's plant and unlocks them when something comes near (module docstring).

    ``station``: the station Diagram of ``MakeStation`` (its plant is the subsystem named ``plant``), alone or as a
    subsystem of the simulated diagram.
    """

    def __init__(self, station, params: SleepParameters | None = None, robot_model: str = "fetch"):
        from pydrake.multibody.tree import JointIndex

        self.params = params or SleepParameters()
        self._plant = station.GetSubsystemByName("plant")
        plant = self._plant
        floating = set(plant.GetFloatingBaseBodies())
        self._joints = []  # (body index, joint) of every free object, in body order
        for j in range(plant.num_joints()):
            joint = plant.get_joint(JointIndex(j))
            if joint.child_body().index() in floating and joint.num_velocities() == 6:
                self._joints.append((joint.child_body().index(), joint))
        self._joints.sort(key=lambda item: int(item[0]))
        self._owner = {}  # geometry id -> object number, or -1 for the robot (shelf geometries are absent)
        for k, (body_index, _) in enumerate(self._joints):
            for g in plant.GetCollisionGeometriesForBody(plant.get_body(body_index)):
                self._owner[g] = k
        robot = plant.GetModelInstanceByName(robot_model)
        for body_index in plant.GetBodyIndices(robot):
            for g in plant.GetCollisionGeometriesForBody(plant.get_body(body_index)):
                self._owner[g] = -1
        # Bounding spheres (centre in the body frame, radius) of every collision geometry of the robot and of each
        # object as a whole: a cheap, conservative first test before the exact distance query.
        inspector = station.GetSubsystemByName("scene_graph").model_inspector()
        self._robot_spheres = []  # (body, centres in the body frame (m, 3), radii (m,)) per robot body
        for b in plant.GetBodyIndices(robot):
            spheres = [_bounding_sphere(inspector, g) for g in plant.GetCollisionGeometriesForBody(plant.get_body(b))]
            if spheres:
                self._robot_spheres.append(
                    (plant.get_body(b), np.array([c for c, _ in spheres]), np.array([r for _, r in spheres]))
                )
        self._num_robot_spheres = sum(len(r) for _, _, r in self._robot_spheres)
        # Farthest point of each robot body's geometry from the body origin (m), for the speed bound.
        self._robot_reach = [(body, float(np.max(np.linalg.norm(c, axis=1) + r))) for body, c, r in self._robot_spheres]
        self._object_radius = []
        for body_index, _ in self._joints:
            spheres = [_bounding_sphere(inspector, g) for g in plant.GetCollisionGeometriesForBody(plant.get_body(body_index))]
            self._object_radius.append(max(np.linalg.norm(c) + r for c, r in spheres))
        self.reset()

    def reset(self) -> None:
        """Forgets how long each object has been still (call after resetting or rewinding the context)."""
        self._still_since = [None] * len(self._joints)
        self._next_check = -np.inf

    def install(self, simulator) -> None:
        """Makes this the simulator's monitor (replacing any other) and resets the bookkeeping."""
        from pydrake.systems.framework import EventStatus

        self.reset()

        def monitor(root_context):
            self.update(root_context)
            return EventStatus.Succeeded()

        simulator.set_monitor(monitor)

    def names(self) -> list[str]:
        """Body names of the objects, in the order of ``sleeping``."""
        return [self._plant.get_body(b).name() for b, _ in self._joints]

    def sleeping(self, root_context) -> list[bool]:
        """Whether each object is asleep (locked)."""
        context = self._plant.GetMyContextFromRoot(root_context)
        return [joint.is_locked(context) for _, joint in self._joints]

    def update(self, root_context) -> None:
        """Applies the sleep and wake rules if a check is due at the context's time (the monitor calls this)."""
        p = self.params
        t = root_context.get_time()
        if t < self._next_check - p.check_period:  # the context was rewound
            self.reset()
        if t < self._next_check:
            return
        self._next_check = t + p.check_period
        plant = self._plant
        context = plant.GetMyMutableContextFromRoot(root_context)
        n = len(self._joints)
        asleep = [joint.is_locked(context) for _, joint in self._joints]
        still = [True] * n
        for k, (body_index, _) in enumerate(self._joints):
            if asleep[k]:
                continue
            V = plant.EvalBodySpatialVelocityInWorld(context, plant.get_body(body_index))
            still[k] = np.linalg.norm(V.translational()) < p.linear_speed and np.linalg.norm(V.rotational()) < p.angular_speed
            if not still[k]:
                self._still_since[k] = None
            elif self._still_since[k] is None:
                self._still_since[k] = t
        active = [not asleep[k] and not still[k] for k in range(n)]
        near_active = [False] * n
        reach = p.wake_distance + 2.0 * p.check_period * self._fastest_active_speed(context, active)
        if self._maybe_near_active(context, active, reach):
            near_active = self._near_active(context, active, reach)
        for k, (_, joint) in enumerate(self._joints):
            if asleep[k] and near_active[k]:
                joint.Unlock(context)
                self._still_since[k] = t
            elif not asleep[k] and still[k] and not near_active[k] and t - self._still_since[k] >= p.still_time:
                joint.Lock(context)

    def _fastest_active_speed(self, context, active) -> float:
        """A bound (m/s) on the speed of any point of the robot's or an active object's collision geometry."""
        plant = self._plant
        best = 0.0
        bodies = [(body, reach) for body, reach in self._robot_reach] + [
            (plant.get_body(b), self._object_radius[k]) for k, (b, _) in enumerate(self._joints) if active[k]
        ]
        for body, reach in bodies:
            w_x, w_y, w_z, v_x, v_y, v_z = plant.EvalBodySpatialVelocityInWorld(context, body).get_coeffs()
            best = max(best, math.sqrt(v_x * v_x + v_y * v_y + v_z * v_z) + math.sqrt(w_x * w_x + w_y * w_y + w_z * w_z) * reach)
        return best

    def _maybe_near_active(self, context, active, reach) -> bool:
        """Whether the bounding spheres put any object within ``reach`` of the robot or an active object."""
        plant = self._plant
        if not self._joints:
            return False
        centres = np.array([plant.EvalBodyPoseInWorld(context, plant.get_body(b)).translation() for b, _ in self._joints])
        radii = np.array(self._object_radius)
        oc, orad = [], []
        for body, c_B, r in self._robot_spheres:
            X = plant.EvalBodyPoseInWorld(context, body).GetAsMatrix4()
            oc.append(c_B @ X[:3, :3].T + X[:3, 3])
            orad.append(r)
        moving = np.flatnonzero(active)
        oc.append(centres[moving])
        orad.append(radii[moving])
        oc, orad = np.concatenate(oc), np.concatenate(orad)
        gap = np.linalg.norm(centres[:, None, :] - oc[None, :, :], axis=2) - radii[:, None] - orad[None, :]
        gap[moving, self._num_robot_spheres + np.arange(len(moving))] = np.inf  # an active object is not near itself
        return bool((gap < reach).any())

    def _near_active(self, context, active, reach) -> list[bool]:
        """Exact test: an object's geometry within ``reach`` of the robot's or an active object's."""
        n = len(active)
        near_active = [False] * n
        query = self._plant.get_geometry_query_input_port().Eval(context)
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(reach):
            a, b = self._owner.get(pair.id_A), self._owner.get(pair.id_B)
            if a is None or b is None or a == b:
                continue
            if a >= 0 and (b == -1 or active[b]):
                near_active[a] = True
            if b >= 0 and (a == -1 or active[a]):
                near_active[b] = True
        return near_active


def _bounding_sphere(inspector, geometry_id):
    """(centre in the body frame, radius) of a sphere that holds the collision geometry (box, cylinder, sphere)."""
    from pydrake.geometry import Box, Cylinder, Sphere

    shape = inspector.GetShape(geometry_id)
    if isinstance(shape, Box):
        radius = 0.5 * float(np.linalg.norm([shape.width(), shape.depth(), shape.height()]))
    elif isinstance(shape, Cylinder):
        radius = float(np.hypot(shape.radius(), shape.length() / 2.0))
    elif isinstance(shape, Sphere):
        radius = shape.radius()
    else:
        raise TypeError(f"no bounding sphere for a {type(shape).__name__} ({inspector.GetName(geometry_id)})")
    return inspector.GetPoseInFrame(geometry_id).translation().copy(), radius
