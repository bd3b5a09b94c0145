"""The estimator's extent ranges on rendered Table I-like scenes: the true footprint lies inside the range."""

from pathlib import Path

import pytest

from slax_drake.config import load_scenario
from slax_drake.perception.estimator import EstimatorConfig, estimate_objects
from slax_drake.perception.observation import labelled_frame
from slax_drake.scene import sample_scene
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.raycast import SceneRaycaster

REPO = Path(__file__).resolve().parents[2]
DENSITIES = (4, 6, 8, 10)
SEEDS = range(1000, 1010)
TOLERANCE = 0.005  # m: the most rectangle is grown by this before the true footprint is compared
AREA_OUT = 1e-4  # m^2 of the true footprint allowed outside it (1 cm^2: polygon round-off)


_FRAMES: dict = {}


def frames(width: int) -> list:
    """(scene, observation) per density and seed at ``width`` px, rendered once per test session."""
    if width not in _FRAMES:
        _FRAMES[width] = list(_frames(width))
    return _FRAMES[width]


def _frames(width: int):
    scenario = load_scenario(REPO / "sim_configs" / "sim_shelf.yaml")
    for n in DENSITIES:
        for seed in SEEDS:
            scene = sample_scene(scenario, n, seed)
            camera = scene.camera.with_resolution(width, int(round(scene.camera.height * width / scene.camera.width)))
            depth, labels = SceneRaycaster(scene, include_target=True).render(camera)
            yield scene, labelled_frame(depth, labels, n, camera)


@pytest.mark.parametrize("width,share", [pytest.param(640, 0.99, marks=pytest.mark.slow), (160, 0.97)])  # full size: slow step
def test_true_footprint_lies_inside_the_extent_range(width, share):
    checked, inside, misses = 0, 0, []
    for scene, obs in frames(width):
        for h in estimate_objects(obs, scene.shelf):
            true = Footprint.of(scene.objects[h.segment_id - 1]).polygon()  # label segmentation: id = index + 1
            extent = h.uncertainty.extent
            out = true.difference(extent.most().polygon().buffer(TOLERANCE)).area
            checked += 1
            if out <= AREA_OUT:
                inside += 1
            else:
                misses.append((len(scene.objects), scene.seed, h.segment_id, round(out * 1e4, 1)))
            # The range holds the observed part, and every edge lies at or beyond it.
            assert min(extent.growth()) >= 0
            assert extent.least().polygon().area <= extent.most().polygon().area + 1e-9
    assert checked >= 200
    assert inside >= share * checked, misses


def test_unseen_depth_reaches_past_the_smallest_object_prior():
    """Objects whose far side is hidden get a range deeper than the fixed 0.06 m prior, never past the back wall
    (along the box's axes: a turned range's corners may cross it)."""
    deeper = 0
    for scene, obs in frames(160):
        for h in estimate_objects(obs, scene.shelf):
            e = h.uncertainty.extent
            if abs(e.yaw) < 1e-9:  # an axis-aligned range: its edges are the ones stepped to the walls
                fp = e.most()
                assert abs(fp.x) + fp.half_x <= scene.shelf.width / 2 + 0.006
                assert fp.y + fp.half_y <= scene.shelf.depth / 2 + 0.006
            deeper += (e.most_hi[1] - e.least_lo[1]) > 0.06 + 1e-6
    assert deeper >= 20


def test_extent_ranges_can_be_switched_off():
    scene, obs = frames(160)[0]
    assert all(h.uncertainty.extent is None
               for h in estimate_objects(obs, scene.shelf, EstimatorConfig(extent_ranges=False)))
