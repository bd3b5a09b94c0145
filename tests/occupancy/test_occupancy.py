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


# ---- the fast paths against the plain ones -------------------------------------------------------------


def test_shared_sizes_equal_separate_calls(sim_scenario):
    from slax_drake.occupancy import compute_occupancies

    sizes = (*SIZES, (0.04, 0.08, 0.05))  # the three ratios share a footprint; the last one does not
    for n, seed in ((3, 31), (8, 32), (12, 33)):
        scene = sample_scene(sim_scenario, n, seed)
        camera = scene.camera.with_resolution(160, 120)
        together = compute_occupancies(scene, sizes, 0.005, camera)
        for size, occ in zip(sizes, together):
            alone = compute_occupancy(scene, size, 0.005, camera)
            assert occ.target_size == alone.target_size == size
            np.testing.assert_array_equal(occ.hidden_xy, alone.hidden_xy)
            np.testing.assert_array_equal(occ.p2d, alone.p2d)
            np.testing.assert_array_equal(occ.p1d, alone.p1d)
        assert together[0].num_hidden >= together[1].num_hidden >= together[2].num_hidden  # taller: fewer


def _lattice_cases(sim_scenario):
    from slax_drake.occupancy.hidden import _lattice

    for n, seed in ((4, 41), (8, 42), (12, 43)):
        scene = sample_scene(sim_scenario, n, seed)
        raycaster = SceneRaycaster(scene)
        for size in SIZES:
            lattice = _lattice(scene.shelf.width, scene.shelf.depth, size, 0.005, 0.005)
            yield scene, lattice, lattice.hidden_mask(scene, raycaster, lattice.candidates(scene))


def test_x_aligned_projection_equals_generic_projection(sim_scenario):
    from slax_drake.occupancy.hidden import _x_aligned

    for scene, lattice, hidden in _lattice_cases(sim_scenario):
        for camera in (scene.camera, scene.camera.with_resolution(256, 192)):
            assert _x_aligned(camera) and hidden.any()
            fast = lattice._counts_x_aligned(hidden, camera, scene.camera.position)
            plain = lattice._counts_generic(hidden, camera, scene.camera.position)
            assert fast.sum() > 0
            np.testing.assert_array_equal(fast, plain)


def test_grid_collision_test_equals_collision_free(sim_scenario):
    for scene, lattice, _ in _lattice_cases(sim_scenario):
        gx, gy = np.meshgrid(lattice.cx, lattice.cy, indexing="ij")
        plain = collision_free(scene, lattice.size, np.column_stack([gx.ravel(), gy.ravel()])).reshape(gx.shape)
        fast = lattice._collision_free(scene)
        assert 0 < fast.sum() < fast.size
        np.testing.assert_array_equal(fast, plain)


def test_window_sums_and_spreads_against_loops():
    from slax_drake.occupancy.hidden import _box_sums, _spread, _spread_1d

    rng = np.random.default_rng(0)
    for stride_a, stride_b, na, nb in ((1, 1, 3, 2), (2, 3, 5, 7), (2, 2, 13, 13)):
        ci, cj = 6, 5
        shape = ((ci - 1) * stride_a + na, (cj - 1) * stride_b + nb)
        values = rng.random(shape) < 0.3
        sums = _box_sums(values, stride_a, stride_b, ci, cj, na, nb)
        marks = rng.random((ci, cj)) < 0.5
        cover = np.zeros(shape, dtype=np.int64)
        for i in range(ci):
            for j in range(cj):
                a, b = i * stride_a, j * stride_b
                assert sums[i, j] == values[a:a + na, b:b + nb].sum()
                cover[a:a + na, b:b + nb] += marks[i, j]
        np.testing.assert_array_equal(_spread(marks, stride_a, stride_b, na, nb, shape), cover)
        cover_a = np.zeros((shape[0], cj), dtype=np.int64)
        for i in range(ci):
            cover_a[i * stride_a:i * stride_a + na] += marks[i]
        np.testing.assert_array_equal(_spread_1d(marks, stride_a, na, shape[0]), cover_a)


def test_rolled_camera_uses_the_generic_projection(sim_scenario):
    """A camera whose x axis is not the shelf's (here rolled by 3 degrees) takes the generic projection,
    which still matches the definition's direct projection."""
    from slax_drake.occupancy.hidden import _x_aligned

    scene = sample_scene(sim_scenario, 6, 51)
    c, s = np.cos(np.radians(3.0)), np.sin(np.radians(3.0))
    X_SC = scene.camera.X_SC.copy()
    X_SC[:3, :3] = X_SC[:3, :3] @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # about the optical axis
    camera = dataclasses.replace(scene.camera.with_resolution(160, 120), X_SC=X_SC)
    assert not _x_aligned(camera)
    size = (0.06, 0.06, 0.06)
    occ = compute_occupancy(scene, size, 0.01, camera)
    assert occ.num_hidden > 0
    direct = project_placements(camera, scene.camera.position, size, occ.hidden_xy, 0.005)
    assert np.abs(direct - occ.p2d).sum() < 0.02


def test_per_footprint_caches_give_what_a_fresh_lattice_gives(sim_scenario):
    """The lattice keeps each footprint's collision window and shadow polygon (the policies evaluate many
    arrangements that share most objects): the occupancy of every arrangement of a walk, computed with those
    caches warm, equals the one computed on a fresh lattice with nothing kept."""
    from slax_drake.occupancy.hidden import _lattice

    scene = sample_scene(sim_scenario, 8, 44)
    rng = np.random.default_rng(0)
    arrangements = [scene.objects]
    for _ in range(6):  # move one object at a time, as a policy's candidates do
        objects = list(arrangements[-1])
        k = int(rng.integers(len(objects)))
        objects[k] = objects[k].moved_to(float(objects[k].center[0]) + float(rng.uniform(-0.05, 0.05)),
                                         float(objects[k].center[1]))
        arrangements.append(tuple(objects))
    warm = [compute_occupancy(scene.with_objects(a), SIZES[1], 0.01) for a in arrangements + arrangements]
    hidden_total = 0
    for k, a in enumerate(arrangements + arrangements):
        _lattice.cache_clear()
        cold = compute_occupancy(scene.with_objects(a), SIZES[1], 0.01)
        np.testing.assert_array_equal(warm[k].hidden_xy, cold.hidden_xy)
        np.testing.assert_array_equal(warm[k].p2d, cold.p2d)
        hidden_total += cold.num_hidden
    assert hidden_total > 0
