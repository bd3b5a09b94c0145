"""The trial diagram's wiring: station camera -> (depth noise) -> perception -> planner; ground truth only to the
evaluator. Builds the diagram (no simulation), so it is fast."""

import pytest

from slax_drake.systems.trial import TrialOptions, build_trial

PLANNER_INPUTS = {"measured_state", "observation", "hypotheses", "occupancy_1d", "stop"}
GUARD_INPUTS = {"measured_efforts"}  # the station's joint efforts, read by the guarded push-in (the stations' default)


def _connections(diagram):
    """[(source system, source port, destination system, destination port)] by name."""
    out = []
    for (dst, dst_port), (src, src_port) in diagram.connection_map().items():
        out.append((src.get_name(), src.get_output_port(src_port).get_name(), dst.get_name(),
                    dst.get_input_port(dst_port).get_name()))
    return out


@pytest.fixture(scope="module")
def trial():
    return build_trial(TrialOptions(objects=3, seed=7))


def test_planner_has_no_input_carrying_true_poses(trial):
    planner = trial.planner_system
    names = {planner.get_input_port(i).get_name() for i in range(planner.num_input_ports())}
    assert names == PLANNER_INPUTS | GUARD_INPUTS
    assert not names & {"body_poses", "label_image", "plant_state", "query_object", "contact_results"}
    feeds = {(src, port) for src, port, dst, _ in _connections(trial.diagram) if dst == "planner"}
    assert feeds == {("station", "measured_state"), ("perception", "observation"), ("perception", "hypotheses"),
                     ("perception", "occupancy_1d"), ("evaluator", "stop"), ("station", "measured_efforts")}


def test_ground_truth_reaches_only_the_evaluator_and_the_target_mask(trial):
    connections = _connections(trial.diagram)
    readers = {(src_port, dst, dst_port) for src, src_port, dst, dst_port in connections
               if src == "station" and src_port in ("body_poses", "label_image")}
    assert readers == {("body_poses", "evaluator", "body_poses"), ("label_image", "evaluator", "label_image"),
                       ("label_image", "perception", "label_image")}
    assert ("station", "depth_image", "perception", "depth_image") in connections
    assert ("planner", "desired_state", "station", "desired_state") in connections
    assert ("planner", "suction_command", "station", "suction_command") in connections


def test_sensor_noise_sits_between_camera_and_perception():
    trial = build_trial(TrialOptions(objects=3, seed=7, sensor_noise=True))
    connections = _connections(trial.diagram)
    assert ("station", "depth_image", "depth_noise", "depth_image") in connections
    assert ("depth_noise", "depth_image", "perception", "depth_image") in connections
    assert ("station", "depth_image", "perception", "depth_image") not in connections


def test_planner_decides_on_hypotheses_from_the_frame(trial):
    """At the first decision the planner's belief holds segment_<id> hypotheses built from the perception ports."""
    import numpy as np

    context = trial.diagram.CreateDefaultContext()
    perception = trial.perception
    pc = perception.GetMyContextFromRoot(context)
    obs = perception.GetOutputPort("observation").Eval(pc)
    hyps = perception.GetOutputPort("hypotheses").Eval(pc)
    p1d = perception.GetOutputPort("occupancy_1d").Eval(pc)
    assert obs.depth.shape == (120, 160) and len(hyps) >= 1
    assert all(h.object.name.startswith("segment_") for h in hyps)
    assert p1d.shape == (160,) and np.isclose(p1d.sum(), 1.0)
    ec = trial.evaluator.GetMyContextFromRoot(context)
    owners = trial.evaluator.segment_owners(ec)
    assert set(owners.values()) <= {o.name for o in trial.scene.objects} and owners


def test_unknown_segmentation_is_refused():
    from slax_drake.errors import TrialError

    with pytest.raises(TrialError, match="segmentation"):
        build_trial(TrialOptions(segmentation="colour"))


def test_a_guarded_trial_feeds_the_planner_the_arm_s_efforts_and_nothing_of_the_hidden_objects(trial):
    """The shipped station places by guarded moves (guarded_placement), so a default trial plans under
    suction_hidden_rule=guarded and its planner also reads the station's joint efforts (what a Fetch's joint_states
    reports), and still no true pose or contact result; with --tool-rule suction_hidden_rule=placement it still reads
    them to weigh what the cup lifts (the station's cup limit, max_suction_moment), and with the paper's weightless
    rules too (max_suction_moment=inf) it reads none."""
    assert trial.tool_rules["suction_hidden_rule"] == "guarded"
    feeds = {(src, port) for src, port, dst, _ in _connections(trial.diagram) if dst == "planner"}
    assert ("station", "measured_efforts") in feeds
    assert not {port for _, port in feeds} & {"body_poses", "contact_results", "plant_state", "query_object"}
    unguarded = build_trial(TrialOptions(objects=3, seed=7, tool_rules={"suction_hidden_rule": "placement"}))
    planner = unguarded.planner_system
    names = {planner.get_input_port(i).get_name() for i in range(planner.num_input_ports())}
    assert names == PLANNER_INPUTS | {"measured_efforts"} and "suction_hidden_rule" not in unguarded.tool_rules
    weightless = build_trial(TrialOptions(objects=3, seed=7, tool_rules={"suction_hidden_rule": "placement",
                                                                         "max_suction_moment": float("inf")}))
    planner = weightless.planner_system
    names = {planner.get_input_port(i).get_name() for i in range(planner.num_input_ports())}
    assert names == PLANNER_INPUTS


def test_the_evaluator_scores_a_moved_target_where_it_stands(trial):
    """A target a move pushed deeper and turned covers fewer pixels than at its start; seen whole there, it still
    reads as wholly visible (its unoccluded pixels are ray-cast where it stands now)."""
    import math

    from pydrake.math import RigidTransform, RollPitchYaw

    context = trial.diagram.CreateDefaultContext()
    plant = trial.plant
    pc = plant.GetMyContextFromRoot(context)
    X_WS = trial.X_WS
    for obj in trial.scene.objects:  # every occluder out of the camera's view
        plant.SetFreeBodyPose(pc, plant.GetBodyByName(obj.name), RigidTransform([10.0, 10.0, 0.0]))
    ec = trial.evaluator.GetMyContextFromRoot(context)
    assert trial.evaluator.visible_fraction(ec) > 0.97
    start_pixels = trial.evaluator._target_pixels[1]
    c = trial.scene.target.center
    X_ST = RigidTransform(RollPitchYaw(0.0, 0.0, math.radians(40.0)), [c[0], c[1] + 0.12, c[2]])
    plant.SetFreeBodyPose(pc, plant.GetBodyByName("target"), X_WS @ X_ST)
    fraction = trial.evaluator.visible_fraction(ec)
    assert trial.evaluator._target_pixels[1] < 0.9 * start_pixels  # deeper: fewer pixels than at the start
    assert fraction > 0.97
    pose = trial.evaluator.target_pose(ec)
    assert abs(pose[1, 3] - (c[1] + 0.12)) < 1e-9
