"""Ground-truth occupancy against a brute-force reference: every grid placement, every surface point, one ray
each, no pruning, no lattice, no height argument."""

import dataclasses

import numpy as np
import pytest

from slax_drake.occupancy import (
    collision_free,
    compute_occupancy,
    grid_placements,
    placements_hidden,
    project_placements,
)
from slax_drake.scene import sample_scene
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.surface import box_surface_points

SIZES = ((0.06, 0.06, 0.03), (0.06, 0.06, 0.06), (0.06, 0.06, 0.12))


def brute_force_hidden(scene, size, step, spacing=0.005):
    """Reference: (centres (K, 2), hidden bool (K,)) for every in-bay grid placement."""
    centers = grid_placements(scene, size, step)
    free = collision_free(scene, size, centers)
    points, _ = box_surface_points(tuple(size), spacing)
    raycaster = SceneRaycaster(scene)
    hidden = np.zeros(len(centers), dtype=bool)
    for k in np.flatnonzero(free):
        p = points + np.array([centers[k, 0], centers[k, 1], size[2] / 2.0])
        hidden[k] = not raycaster.visible(scene.camera.position, p).any()
    return centers, hidden


def _keys(xy, step):
    return {(int(round(x / step)), int(round(y / step))) for x, y in xy}


def _disagreements_off_boundary(fast_keys, ref_keys):
    """Placements on which the fast path and the reference differ although every grid neighbour (8-connected)
    has the same reference status as the placement itself, i.e. not within one grid step of the boundary."""
    bad = []
    for key in fast_keys ^ ref_keys:
        status = key in ref_keys
        near = [(key[0] + dx, key[1] + dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1) if dx or dy]
        if all((n in ref_keys) == status for n in near):
            bad.append(key)
    return bad


CASES = [(n, seed, SIZES[seed % 3]) for seed, n in enumerate((2, 4, 6, 8, 10, 12, 3, 5, 7, 9, 11, 8))]


@pytest.mark.parametrize("num_objects,seed,size", CASES)
def test_agrees_with_brute_force_reference(sim_scenario, num_objects, seed, size):
    scene = sample_scene(sim_scenario, num_objects, 100 + seed)
    step = 0.01
    camera = scene.camera.with_resolution(160, 120)
    occ = compute_occupancy(scene, size, step, camera)
    centers, hidden = brute_force_hidden(scene, size, step)
    fast, ref = _keys(occ.hidden_xy, step), _keys(centers[hidden], step)
    assert not _disagreements_off_boundary(fast, ref)
    # In practice the two agree exactly; the distribution then equals the definition's direct projection.
    assert len(fast ^ ref) <= max(2, len(ref) // 50)
    if fast == ref:
        direct = project_placements(camera, scene.camera.position, size, centers[hidden], 0.005)
        assert np.abs(direct - occ.p2d).sum() < 0.02  # only points on pixel borders may round apart


def test_fine_grid_agrees_with_reference(sim_scenario):
    scene = sample_scene(sim_scenario, 8, 7)
    occ = compute_occupancy(scene, (0.06, 0.06, 0.06), 0.005, scene.camera.with_resolution(160, 120))
    centers, hidden = brute_force_hidden(scene, (0.06, 0.06, 0.06), 0.005)
    assert not _disagreements_off_boundary(_keys(occ.hidden_xy, 0.005), _keys(centers[hidden], 0.005))


@pytest.mark.parametrize("size", SIZES)
def test_true_target_is_hidden_feasible(sim_scenario, size):
    for seed in range(8):
        scene = sample_scene(sim_scenario, 4 + seed, 500 + seed, target_size=size)
        center = scene.target.center[:2]
        assert placements_hidden(scene, size, center[None, :])[0]
        occ = compute_occupancy(scene, size, 0.005, scene.camera.with_resolution(160, 120))
        assert occ.num_hidden > 0  # the hidden region around the true target holds grid placements too


def test_distributions_normalised(sim_scenario):
    scene = sample_scene(sim_scenario, 8, 3)
    camera = scene.camera.with_resolution(160, 120)
    for size in SIZES:
        occ = compute_occupancy(scene, size, 0.01, camera)
        assert occ.p2d.shape == (120, 160) and occ.p2d.dtype == np.float32
        assert occ.p1d.shape == (160,) and occ.p1d.dtype == np.float32
        assert (occ.p2d >= 0).all() and occ.num_hidden > 0
        assert occ.p2d.sum() == pytest.approx(1.0, abs=1e-5)
        np.testing.assert_allclose(occ.p1d, occ.p2d.sum(axis=0), atol=1e-7)
        assert occ.hidden_xy.shape == (occ.num_hidden, 2) and occ.hidden_xy.dtype == np.float64


def test_empty_shelf_has_no_hidden_placement(sim_scenario):
    scene = sample_scene(sim_scenario, 4, 0).with_objects(())
    occ = compute_occupancy(scene, (0.06, 0.06, 0.06), 0.01, scene.camera.with_resolution(160, 120))
    assert occ.num_hidden == 0 and occ.hidden_xy.shape == (0, 2)
    assert not occ.p2d.any() and not occ.p1d.any()


def test_scene_target_is_ignored_and_result_deterministic(sim_scenario):
    scene = sample_scene(sim_scenario, 8, 11)
    a = compute_occupancy(scene, (0.06, 0.06, 0.06), 0.01)
    b = compute_occupancy(dataclasses.replace(scene, target=None), (0.06, 0.06, 0.06), 0.01)
    np.testing.assert_array_equal(a.hidden_xy, b.hidden_xy)
    np.testing.assert_array_equal(a.p2d, b.p2d)
    assert a.p2d.shape == (scene.camera.height, scene.camera.width)


def test_unaligned_grid_uses_the_direct_definition(sim_scenario):
    scene = sample_scene(sim_scenario, 6, 21)
    step = 0.007  # not a multiple of the 5 mm surface samples: evaluated placement by placement
    occ = compute_occupancy(scene, (0.06, 0.06, 0.06), step, scene.camera.with_resolution(160, 120))
    centers, hidden = brute_force_hidden(scene, (0.06, 0.06, 0.06), step)
    assert _keys(occ.hidden_xy, step) == _keys(centers[hidden], step)


def test_bad_arguments_raise(sim_scenario):
    scene = sample_scene(sim_scenario, 2, 0)
    with pytest.raises(ValueError, match="target_size"):
        compute_occupancy(scene, (0.06, 0.06), 0.01)
    with pytest.raises(ValueError, match="grid_step"):
        compute_occupancy(scene, (0.06, 0.06, 0.06), 0.0)
