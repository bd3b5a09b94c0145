"""slax-hindsight's per-object occlusion masks (Worlds.hidden_by: rays only to the points the empty shelf shows, cast
against the object alone, on the process's shared Embree device) equal the plain computation: every target point of
every world ray cast against the shelf and the object together, on a scene with its own device. These guard a
speed-up whose trials must stay identical (benchmarks/compare_trial_outputs.py)."""

import numpy as np
import pytest
from embreex import mesh_construction, rtcore_scene

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import scene_seed
from slax_drake.policies.hindsight import Worlds, possible_placements
from slax_drake.scene.raycast import VISIBILITY_EPS, SceneRaycaster, object_triangles, shelf_triangles
from slax_drake.scene.sampling import sample_scene

TARGET = (0.06, 0.06, 0.06)


@pytest.fixture(scope="module")
def scene():
    paper = load_scenario("sim_configs/table1.yaml")
    return sample_scene(paper, 10, scene_seed(0, 10, 1), target_size=TARGET)


def plain_visible(scene, objects, eye, points) -> np.ndarray:
    """Whether each point (N, 3) is seen from ``eye`` past the shelf and ``objects``: one Embree scene with its own
    device, every ray cast."""
    embree = rtcore_scene.EmbreeScene()
    for tris in [shelf_triangles(scene.shelf)] + [object_triangles(o) for o in objects]:
        mesh_construction.TriangleMesh(embree, tris.astype(np.float32))
    origins = np.ascontiguousarray(np.broadcast_to(eye, points.shape), dtype=np.float32)
    t = embree.run(origins, np.ascontiguousarray(points - eye, dtype=np.float32), query="DISTANCE").astype(float)
    return t >= 1.0 - VISIBILITY_EPS  # no hit: t is huge


def test_hidden_by_equals_rays_against_the_shelf_and_the_object(scene):
    centers = possible_placements(scene, TARGET, 0.01, 1e-9)
    worlds = Worlds(scene.with_objects(()), centers[:: max(1, len(centers) // 40)], TARGET, 0.8)
    eye = worlds.eye
    flat = worlds.points.reshape(-1, 3)
    hidden_points = 0
    for obj in scene.objects:
        expected = (worlds.shown & ~plain_visible(scene, (obj,), eye, flat).reshape(worlds.shown.shape))
        got = worlds.hidden_by(obj)
        assert np.array_equal(got, expected), obj.name
        hidden_points += int(got.sum())
    assert hidden_points > 0  # the objects hide some of the worlds' points


def test_a_scene_on_the_shared_device_sees_what_one_on_its_own_device_sees(scene):
    eye = np.asarray(scene.camera.position, dtype=float)
    rng = np.random.default_rng(0)
    points = np.column_stack([rng.uniform(-0.3, 0.3, 4000), rng.uniform(-0.3, 0.3, 4000), rng.uniform(0, 0.3, 4000)])
    got = SceneRaycaster(scene).visible(eye, points)
    expected = plain_visible(scene, scene.objects, eye, points)
    assert np.array_equal(got, expected)
    assert 0 < got.sum() < len(got)
