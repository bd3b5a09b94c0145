"""A depth camera's range offset and range noise, measured on the shelf's own back panel in the frame.

A time-of-flight camera's absolute accuracy is a range offset common to a whole frame sequence (the L515: ~5 mm
to ~14 mm through 9 m; :mod:`slax_drake.perception.sensor_noise` models it as one draw per seed). It moves every
surface the estimator fits, and so every hypothesis' front face, by the same few millimetres toward or away from
the camera; a suction cup that stops 5 mm short of a face does not seal. The shelf's geometry is known (it is in
the scenario, as it is to the planner), so the offset can be read off the frame: wherever the camera sees the back
panel of the bay (y = depth / 2, facing the camera: the best gauge of a range error), the depth it should read
there follows from the pixel's ray. (The support surface is seen near grazing incidence from the camera's height:
a range error hardly moves its points, so it is no gauge.) The median difference, measured minus expected, over
those pixels is the frame's range offset (metres along the optical axis, positive: the camera reads too far), and
their spread about it (1.4826 times the median absolute deviation) the frame's per-pixel range noise, which the
estimator needs to place a face amid its noisy points.

Which pixels count: unsegmented, not target, with a return, whose back-projected point lies within ``band`` of
the panel (farther ones are something else: an unsegmented object, a side wall) and whose ray meets the panel inside
the bay's opening (|x| < width / 2, 0 < z < height). Fewer than ``min_pixels`` such pixels: no estimate (0).
The correction assumes the camera's pose relative to the shelf is right: an error of that pose along the optical
axis reads as an offset too (and is then corrected with it, up to ``max_offset``).
"""

from __future__ import annotations

import dataclasses
import numpy as np

from slax_drake.perception.observation import Observation
from slax_drake.scene.model import Shelf


@dataclasses.dataclass(frozen=True)
class RangeOffsetConfig:
    """Tuning of :func:`shelf_range_calibration` (metres)."""

    band: float = 0.02  # a back-panel pixel's back-projected point lies this close to the panel
    min_pixels: int = 30  # fewer shelf pixels: no estimate
    max_offset: float = 0.02  # estimates beyond +-this are not trusted (offset 0): not a range offset
    deadband: float = 0.0005  # estimates within +-this are taken as 0 (a clean render reads the panel to 1e-7 m)


@dataclasses.dataclass(frozen=True)
class RangeCalibration:
    """What the back panel tells about a frame's depths (metres along the optical axis)."""

    offset: float  # the range offset (positive: the camera reads too far); 0 when not measured or not trusted
    sigma: float  # the per-pixel range noise (1.4826 x the median absolute deviation); 0 when not measured
    pixels: int  # the back-panel pixels both rest on


def shelf_range_calibration(observation: Observation, shelf: Shelf, config: RangeOffsetConfig = RangeOffsetConfig()
                            ) -> RangeCalibration:
    """The frame's range offset and range noise, measured on the back panel (see the module docstring). Offset and
    noise are 0 when fewer than ``config.min_pixels`` panel pixels are seen; the offset is also 0 when it lies
    beyond ``config.max_offset`` or within ``config.deadband``."""
    free = (observation.segmentation == 0) & ~observation.target_mask
    return range_calibration(observation.depth, observation.camera, shelf, free, config)


def range_calibration(depth: np.ndarray, camera, shelf: Shelf, candidates: np.ndarray,
                      config: RangeOffsetConfig = RangeOffsetConfig()) -> RangeCalibration:
    """:func:`shelf_range_calibration` on a depth image (H, W) metres of ``camera``'s resolution, reading the
    ``candidates`` pixels (bool, H x W) with a return: those whose point lies within ``config.band`` of the back
    panel's plane and whose ray meets the panel inside the bay. Before any segmentation, every pixel may be a
    candidate (the band keeps the objects' pixels out but for a few right against the panel; the median holds)."""
    v, u = np.nonzero(candidates & (depth > 0))
    if len(v) == 0:
        return RangeCalibration(0.0, 0.0, 0)
    z = depth[v, u].astype(np.float64)
    rays_C = np.stack([(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, np.ones(len(u))], axis=-1)
    R, o = camera.X_SC[:3, :3], camera.X_SC[:3, 3]
    rays = rays_C @ R.T  # S-frame point per unit of depth: p = o + z * ray
    points = o + z[:, None] * rays
    level = shelf.depth / 2  # the back panel's y
    with np.errstate(divide="ignore", invalid="ignore"):
        z_panel = (level - o[1]) / rays[:, 1]  # the depth at which the pixel's ray meets the panel's plane
    hit = o + z_panel[:, None] * rays
    ok = ((np.abs(points[:, 1] - level) < config.band) & (z_panel > 0) & (np.abs(hit[:, 0]) < shelf.width / 2)
          & (hit[:, 2] > 0.0) & (hit[:, 2] < shelf.height))
    difference = z[ok] - z_panel[ok]
    n = int(len(difference))
    if n < config.min_pixels:
        return RangeCalibration(0.0, 0.0, n)
    offset = float(np.median(difference))
    sigma = float(1.4826 * np.median(np.abs(difference - offset)))
    if abs(offset) > config.max_offset or abs(offset) < config.deadband:
        offset = 0.0
    return RangeCalibration(offset, sigma, n)


def without_range_offset(observation: Observation, offset: float) -> Observation:
    """The frame with ``offset`` (metres) taken off every return (pixels without one stay 0)."""
    if offset == 0.0:
        return observation
    depth = np.where(observation.depth > 0, np.maximum(observation.depth - offset, 1e-6), 0.0).astype(np.float32)
    return dataclasses.replace(observation, depth=depth)
