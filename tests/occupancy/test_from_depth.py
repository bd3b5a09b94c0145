"""Target occupancy from a depth image alone (slax_drake.occupancy.from_depth) against the ray-cast ground truth
(compute_occupancy) on rendered scenes, and its own definitions."""

import numpy as np
import pytest

from slax_drake.config import load_scenario
from slax_drake.occupancy import compute_occupancy
from slax_drake.errors import DepthOccupancyError
from slax_drake.occupancy.from_depth import occupancy_from_depth
from slax_drake.scene import sample_scene
from slax_drake.scene.raycast import SceneRaycaster

SIZE = (0.06, 0.06, 0.06)


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("sim_configs/table1.yaml")


def _iou(a, b) -> float:
    return float((a & b).sum()) / max(1, int((a | b).sum()))


def _coarse(scene):
    return scene.camera.with_resolution(160, 120)


@pytest.mark.parametrize("objects,seed", [(4, 0), (6, 3), (10, 1)])
def test_agrees_with_ray_cast_occupancy(scenario, objects, seed):
    scene = sample_scene(scenario, objects, seed, target_size=SIZE)
    cam = _coarse(scene)
    truth = compute_occupancy(scene, SIZE, 0.01, camera=cam, surface_spacing=0.01)
    depth, _ = SceneRaycaster(scene).render(cam)
    got = occupancy_from_depth(depth, cam, scene.shelf, SIZE, obstacles=scene.objects)
    assert got.p1d.shape == truth.p1d.shape
    assert _iou(got.p1d > 0, truth.p1d > 0) >= 0.9
    placed_truth = set(map(tuple, np.round(truth.hidden_xy, 3)))
    placed = set(map(tuple, np.round(got.hidden_xy, 3)))
    assert len(placed & placed_truth) / len(placed | placed_truth) >= 0.85
    assert abs(float(got.p2d.sum()) - 1.0) < 1e-4


def test_empty_shelf_hides_nothing_in_view(scenario):
    scene = sample_scene(scenario, 4, 0, target_size=SIZE).with_objects(())
    cam = _coarse(scene)
    depth, _ = SceneRaycaster(scene).render(cam)
    got = occupancy_from_depth(depth, cam, scene.shelf, SIZE)
    truth = compute_occupancy(scene, SIZE, 0.01, camera=cam, surface_spacing=0.01)
    assert got.num_hidden <= truth.num_hidden + 5


def test_no_return_pixels_hide_and_obstacles_exclude(scenario):
    scene = sample_scene(scenario, 4, 0, target_size=SIZE).with_objects(())
    cam = _coarse(scene)
    depth, _ = SceneRaycaster(scene).render(cam)
    blind = np.zeros_like(depth)  # nothing returned: everything in the bay could hide the target
    everything = occupancy_from_depth(blind, cam, scene.shelf, SIZE)
    assert everything.num_hidden > 100 * max(1, occupancy_from_depth(depth, cam, scene.shelf, SIZE).num_hidden)
    some = sample_scene(scenario, 6, 2, target_size=SIZE)
    fewer = occupancy_from_depth(blind, cam, scene.shelf, SIZE, obstacles=some.objects)
    assert fewer.num_hidden < everything.num_hidden


def test_wrong_shape_refused(scenario):
    scene = sample_scene(scenario, 4, 0, target_size=SIZE)
    with pytest.raises(DepthOccupancyError, match="does not fit"):
        occupancy_from_depth(np.zeros((10, 10), np.float32), _coarse(scene), scene.shelf, SIZE)
