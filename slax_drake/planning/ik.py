"""Inverse kinematics of a tool frame pose with Drake's InverseKinematics (SNOPT from the pip wheel).

One solve places a tool frame (``blade_face_frame`` or ``cup_tip_frame``) at a pose in the shelf frame S
within ``position_tolerance`` metres (a box) and ``angle_tolerance`` radians, ``LIMIT_MARGIN`` inside the joint
limits, with the head and the tool shaft locked (the shaft angle is given: ``SHAFT_BLADE_DOWN`` or ``SHAFT_BLADE_UP``; it
turns about the same axis as the wrist roll, so leaving it free would make the problem redundant) and, when
``min_distance`` is given, every unfiltered distance (robot-environment, and between non-adjacent robot links)
above it (AddMinimumDistanceLowerBoundConstraint).
The cost keeps the solution near the warm start (the previous waypoint's configuration), so consecutive
waypoints along a path give neighbouring configurations.
"""

from __future__ import annotations

import functools

import numpy as np

from slax_drake.station import robot as robot_model

POSITION_TOLERANCE = 5e-4  # m
# Joint-limit margin: every planned configuration keeps this far inside the position limits of the limited
# joints (rad for revolute joints, m for the torso), so that the trajectories pass the hardware checker's
# ``check-trajectory --margin 0.01``; solved with LIMIT_SOLVER_SLACK more to absorb the solver's tolerance.
# Rest-to-rest Ruckig segments move on the straight line between their ends (no overshoot), so the margin of
# the waypoints holds along the whole trajectory (the planner verifies it after timing).
LIMIT_MARGIN = 0.01
LIMIT_SOLVER_SLACK = 1e-4
ANGLE_TOLERANCE = 0.01  # rad
# SNOPT's major iterations per solve (Drake's default: 1000). A pose the arm cannot take, or one the distance
# constraint makes infeasible, often ran to that limit (0.15 s a plain solve, up to 1.3 s with the distance
# constraint, against 5-10 ms for a solve that converges); a solve that converges within this limit returns the
# same solution as before (the iterations are the same up to it). Chosen by replaying Drake trial decisions and
# checked against the planner's verdicts on Table I candidates (docs/research/reach-and-planning-speed.md).
MAJOR_ITERATIONS_LIMIT = 200
CONTINUOUS_JOINTS = ("upperarm_roll_joint", "forearm_roll_joint", "wrist_roll_joint")


@functools.cache
def _solver_options():
    """The SolverOptions of every IK solve (SNOPT's ``MAJOR_ITERATIONS_LIMIT``), made once: a planning decision
    solves hundreds of poses."""
    from pydrake.solvers import SnoptSolver, SolverOptions

    options = SolverOptions()
    options.SetOption(SnoptSolver().solver_id(), "Major iterations limit", MAJOR_ITERATIONS_LIMIT)
    return options


def margin_limits(plant, robot, margin: float):
    """(lower, upper) of the plant's positions shrunk by ``margin`` for the robot's limited joints (planned and
    head); +-inf elsewhere. The head is locked during IK and only needs its own value inside the range."""
    lower = np.full(plant.num_positions(), -np.inf)
    upper = np.full(plant.num_positions(), np.inf)
    for name in robot_model.PLANNED_JOINTS:
        joint = plant.GetJointByName(name, robot)
        lo, hi = joint.position_lower_limits()[0], joint.position_upper_limits()[0]
        if np.isfinite(lo) and np.isfinite(hi):
            lower[joint.position_start()] = lo + margin
            upper[joint.position_start()] = hi - margin
    return lower, upper


def solve_tool_pose(world, frame: str, X_S_target, q_guess, shaft: float, min_distance: float | None = None,
                    position_tolerance: float = POSITION_TOLERANCE, angle_tolerance: float = ANGLE_TOLERANCE):
    """Planned joint values (9,) placing ``frame`` at X_S_target (RigidTransform in S), or None if the solver
    finds no solution. ``q_guess`` (9,) is the initial guess and the configuration the cost stays near."""
    from pydrake.math import RotationMatrix
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.solvers import Solve

    plant, context = world.plant, world.plant_context
    q_start = np.asarray(q_guess, float).copy()
    q_start[robot_model.PLANNED_JOINTS.index("tool_shaft_joint")] = shaft
    plant.SetPositions(context, world.full_q(q_start))
    for name in robot_model.HEAD_JOINTS + ("tool_shaft_joint",):
        plant.GetJointByName(name, world.robot).Lock(context)
    ik = InverseKinematics(plant, context, with_joint_limits=True)
    q = ik.q()
    X_WT = world.X_WS @ X_S_target
    p = X_WT.translation()
    tol = np.full(3, position_tolerance)
    tool = plant.GetFrameByName(frame, world.robot)
    ik.AddPositionConstraint(tool, np.zeros(3), plant.world_frame(), p - tol, p + tol)
    ik.AddOrientationConstraint(plant.world_frame(), X_WT.rotation(), tool, RotationMatrix(), angle_tolerance)
    if min_distance is not None:
        ik.AddMinimumDistanceLowerBoundConstraint(min_distance, 0.02)
    prog = ik.get_mutable_prog()
    q0 = world.full_q(q_start)
    for name in CONTINUOUS_JOINTS:  # unbounded joints: stay within half a turn of the warm start
        i = plant.GetJointByName(name, world.robot).position_start()
        prog.AddBoundingBoxConstraint(q0[i] - np.pi, q0[i] + np.pi, q[i])
    lower, upper = margin_limits(plant, world.robot, LIMIT_MARGIN + LIMIT_SOLVER_SLACK)
    limited = np.isfinite(lower) & np.isfinite(upper)
    prog.AddBoundingBoxConstraint(lower[limited], upper[limited], q[limited])
    q0 = np.clip(q0, np.where(limited, lower, -np.inf), np.where(limited, upper, np.inf))
    prog.AddQuadraticErrorCost(np.eye(len(q0)), q0, q)
    prog.SetInitialGuess(q, q0)
    result = Solve(prog, solver_options=_solver_options())
    for name in robot_model.HEAD_JOINTS + ("tool_shaft_joint",):
        plant.GetJointByName(name, world.robot).Unlock(context)
    if not result.is_success():
        return None
    return world.planned_q(result.GetSolution(q))
