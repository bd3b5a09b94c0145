"""A depth-sensor model after the Intel RealSense LiDAR Camera L515, the camera of the paper's experiments.

:func:`l515_depth_noise` turns an ideal depth image (metres along the optical axis, 0 = no return) into what an
L515 would plausibly return, in plain numpy (the shelf simulator uses it directly; the Drake diagram through
``slax_drake.systems.depth_noise.DepthNoiseSystem``). Four effects, each a field of :class:`L515Noise`:

1. Range limits. No return nearer than ``min_range`` (datasheet: minimum depth distance 0.25 m) or farther than
   ``max_range`` (datasheet: up to 9 m at 95 % reflectivity).
2. Range noise growing with distance: per pixel, Gaussian with standard deviation
   ``sigma_at_1m + sigma_per_m * (z - 1 m)`` (metres), z the depth. The defaults make it 2.5 mm at 1 m and
   15.5 mm at 9 m, the datasheet's depth precision (temporal noise, 1 sigma) at those distances, linear between.
   A per-frame-sequence offset (drawn once per seed, the same for every time step) models the absolute accuracy:
   ``u * (accuracy_near + accuracy_per_m * z)``, u uniform in [-1, 1]; the defaults give 5 mm near and 14 mm at
   9 m, the datasheet's "~5 mm to ~14 mm through 9 m" depth accuracy.
3. Missing returns at depth edges: a time-of-flight spot that straddles an occluding edge mixes two ranges, and
   the L515's confidence filter drops such pixels. Every pixel with a 4-neighbour more than
   ``edge_jump`` metres away in depth (or without a return) is dropped with probability ``edge_dropout`` times the share of the pixel
   covered by an ``edge_band_native_px`` wide band of the sensor's native 1024-pixel-wide grid (so a coarse
   image, whose pixels span several native pixels, loses proportionally fewer edge pixels).
4. Missing returns on grazing surfaces (too little light comes back): a pixel whose surface normal (from the depth
   image's own gradient) makes an angle theta with its ray is dropped with probability rising linearly from 0 at
   ``grazing_start_deg`` to ``grazing_dropout`` at ``grazing_full_deg`` (the normal from one-sided differences,
   the side that changes depth less, so that a pixel at an occluding edge takes its own surface's normal).
   A pixel at an edge drops with the larger of the two probabilities. Dark (low-reflectivity) surfaces behave
   alike on the real sensor; a depth image carries no reflectivity, so they are not modelled.

Effects 3-4 and the range-noise parameters beyond the datasheet's two precision points are modelling choices of
slax-drake, not datasheet figures. Determinism: the random draws come from ``numpy.random.default_rng((seed,
step))``, so one seed and one time step always give the same image, and different steps give independent
noise (the offset of effect 2 depends on the seed only).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slax_drake.scene.camera import Camera

L515_NATIVE_WIDTH = 1024  # the L515's depth resolution is 1024 x 768


@dataclasses.dataclass(frozen=True)
class L515Noise:
    """Parameters of :func:`l515_depth_noise` (metres, degrees, probabilities); see the module docstring."""

    min_range: float = 0.25
    max_range: float = 9.0
    sigma_at_1m: float = 0.0025
    sigma_per_m: float = 0.001625  # (15.5 mm - 2.5 mm) / 8 m
    accuracy_near: float = 0.005
    accuracy_per_m: float = 0.001  # 5 mm + 9 m * 1 mm/m = 14 mm at 9 m
    edge_jump: float = 0.02
    edge_dropout: float = 0.8
    edge_band_native_px: float = 2.0
    grazing_start_deg: float = 75.0
    grazing_full_deg: float = 88.0
    grazing_dropout: float = 1.0

    def sigma(self, z: np.ndarray) -> np.ndarray:
        """Range noise standard deviation (metres) at depth z (metres), never below 0."""
        return np.maximum(self.sigma_at_1m + self.sigma_per_m * (z - 1.0), 0.0)


def l515_depth_noise(depth: np.ndarray, camera: Camera, seed: int, step: int = 0,
                     noise: L515Noise = L515Noise()) -> np.ndarray:
    """An ideal depth image (H, W) float metres, 0 or non-finite = no return, seen by ``camera`` (its
    resolution) -> the noisy float32 image, 0 where the L515 model has no return. ``seed`` and ``step``
    (non-negative integers) fix every random draw."""
    depth = np.asarray(depth, dtype=np.float64)
    if depth.shape != (camera.height, camera.width):
        raise ValueError(f"depth image of shape {depth.shape} does not fit the camera {camera.width}x{camera.height}")
    valid = np.isfinite(depth) & (depth > 0)
    z = np.where(valid, depth, 0.0)
    offset_u = np.random.default_rng((int(seed), 0xACC)).uniform(-1.0, 1.0)
    rng = np.random.default_rng((int(seed), int(step)))
    noisy = z + offset_u * (noise.accuracy_near + noise.accuracy_per_m * z) + rng.standard_normal(z.shape) * noise.sigma(z)
    keep = valid & (z >= noise.min_range) & (z <= noise.max_range)
    share = min(1.0, noise.edge_band_native_px * camera.width / L515_NATIVE_WIDTH)
    p_drop = np.where(_edges(z, valid, noise.edge_jump), noise.edge_dropout * share, 0.0)
    p_drop = np.maximum(p_drop, _grazing_probability(z, valid, camera, noise))
    keep &= rng.random(z.shape) >= p_drop
    return np.where(keep & (noisy > 0), noisy, 0.0).astype(np.float32)


def _edges(z: np.ndarray, valid: np.ndarray, jump: float) -> np.ndarray:
    """Valid pixels with a 4-neighbour more than ``jump`` away in depth or without a return."""
    edges = np.zeros(z.shape, dtype=bool)
    far = np.where(valid, z, np.inf)
    with np.errstate(invalid="ignore"):  # inf - inf between two pixels without a return: NaN, counted as a jump
        dx = np.abs(np.diff(far, axis=1))
        dy = np.abs(np.diff(far, axis=0))
        jx = ~(dx <= jump)
        jy = ~(dy <= jump)
    edges[:, 1:] |= jx
    edges[:, :-1] |= jx
    edges[1:, :] |= jy
    edges[:-1, :] |= jy
    return edges & valid


def _smoother_difference(p: np.ndarray, z: np.ndarray, axis: int) -> np.ndarray:
    """Per pixel, the forward or the backward difference of the points p (H, W, 3) along ``axis``, whichever
    changes depth less: at an occluding edge the side on the same surface wins, so the normal is that
    surface's; on a grazing surface both sides agree."""
    fwd = np.diff(p, axis=axis, append=np.take(p, [-1], axis=axis))
    bwd = np.diff(p, axis=axis, prepend=np.take(p, [0], axis=axis))
    dz_f = np.abs(np.diff(z, axis=axis, append=np.take(z, [-1], axis=axis)))
    dz_b = np.abs(np.diff(z, axis=axis, prepend=np.take(z, [0], axis=axis)))
    # At the image border one difference is zero (a copy of the pixel): use the other one.
    use_f = ((dz_f <= dz_b) | (np.linalg.norm(bwd, axis=-1) == 0)) & (np.linalg.norm(fwd, axis=-1) > 0)
    return np.where(use_f[..., None], fwd, bwd)


def _grazing_probability(z: np.ndarray, valid: np.ndarray, camera: Camera, noise: L515Noise) -> np.ndarray:
    """Drop probability (H, W) from the angle between each pixel's ray and its surface normal."""
    h, w = z.shape
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    p = np.stack([(u - camera.cx) / camera.fx * z, (v - camera.cy) / camera.fy * z, z], axis=-1)
    du = _smoother_difference(p, z, axis=1)
    dv = _smoother_difference(p, z, axis=0)
    n = np.cross(du, dv)
    norm = np.linalg.norm(n, axis=-1) * np.linalg.norm(p, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(np.sum(n * p, axis=-1)) / norm
    angle = np.degrees(np.arccos(np.clip(np.nan_to_num(cos, nan=1.0), 0.0, 1.0)))
    span = max(noise.grazing_full_deg - noise.grazing_start_deg, 1e-9)
    prob = noise.grazing_dropout * np.clip((angle - noise.grazing_start_deg) / span, 0.0, 1.0)
    return np.where(valid, prob, 0.0)
