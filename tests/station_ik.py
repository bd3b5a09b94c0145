"""Blade-pose inverse kinematics on the station's own plant, for the push and reach tests (not library code: the
planning stage owns the product's IK). Uses Drake's InverseKinematics directly.

Pushing pose of the bluction tool (paper Sec. III): the tube enters the bay horizontally along the shelf's +y
(depth), the blade hangs below it (``tool_shaft_joint`` = 0) and its faces point along the shelf's +-x, the push
direction. In the shelf frame S the blade frame B is therefore R_SB = [x_B = +y_S, y_B = -x_S, z_B = +z_S].
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.station import robot as robot_model
from slax_drake.station.scenario import SHELF_BODY, observation_positions

BLADE_HALF_HEIGHT = 0.0375  # m, blade is 0.075 m high; blade_face_frame is at its centre
BLADE_LIFT = 0.008  # m, gap between the blade's lower edge and the support board


def pushing_rotation():
    """R_SB of the pushing pose (module docstring)."""
    from pydrake.math import RotationMatrix

    return RotationMatrix(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))  # columns: x_B, y_B, z_B in S


def blade_centre_height() -> float:
    """z_S (m) of the blade centre with its lower edge BLADE_LIFT above the support board."""
    return BLADE_HALF_HEIGHT + BLADE_LIFT


@dataclasses.dataclass
class BladeIk:
    """Solves for planned-joint positions that put the blade frame at a point of the shelf frame in pushing pose."""

    diagram: object
    position_tolerance: float = 0.001  # m, box half-width around the target point
    angle_tolerance_deg: float = 3.0  # rad bound on the angle between R_SB and the pushing rotation
    clearance: float = 0.003  # m, minimum distance between any unfiltered collision pair (robot vs shelf/objects)

    def __post_init__(self):
        self.plant = self.diagram.GetSubsystemByName("plant")
        self.context = self.diagram.CreateDefaultContext()
        self.plant_context = self.plant.GetMyContextFromRoot(self.context)
        self.robot = self.plant.GetModelInstanceByName("fetch")
        self.planned = robot_model.planned_joint_indices(self.plant, self.robot)
        self.q_default = self.plant.GetPositions(self.plant_context).copy()

    def solve(self, p_S, q_guess=None, collision_free: bool = True, shaft: float = robot_model.SHAFT_BLADE_DOWN):
        """(success, q of PLANNED_JOINTS) for the blade centre at ``p_S`` (shelf frame, m), the tool shaft at
        ``shaft`` (rad). The blade hangs down with the shaft at 0 and the camera left of the tube (seen from the
        camera), or with the shaft at pi and the wrist rolled over, which puts the camera right of the tube."""
        from pydrake.multibody.inverse_kinematics import InverseKinematics
        from pydrake.solvers import Solve

        plant = self.plant
        ik = InverseKinematics(plant, self.plant_context, with_joint_limits=True)
        shelf = plant.GetFrameByName(SHELF_BODY)
        blade = plant.GetFrameByName(robot_model.BLADE_FACE_FRAME, self.robot)
        p = np.asarray(p_S, dtype=float)
        tol = self.position_tolerance
        ik.AddPositionConstraint(blade, np.zeros(3), shelf, p - tol, p + tol)
        from pydrake.math import RotationMatrix

        ik.AddOrientationConstraint(
            shelf, pushing_rotation(), blade, RotationMatrix(), math.radians(self.angle_tolerance_deg)
        )
        if collision_free:
            ik.AddMinimumDistanceLowerBoundConstraint(self.clearance, 0.05)
        prog = ik.prog()
        q = ik.q()
        # Every joint but the planned arm joints stays at its default (head, free bodies); blade down.
        fixed = [i for i in range(plant.num_positions()) if i not in set(self.planned.tolist())]
        prog.AddBoundingBoxConstraint(self.q_default[fixed], self.q_default[fixed], q[fixed])
        shaft_index = self.planned[robot_model.PLANNED_JOINTS.index("tool_shaft_joint")]
        prog.AddBoundingBoxConstraint(shaft, shaft, q[shaft_index])
        guess = self.q_default.copy()
        if q_guess is not None:
            guess[self.planned] = q_guess
        guess[shaft_index] = shaft
        # Stay near the guess (keeps consecutive solutions on one branch of the arm's IK).
        prog.AddQuadraticErrorCost(np.eye(len(self.planned)), guess[self.planned], q[self.planned])
        prog.SetInitialGuess(q, guess)
        result = Solve(prog)
        return result.is_success(), result.GetSolution(q)[self.planned]


def reach_seeds(scenario) -> list[np.ndarray]:
    """Initial guesses: the observation pose, with the shoulder panned and the elbow flexed a few ways."""
    q_obs = observation_positions(scenario)
    seeds = [q_obs]
    for pan, lift, elbow in ((0.0, 0.0, 1.0), (-0.5, 0.2, 1.2), (0.5, 0.2, 1.2), (0.0, -0.4, 1.5)):
        q = np.zeros(9)
        q[0], q[1], q[2], q[4], q[6] = 0.2, pan, lift, elbow, -elbow + 0.0
        seeds.append(q)
    return seeds


def reach_map(path=None, xs=(-0.25, -0.23, -0.2, -0.1, 0.0, 0.1, 0.2, 0.23, 0.25), ys=(-0.2, -0.1, 0.0, 0.1, 0.15, 0.2, 0.24)):
    """Prints which blade centres (shelf x across, y deep) the sim station reaches collision-free in pushing pose:
    'Y' with the shaft at 0 (camera left of the tube), 'F' only with the wrist rolled over (shaft at pi), '-' with
    neither (from the seeds of ``reach_seeds``; a local solver, so '-' means not found, not proven impossible)."""
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.station import MakeStation

    scenario = load_station_scenario(path) if path else load_station_scenario()
    ik = BladeIk(MakeStation(scenario, None, camera=False))
    z = blade_centre_height()
    roll = robot_model.PLANNED_JOINTS.index("wrist_roll_joint")
    print("blade centre z = %.4f m; columns x (m), rows y (m)" % z)
    print("        " + " ".join(f"{x:+6.2f}" for x in xs))
    for y in ys:
        row = []
        for x in xs:
            mark = "-"
            for shaft, label in ((robot_model.SHAFT_BLADE_DOWN, "Y"), (math.pi, "F")):
                for seed in reach_seeds(scenario):
                    seed = seed.copy()
                    if shaft:
                        seed[roll] += math.pi
                    if ik.solve([x, y, z], seed, shaft=shaft)[0]:
                        mark = label
                        break
                if mark != "-":
                    break
            row.append(f"{mark:>6}")
        print(f"y={y:+.2f} " + " ".join(row), flush=True)


if __name__ == "__main__":
    import sys
    reach_map(sys.argv[1] if len(sys.argv) > 1 else None)
