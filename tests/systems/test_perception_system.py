"""PerceptionSystem (Drake LeafSystem), the policies' learned distribution model and depth-only segmentation."""

import numpy as np
import pytest
import torch
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource
from pydrake.systems.sensors import ImageDepth32F

from slax_drake.perception.distribution_model import LearnedDistribution
from slax_drake.errors import ImageSizeError
from slax_drake.perception.inference import OccupancyPredictor
from slax_drake.perception.network import NetworkConfig, OccupancyUNet
from slax_drake.perception.segmentation import instance_mean_iou, segment_depth
from slax_drake.perception.weights import make_header, save_weights
from slax_drake.scene import sample_scene
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.systems.perception_system import PerceptionSystem

TINY = NetworkConfig(width=32, height=24, base_channels=4, levels=3)


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory):
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("model") / "model.pt"
    save_weights(path, OccupancyUNet(TINY), make_header(TINY, support_threshold_1d=0.5, support_threshold_2d=0.5))
    return path


@pytest.fixture(scope="module")
def scene(sim_scenario):
    return sample_scene(sim_scenario, 6, 3)


def rendered(scene, width, height):
    camera = scene.camera.with_resolution(width, height)
    depth, labels = SceneRaycaster(scene).render(camera)
    return camera, depth.astype(np.float32), labels


def test_perception_system_ports_evaluate_lazily(tiny_model, scene):
    _, depth, _ = rendered(scene, 32, 24)
    image = ImageDepth32F(32, 24)
    image.mutable_data[:, :, 0] = np.where(depth > 0, depth, np.inf)  # Drake marks no return as +inf
    builder = DiagramBuilder()
    source = builder.AddSystem(ConstantValueSource(AbstractValue.Make(image)))
    perception = builder.AddSystem(PerceptionSystem(scene.camera, scene.shelf, (0.06, 0.06, 0.12), model=tiny_model))
    builder.Connect(source.get_output_port(), perception.GetInputPort("depth_image"))
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(0.5)
    assert perception.network_evaluations == 0 and perception.segmentations == 0
    context = perception.GetMyContextFromRoot(simulator.get_context())
    p1 = perception.GetOutputPort("occupancy_1d").Eval(context)
    p2 = perception.GetOutputPort("occupancy_2d").Eval(context)
    assert perception.network_evaluations == 1  # one network run serves both ports
    expected = OccupancyPredictor(tiny_model).predict(depth, head=2)
    assert np.allclose(p1, expected.p1d[0], atol=1e-6) and np.allclose(p2, expected.p2d[0], atol=1e-6)
    assert p1.shape == (32,) and p2.shape == (24, 32) and p1.sum() == pytest.approx(1.0)
    labels = perception.GetOutputPort("segmentation").Eval(context)
    assert labels.data.shape == (24, 32, 1) and perception.segmentations == 1
    camera = scene.camera.with_resolution(32, 24)
    assert np.array_equal(labels.data[:, :, 0], segment_depth(depth, camera, scene.shelf))
    perception.GetOutputPort("occupancy_1d").Eval(context)
    assert perception.network_evaluations == 1  # cached until the depth image changes


def test_perception_system_rejects_a_camera_of_another_aspect(tiny_model, scene):
    with pytest.raises(ImageSizeError, match="does not have the aspect"):
        PerceptionSystem(scene.camera.with_resolution(64, 64), scene.shelf, model=tiny_model)


def test_learned_distribution_renders_the_believed_scene(tiny_model, scene):
    model = LearnedDistribution((0.06, 0.06, 0.06), model=tiny_model)
    p = model.distribution(scene)
    assert p.shape == (32,) and p.sum() == pytest.approx(1.0) and not p.flags.writeable
    assert model.distribution(scene) is p and model.calls == 1
    _, depth, _ = rendered(scene, 32, 24)
    assert np.allclose(p, OccupancyPredictor(tiny_model).predict(depth, head=1).p1d[0], atol=1e-6)
    fewer = model.distribution(scene.with_objects(scene.objects[:2]))
    assert model.calls == 2 and not np.array_equal(fewer, p)


def test_segmentation_of_rendered_scenes_matches_the_label_images(sim_scenario):
    ious = []
    for seed in range(4):
        scene = sample_scene(sim_scenario, 6, seed)
        camera, depth, labels = rendered(scene, 256, 192)
        truth = np.where((labels > 0) & (labels <= len(scene.objects)), labels, 0)
        predicted = segment_depth(depth, camera, scene.shelf)
        assert predicted.dtype == np.int32 and predicted.shape == depth.shape
        # No object pixel is claimed on the shelf's panels far from any object edge.
        assert (predicted[labels == 0] > 0).mean() < 0.02
        ious.append(instance_mean_iou(predicted, truth, min_true_pixels=10))
    assert np.mean(ious) > 0.6, ious  # measured 0.76 over 10 scenes of 8 objects at this resolution


def test_segmentation_separates_two_boxes_and_checks_the_size(sim_scenario):
    from slax_drake.scene.model import SceneObject, planar_pose

    base = sample_scene(sim_scenario, 2, 0)
    objects = (
        SceneObject("a", "box", (0.10, 0.10, 0.15), planar_pose(-0.15, 0.0, 0.075, 0.0)),
        SceneObject("b", "box", (0.10, 0.10, 0.10), planar_pose(0.12, -0.1, 0.05, 0.0)),
    )
    scene = base.with_objects(objects)
    camera, depth, labels = rendered(scene, 128, 96)
    predicted = segment_depth(depth, camera, scene.shelf)
    assert predicted.max() == 2
    truth = np.where((labels > 0) & (labels <= 2), labels, 0)
    assert instance_mean_iou(predicted, truth) > 0.85
    with pytest.raises(ImageSizeError, match="camera is 128x96"):
        segment_depth(depth[:, :64], camera, scene.shelf)


def test_instance_mean_iou_matches_one_to_one():
    truth = np.zeros((4, 6), int)
    truth[:, :3] = 1
    truth[:, 3:] = 2
    assert instance_mean_iou(truth, truth) == 1.0
    assert instance_mean_iou(np.where(truth > 0, 7, 0), truth) == pytest.approx(0.25)  # merged: 0.5 and 0 -> 0.25
    assert instance_mean_iou(np.zeros_like(truth), truth) == 0.0
    assert instance_mean_iou(np.zeros_like(truth), np.zeros_like(truth)) == 1.0
