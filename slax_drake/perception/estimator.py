"""Belief from one observation: every occluder segment -> an object hypothesis in the shelf frame S.

For each segment of an :class:`~slax_drake.perception.observation.Observation`:

0. The frame's range offset (a time-of-flight camera's absolute accuracy, common to the whole frame) and its
   per-pixel range noise are measured on the shelf's back panel where the camera sees it; the offset is taken off
   every return (:mod:`~slax_drake.perception.range_offset`; ``correct_range_offset``).
1. Its pixels are back-projected into S (``segmentation.back_project``).
   Points within ``floor_band`` of the support surface or ``back_wall_band`` of the back panel are left out:
   range noise (and a range offset) moves floor and panel pixels past the segmentation's margins and into
   object segments.
2. Height: the 99th percentile of the points' z (the top face when the camera sees it, else the front face's
   upper edge).
3. Outline on the support surface: the x-y of the side points (those below the top face), one median point per
   image column, is the visible front of the object. A circle fitted to them (algebraic fit) that explains them clearly better than a rectangle,
   with a plausible radius, makes a cylinder (both judged by the root of the median squared residual, robust to
   stray pixels at the silhouette); otherwise a box whose yaw is the rectangle (L-shape) fit of those
   points: the yaw in [0, pi/2) that packs them closest to two perpendicular edges (the "closeness" criterion of
   L-shape fitting on a 2 degree grid, then the least rms distance to the nearest edge within +-2 degrees). Yaw 0 when fewer than ``min_fit_points`` points are available.
4. Extents along the box's two axes: the 0.5th and 99.5th percentiles of all the segment's points (side and top;
   robust to flying pixels), widened over the trimmed points that continue the surface without a gap (the few
   returns of the far end of a face seen at a grazing angle; a stray return stands apart), except, on a noisy frame, the camera-facing faces: range noise spreads a face's points
   both ways along the rays, so a low percentile lies in front of the face; the face is placed at the median of
   its points near that edge (the band follows the range noise measured on the back panel). The extents are
   grown by ``silhouette_growth`` (half) a pixel's footprint on the silhouette sides (pixel centres sample the
   surface, the edge lies on average half a pixel beyond the outermost centre).
4b. A segment whose fit stands mostly inside a larger segment's (its observed footprint, grown by 5 mm, at least
   ``contained_share`` inside the other's footprint with its prior; ``drop_contained``) is a part of that object,
   cut off by a depth-only segmentation (a top face seen as one row, a sliver beside the occluder), and yields no
   hypothesis: two objects cannot stand in one place.
5. The unseen depth -- the part of the object behind its visible surfaces -- is a stated prior
   (:class:`DepthPrior`): along each axis the box extends away from the camera to at least

   - ``"smallest-object"`` (default): the smallest object dimension of the scenes, 0.06 m (Sec. V-A: every
     dimension of an object is drawn from [0.06, 0.20] m). Optimistic: the least material that could stand
     there, so no hidden space is claimed as occupied on a guess;
   - ``"visible-extent"``: as deep as the object is wide (the visible extent along the other axis, clipped to
     [smallest, largest]): the rule of the paper's image-space collision checks, where an object is as large as
     its segment;
   - ``"fixed"``: a stated depth (``DepthPrior.fixed``, clipped to [smallest, largest]), e.g. the mean object
     dimension (0.13 m): a policy that must not run objects into the unseen part of an object assumes more than
     the least material there;
   - ``"range"``: each unseen edge a stated share (``DepthPrior.fraction``) of the way from the observed part to
     the farthest the frame allows (the extent range, step 7), at least the smallest object deep.

   The prior never pushes a box through the back or side wall nor into another hypothesis: the extension is
   shortened until the overlap is at most ``overlap_tolerance`` (m^2).
6. Uncertainty (:class:`Uncertainty`): intervals for the footprint's front y, its x_min and x_max (a side that
   borders a nearer segment, an unknown pixel or the image border is *occluded*: the object may extend behind
   it until its x-extent is the diagonal of the largest object, so the visible edge is then only a bound), and
   its depth (the observed part .. the largest possible; whether the prior extended it).
7. Extent range (:class:`ExtentRange`, ``Uncertainty.extent``): the measured faces and visible width are what was
   seen; every edge of the footprint is stepped outward to the nearest bound: a wall, another hypothesis's observed
   footprint, space the camera sees as empty (a point of the stepped edge that the frame shows in front of the
   surface behind it), or the largest object dimension. The true footprint lies inside the farthest rectangle.

The hypotheses are :class:`~slax_drake.scene.model.SceneObject` boxes and cylinders named ``segment_<id>``, so
the action model consumes them as it consumes true objects. Everything is deterministic (no random draws).

:func:`predict_observation` predicts the next frame after a planar move of one segment's object, as SLAX-RAY
predicts the next distribution: the segment's back-projected points move by (dx, dy) in S and are projected
into the image, z-buffered against the rest of the frame; the pixels the object leaves become unknown.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from slax_drake.errors import ObservationError
from slax_drake.perception.observation import Observation
from slax_drake.perception.range_offset import shelf_range_calibration, without_range_offset
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import SceneObject, Shelf, planar_pose

DEPTH_RULES = ("smallest-object", "visible-extent", "fixed", "range")


@dataclasses.dataclass(frozen=True)
class DepthPrior:
    """The assumption for what the camera cannot see: how deep an object reaches behind its visible surfaces.

    ``rule`` "smallest-object" (default) or "visible-extent" (see the module docstring); ``smallest`` and
    ``largest`` bound every object dimension (metres; the paper's scenes: 0.06 and 0.20); ``fixed``: the depth of
    the "fixed" rule (metres); ``fraction``: the "range" rule's share, in [0, 1], of the way from the observed part
    to the farthest the frame allows (:class:`ExtentRange`) at which each unseen edge is placed (an edge whose range
    is within ``EstimatorConfig.range_margin`` plus two steps of the observed one counts as seen and stays), never
    less deep than the smallest object."""

    rule: str = "smallest-object"
    smallest: float = 0.06
    largest: float = 0.20
    fixed: float = 0.13
    fraction: float = 0.5

    def __post_init__(self) -> None:
        if self.rule not in DEPTH_RULES:
            raise ValueError(f"unknown depth prior {self.rule!r}; choose one of {', '.join(DEPTH_RULES)}")
        if not 0 < self.smallest <= self.largest:
            raise ValueError(f"depth prior needs 0 < smallest <= largest, got {self.smallest}, {self.largest}")
        if not 0 <= self.fraction <= 1:
            raise ValueError(f"depth prior fraction must be in [0, 1], got {self.fraction}")

    def depth(self, visible_width: float) -> float:
        """The assumed full extent (m) along an axis the camera looks along, given the extent across it."""
        if self.rule in ("smallest-object", "range"):  # "range": widened later from the extent range
            return self.smallest
        if self.rule == "fixed":
            return float(np.clip(self.fixed, self.smallest, self.largest))
        return float(np.clip(visible_width, self.smallest, self.largest))


@dataclasses.dataclass(frozen=True)
class EstimatorConfig:
    """Tuning of :func:`estimate_objects` (metres unless stated)."""

    prior: DepthPrior = DepthPrior()
    min_points: int = 8  # a segment with fewer valid points yields no hypothesis
    min_fit_points: int = 5  # fewer outline points (image columns): yaw 0 (no line fit)
    max_fit_points: int = 600  # outline points used for the yaw and circle fits (evenly subsampled)
    edge_percentile: float = 0.5  # robust extents: this percentile and 100 minus it
    # ... widened over the trimmed points that continue the surface, each with this many others within tail_radius
    # on the support surface (the far end of a face seen at a grazing angle; 0: percentile only)
    tail_neighbours: int = 3
    tail_radius: float = 0.01
    tail_gap: float = 0.01  # ... joining while each is within this of the edge so far
    tail_gap_pixels: float = 6.0  # ... or within this many pixel footprints at the segment
    # the extents' growth on the silhouette sides, in pixel footprints at the segment (0.5: the edge half a pixel
    # beyond the outermost pixel centre on average)
    silhouette_growth: float = 0.5
    yaw_step_deg: float = 2.0  # coarse yaw search step; refined to a twentieth of it
    closeness_floor: float = 0.001  # the L-shape criterion's minimum distance (m)
    cylinder_residual_ratio: float = 0.8  # circle rms below this fraction of the rectangle's rms -> cylinder
    occluded_row_fraction: float = 0.15  # a side is occluded when this fraction of its border rows is
    floor_band: float = 0.015  # points this close to the support surface are left out (noisy floor)
    back_wall_band: float = 0.015  # ... and this close to the back panel (a range offset joins it to segments)
    overlap_tolerance: float = 1e-4  # m^2 of footprint overlap allowed between hypotheses
    drop_contained: bool = True  # a segment whose fit lies mostly inside a larger segment's is a part of it
    contained_share: float = 0.5  # ... the share of its observed footprint (grown by 5 mm) inside the other's
    wall_clearance: float = 0.0  # the prior keeps boxes this far inside the walls
    # The frame's range offset, measured on the shelf's back panel (not the support surface: see
    # :mod:`slax_drake.perception.range_offset`), is taken off every return before fitting; False: the depths are
    # used as they come.
    correct_range_offset: bool = True
    # On a noisy frame (range noise measured on the back panel at least ``min_face_noise``) a box's camera-facing
    # faces are placed amid their points (:func:`_facing_edges`: the median of the face's points within twice
    # ``face_band_sigmas`` noise deviations of the percentile edge), not at the low percentile, which the noise
    # pulls toward the camera; False: the percentile always. 2.576: the 0.5th percentile of a normal distribution.
    face_from_points: bool = True
    face_band_sigmas: float = 2.576  # standard deviations of the range noise
    min_face_noise: float = 0.0005  # m: range noise below this counts as a clean frame
    # The extent range (:class:`ExtentRange`): each edge of the footprint is stepped outward by ``range_step``
    # until the line it reaches is seen empty (at least ``range_empty_points`` of its sample points lie in front
    # of the observed surface by ``range_margin`` plus three range-noise deviations), meets a wall or another
    # hypothesis's observed footprint, or the object would be wider than the largest object.
    extent_ranges: bool = True
    range_step: float = 0.005
    range_margin: float = 0.01
    range_empty_points: int = 2


@dataclasses.dataclass(frozen=True)
class Uncertainty:
    """What the observation leaves open about one hypothesis (intervals (lo, hi) in S, metres)."""

    front_y: tuple[float, float]  # the footprint's nearest y
    x_min: tuple[float, float]  # the footprint's left and right extremes
    x_max: tuple[float, float]
    depth: tuple[float, float]  # the extent along the viewing axis: observed part .. largest possible
    depth_from_prior: bool  # the box was extended by the depth prior
    occluded_left: bool
    occluded_right: bool
    residual: float  # robust rms distance (m) of the outline points to the fitted outline
    extent: "ExtentRange | None" = None  # the range of the object's footprint (None: not computed)


@dataclasses.dataclass(frozen=True)
class ExtentRange:
    """The range of what one seen object's footprint may be, in S (metres): a rectangle of yaw ``yaw`` (radians)
    whose edges along its two axes e1 = (cos yaw, sin yaw), e2 = (-sin yaw, cos yaw) lie between the observed
    part (``least_lo``, ``least_hi``: the coordinates along e1 and e2 of what the camera measured) and the largest
    the frame allows (``most_lo``, ``most_hi``). The measured faces are known to within the frame's resolution;
    the unseen depth and the hidden part of the width reach from what was seen to the nearest bound: a wall, a
    neighbour's observed footprint, space the camera sees as empty, or the largest object dimension. The true
    footprint contains the least rectangle (up to the fit's error) and lies inside the most one. A cylinder's
    range is its fitted circle's bounding square (yaw 0) and its growth."""

    shape: str  # the hypothesis's shape, "box" or "cylinder"
    yaw: float
    least_lo: tuple[float, float]
    least_hi: tuple[float, float]
    most_lo: tuple[float, float]
    most_hi: tuple[float, float]

    def _footprint(self, lo, hi) -> Footprint:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        m = (np.asarray(lo) + np.asarray(hi)) / 2
        return Footprint("box", float(c * m[0] - s * m[1]), float(s * m[0] + c * m[1]), self.yaw,
                         float(hi[0] - lo[0]) / 2, float(hi[1] - lo[1]) / 2)

    def least(self) -> Footprint:
        """The observed part's rectangle."""
        return self._footprint(self.least_lo, self.least_hi)

    def most(self) -> Footprint:
        """The largest footprint the frame allows (every edge at its farthest)."""
        return self._footprint(self.most_lo, self.most_hi)

    def growth(self) -> tuple[float, float, float, float]:
        """How far (m) each edge may lie beyond the observed part: (lo e1, hi e1, lo e2, hi e2)."""
        return (self.least_lo[0] - self.most_lo[0], self.most_hi[0] - self.least_hi[0],
                self.least_lo[1] - self.most_lo[1], self.most_hi[1] - self.least_hi[1])

    def contains(self, footprint: Footprint, tolerance: float = 0.0) -> bool:
        """Whether ``footprint`` lies inside the most rectangle grown by ``tolerance`` (m)."""
        return bool(self.most().polygon().buffer(tolerance).contains(footprint.polygon()))


@dataclasses.dataclass(frozen=True)
class Hypothesis:
    """One segment's object hypothesis: ``object`` (a SceneObject named ``segment_<id>``) and its uncertainty."""

    segment_id: int
    object: SceneObject
    uncertainty: Uncertainty
    pixels: int


@dataclasses.dataclass
class _Box:
    """A box being fitted: yaw and the interval of the footprint along its two axes (e1, e2)."""

    yaw: float
    lo: np.ndarray  # (2,)
    hi: np.ndarray  # (2,)
    observed_hi: np.ndarray  # (2,) edges before the prior extended them (far edges; lo side likewise below)
    observed_lo: np.ndarray
    height: float

    def with_extension(self, fraction: float) -> tuple[np.ndarray, np.ndarray]:
        lo = self.observed_lo + fraction * (self.lo - self.observed_lo)
        hi = self.observed_hi + fraction * (self.hi - self.observed_hi)
        return lo, hi

    @property
    def extended(self) -> bool:
        return bool(np.any(self.lo != self.observed_lo) or np.any(self.hi != self.observed_hi))


def estimate_objects(observation: Observation, shelf: Shelf, config: EstimatorConfig = EstimatorConfig()
                     ) -> list[Hypothesis]:
    """One hypothesis per occluder segment with at least ``config.min_points`` valid pixels off the back panel
    (farther than ``config.back_wall_band`` from it) that is not a part of a larger segment's object (step 4b), in
    segment order."""
    calibration = shelf_range_calibration(observation, shelf)
    if config.correct_range_offset:
        observation = without_range_offset(observation, calibration.offset)
    noise = calibration.sigma if calibration.sigma >= config.min_face_noise else 0.0
    camera = observation.camera
    eye = camera.position[:2]
    labels = observation.segmentation
    fits = []
    for sid in observation.segment_ids:
        mask = labels == sid
        p, columns = _segment_points(observation.depth, camera, mask)
        # A segment with too few points off the back panel is the panel itself (range noise brings its pixels
        # past the segmentation's margin): no object is thinner than the band.
        inside = p[:, 1] < shelf.depth / 2 - config.back_wall_band
        p, columns = p[inside], columns[inside]
        if len(p) < config.min_points:
            continue
        left, right = _occluded_sides(observation, mask, sid, config.occluded_row_fraction)
        fits.append((sid, int(mask.sum()), left, right, _fit(p, columns, eye, camera, left, right, config, noise)))
    if config.drop_contained:
        fits = _without_contained(fits, config)
    boxes = [f[4] for f in fits]
    if config.prior.rule == "range":
        for i, fit in enumerate(boxes):
            if fit.shape == "box":
                _widen_to_range(fit, _extent_range(fit, [f for j, f in enumerate(boxes) if j != i], observation,
                                                   shelf, noise, config), config)
    _limit_priors(boxes, shelf, config)
    _separate(boxes, eye, config)
    out = []
    for i, (sid, pixels, left, right, fit) in enumerate(fits):
        h = _hypothesis(sid, pixels, left, right, fit, eye, config)
        if config.extent_ranges:
            extent = _extent_range(fit, [f for j, f in enumerate(boxes) if j != i], observation, shelf, noise, config)
            h = dataclasses.replace(h, uncertainty=dataclasses.replace(h.uncertainty, extent=extent))
        out.append(h)
    return out


def _without_contained(fits: list, config: EstimatorConfig) -> list:
    """``fits`` (sid, pixels, left, right, _Fit) less those that are a part of a larger segment's object: the fit's
    observed footprint, grown by 5 mm (a one-row strip has next to no area), lies at least ``config.contained_share``
    inside the footprint of a fit of more pixels (with its prior). Two objects cannot stand in one place: a
    depth-only segmentation cuts a box's top face seen as one row, or a sliver of an object beside its occluder,
    into a segment of its own, whose fit (a 1 cm box, a 2 cm cylinder) stands inside the object's own fit. Fitted
    alone, it was shrunk or moved out of the way (the farther one gives way) and became a hypothesis of its own."""
    order = sorted(range(len(fits)), key=lambda k: fits[k][1])
    full = [_fit_footprint(f[4], 1.0).polygon() for f in fits]
    dropped = set()
    for rank, i in enumerate(order):
        own = _fit_footprint(fits[i][4], 0.0).polygon().buffer(0.005)
        if own.area <= 0:
            continue
        for j in order[rank + 1:]:
            if j in dropped or fits[j][1] <= fits[i][1]:
                continue
            if own.intersection(full[j]).area >= config.contained_share * own.area:
                dropped.add(i)
                break
    return [f for k, f in enumerate(fits) if k not in dropped]


def _segment_points(depth: np.ndarray, camera, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The valid pixels of ``mask`` back-projected into S, (N, 3) (as ``segmentation.back_project``, for a few
    pixels rather than the whole image), and their image columns (N,)."""
    v, u = np.nonzero(mask & (depth > 0))
    z = depth[v, u].astype(np.float64)
    p_C = np.stack([(u - camera.cx) / camera.fx * z, (v - camera.cy) / camera.fy * z, z], axis=-1)
    return p_C @ camera.X_SC[:3, :3].T + camera.X_SC[:3, 3], u


def hypothesis_objects(hypotheses) -> tuple[SceneObject, ...]:
    """The hypotheses' SceneObjects, for the action model."""
    return tuple(h.object for h in hypotheses)


# ---------------------------------------------------------------------------------------------- fitting


@dataclasses.dataclass
class _Fit:
    shape: str  # "box" or "cylinder"
    box: _Box | None
    circle: tuple[float, float, float] | None  # (x, y, r)
    height: float
    residual: float
    front_sigma: float


def _fit(p: np.ndarray, columns: np.ndarray, eye: np.ndarray, camera, occluded_left: bool,
         occluded_right: bool, config: EstimatorConfig, noise: float = 0.0) -> _Fit:
    above = p[:, 2] > config.floor_band  # range noise lifts the floor around an object's base into its segment
    if np.count_nonzero(above) >= config.min_points:
        p, columns = p[above], columns[above]
    z = p[:, 2]
    height = float(max(np.percentile(z, 99.0), 0.01))
    pixel = float(np.median(camera.to_camera(p)[:, 2])) / camera.fx  # a pixel's footprint (m) at the segment
    top_band = max(0.005, 1.5 * pixel)
    is_side = z < height - top_band
    if np.count_nonzero(is_side) < config.min_fit_points:
        is_side[:] = True
    side = _outline(p[is_side, :2], columns[is_side])
    # One object's outline spans at most the largest object's diagonal: farther columns are strays.
    side = side[np.hypot(*(side - np.median(side, axis=0)).T) <= math.sqrt(2.0) * config.prior.largest / 2 + 0.02]
    side = _subsample(side, config.max_fit_points)
    xy = p[:, :2]
    yaw, rect_rms = _rectangle_yaw(side, config) if len(side) >= config.min_fit_points else (0.0, math.inf)
    circle = _circle_fit(side) if len(side) >= config.min_fit_points else None
    if circle is not None:
        cx, cy, r, circle_rms = circle
        # The camera must see the near side of the circle (its centre lies beyond the points).
        plausible = (config.prior.smallest * 0.35 <= r <= config.prior.largest * 0.6
                     and np.hypot(cx - eye[0], cy - eye[1]) > np.median(np.hypot(*(side - eye).T)))
        if plausible and circle_rms < config.cylinder_residual_ratio * rect_rms:
            return _Fit("cylinder", None, (cx, cy, r), height, circle_rms, circle_rms)
    box = _box_extents(xy, yaw, eye, pixel, occluded_left, occluded_right, height, config,
                       face_xy=p[is_side, :2], noise=noise)
    return _Fit("box", box, None, height, rect_rms if math.isfinite(rect_rms) else 0.0,
                rect_rms if math.isfinite(rect_rms) else pixel)


def _outline(xy: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """The visible outline on the support surface: per image column, the median x-y of the side points. A
    column cuts an upright surface along one footprint point, so the median keeps the outline and averages the
    range noise of the column's pixels away."""
    order = np.argsort(columns, kind="stable")
    cols, xy = columns[order], xy[order]
    starts = np.flatnonzero(np.r_[True, cols[1:] != cols[:-1]])
    ends = np.r_[starts[1:], len(cols)]
    return np.array([np.median(xy[a:b], axis=0) for a, b in zip(starts, ends)])


def _subsample(points: np.ndarray, limit: int) -> np.ndarray:
    if len(points) <= limit:
        return points
    return points[np.linspace(0, len(points) - 1, limit).astype(int)]


def _rectangle_yaw(xy: np.ndarray, config: EstimatorConfig) -> tuple[float, float]:
    """The yaw in [0, pi/2) whose two perpendicular edges the points hug most closely, and the points' robust
    rms distance (root of the median square) to the nearest edge of the rectangle at that yaw."""
    def scores(angles):
        c, s = np.cos(angles), np.sin(angles)
        a = xy[:, :1] * c + xy[:, 1:] * s  # (N, A)
        b = -xy[:, :1] * s + xy[:, 1:] * c
        q = config.edge_percentile
        da = np.minimum(a - np.percentile(a, q, axis=0), np.percentile(a, 100 - q, axis=0) - a)
        db = np.minimum(b - np.percentile(b, q, axis=0), np.percentile(b, 100 - q, axis=0) - b)
        d = np.clip(np.minimum(np.abs(da), np.abs(db)), config.closeness_floor, None)
        return (1.0 / d).sum(axis=0), np.sqrt(np.median(np.minimum(np.abs(da), np.abs(db)) ** 2, axis=0))

    step = math.radians(config.yaw_step_deg)
    coarse = np.arange(0.0, math.pi / 2, step)
    best = float(coarse[int(np.argmax(scores(coarse)[0]))])
    fine = best + np.linspace(-step, step, 41)
    _, rms = scores(fine)
    k = int(np.argmin(rms))  # the closeness score saturates within its floor: the rms decides the fine yaw
    return float(fine[k] % (math.pi / 2)), float(rms[k])


def _circle_fit(xy: np.ndarray) -> tuple[float, float, float, float] | None:
    """Circle through the points: an algebraic (Kasa) fit refined by Gauss-Newton, then refitted (up to three
    times) to the points within three robust standard deviations of it (pixels of a neighbour at the silhouette are outliers).
    Returns centre x, y, radius and the robust rms residual (root of the median square), or None."""
    fit = _circle_least_squares(xy)
    if fit is None:
        return None
    residual = np.abs(np.hypot(xy[:, 0] - fit[0], xy[:, 1] - fit[1]) - fit[2])
    for _ in range(3):
        inliers = residual <= max(3.0 * 1.4826 * np.median(residual), 1e-3)
        if not 3 <= np.count_nonzero(inliers) < len(xy):
            break
        fit = _circle_least_squares(xy[inliers]) or fit
        residual = np.abs(np.hypot(xy[:, 0] - fit[0], xy[:, 1] - fit[1]) - fit[2])
    return fit[0], fit[1], fit[2], float(np.sqrt(np.median(residual ** 2)))


def _circle_least_squares(xy: np.ndarray) -> tuple[float, float, float] | None:
    mean = xy.mean(axis=0)
    q = xy - mean
    A = np.column_stack([2 * q, np.ones(len(q))])
    rhs = (q ** 2).sum(axis=1)
    sol, *_ = np.linalg.lstsq(A, rhs, rcond=None)
    c = sol[:2]
    r2 = sol[2] + c @ c
    if not r2 > 0:
        return None
    r = math.sqrt(r2)
    for _ in range(5):
        d = q - c
        dist = np.hypot(d[:, 0], d[:, 1])
        if np.any(dist < 1e-9):
            break
        J = np.column_stack([-d / dist[:, None], -np.ones(len(q))])
        step, *_ = np.linalg.lstsq(J, -(dist - r), rcond=None)
        c = c + step[:2]
        r = r + step[2]
    if not (math.isfinite(r) and r > 0 and np.all(np.isfinite(c))):
        return None
    return float(c[0] + mean[0]), float(c[1] + mean[1]), float(r)


def _box_extents(xy, yaw, eye, pixel, occluded_left, occluded_right, height, config, face_xy=None,
                 noise: float = 0.0) -> _Box:
    """Percentile extents along the yawed axes, the camera-facing faces placed amid their points on a noisy frame
    (:func:`_facing_edges`, from ``face_xy``, the side points, and ``noise``, the range noise in metres),
    half-pixel growth on the silhouette sides, and the depth prior's extension away from the camera."""
    c, s = math.cos(yaw), math.sin(yaw)
    axes = np.array([[c, s], [-s, c]])  # rows e1, e2
    coords = xy @ axes.T
    q = config.edge_percentile
    lo = np.percentile(coords, q, axis=0)
    hi = np.percentile(coords, 100 - q, axis=0)
    lo, hi = _supported_tails(coords, lo, hi, config, pixel)
    if config.face_from_points and noise > 0 and face_xy is not None and len(face_xy) >= config.min_fit_points:
        centre = axes.T @ ((lo + hi) / 2)
        view = (centre - eye) / max(float(np.linalg.norm(centre - eye)), 1e-9)
        spread = noise * np.abs(axes @ view)  # the range noise along each axis (it acts along the rays)
        _facing_edges(face_xy @ axes.T, lo, hi, axes @ eye, 2.0 * config.face_band_sigmas * spread)
    centre = axes.T @ ((lo + hi) / 2)
    view = centre - eye
    view /= max(np.linalg.norm(view), 1e-9)
    lateral = np.array([-view[1], view[0]])
    eye_c = axes @ eye
    for k in range(2):
        growth = config.silhouette_growth * pixel * abs(axes[k] @ lateral)  # silhouette sides only: those facing sideways
        lo[k] -= growth
        hi[k] += growth
    observed_lo, observed_hi = lo.copy(), hi.copy()
    widths = hi - lo
    for k in range(2):
        other = widths[1 - k]
        need = config.prior.depth(other)
        if widths[k] >= need:
            continue
        if eye_c[k] < lo[k]:  # the camera sees the lo side: the object continues beyond hi
            hi[k] = lo[k] + need
        elif eye_c[k] > hi[k]:
            lo[k] = hi[k] - need
        else:  # seen across: a lateral axis grows only toward an occluded side
            x_dir = axes[k][0]  # + when the axis points to the right in S
            grow_hi = (occluded_right and x_dir > 0) or (occluded_left and x_dir < 0)
            grow_lo = (occluded_left and x_dir > 0) or (occluded_right and x_dir < 0)
            if grow_hi and not grow_lo:
                hi[k] = lo[k] + need
            elif grow_lo and not grow_hi:
                lo[k] = hi[k] - need
    return _Box(yaw, lo, hi, observed_hi, observed_lo, height)


def _supported_tails(coords: np.ndarray, lo: np.ndarray, hi: np.ndarray, config: EstimatorConfig,
                     pixel: float):
    """The percentile extents ``lo``, ``hi`` (per box axis) widened over the trimmed points that continue the
    surface: walking outward from each edge, a point joins while it lies within ``config.tail_gap`` metres (or
    ``config.tail_gap_pixels`` footprints of a pixel, ``pixel`` metres, at the segment: on a face at a grazing angle
    neighbouring columns lie several footprints apart) of the edge so far and has at least ``config.tail_neighbours`` other points within ``config.tail_radius`` on the
    support surface. The percentile drops stray returns (flying pixels, a neighbour's pixels at the silhouette,
    which stand apart); it also drops the far end of a face seen at a grazing angle, whose few returns stack in
    columns (a vertical face's pixels share their x-y) and continue the face without a gap."""
    if config.tail_neighbours <= 0 or len(coords) <= config.tail_neighbours:
        return lo, hi
    lo, hi = lo.copy(), hi.copy()
    tree = None
    for k in range(coords.shape[1]):
        for side in (-1.0, 1.0):
            edge = lo[k] if side < 0 else hi[k]
            beyond = np.nonzero(side * (coords[:, k] - edge) > 0)[0]
            if len(beyond) == 0:
                continue
            if tree is None:
                from scipy.spatial import cKDTree

                tree = cKDTree(coords)
            counts = np.array([len(n) - 1 for n in tree.query_ball_point(coords[beyond], config.tail_radius)])
            steps = np.sort(side * (coords[beyond[counts >= config.tail_neighbours], k] - edge))
            gap = max(config.tail_gap, config.tail_gap_pixels * pixel)
            reach = 0.0
            for step in steps:
                if step - reach > gap:
                    break
                reach = step
            if side < 0:
                lo[k] = edge - reach
            else:
                hi[k] = edge + reach
    return lo, hi


def _facing_edges(coords: np.ndarray, lo: np.ndarray, hi: np.ndarray, eye_c: np.ndarray, band: np.ndarray) -> None:
    """Moves each camera-facing edge (lo or hi along a box axis, in place) into the middle of its face's noisy
    points. Range noise spreads a face's points both ways along the rays, so a low percentile of them (the edge
    as it comes in) lies about ``EstimatorConfig.face_band_sigmas`` standard deviations in front of the face; the
    face's points within ``band[k]`` (twice that) of the edge straddle the face evenly, and their median is the
    new edge. A face's points are the side points nearer its edge than the other camera-facing edge (a turned box
    shows two faces). The edge only moves away from the camera and never past the far edge; edges seen across
    (silhouette sides) are kept."""
    facing = [k for k in range(2) if eye_c[k] < lo[k] or eye_c[k] > hi[k]]
    if not facing:
        return
    edge = {k: lo[k] if eye_c[k] < lo[k] else hi[k] for k in facing}
    distance = np.stack([np.abs(coords[:, k] - edge[k]) for k in facing], axis=1)
    owner = np.argmin(distance, axis=1)
    for i, k in enumerate(facing):
        mine = coords[(owner == i) & (distance[:, i] <= band[k]), k]
        if len(mine) == 0:
            continue
        face = float(np.median(mine))
        if eye_c[k] < lo[k]:
            lo[k] = min(max(face, lo[k]), hi[k])
        else:
            hi[k] = max(min(face, hi[k]), lo[k])


def _box_footprint(box: _Box, fraction: float = 1.0) -> Footprint:
    lo, hi = box.with_extension(fraction)
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    mid = (lo + hi) / 2
    x, y = c * mid[0] - s * mid[1], s * mid[0] + c * mid[1]
    return Footprint("box", float(x), float(y), box.yaw, float(hi[0] - lo[0]) / 2, float(hi[1] - lo[1]) / 2)


def _fit_footprint(fit: _Fit, fraction: float = 1.0) -> Footprint:
    if fit.shape == "cylinder":
        x, y, r = fit.circle
        return Footprint("cylinder", x, y, 0.0, r, r)
    return _box_footprint(fit.box, fraction)


def _limit_priors(fits: list[_Fit], shelf: Shelf, config: EstimatorConfig) -> None:
    """Shortens each box's prior extension (in segment order) until it stays inside the walls and overlaps
    no other hypothesis by more than ``config.overlap_tolerance``. Observed extents are never cut."""
    polygons = [_fit_footprint(f, 0.0).polygon() for f in fits]  # the observed parts
    for i, fit in enumerate(fits):
        if fit.shape != "box" or not fit.box.extended:
            continue
        others = [polygons[j] for j in range(len(fits)) if j != i]

        def acceptable(fraction: float) -> bool:
            fp = _box_footprint(fit.box, fraction)
            poly = fp.polygon()
            ex, ey = fp.extents()
            inside = (abs(fp.x) + ex <= shelf.width / 2 - config.wall_clearance + 1e-9
                      and fp.y + ey <= shelf.depth / 2 - config.wall_clearance + 1e-9)
            base = _box_footprint(fit.box, 0.0).polygon()
            grown = poly.difference(base)  # only the prior's part may not overlap
            return inside and all(grown.intersection(o).area <= config.overlap_tolerance for o in others)

        if acceptable(1.0):
            fraction = 1.0
        else:
            lo_f, hi_f = 0.0, 1.0
            for _ in range(12):
                mid = (lo_f + hi_f) / 2
                if acceptable(mid):
                    lo_f = mid
                else:
                    hi_f = mid
            fraction = lo_f
        lo, hi = fit.box.with_extension(fraction)
        fit.box.lo, fit.box.hi = lo, hi
        polygons[i] = _box_footprint(fit.box).polygon()


def _separate(fits: list[_Fit], eye: np.ndarray, config: EstimatorConfig) -> None:
    """Where two hypotheses still overlap by more than ``config.overlap_tolerance`` (their observed parts: a
    misfit, e.g. a partly hidden cylinder taken for a box), the farther one (from the camera) gives way: a box
    moves its edge facing the other back, a cylinder shrinks about its front point, until the overlap is
    within the tolerance. Nearer objects are seen better, so they keep their shape."""
    def distance(fit):
        fp = _fit_footprint(fit)
        return math.hypot(fp.x - eye[0], fp.y - eye[1])

    for i in range(len(fits)):
        for j in range(i + 1, len(fits)):
            a, b = fits[i], fits[j]
            if _fit_footprint(a).polygon().intersection(_fit_footprint(b).polygon()).area <= config.overlap_tolerance:
                continue
            near, far = (a, b) if distance(a) <= distance(b) else (b, a)
            if far.shape == "cylinder" and near.shape == "box":
                near, far = far, near  # shrink the box: a cylinder has no edge to move
            _give_way(far, _fit_footprint(near).polygon(), eye, config.overlap_tolerance)


def _give_way(fit: _Fit, other, eye: np.ndarray, tolerance: float) -> None:
    """Shrinks ``fit`` (in place) away from the polygon ``other`` until they overlap by at most ``tolerance``."""
    def overlap() -> float:
        return _fit_footprint(fit).polygon().intersection(other).area

    if fit.shape == "cylinder":
        x, y, r = fit.circle
        front = np.array([x, y]) - r * (np.array([x, y]) - eye) / max(math.hypot(x - eye[0], y - eye[1]), 1e-9)
        direction = (np.array([x, y]) - front) / r
        lo, hi = 0.1, 1.0
        for _ in range(14):
            mid = (lo + hi) / 2
            fit.circle = (*(front + direction * r * mid), r * mid)
            lo, hi = (lo, mid) if overlap() > tolerance else (mid, hi)
        fit.circle = (*(front + direction * r * lo), r * lo)
        return
    box = fit.box
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    axes = np.array([[c, s], [-s, c]])
    centre = np.array(other.centroid.coords[0])
    offset = axes @ (centre - np.array([_fit_footprint(fit).x, _fit_footprint(fit).y]))
    k = int(np.argmax(np.abs(offset)))
    side_hi = offset[k] > 0  # the other lies on the hi side of axis k: move hi down (or lo up)
    start = box.hi[k] if side_hi else box.lo[k]
    stop = box.lo[k] + 0.01 if side_hi else box.hi[k] - 0.01
    lo_f, hi_f = 0.0, 1.0  # fraction of the way from start to stop
    for _ in range(14):
        mid = (lo_f + hi_f) / 2
        value = start + mid * (stop - start)
        if side_hi:
            box.hi[k] = value
        else:
            box.lo[k] = value
        lo_f, hi_f = (mid, hi_f) if overlap() > tolerance else (lo_f, mid)
    value = start + hi_f * (stop - start)
    if side_hi:
        box.hi[k] = min(value, box.hi[k]) if overlap() <= tolerance else value
        box.hi[k] = value
        box.observed_hi[k] = min(box.observed_hi[k], value)
    else:
        box.lo[k] = value
        box.observed_lo[k] = max(box.observed_lo[k], value)


# ------------------------------------------------------------------------------------------ extent range


def _least_box(fit: _Fit) -> tuple[float, np.ndarray, np.ndarray]:
    """(yaw, lo, hi) of a fit's observed part along its axes (a cylinder: its circle's bounding square)."""
    if fit.shape == "cylinder":
        x, y, r = fit.circle
        return 0.0, np.array([x - r, y - r]), np.array([x + r, y + r])
    return fit.box.yaw, fit.box.observed_lo.astype(float).copy(), fit.box.observed_hi.astype(float).copy()


def _inside_least(points: np.ndarray, fit: _Fit, shrink: float) -> np.ndarray:
    """Which points (N, 2) lie inside ``fit``'s observed footprint shrunk by ``shrink`` (m)."""
    if fit.shape == "cylinder":
        x, y, r = fit.circle
        return np.hypot(points[:, 0] - x, points[:, 1] - y) < r - shrink
    yaw, lo, hi = _least_box(fit)
    c, s = math.cos(yaw), math.sin(yaw)
    q = points @ np.array([[c, s], [-s, c]]).T
    return np.all((q > lo + shrink) & (q < hi - shrink), axis=1)


def _extent_range(fit: _Fit, others: list[_Fit], observation: Observation, shelf: Shelf, noise: float,
                  config: EstimatorConfig) -> ExtentRange:
    """The range of ``fit``'s footprint (:class:`ExtentRange`): each edge of the observed part is stepped outward
    (``config.range_step``) until the line it reaches (sampled across the observed width, at a quarter, half and
    three quarters of the height) is seen empty, leaves the shelf or enters another hypothesis's observed
    footprint; the edge may reach that line, no farther. Along an axis the object is at most the largest object
    dimension (``config.prior.largest``) wide, counted from the opposite observed edge; when the observed part is
    narrower than the smallest object along both axes, its outline does not fix the yaw: the object may be as
    wide as the largest object's diagonal along either axis, and a line seen empty no longer bounds it (a turned
    object need not span the observed width beyond its visible corner), so only walls and neighbours do."""
    yaw, lo, hi = _least_box(fit)
    c, s = math.cos(yaw), math.sin(yaw)
    axes = np.array([[c, s], [-s, c]])
    camera = observation.camera
    depth = observation.depth
    h_img, w_img = depth.shape
    largest = config.prior.largest
    yaw_known = float(np.max(hi - lo)) >= config.prior.smallest
    if not yaw_known:  # any turned object must fit the range
        largest *= math.sqrt(2.0)
    margin = config.range_margin + 3.0 * noise
    heights = np.array([0.25, 0.5, 0.75]) * fit.height
    step = config.range_step
    most_lo, most_hi = lo.copy(), hi.copy()
    for k in range(2):
        across = 1 - k
        inset = min(0.01, (hi[across] - lo[across]) / 4)
        cross = np.linspace(lo[across] + inset, hi[across] - inset, 5)
        for sign in (-1.0, 1.0):
            edge = hi[k] if sign > 0 else lo[k]
            reach = max(largest - (hi[k] - lo[k]), 0.0)  # the object is at most ``largest`` along the axis
            n = int(math.ceil(reach / step))
            if n == 0:
                continue
            t = np.minimum(np.arange(1, n + 1) * step, reach)  # (n,) offsets beyond the edge
            coords = np.zeros((n, len(cross), 2))
            coords[:, :, k] = edge + sign * t[:, None]
            coords[:, :, across] = cross[None, :]
            xy = coords @ axes  # (n, m, 2) in S
            flat = xy.reshape(-1, 2)
            bad = ((np.abs(flat[:, 0]) > shelf.width / 2) | (flat[:, 1] > shelf.depth / 2)
                   | (flat[:, 1] < -shelf.depth / 2))
            for other in others:
                bad |= _inside_least(flat, other, 0.005)
            bad = bad.reshape(n, -1).any(axis=1)
            p = np.concatenate([np.broadcast_to(flat[:, None, :], (len(flat), len(heights), 2)),
                                np.broadcast_to(heights[None, :, None], (len(flat), len(heights), 1))], axis=-1)
            p = p.reshape(-1, 3)
            z = camera.to_camera(p)[:, 2]
            uv = np.rint(camera.project(p)).astype(np.int64)
            ok = (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < w_img) & (uv[:, 1] >= 0) & (uv[:, 1] < h_img)
            seen = np.zeros(len(p), dtype=np.float64)
            seen[ok] = depth[uv[ok, 1], uv[ok, 0]]
            empty = (seen > 0) & (z < seen - margin)
            empty_count = empty.reshape(n, -1).sum(axis=1)
            if yaw_known:
                bad |= empty_count >= min(config.range_empty_points, empty.reshape(n, -1).shape[1])
            first = int(np.argmax(bad)) if bad.any() else n - 1
            value = edge + sign * float(t[first])
            if sign > 0:
                most_hi[k] = value
            else:
                most_lo[k] = value
    return ExtentRange(fit.shape, float(yaw), tuple(map(float, lo)), tuple(map(float, hi)),
                       tuple(map(float, np.minimum(most_lo, lo))), tuple(map(float, np.maximum(most_hi, hi))))


def _widen_to_range(fit: _Fit, extent: ExtentRange, config: EstimatorConfig) -> None:
    """The "range" depth prior: each unseen edge of the box (its range reaches more than ``range_margin`` plus two
    steps beyond the observed part) moves ``config.prior.fraction`` of the way to its farthest, if that is beyond
    where it stands (in place; the observed part is kept for :func:`_limit_priors`)."""
    box = fit.box
    seen = config.range_margin + 2 * config.range_step
    f = config.prior.fraction
    for k in range(2):
        grow_lo = extent.least_lo[k] - extent.most_lo[k]
        grow_hi = extent.most_hi[k] - extent.least_hi[k]
        if grow_lo > seen:
            box.lo[k] = min(box.lo[k], extent.least_lo[k] - f * grow_lo)
        if grow_hi > seen:
            box.hi[k] = max(box.hi[k], extent.least_hi[k] + f * grow_hi)


# ------------------------------------------------------------------------------------------- hypotheses


def _hypothesis(sid: int, pixels: int, occluded_left: bool, occluded_right: bool, fit: _Fit, eye,
                config: EstimatorConfig) -> Hypothesis:
    fp = _fit_footprint(fit)
    prior = config.prior
    if fit.shape == "cylinder":
        x, y, r = fit.circle
        obj = SceneObject(f"segment_{sid}", "cylinder", (2 * r, 2 * r, fit.height), planar_pose(x, y, fit.height / 2, 0.0))
        observed_depth = 2 * r
        depth_interval = (2 * r, 2 * r)
        from_prior = False
    else:
        box = fit.box
        size = (float(box.hi[0] - box.lo[0]), float(box.hi[1] - box.lo[1]), fit.height)
        obj = SceneObject(f"segment_{sid}", "box", size, planar_pose(fp.x, fp.y, fit.height / 2, box.yaw))
        view = np.array([fp.x, fp.y]) - eye
        k = int(np.argmax(np.abs(np.array([[math.cos(box.yaw), math.sin(box.yaw)],
                                           [-math.sin(box.yaw), math.cos(box.yaw)]]) @ view)))
        observed_depth = float(box.observed_hi[k] - box.observed_lo[k])
        depth_interval = (observed_depth, max(prior.largest, observed_depth))
        from_prior = box.extended
    ex, _ = fp.extents()
    x_lo, x_hi = fp.x - ex, fp.x + ex
    front = _front_y(fp)
    sigma = 2.0 * fit.front_sigma + 1e-3
    slack = max(math.sqrt(2.0) * prior.largest - (x_hi - x_lo), 0.0)  # a box's widest x-extent: its diagonal
    uncertainty = Uncertainty(
        front_y=(front - sigma, front + sigma),
        x_min=(x_lo - slack - sigma if occluded_left else x_lo - sigma, x_lo + sigma),
        x_max=(x_hi - sigma, x_hi + slack + sigma if occluded_right else x_hi + sigma),
        depth=depth_interval,
        depth_from_prior=from_prior,
        occluded_left=occluded_left,
        occluded_right=occluded_right,
        residual=fit.residual,
    )
    return Hypothesis(sid, obj, uncertainty, pixels)


def _front_y(fp: Footprint) -> float:
    if fp.shape == "cylinder":
        return fp.y - fp.half_x
    return float(fp.corners()[:, 1].min())


def _occluded_sides(observation: Observation, mask: np.ndarray, sid: int, row_fraction: float) -> tuple[bool, bool]:
    """Whether the segment's left and right borders (in the image) are occluded: in at least ``row_fraction``
    of its rows the pixel just beyond its extreme pixel is nearer (another segment or the target), has no
    depth, or lies outside the image."""
    depth = observation.depth
    rows = np.nonzero(mask.any(axis=1))[0]
    if len(rows) == 0:
        return False, False
    w = mask.shape[1]
    sub = mask[rows]
    first = np.argmax(sub, axis=1)
    last = w - 1 - np.argmax(sub[:, ::-1], axis=1)
    own_left = depth[rows, first]
    own_right = depth[rows, last]

    def occluded(cols, own):
        outside = (cols < 0) | (cols >= w)
        c = np.clip(cols, 0, w - 1)
        nd = depth[rows, c]
        nearer = (nd > 0) & (nd < own - 0.005)
        unknown = nd <= 0
        hit = outside | nearer | unknown
        return float(hit.mean()) >= row_fraction

    return occluded(first - 1, own_left), occluded(last + 1, own_right)


# ------------------------------------------------------------------------------------------ prediction


def predict_observation(observation: Observation, segment_id: int, dx: float, dy: float,
                        uncovered_depth: float = 0.0) -> Observation:
    """The frame expected after the object of ``segment_id`` moves by (dx, dy) metres in S (a planar move).

    The segment's valid pixels are back-projected, moved, projected back (rounded to the nearest pixel) and
    drawn z-buffered over the frame without the segment: a moved point is drawn where it is nearer than what
    is there or where nothing is known. Single-pixel holes in the moved segment (magnification when it comes
    nearer) are closed with the mean depth of their drawn neighbours. Pixels the object left that it does not
    cover again become unknown: depth ``uncovered_depth`` (0, no return, by default), no segment, not target.
    Where the object now covers the target, the target mask is cleared."""
    if segment_id not in observation.segment_ids:
        raise ObservationError(f"segment {segment_id} is not in the observation (segments {observation.segment_ids})")
    camera = observation.camera
    mask = observation.segmentation == segment_id
    depth = observation.depth.copy()
    labels = observation.segmentation.copy()
    target = observation.target_mask.copy()
    pts = _segment_points(observation.depth, camera, mask)[0] + np.array([dx, dy, 0.0])
    depth[mask] = 0.0
    labels[mask] = 0
    h, w = depth.shape
    drawn = np.full((h, w), np.inf)
    if len(pts):
        z = camera.to_camera(pts)[:, 2]
        uv = np.rint(camera.project(pts)).astype(np.int64)
        ok = (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)
        u, v, z = uv[ok, 0], uv[ok, 1], z[ok]
        np.minimum.at(drawn, (v, u), z)
    moved = np.isfinite(drawn)
    if moved.any():
        closed = cv2.morphologyEx(moved.astype(np.uint8), cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8)).astype(bool)
        holes = closed & ~moved
        if holes.any():
            weights = cv2.blur(moved.astype(np.float32), (3, 3), borderType=cv2.BORDER_CONSTANT)
            sums = cv2.blur(np.where(moved, drawn, 0.0).astype(np.float32), (3, 3), borderType=cv2.BORDER_CONSTANT)
            drawn[holes] = sums[holes] / np.maximum(weights[holes], 1e-6)
            moved = closed
    in_front = moved & ((depth <= 0) | (drawn < depth))
    depth[in_front] = drawn[in_front].astype(np.float32)
    labels[in_front] = segment_id
    target[in_front] = False
    left = mask & ~in_front
    depth[left] = uncovered_depth
    return dataclasses.replace(observation, depth=depth, segmentation=labels, target_mask=target,
                               min_valid_fraction=0.0)
