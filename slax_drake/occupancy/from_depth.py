"""Target occupancy from a depth image alone: what a robot can compute from its camera, no object poses.

The definitions of :mod:`slax_drake.occupancy.hidden` with the ray caster replaced by the observed depth image:

- Placements: target centres (x, y) on the lattice ``grid_step * Z^2`` of the shelf frame S (metres), yaw 0,
  resting on the support surface, whose footprint lies inside the bay (the static shelf model: the shelf and
  the camera do not move relative to each other) and, when ``obstacles`` are given (e.g. the estimator's object
  hypotheses), clear of each of them (clearance 0).
- A target surface sample point (``scene.surface.box_surface_points``, ``surface_spacing`` apart, every face but
  the bottom) is *seen* when it projects into the image (nearest pixel centre), lies in front of the camera and
  its depth along the optical axis is less than the observed depth at that pixel minus ``margin``. A pixel with
  no return (depth 0) hides what projects onto it (nothing is known there), and so does the outside of the image.
- A placement is hidden when none of its sample points is seen. The shelf's panels need no model of their own:
  they are in the depth image like everything else.
- p2d / p1d: as in ``compute_occupancy`` (the eye-facing samples of every hidden placement projected into
  ``camera``, counted per pixel, normalised; p1d = p2d.sum(axis=0)).

For a noise-free depth image of a scene this is ``compute_occupancy`` with every ray replaced by a depth lookup at
the nearest pixel: they differ at silhouettes, within about a pixel's footprint (tests/occupancy/test_from_depth.py
and benchmarks/bench_occupancy_from_depth.py measure the agreement).

How it stays fast: every sample point of every placement lies on one 3D lattice (the fine x-y lattice of
``hidden._Lattice`` times the vertical faces' sample heights), whose pixel indices and depths are tabulated
once per camera. Per image, the test is one gather and one comparison per lattice point; "no sample seen" is
then two box sums: the top face's window at the top height, and the window's rim (the four vertical faces) over
every height.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slax_drake.occupancy.hidden import (
    DEFAULT_SURFACE_SPACING, Occupancy, _box_sums, _camera_key, _check_size, _lattice,
)
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Shelf
from slax_drake.errors import DepthOccupancyError

COARSE_GRID_STEP = 0.01  # the policies' settings (GroundTruthDistribution): 1 cm lattice, 1 cm samples
COARSE_SURFACE_SPACING = 0.01


@dataclasses.dataclass(frozen=True)
class _Bay:
    """What ``_Lattice._collision_free`` reads of a scene: the shelf and the obstacles."""

    shelf: Shelf
    objects: tuple


def occupancy_from_depth(depth: np.ndarray, camera: Camera, shelf: Shelf, target_size=(0.06, 0.06, 0.06),
                         grid_step: float = COARSE_GRID_STEP, surface_spacing: float | None = COARSE_SURFACE_SPACING,
                         obstacles=(), margin: float = 0.0, out_camera: Camera | None = None) -> Occupancy:
    """Every hidden placement of a ``target_size`` box judged from ``depth`` ((H, W) metres along the optical axis
    of ``camera``, which must have the image's resolution; 0 = no return) and its distributions in
    ``out_camera`` (default ``camera``). See the module docstring; ``grid_step`` must be a whole multiple of the
    surface sample spacing (as for the fast path of ``compute_occupancy``)."""
    size = _check_size(target_size)
    depth = np.asarray(depth)
    if depth.shape != (camera.height, camera.width):
        raise DepthOccupancyError(f"depth image of shape {depth.shape} does not fit the camera's "
                                  f"({camera.height}, {camera.width})")
    spacing = DEFAULT_SURFACE_SPACING if surface_spacing is None else float(surface_spacing)
    lattice = _lattice(shelf.width, shelf.depth, size, float(grid_step), spacing)
    if lattice is None:
        raise DepthOccupancyError(f"grid step {grid_step} m is not a whole multiple of the sample spacing of a "
                                  f"{size} target at {spacing} m, or no placement fits the bay")
    index, z_cam = _lattice_pixels(lattice, camera)
    flat = np.where(np.isfinite(depth) & (depth > 0), depth, 0.0).astype(np.float64).ravel()
    observed = np.append(flat, 0.0)[index]  # the last entry: outside the image (hides)
    seen = (observed > 0) & (z_cam < observed - margin)
    hidden = _hidden_placements(lattice, seen)
    hidden &= lattice._collision_free(_Bay(shelf, tuple(obstacles)))
    out = camera if out_camera is None else out_camera
    p2d = lattice.distribution(hidden, out, camera.position)
    ii, jj = np.nonzero(hidden)
    hidden_xy = np.column_stack([lattice.cx[ii], lattice.cy[jj]])
    return Occupancy(hidden_xy, p2d, p2d.sum(axis=0), size, float(grid_step), spacing)


def _hidden_placements(lattice, seen: np.ndarray) -> np.ndarray:
    """bool (n_i, n_j): no seen lattice point on the placement's top face (top height) or on its rim (the vertical
    faces, any height). ``seen``: (n_a, n_b, n_z) bool, heights ``lattice.oz`` ascending (the last is the top)."""
    n_i, n_j = len(lattice.cx), len(lattice.cy)
    nk, nl = len(lattice.ox), len(lattice.oy)
    top = seen[:, :, -1].astype(np.int64)
    anywhere = seen.any(axis=2).astype(np.int64)
    on_top = lattice.window_counts(top)
    whole = _box_sums(anywhere, lattice.mx, lattice.my, n_i, n_j, nk, nl)
    if nk > 2 and nl > 2:
        inner = _box_sums(anywhere[1:, 1:], lattice.mx, lattice.my, n_i, n_j, nk - 2, nl - 2)
    else:
        inner = np.zeros_like(whole)
    return (on_top == 0) & (whole - inner == 0)


def _lattice_pixels(lattice, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Flat pixel index (width * height outside the image) and optical-axis depth (m) of every 3D lattice point,
    (n_a, n_b, n_z) each, tabulated once per lattice and camera (kept in the lattice's memo)."""
    key = ("depth-pixels", _camera_key(camera), camera.near, camera.far)
    hit = lattice._memo.get(key)
    if hit is not None:
        return hit
    ax, ay, oz = lattice.ax, lattice.ay, lattice.oz
    pts = np.empty((len(ax), len(ay), len(oz), 3))
    pts[..., 0] = ax[:, None, None]
    pts[..., 1] = ay[None, :, None]
    pts[..., 2] = oz[None, None, :]
    p_C = camera.to_camera(pts.reshape(-1, 3))
    z = p_C[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.rint(camera.fx * p_C[:, 0] / z + camera.cx)
        v = np.rint(camera.fy * p_C[:, 1] / z + camera.cy)
    inside = (z > 0) & (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height)
    size = camera.width * camera.height
    index = np.full(len(z), size, dtype=np.int64)
    index[inside] = v[inside].astype(np.int64) * camera.width + u[inside].astype(np.int64)
    shape = (len(ax), len(ay), len(oz))
    index, z = index.reshape(shape), z.reshape(shape)
    index.setflags(write=False)
    z.setflags(write=False)
    lattice._remember(key, (index, z))
    return index, z
