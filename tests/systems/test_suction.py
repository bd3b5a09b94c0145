"""The suction force element on a fixture: a welded cup (the tool's tube end, lip spheres and cup_tip frame)
holding a box against gravity, dropping it when the command is off or the load exceeds the cup's pull."""

import math

import numpy as np
import pytest
from pydrake.geometry import Box, Cylinder, ProximityProperties, Sphere, AddContactMaterial
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlantConfig
from pydrake.multibody.tree import FixedOffsetFrame, SpatialInertia, UnitInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from slax_drake.station.scenario import load_station_scenario
from slax_drake.station.scenario import SuctionParameters
from slax_drake.systems.suction import SuctionCup

BOX = 0.10  # m, cube
STATION_TIME_STEP = load_station_scenario().plant_config.time_step  # s, the fixture steps like the station (5 ms)


def _props(mu):
    props = ProximityProperties()
    AddContactMaterial(dissipation=5.0, point_stiffness=2e5, friction=CoulombFriction(mu, mu), properties=props)
    return props


def _fixture(cup_axis, mass, command):
    """A cup welded at 1 m with its axis along ``cup_axis`` ('down' or 'side') and a box touching its lip."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(
        MultibodyPlantConfig(time_step=STATION_TIME_STEP, contact_model="point", discrete_contact_approximation="lagged"), builder
    )
    cup = plant.AddRigidBody("cup", SpatialInertia(0.1, np.zeros(3), UnitInertia.SolidSphere(0.02)))
    # cup frame: x along the cup axis; lip spheres with their tips at x = 0 (the cup tip)
    R = RotationMatrix.MakeYRotation(math.pi / 2) if cup_axis == "down" else RotationMatrix.MakeZRotation(math.pi / 2)
    plant.WeldFrames(plant.world_frame(), cup.body_frame(), RigidTransform(R, [0, 0, 1.0]))
    plant.RegisterCollisionGeometry(
        cup, RigidTransform(RotationMatrix.MakeYRotation(math.pi / 2), [-0.013, 0, 0]), Cylinder(0.015, 0.014), "cup_body", _props(1.0)
    )
    for k in range(8):
        a = 2 * math.pi * k / 8
        plant.RegisterCollisionGeometry(
            cup, RigidTransform([-0.002, 0.013 * math.cos(a), 0.013 * math.sin(a)]), Sphere(0.002), f"lip_{k}", _props(1.0)
        )
    tip = plant.AddFrame(FixedOffsetFrame("cup_tip", cup.body_frame(), RigidTransform()))
    box = plant.AddRigidBody("box", SpatialInertia(mass, np.zeros(3), UnitInertia.SolidBox(BOX, BOX, BOX)))
    plant.RegisterCollisionGeometry(box, RigidTransform(), Box(BOX, BOX, BOX), "box", _props(0.5))
    plant.Finalize()
    axis_W = R.matrix()[:, 0].copy()
    X_WB = RigidTransform([0, 0, 1.0] + axis_W * (BOX / 2 - 1e-5))
    plant.SetDefaultFloatingBaseBodyPose(box, X_WB)
    suction = builder.AddSystem(SuctionCup(plant, scene_graph, tip, SuctionParameters(), object_bodies=[box.index()]))
    builder.Connect(scene_graph.get_query_output_port(), suction.GetInputPort("query_object"))
    builder.Connect(suction.GetOutputPort("spatial_forces"), plant.get_applied_spatial_force_input_port())
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    suction.GetInputPort("suction_command").FixValue(suction.GetMyContextFromRoot(context), [command])
    return simulator, plant, box, suction, X_WB.translation()


def _position(simulator, plant, box):
    return plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(simulator.get_context()), box).translation()


@pytest.mark.parametrize("cup_axis", ["down", "side"])
def test_half_kilo_box_held_for_five_seconds(cup_axis):
    simulator, plant, box, suction, p0 = _fixture(cup_axis, 0.5, command=1.0)
    simulator.AdvanceTo(5.0)
    moved = np.linalg.norm(_position(simulator, plant, box) - p0)
    assert moved < 0.005
    pull = suction.GetOutputPort("suction_state").Eval(suction.GetMyContextFromRoot(simulator.get_context()))[0]
    assert pull == pytest.approx(SuctionParameters().max_force, rel=0.05)


def test_box_falls_with_command_off():
    simulator, plant, box, _, p0 = _fixture("down", 0.5, command=0.0)
    simulator.AdvanceTo(0.5)
    assert p0[2] - _position(simulator, plant, box)[2] > 0.5 * 9.81 * 0.5**2 * 0.9


def test_seal_breaks_under_a_load_above_the_cup_pull():
    heavy = 1.2 * SuctionParameters().max_force / 9.81  # kg: weight 20 % above vacuum pressure x cup area
    simulator, plant, box, _, p0 = _fixture("down", heavy, command=1.0)
    simulator.AdvanceTo(0.5)
    assert p0[2] - _position(simulator, plant, box)[2] > 0.1


def test_max_force_is_pressure_times_area():
    assert SuctionParameters(vacuum_pressure=50000.0, cup_radius=0.015).max_force == pytest.approx(50000.0 * math.pi * 0.015**2)
