"""The station's blade: a blade push moves a box along the shelf's x without toppling it, and the blade reaches
the front, middle and back of the sim shelf's bay across its width (IK with the tool's blade frame).

Joint trajectories come from Drake's InverseKinematics (``tests/station_ik.py``) at closely spaced blade poses on
an empty shelf, interpolated in joint space and fed through a TrajectorySource into the station's
``desired_state`` port.
"""

import math

import numpy as np
import pytest

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.station import robot as robot_model
from slax_drake.station.scenario import load_station_scenario
from slax_drake.systems.station import MakeStation

from station_ik import BladeIk, blade_centre_height, reach_seeds

BLADE_HALF_THICKNESS = 0.002  # m (the blade is 4 mm thick along the push direction)
TUBE_RADIUS = 0.015  # m: the tube above the blade is wider than the blade, so it leads on tall objects
GAP = 0.02  # m between the tool's leading surface and the box before the push
PUSH = 0.10  # m, commanded blade travel along +x
# Boxes (x y z extents, m; 400 kg/m^3) and the half-width of the tool's part that meets them: the low box stays
# below the tube (whose underside is 0.067 m above the board), so the blade alone pushes it; the tube and the
# cup meet the tall one first, 13 mm before the blade would.
BOXES = {
    "low box, blade alone": ((0.10, 0.10, 0.06), BLADE_HALF_THICKNESS),
    "tall box, tube leads": ((0.10, 0.10, 0.15), TUBE_RADIUS),
}


@pytest.fixture(scope="module")
def station_scenario():
    return load_station_scenario("sim_configs/station_sim_shelf.yaml")


@pytest.fixture(scope="module")
def blade_ik(station_scenario):
    return BladeIk(MakeStation(station_scenario, None, camera=False))


def _ik_path(ik, points, q_start):
    """IK solutions along blade-centre points (shelf frame), each seeded with the previous one."""
    qs, q = [], q_start
    for p in points:
        ok, q = ik.solve(p, q)
        assert ok, f"no IK solution for the blade at {np.round(p, 3)}"
        qs.append(q)
    return qs


def _push_trajectory(ik, scenario, box, lead):
    """(PiecewisePolynomial of the 9 planned joints, times of the push start and end) for: insert the blade from
    in front of the bay to beside the box, pause, push along +x by PUSH, hold."""
    from pydrake.trajectories import PiecewisePolynomial

    z = blade_centre_height()
    x0 = -box[0] / 2 - lead - GAP
    insert = [np.array([x0, y, z]) for y in np.linspace(-0.42, 0.0, 15)]
    push = [np.array([x, 0.0, z]) for x in np.linspace(x0, x0 + PUSH, 11)]
    q_first = None
    for seed in reach_seeds(scenario):
        ok, q_first = ik.solve(insert[0], seed)
        if ok:
            break
    assert ok, "no IK solution in front of the bay"
    q_insert = _ik_path(ik, insert, q_first)
    q_push = _ik_path(ik, push, q_insert[-1])
    t_insert = np.linspace(0.0, 2.5, len(q_insert))
    t_push0 = 3.0
    t_push = np.linspace(t_push0, t_push0 + 2.0, len(q_push))
    times = np.concatenate([t_insert, t_push, [t_push[-1] + 0.5]])
    knots = np.array(q_insert + q_push + [q_push[-1]]).T
    traj = PiecewisePolynomial.CubicShapePreserving(times, knots, zero_end_point_derivatives=True)
    return traj, t_push0, t_push[-1]


def _one_box_scene(sim_scenario, size):
    box = SceneObject("box", "box", size, planar_pose(0.0, 0.0, size[2] / 2, 0.0))
    return Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (box,), None, 0)


def _simulate_push(sim_scenario, station_scenario, blade_ik, case, sleep=False):
    """Runs the push of BOXES[case]; returns (box pose before the push, after it, tool parts touching the box
    half-way, whether the box slept while the blade was still outside the bay)."""
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder
    from pydrake.systems.primitives import TrajectorySource

    from slax_drake.systems.sleep import ObjectSleep

    size, lead = BOXES[case]
    traj, t_push0, t_push1 = _push_trajectory(blade_ik, station_scenario, size, lead)
    scene = _one_box_scene(sim_scenario, size)
    builder = DiagramBuilder()
    station = builder.AddSystem(MakeStation(station_scenario, scene, camera=False))
    source = builder.AddSystem(TrajectorySource(traj, output_derivative_order=1))
    builder.Connect(source.get_output_port(), station.GetInputPort("desired_state"))
    builder.ExportInput(station.GetInputPort("suction_command"), "suction_command")
    diagram = builder.Build()

    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    diagram.GetInputPort("suction_command").FixValue(context, [0.0])
    plant = station.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    robot = plant.GetModelInstanceByName("fetch")
    q_robot = plant.GetPositions(plant_context, robot)
    q_robot[_robot_local(plant, robot)] = traj.value(0.0).ravel()
    plant.SetPositions(plant_context, robot, q_robot)
    slept = False
    if sleep:
        sleeper = ObjectSleep(station)
        sleeper.install(simulator)
        simulator.AdvanceTo(0.5)  # the blade is still 0.3 m in front of the box
        slept = sleeper.sleeping(context) == [True]

    shelf = plant.GetFrameByName("shelf_body")
    box = plant.GetBodyByName("box")

    def box_pose():
        return shelf.CalcPoseInWorld(plant_context).inverse() @ plant.EvalBodyPoseInWorld(plant_context, box)

    simulator.AdvanceTo(t_push0)
    before = box_pose()
    simulator.AdvanceTo((t_push0 + t_push1) / 2)
    touching = _robot_geometries_touching(plant, plant_context, box)
    simulator.AdvanceTo(traj.end_time())
    return before, box_pose(), touching, slept


@pytest.mark.parametrize("case", list(BOXES))
def test_blade_push_moves_a_box_along_x_without_toppling_it(sim_scenario, station_scenario, blade_ik, case):
    size, lead = BOXES[case]
    before, after, touching, _ = _simulate_push(sim_scenario, station_scenario, blade_ik, case)
    # Inserting the blade beside the box leaves it where the scene put it.
    assert np.linalg.norm(before.translation() - [0.0, 0.0, size[2] / 2]) < 2e-3
    moved = after.translation() - before.translation()
    print(f"{case}: moved {np.round(moved, 4)} m, touching {sorted(touching)}")
    expected = PUSH - GAP  # the tool first closes the gap, then carries the box
    tilt = math.degrees(math.acos(np.clip(after.rotation().matrix()[2, 2], -1.0, 1.0)))
    # The IK tolerance (1 mm), the PD joints' tracking error and the contact compliance cost a few millimetres.
    assert moved[0] == pytest.approx(expected, abs=0.01), moved
    assert abs(moved[1]) < 0.01, moved
    assert abs(moved[2]) < 2e-3, moved
    assert tilt < 5.0
    # Which part of the tool carried the box half-way through the push.
    if lead == BLADE_HALF_THICKNESS:
        assert touching == {"blade"}
    else:
        assert "tube" in touching, touching


@pytest.mark.slow
def test_a_sleeping_box_wakes_for_the_push_and_moves_as_an_awake_one(sim_scenario, station_scenario, blade_ik):
    case = "low box, blade alone"
    _, awake, _, _ = _simulate_push(sim_scenario, station_scenario, blade_ik, case)
    _, woken, touching, slept = _simulate_push(sim_scenario, station_scenario, blade_ik, case, sleep=True)
    assert slept  # asleep while the blade was far, so the push itself had to wake it
    assert touching == {"blade"}
    assert np.linalg.norm(woken.translation() - awake.translation()) < 1e-3
    assert np.allclose(woken.rotation().matrix(), awake.rotation().matrix(), atol=1e-3)


def _robot_geometries_touching(plant, plant_context, body):
    """Names (without the model prefix) of the robot's collision geometries in contact with ``body``."""
    results = plant.get_contact_results_output_port().Eval(plant_context)
    inspector = plant.get_geometry_query_input_port().Eval(plant_context).inspector()
    mine = set(plant.GetCollisionGeometriesForBody(body))
    names = set()
    for i in range(results.num_point_pair_contacts()):
        pair = results.point_pair_contact_info(i).point_pair()
        for a, b in ((pair.id_A, pair.id_B), (pair.id_B, pair.id_A)):
            if a in mine and inspector.GetName(b).startswith("fetch::"):
                names.add(inspector.GetName(b).split("::", 1)[1])
    return names


def _robot_local(plant, robot):
    q = np.arange(plant.num_positions(), dtype=float)
    local = plant.GetPositionsFromArray(robot, q).astype(int).tolist()
    return [local.index(plant.GetJointByName(n, robot).position_start()) for n in robot_model.PLANNED_JOINTS]


# Blade centres (shelf frame x, y; m) across the bay's width at its front, middle and back, the blade's lower
# edge 8 mm above the board. Measured limits (the map printed by `python tests/station_ik.py`; the station's
# observation pose puts the bay 0.15 m beyond the arm's folded reach, so its back is at the stretched arm's):
# across the whole width up to y = 0, at y = 0.10 m from x = -0.10 m rightwards, at y = 0.15 m from x = 0, and
# nowhere deeper than y = 0.20 m.
REACH_X = {"front": (-0.22, -0.11, 0.0, 0.11, 0.22), "middle": (-0.22, -0.11, 0.0, 0.11, 0.22),
           "back": (-0.10, 0.0, 0.11, 0.22)}
REACH_Y = {"front": -0.2, "middle": 0.0, "back": 0.1}


@pytest.mark.parametrize("region", list(REACH_Y))
def test_blade_reaches_across_the_bay_collision_free(station_scenario, blade_ik, region):
    from slax_drake.station.robot import BLADE_FACE_FRAME

    z = blade_centre_height()
    plant, context = blade_ik.plant, blade_ik.plant_context
    shelf = plant.GetFrameByName("shelf_body")
    blade = plant.GetFrameByName(BLADE_FACE_FRAME)
    q_guess = None
    for x in REACH_X[region]:
        target = np.array([x, REACH_Y[region], z])
        ok = False
        for seed in ([q_guess] if q_guess is not None else []) + reach_seeds(station_scenario):
            ok, q = blade_ik.solve(target, seed)
            if ok:
                break
        assert ok, f"blade not placed at {target}"
        q_guess = q
        # The solution is checked independently of the solver: forward kinematics and the distance query.
        q_full = blade_ik.q_default.copy()
        q_full[blade_ik.planned] = q
        plant.SetPositions(context, q_full)
        X_SB = blade.CalcPose(context, shelf)
        assert np.abs(X_SB.translation() - target).max() < 1.1e-3
        assert X_SB.rotation().matrix()[:, 1] @ np.array([-1.0, 0.0, 0.0]) > math.cos(math.radians(3.1))
        query = plant.get_geometry_query_input_port().Eval(context)
        assert all(pair.distance > 0.0 for pair in query.ComputeSignedDistancePairwiseClosestPoints(0.01))
