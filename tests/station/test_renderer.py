"""The Drake renderer (RenderEngineVtk through an RgbdSensor) against analytic depth and the Embree ray caster."""

import dataclasses

import numpy as np
import pytest

from slax_drake.scene import SceneObject, planar_pose, sample_scene
from slax_drake.scene.camera import camera_pose
from slax_drake.scene.raycast import SceneRaycaster

pytest.importorskip("pydrake")


@pytest.fixture(scope="module")
def scenes(sim_scenario):
    return [sample_scene(sim_scenario, n, 40 + n) for n in (3, 8, 12)]


@pytest.fixture(scope="module")
def renderer(scenes):
    from slax_drake.station.renderer import SceneRenderer

    return SceneRenderer(scenes[0].camera.with_resolution(256, 192))


def test_known_box_depth_is_analytic(sim_scenario):
    from slax_drake.station.renderer import SceneRenderer

    base = sample_scene(sim_scenario, 2, 0)
    camera = dataclasses.replace(base.camera.with_resolution(160, 120), X_SC=camera_pose([0.0, -0.75, 0.10], 0.0))
    box = SceneObject("object_0", "box", (0.20, 0.10, 0.20), planar_pose(0.0, -0.10, 0.10, 0.0))
    scene = dataclasses.replace(base, camera=camera, objects=(box,), target=None)
    depth, label = SceneRenderer(camera).render(scene)
    # The box's front face is the plane y = -0.15, perpendicular to the optical axis: depth 0.60 m.
    u = np.arange(160)
    v = np.arange(120)
    x = (u - camera.cx) / camera.fx * 0.60
    z = 0.10 - (v - camera.cy) / camera.fy * 0.60
    inner = (np.abs(z)[:, None] < 1) & (np.abs(x)[None, :] < 0.09) & (z[:, None] > 0.01) & (z[:, None] < 0.19)
    assert inner.sum() > 200
    assert np.abs(depth[inner] - 0.60).max() < 1e-3
    assert (label[inner] == 1).all()
    assert depth.dtype == np.float32


def test_matches_ray_caster_and_reuses_the_diagram(renderer, scenes):
    first = renderer.render(scenes[0])
    for scene in scenes:
        depth, label = renderer.render(scene)
        ref_depth, ref_label = SceneRaycaster(scene, include_target=True).render(renderer.camera)
        both = (depth > 0) & (ref_depth > 0)
        assert ((depth > 0) == (ref_depth > 0)).mean() > 0.99 and both.mean() > 0.5
        assert np.median(np.abs(depth - ref_depth)[both]) < 1e-4
        # Cylinders are smooth in VTK and 32-sided prisms in Embree: only their silhouettes may differ.
        assert (label == ref_label).mean() > 0.99
    again = renderer.render(scenes[0])
    np.testing.assert_array_equal(first[0], again[0])
    np.testing.assert_array_equal(first[1], again[1])


def test_target_pixels_inside_projected_support(renderer, scenes):
    for scene in scenes:
        visible = scene.with_objects(())  # remove the occluders so that the target shows
        depth, label = renderer.render(visible)
        target_label = 1  # no objects: shelf 0, target 1
        mask = label == target_label
        assert mask.sum() > 20
        t = scene.target
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * np.asarray(t.size) / 2
        uv = renderer.camera.project(corners + t.center)
        vv, uu = np.nonzero(mask)
        # Every target pixel's centre lies in the projected box's bounding rectangle (grown by one pixel).
        assert uu.min() >= uv[:, 0].min() - 1 and uu.max() <= uv[:, 0].max() + 1
        assert vv.min() >= uv[:, 1].min() - 1 and vv.max() <= uv[:, 1].max() + 1
        # And the centre of the target projects onto a target pixel.
        cu, cv = np.rint(renderer.camera.project(t.center + [0, 0, t.size[2] / 2 - 1e-3])).astype(int)
        assert mask[cv, cu]
    # In the sampled scenes the target is completely hidden: no target pixel at all.
    for scene in scenes:
        _, label = renderer.render(scene)
        assert not (label == len(scene.objects) + 1).any()


def test_shelf_change_and_object_count_changes_match_a_fresh_renderer(renderer, scenes, physical_scenario):
    """The renderer keeps the shelf's panels registered between scenes and swaps only objects and target:
    after scenes with another shelf and other object counts, each image equals that of a new renderer."""
    from slax_drake.station.renderer import SceneRenderer

    other_shelf = dataclasses.replace(sample_scene(physical_scenario, 5, 3), camera=scenes[0].camera)
    assert other_shelf.shelf != scenes[0].shelf
    for scene in (scenes[2], other_shelf, scenes[1].with_objects(()), scenes[1]):
        depth, label = renderer.render(scene)
        ref_depth, ref_label = SceneRenderer(renderer.camera).render(scene)
        np.testing.assert_array_equal(depth, ref_depth)
        np.testing.assert_array_equal(label, ref_label)
