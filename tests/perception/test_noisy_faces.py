"""The estimator on noisy frames: the range offset and noise read off the back panel, and the faces the suction
cup seals on placed where the real faces are (issue 16 item 4; the seal that never formed on a noisy frame)."""

import functools
import math
from pathlib import Path

import numpy as np
import shapely

from slax_drake.config import load_scenario
from slax_drake.perception.estimator import EstimatorConfig, estimate_objects
from slax_drake.perception.observation import Observation, occluder_segmentation
from slax_drake.perception.range_offset import shelf_range_calibration, without_range_offset
from slax_drake.perception.sensor_noise import L515Noise, l515_depth_noise
from slax_drake.planning.waypoints import SEAL_PRESS
from slax_drake.shelf.actions import ActionModel
from slax_drake.shelf.rules import ToolConfig
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.sampling import sample_scene

REPO = Path(__file__).resolve().parents[2]
SEEDS = (31, 32, 33, 34, 35, 36, 37, 38)  # range offsets from -5.3 to +4.8 mm
UNCORRECTED = EstimatorConfig(correct_range_offset=False, face_from_points=False)


def nearest(image, width, height):
    h, w = image.shape
    rows = np.clip(np.rint((np.arange(height) + 0.5) * h / height - 0.5), 0, h - 1).astype(int)
    cols = np.clip(np.rint((np.arange(width) + 0.5) * w / width - 0.5), 0, w - 1).astype(int)
    return image[np.ix_(rows, cols)]


@functools.lru_cache(maxsize=None)
def frame(seed, objects=6):
    """(scene, clean frame, noisy frame): a Table I scene ray-cast at 640x480, the L515 model (seeded by the scene
    seed), nearest-pixel to 160x120 as the trial's perception does, the render's labels as segmentation."""
    scenario = load_scenario(REPO / "sim_configs" / "table1.yaml")
    scene = sample_scene(scenario, objects, seed, target_size=tuple(scenario.target.sizes[0]))
    camera = scene.camera
    depth, labels = SceneRaycaster(scene, include_target=True).render(camera)
    small = camera.with_resolution(160, 120)
    labels = nearest(labels, 160, 120)
    n = len(scene.objects)
    target = labels == n + 1
    segments = occluder_segmentation(np.where((labels >= 1) & (labels <= n), labels, 0), target)
    made = [Observation(nearest(d, 160, 120), segments, target, small, min_valid_fraction=0.0)
            for d in (depth, l515_depth_noise(depth, camera, seed, 0))]
    return (scene, *made)


def frames(seeds):
    return [frame(s) for s in seeds]


def offset_of(seed, noise=L515Noise(), depth=0.9):
    """The L515 model's range offset for ``seed`` at ``depth`` metres (its accuracy term)."""
    u = np.random.default_rng((int(seed), 0xACC)).uniform(-1.0, 1.0)
    return u * (noise.accuracy_near + noise.accuracy_per_m * depth)


def contact_gaps(scene, hypotheses):
    """Per suction contact the action model puts on a hypothesis: the distance (m) from the cup's seal point
    along the tube's axis to the true object's surface (positive: the cup stops short of the real face)."""
    model = ActionModel(scene.shelf, scene.camera.position[:2], ToolConfig.build("station"))
    gaps = []
    for h in hypotheses:
        contact = model.suction_contact(h.object)
        if contact is None or h.pixels < 30:
            continue
        yaw = model.tool_yaw(h.object, contact[:2])
        axis = np.array([-math.sin(yaw), math.cos(yaw)])
        start = np.array(contact[:2]) + SEAL_PRESS * axis
        polygon = Footprint.of(scene.objects[h.segment_id - 1]).polygon(segments=180)
        # march along the axis in 0.1 mm steps from 3 cm before the seal point to the first point inside
        steps = np.arange(-0.03, 0.03, 1e-4)
        points = start + steps[:, None] * axis
        inside = shapely.contains_xy(polygon, points[:, 0], points[:, 1])
        if inside.any():
            gaps.append(float(steps[int(np.argmax(inside))]))
    return np.array(gaps)


def test_range_calibration_reads_the_offset_and_noise_off_the_back_panel():
    for scene, clean, noisy in frames(SEEDS[:4]):
        calibration = shelf_range_calibration(noisy, scene.shelf)
        assert calibration.pixels >= 200
        assert abs(calibration.offset - offset_of(scene.seed, depth=1.0)) < 0.001, scene.seed
        sigma = L515Noise().sigma(1.0)  # the panel stands about 1 m from the camera
        assert 0.7 * sigma < calibration.sigma < 1.4 * sigma
        still = shelf_range_calibration(clean, scene.shelf)
        assert still.offset == 0.0 and still.sigma < 1e-4


def test_taking_the_offset_off_keeps_missing_returns_missing():
    scene, _, noisy = frame(SEEDS[0])
    moved = without_range_offset(noisy, 0.004)
    assert np.array_equal(moved.depth > 0, noisy.depth > 0)
    np.testing.assert_allclose(moved.depth[noisy.depth > 0], noisy.depth[noisy.depth > 0] - 0.004, atol=1e-6)
    assert without_range_offset(noisy, 0.0) is noisy


def test_clean_frames_give_the_same_hypotheses_as_without_the_corrections():
    for scene, clean, _ in frames(SEEDS[4:7]):
        a = estimate_objects(clean, scene.shelf)
        b = estimate_objects(clean, scene.shelf, UNCORRECTED)
        assert [h.object.name for h in a] == [h.object.name for h in b]
        for ha, hb in zip(a, b):
            np.testing.assert_array_equal(ha.object.X_SO, hb.object.X_SO)
            assert ha.object.size == hb.object.size


def test_on_noisy_frames_the_cup_meets_the_real_face():
    """Scenes whose range offset reads nearer than true (the seal failures of the noisy physics run) and farther:
    the cup's seal point lies within 2 mm of the true face at the median (the station's cup pulls within 5 mm),
    and rarely more than 2.5 mm short, where the estimator without the corrections often is."""
    seeds = SEEDS
    cases = frames(seeds)
    assert min(offset_of(s) for s in seeds) < -0.003 and max(offset_of(s) for s in seeds) > 0.003
    corrected, uncorrected, clean = [], [], []
    for scene, clean_frame, noisy in cases:
        corrected.append(contact_gaps(scene, estimate_objects(noisy, scene.shelf)))
        uncorrected.append(contact_gaps(scene, estimate_objects(noisy, scene.shelf, UNCORRECTED)))
        clean.append(contact_gaps(scene, estimate_objects(clean_frame, scene.shelf)))
    near = np.concatenate([g for s, g in zip(seeds, corrected) if offset_of(s) < -0.003])
    corrected, uncorrected, clean = (np.concatenate(g) for g in (corrected, uncorrected, clean))
    assert len(corrected) >= 20 and len(near) >= 5
    assert abs(np.median(corrected)) < 0.002
    assert abs(np.median(near)) < 0.002
    assert np.mean(corrected < 0.005) >= np.mean(clean < 0.005) - 0.05  # as many within the cup's pull as clean
    # Short of the face by more than half the cup's 5 mm reach (under half the pull): rare, and far rarer than
    # without the corrections.
    assert np.mean(corrected > 0.0025) <= 0.1
    assert np.mean(uncorrected > 0.0025) >= 0.25
