"""Ground-truth target occupancy: every hidden, collision-free target placement on a regular grid, and its
image-space distribution (paper Sec. IV-A, Fig. 3 b-f).

Definitions (the brute-force reference in tests/occupancy/test_occupancy.py checks these literally):

- Placements: target centres (x, y) on the lattice ``grid_step * Z^2`` of the shelf frame S (metres), target yaw
  0, resting on the support surface (z = size_z / 2), whose footprint lies inside the bay and clear of every
  occluding object (clearance 0: touching is allowed).
- A placement is hidden when none of the target's surface points (``scene.surface.box_surface_points``,
  ``surface_spacing`` apart, every face but the bottom) is visible from the camera's optical centre past the
  shelf and the objects (``SceneRaycaster``; the scene's own target is never an occluder).
- p2d: the eye-facing surface points of every hidden placement projected into ``camera`` and counted per pixel
  (rounded to the nearest pixel centre), normalised to sum to 1; p1d = p2d.sum(axis=0).

How it stays fast (the paper's pruning plus two exact reductions):

1. Monotone in height. Every occluder is a vertical prism standing on the support surface (boxes yawed about
   z, cylinders, the side and back walls), and the camera sits below the shelf's top panel. Raising a point
   raises the ray to it at every point of its top-down path, so a hidden point hides every point below it.
   Every vertical face's sample points lie directly below the top face's rim samples, hence a placement is
   hidden exactly when all of its top-face samples are hidden.
2. Shared lattice. When ``grid_step`` is a whole multiple of the top-face sample spacing, the top-face samples
   of all placements lie on one fine lattice at height size_z. Each lattice point is decided once; "all
   samples of a placement hidden" becomes a box sum over the lattice (a summed-area table).
3. 2D visibility and Minkowski sum (the paper's pruning). Top down, a lattice point outside every object's
   shadow polygon (the convex hull of the footprint and its projection away from the eye) and seen through the
   shelf's opening is visible in 3D. The shadows are rasterised onto the lattice and grown by one lattice cell,
   so that only certainly visible points are marked without a ray. A placement whose window holds such a point
   (the Minkowski sum of the visible region with the target's footprint samples) is discarded, and one Embree
   call decides the lattice points that the remaining candidates need.
4. p2d by multiplicity: every face's samples also lie on lattices, so the number of hidden placements sharing a
   sample point is again a box sum; each distinct point is projected once with that weight.
5. Shared across heights (``compute_occupancies``): target sizes with one footprint (x, y), like the paper's
   three aspect ratios, share the collision-free grid, the 2D pruning and the set of lattice points to decide;
   only the rays (one height each) and the projections are made per size.
6. Projection by tables: for a camera whose x axis is the shelf's (any pitch, no roll or yaw: every
   ``camera_pose`` camera), y_C and z_C depend only on a point's (y, z), so image rows and depths are tabulated
   per face plane once per camera and lattice, and a point costs one division. The per-point arithmetic is
   the same as the generic projection's, so the result is identical to the bit (tested).

When the grid is not aligned with the samples, or the camera is above the shelf's top, the same definitions are
evaluated directly (every placement, every sample point): correct, only slower.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from slax_drake.scene.camera import Camera
from slax_drake.scene.footprint import Footprint, clear_of
from slax_drake.scene.model import Scene
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.surface import box_surface_points, facing_points

DEFAULT_GRID_STEP = 0.005
DEFAULT_SURFACE_SPACING = 0.005
# Lattice points this close (metres) to the wall shadow's edge are decided by a ray, not by the 2D test.
WALL_MARGIN = 1e-3
# An object is collision-tested only against placements whose bounding box comes this close (metres) to its own.
_NEAR = 1e-6
_FAR = 20.0  # how far (in units of the eye-to-vertex distance) a shadow polygon reaches behind an object


@dataclasses.dataclass(frozen=True)
class Occupancy:
    """The hidden placements of one target size in one scene and their image-space distribution.

    ``hidden_xy`` (K, 2) float64: placement centres (x, y) in the shelf frame S, metres; the target rests on the
    support surface with yaw 0. ``p2d`` (camera.height, camera.width) float32, non-negative, sums to 1 (all
    zeros when K == 0). ``p1d`` (camera.width,) float32 = p2d.sum(axis=0).
    """

    hidden_xy: np.ndarray
    p2d: np.ndarray
    p1d: np.ndarray
    target_size: tuple[float, float, float]
    grid_step: float
    surface_spacing: float

    @property
    def num_hidden(self) -> int:
        return len(self.hidden_xy)


def compute_occupancy(
    scene: Scene,
    target_size=(0.06, 0.06, 0.06),
    grid_step: float = DEFAULT_GRID_STEP,
    camera: Camera | None = None,
    surface_spacing: float | None = None,
    raycaster: SceneRaycaster | None = None,
) -> Occupancy:
    """Every hidden placement of a ``target_size`` [x, y, z] (metres) box on the ``grid_step`` lattice of the
    shelf, and the distributions p2d / p1d in ``camera`` (default ``scene.camera``).

    Only ``scene.objects`` and the shelf occlude and collide; the scene's own target is ignored.
    ``surface_spacing`` (default 0.005 m) spaces the target's surface samples. ``raycaster`` may pass a
    ``SceneRaycaster(scene)`` already built for this scene's objects (without the target)."""
    return compute_occupancies(scene, (target_size,), grid_step, camera, surface_spacing, raycaster)[0]


def compute_occupancies(
    scene: Scene,
    target_sizes,
    grid_step: float = DEFAULT_GRID_STEP,
    camera: Camera | None = None,
    surface_spacing: float | None = None,
    raycaster: SceneRaycaster | None = None,
) -> tuple[Occupancy, ...]:
    """``compute_occupancy`` for several target sizes of one scene, in order; each result equals that of its
    own ``compute_occupancy`` call.

    Sizes that share a footprint (x, y), like the paper's three aspect ratios, share the work that does not
    depend on the target's height: the collision-free grid, the 2D shadow pruning and the lattice points to
    ray-cast. Only the rays (at each height) and the distributions are made per size."""
    sizes = [_check_size(s) for s in target_sizes]
    if not (isinstance(grid_step, (int, float)) and math.isfinite(grid_step) and grid_step > 0):
        raise ValueError(f"grid_step must be a positive length in metres, got {grid_step!r}")
    step = float(grid_step)
    spacing = DEFAULT_SURFACE_SPACING if surface_spacing is None else float(surface_spacing)
    if not spacing > 0:
        raise ValueError(f"surface_spacing must be positive, got {surface_spacing!r}")
    camera = scene.camera if camera is None else camera
    if raycaster is None:
        raycaster = SceneRaycaster(scene)
    eye = scene.camera.position
    shared: dict[tuple[float, float], _Candidates] = {}
    results = []
    for size in sizes:
        lattice = _lattice(scene.shelf.width, scene.shelf.depth, size, step, spacing)
        if lattice is None or eye[2] >= scene.shelf.height:
            results.append(_occupancy_direct(scene, size, step, spacing, camera, raycaster))
            continue
        if size[:2] not in shared:
            shared[size[:2]] = lattice.candidates(scene)
        hidden = lattice.hidden_mask(scene, raycaster, shared[size[:2]])
        p2d = lattice.distribution(hidden, camera, eye)
        ii, jj = np.nonzero(hidden)
        hidden_xy = np.column_stack([lattice.cx[ii], lattice.cy[jj]])
        results.append(Occupancy(hidden_xy, p2d, p2d.sum(axis=0), size, step, spacing))
    return tuple(results)


def occupancy_memory_bytes(scene: Scene, target_sizes, grid_step: float, surface_spacing: float,
                           camera: Camera | None = None) -> float:
    """Estimated peak bytes of the large arrays of ``compute_occupancies`` with these arguments, from counts
    alone (nothing is allocated): the lattice path holds a few int64 / float64 / bool arrays over the fine
    lattice and the placement grid (64 bytes per point, generous); the direct path holds every surface sample of
    every placement with its ray (about 100 bytes each); both hold float64 per-pixel counts."""
    camera = scene.camera if camera is None else camera
    pixels = camera.width * camera.height
    worst = 0.0
    for size in (_check_size(s) for s in target_sizes):
        def samples(u: float) -> int:
            return max(2, math.ceil(u / surface_spacing) + 1)

        def placements(extent: float, half: float) -> int:
            n = math.floor((extent / 2.0 - half) / grid_step + 1e-9)
            return 2 * n + 1 if n >= 0 else 0

        n_i = placements(scene.shelf.width, size[0] / 2.0)
        n_j = placements(scene.shelf.depth, size[1] / 2.0)
        nx, ny, nz = samples(size[0]), samples(size[1]), samples(size[2])
        per_placement = nx * ny + 2 * nx * nz + 2 * ny * nz
        mx, my = _multiple(grid_step, size[0] / (nx - 1)), _multiple(grid_step, size[1] / (ny - 1))
        if mx is not None and my is not None and scene.camera.position[2] < scene.shelf.height:
            fine = (max(n_i - 1, 0) * mx + nx) * (max(n_j - 1, 0) * my + ny)
            need = 64.0 * (fine + n_i * n_j)
        else:
            need = 16.0 * n_i * n_j + 100.0 * n_i * n_j * per_placement
        worst = max(worst, need + 32.0 * pixels)
    return worst


def grid_placements(scene: Scene, target_size, grid_step: float) -> np.ndarray:
    """All lattice centres (K, 2) whose yaw-0 target footprint fits in the bay (ignoring objects), x-major."""
    cx, cy = _grid_axes(scene, _check_size(target_size), grid_step)
    gx, gy = np.meshgrid(cx, cy, indexing="ij")
    return np.column_stack([gx.ravel(), gy.ravel()])


def collision_free(scene: Scene, target_size, centers_xy: np.ndarray) -> np.ndarray:
    """Whether a yaw-0 target at each centre (K, 2) lies inside the bay and clear of every object
    (clearance 0, touching allowed); bool (K,)."""
    size = _check_size(target_size)
    centers = np.atleast_2d(np.asarray(centers_xy, dtype=float))
    half = (size[0] / 2.0, size[1] / 2.0)
    shelf = scene.shelf
    ok = (np.abs(centers[:, 0]) + half[0] <= shelf.width / 2.0 + 1e-12) & (
        np.abs(centers[:, 1]) + half[1] <= shelf.depth / 2.0 + 1e-12
    )
    for obj in scene.objects:
        ok &= clear_of("box", centers, 0.0, half, Footprint.of(obj), 0.0)
    return ok


def placements_hidden(
    scene: Scene,
    target_size,
    centers_xy: np.ndarray,
    surface_spacing: float | None = None,
    raycaster: SceneRaycaster | None = None,
) -> np.ndarray:
    """The direct test of given placements (K, 2): collision free and every surface sample hidden; bool (K,).

    No pruning and no lattice: every sample point of every placement gets its own ray. Use it to check one
    placement exactly (for example a sampled scene's true target centre, which need not lie on the grid)."""
    size = _check_size(target_size)
    spacing = DEFAULT_SURFACE_SPACING if surface_spacing is None else float(surface_spacing)
    centers = np.atleast_2d(np.asarray(centers_xy, dtype=float))
    ok = collision_free(scene, size, centers)
    if not ok.any():
        return ok
    raycaster = SceneRaycaster(scene) if raycaster is None else raycaster
    points, _ = box_surface_points(size, spacing)
    offsets = np.column_stack([centers[ok], np.full(int(ok.sum()), size[2] / 2.0)])
    seen = raycaster.visible(scene.camera.position, points[None, :, :] + offsets[:, None, :]).any(axis=1)
    ok[np.flatnonzero(ok)[seen]] = False
    return ok


def project_placements(
    camera: Camera, eye: np.ndarray, target_size, centers_xy: np.ndarray, surface_spacing: float
) -> np.ndarray:
    """p2d by its definition: the eye-facing surface samples of every placement projected into ``camera``
    and counted per pixel, normalised; float32 (H, W). Direct and slow (one projection per sample)."""
    size = _check_size(target_size)
    points, normals = box_surface_points(size, surface_spacing)
    counts = np.zeros(camera.height * camera.width, dtype=np.float64)
    for c in np.atleast_2d(np.asarray(centers_xy, dtype=float)).reshape(-1, 2):
        pts = facing_points(points, normals, np.array([c[0], c[1], size[2] / 2.0]), np.asarray(eye, float))
        counts += _pixel_counts(camera, pts, None)
    return _normalised(counts, camera)


# --------------------------------------------------------------------------------------------------------


def _check_size(target_size) -> tuple[float, float, float]:
    try:
        size = tuple(float(v) for v in target_size)
    except (TypeError, ValueError):
        raise ValueError(f"target_size must be three lengths [x, y, z] in metres, got {target_size!r}") from None
    if len(size) != 3 or not all(math.isfinite(v) and v > 0 for v in size):
        raise ValueError(f"target_size must be three positive lengths [x, y, z] in metres, got {target_size!r}")
    return size


def _grid_axes(scene: Scene, size, step: float) -> tuple[np.ndarray, np.ndarray]:
    return _axes_in_bay(scene.shelf.width, scene.shelf.depth, size, step)


def _axes_in_bay(width: float, depth: float, size, step: float) -> tuple[np.ndarray, np.ndarray]:
    def axis(extent: float, half: float) -> np.ndarray:
        n = math.floor((extent / 2.0 - half) / step + 1e-9)
        return np.arange(-n, n + 1) * step if n >= 0 else np.zeros(0)

    return axis(width, size[0] / 2.0), axis(depth, size[1] / 2.0)


def _face(points: np.ndarray, normals: np.ndarray, normal) -> np.ndarray:
    return points[np.all(normals == np.asarray(normal, dtype=float), axis=1)]


def _multiple(step: float, sample: float) -> int | None:
    m = step / sample
    r = round(m)
    return int(r) if r >= 1 and abs(m - r) < 1e-6 else None


def _box_sums(values: np.ndarray, stride_a: int, stride_b: int, count_a: int, count_b: int, na: int,
              nb: int) -> np.ndarray:
    """Sums of ``values`` over the windows [i * stride_a, i * stride_a + na) x [j * stride_b, j * stride_b + nb)
    for i < count_a, j < count_b (int64, (count_a, count_b))."""
    sat = np.zeros((values.shape[0] + 1, values.shape[1] + 1), dtype=np.int64)
    np.cumsum(np.cumsum(values, axis=0, dtype=np.int64), axis=1, out=sat[1:, 1:])
    lo_a, hi_a = sat[::stride_a][:count_a], sat[na::stride_a][:count_a]
    return (hi_a[:, nb::stride_b][:, :count_b] - hi_a[:, ::stride_b][:, :count_b]
            - lo_a[:, nb::stride_b][:, :count_b] + lo_a[:, ::stride_b][:, :count_b])


def _spread(marks: np.ndarray, stride_a: int, stride_b: int, na: int, nb: int, shape) -> np.ndarray:
    """How many marked placements' windows cover each lattice point: placement (i, j) covers
    [i * stride_a, i * stride_a + na) x [j * stride_b, j * stride_b + nb)."""
    along_a = _spread_1d(marks, stride_a, na, shape[0])
    return _spread_1d(along_a.T, stride_b, nb, shape[1]).T


def _spread_1d(marks: np.ndarray, stride: int, n: int, length: int) -> np.ndarray:
    """Along axis 0 only: how many marked placements' windows [i * stride, i * stride + n) cover each index
    (int64, (length, marks.shape[1]))."""
    z = np.zeros((length, marks.shape[1]), dtype=np.int64)
    z[::stride][: marks.shape[0]] = marks
    c = np.cumsum(z, axis=0)
    if n < length:
        c[n:] -= c[: length - n].copy()
    return c


def _pixel_counts(camera: Camera, points: np.ndarray, weights: np.ndarray | None) -> np.ndarray:
    p_C = camera.to_camera(points)
    z = p_C[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.rint(camera.fx * p_C[:, 0] / z + camera.cx)
        v = np.rint(camera.fy * p_C[:, 1] / z + camera.cy)
    inside = (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height) & (z > 0)
    index = v[inside].astype(np.int64) * camera.width + u[inside].astype(np.int64)
    w = None if weights is None else weights[inside]
    return np.bincount(index, weights=w, minlength=camera.width * camera.height).astype(np.float64)


def _normalised(counts: np.ndarray, camera: Camera) -> np.ndarray:
    total = counts.sum()
    p = counts / total if total > 0 else counts
    return p.reshape(camera.height, camera.width).astype(np.float32)


def _occupancy_direct(scene, size, step, spacing, camera, raycaster) -> Occupancy:
    centers = grid_placements(scene, size, step)
    hidden = placements_hidden(scene, size, centers, spacing, raycaster)
    hidden_xy = centers[hidden]
    p2d = project_placements(camera, scene.camera.position, size, hidden_xy, spacing)
    return Occupancy(hidden_xy, p2d, p2d.sum(axis=0), size, step, spacing)


@dataclasses.dataclass(frozen=True)
class _Candidates:
    """The part of the hidden test that does not depend on the target's height (shared by sizes with one
    footprint): placements (n_i, n_j) that are collision free and not certainly visible top down, and the
    fine-lattice points (need_a, need_b) whose rays decide them."""

    placements: np.ndarray
    need_a: np.ndarray
    need_b: np.ndarray


@functools.lru_cache(maxsize=64)
def _lattice(width: float, depth: float, size, step: float, spacing: float) -> "_Lattice | None":
    """The lattice of a ``width`` x ``depth`` bay (metres), cached: it depends on nothing else of the scene."""
    return _Lattice.build(width, depth, size, step, spacing)


@dataclasses.dataclass(frozen=True)
class _Lattice:
    """Placement grid (cx, cy) and the fine lattice of top-face samples shared by all placements."""

    size: tuple[float, float, float]
    cx: np.ndarray  # placement centres along x (n_i,)
    cy: np.ndarray  # along y (n_j,)
    mx: int  # placement step in top-face sample steps
    my: int
    ox: np.ndarray  # top-face sample offsets along x (nk,), ascending
    oy: np.ndarray  # (nl,)
    oz: np.ndarray  # vertical faces' sample heights above the support (nz,)
    ax: np.ndarray  # fine lattice x coordinates (n_a,)
    ay: np.ndarray  # fine lattice y coordinates (n_b,)
    _memo: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)  # per camera / eye
    # per object footprint (and eye): its collision window and its shadow's raster polygon (_per_footprint)
    _footprints: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)

    @staticmethod
    def build(width: float, depth: float, size, step: float, spacing: float) -> "_Lattice | None":
        points, normals = box_surface_points(size, spacing)
        top = _face(points, normals, (0, 0, 1))
        front = _face(points, normals, (0, -1, 0))
        ox, oy, oz = np.unique(top[:, 0]), np.unique(top[:, 1]), np.unique(front[:, 2]) + size[2] / 2.0
        cx, cy = _axes_in_bay(width, depth, size, step)
        if len(cx) == 0 or len(cy) == 0:
            return None
        mx, my = _multiple(step, ox[1] - ox[0]), _multiple(step, oy[1] - oy[0])
        if mx is None or my is None or not _uniform(ox) or not _uniform(oy):
            return None
        sx, sy = step / mx, step / my
        ax = cx[0] + ox[0] + sx * np.arange((len(cx) - 1) * mx + len(ox))
        ay = cy[0] + oy[0] + sy * np.arange((len(cy) - 1) * my + len(oy))
        for a in (cx, cy, ox, oy, oz, ax, ay):
            a.setflags(write=False)  # shared through the cache
        return _Lattice(size, cx, cy, mx, my, ox, oy, oz, ax, ay)

    def window_counts(self, per_point: np.ndarray) -> np.ndarray:
        """For each placement, the number of flagged lattice points among its top-face samples."""
        return _box_sums(per_point, self.mx, self.my, len(self.cx), len(self.cy), len(self.ox), len(self.oy))

    def covered(self, placements: np.ndarray) -> np.ndarray:
        """How many of the marked placements have each lattice point among their top-face samples."""
        return _spread(placements.astype(np.int64), self.mx, self.my, len(self.ox), len(self.oy),
                       (len(self.ax), len(self.ay)))

    def candidates(self, scene: Scene) -> _Candidates:
        """Collision free placements not proved visible by the 2D test, and the lattice points they need."""
        placements = self._collision_free(scene)
        if placements.any():
            placements &= self.window_counts(self._certainly_visible(scene)) == 0
        if not placements.any():
            return _Candidates(placements, np.zeros(0, np.int64), np.zeros(0, np.int64))
        need_a, need_b = np.nonzero(self.covered(placements) > 0)
        return _Candidates(placements, need_a, need_b)

    def hidden_mask(self, scene: Scene, raycaster: SceneRaycaster, candidates: _Candidates) -> np.ndarray:
        """bool (n_i, n_j): collision free and every top-face sample (at this lattice's height) hidden."""
        if len(candidates.need_a) == 0:
            return candidates.placements.copy()
        ia, ib = candidates.need_a, candidates.need_b
        pts = np.column_stack([self.ax[ia], self.ay[ib], np.full(len(ia), self.size[2])])
        seen = np.zeros((len(self.ax), len(self.ay)), dtype=bool)
        seen[ia, ib] = raycaster.visible(scene.camera.position, pts)
        return candidates.placements & (self.window_counts(seen) == 0)

    def _collision_free(self, scene: Scene) -> np.ndarray:
        """``collision_free`` of every placement, bool (n_i, n_j). An object is tested (with the same
        ``clear_of``) only against the placements whose bounding box comes within ``_NEAR`` of its own: all
        others are clear of it by at least that gap."""
        hx, hy = self.size[0] / 2.0, self.size[1] / 2.0
        in_x = np.abs(self.cx) + hx <= scene.shelf.width / 2.0 + 1e-12
        in_y = np.abs(self.cy) + hy <= scene.shelf.depth / 2.0 + 1e-12
        free = in_x[:, None] & in_y[None, :]
        for obj in scene.objects:
            window = self._per_footprint(("free", Footprint.of(obj)), self._clear_window)
            if window is not None:
                i0, i1, j0, j1, clear = window
                free[i0:i1, j0:j1] &= clear
        return free

    def _clear_window(self, key) -> tuple | None:
        """(i0, i1, j0, j1, clear): the placements [i0:i1, j0:j1] whose bounding box comes within ``_NEAR`` of the
        footprint ``key[1]``'s, and which of them are clear of it (bool); None when there are none."""
        fp = key[1]
        hx, hy = self.size[0] / 2.0, self.size[1] / 2.0
        ex, ey = fp.extents()
        i0, i1 = np.searchsorted(self.cx, [fp.x - ex - hx - _NEAR, fp.x + ex + hx + _NEAR])
        j0, j1 = np.searchsorted(self.cy, [fp.y - ey - hy - _NEAR, fp.y + ey + hy + _NEAR])
        if i0 >= i1 or j0 >= j1:
            return None
        gx, gy = np.meshgrid(self.cx[i0:i1], self.cy[j0:j1], indexing="ij")
        clear = clear_of("box", np.column_stack([gx.ravel(), gy.ravel()]), 0.0, (hx, hy), fp, 0.0)
        clear = clear.reshape(gx.shape)
        clear.setflags(write=False)  # shared through the cache
        return i0, i1, j0, j1, clear

    def _per_footprint(self, key, compute):
        """``compute(key)``, kept per key (a footprint, with the eye where it matters): the policies evaluate many
        arrangements in which most objects stand where they stood. Bounded (emptied at 4096 entries)."""
        if key in self._footprints:
            return self._footprints[key]
        if len(self._footprints) >= 4096:
            self._footprints.clear()
        value = self._footprints[key] = compute(key)
        return value

    def _certainly_visible(self, scene: Scene) -> np.ndarray:
        """bool (n_a, n_b): lattice points that the top-down (2D) test proves visible from the camera."""
        import cv2

        eye = scene.camera.position
        ex, ey = float(eye[0]), float(eye[1])
        sx, sy = self.ax[1] - self.ax[0], self.ay[1] - self.ay[0]
        shadow = np.zeros((len(self.ax), len(self.ay)), dtype=np.uint8)
        shift = 8

        def shadow_polygon(key) -> np.ndarray:
            """The raster polygon (fixed point, ``shift`` fractional bits) of the footprint's top-down shadow."""
            poly = np.asarray(key[1].polygon(segments=16).exterior.coords)[:-1]
            far = poly + _FAR * (poly - (ex, ey))
            hull = cv2.convexHull(np.concatenate([poly, far]).astype(np.float32))[:, 0, :]
            # Raster rows are lattice x indices, columns lattice y indices; cv2 takes (column, row) points.
            pix = np.column_stack([(hull[:, 1] - self.ay[0]) / sy, (hull[:, 0] - self.ax[0]) / sx])
            return np.rint(pix * (1 << shift)).astype(np.int32)

        for obj in scene.objects:
            polygon = self._per_footprint(("shadow", Footprint.of(obj), ex, ey), shadow_polygon)
            cv2.fillConvexPoly(shadow, polygon, 1, lineType=cv2.LINE_8, shift=shift)
        shadow = cv2.dilate(shadow, np.ones((3, 3), np.uint8))
        return (shadow == 0) & self._through_opening(scene)

    def _through_opening(self, scene: Scene) -> np.ndarray:
        """bool (n_a, n_b): the top-down segment from the eye to the lattice point crosses the front plane
        y = -depth/2 inside the bay (kept per eye and shelf: the same for every scene of a scenario)."""
        eye = scene.camera.position
        key = ("through", eye.tobytes(), scene.shelf.width, scene.shelf.depth)
        if key not in self._memo:
            ex, ey = float(eye[0]), float(eye[1])
            y_front = -scene.shelf.depth / 2.0
            t = (y_front - ey) / (self.ay - ey)
            x_cross = ex + t[None, :] * (self.ax[:, None] - ex)
            through = (np.abs(x_cross) < scene.shelf.width / 2.0 - WALL_MARGIN) & (ey < y_front)
            through.setflags(write=False)
            self._remember(key, through)
        return self._memo[key]

    def _remember(self, key, value) -> None:
        if len(self._memo) > 64:
            self._memo.clear()
        self._memo[key] = value

    def distribution(self, hidden: np.ndarray, camera: Camera, eye: np.ndarray) -> np.ndarray:
        """p2d (H, W) float32: every eye-facing surface sample of every hidden placement, projected once per
        distinct point with the number of hidden placements that share it as its weight."""
        if not hidden.any():
            return _normalised(np.zeros(camera.height * camera.width), camera)
        if _x_aligned(camera):
            return _normalised(self._counts_x_aligned(hidden, camera, eye), camera)
        return _normalised(self._counts_generic(hidden, camera, eye), camera)

    def _faces(self, hidden: np.ndarray, eye: np.ndarray) -> list[tuple]:
        """The eye-facing faces' sample points with their weights (the number of hidden placements that share
        each point), as (kind, plane, first, second, weight) with index arrays ``first``, ``second``:

        - ("top", None, a, b, w): points (ax[a], ay[b], size_z) of the top faces;
        - ("y", plane_y (n_j,), a, j, w): points (ax[a], plane_y[j], oz[k]) for every k, front or back faces;
        - ("x", plane_x (n_i,), b, i, w): points (plane_x[i], ay[b], oz[k]) for every k, left or right faces.
        """
        ex, ey, ez = (float(v) for v in eye)
        faces = []
        if ez > self.size[2]:
            faces.append(("top", None, *_nonzero(self.covered(hidden))))
        a, j, wx = _nonzero(_spread_1d(hidden, self.mx, len(self.ox), len(self.ax)))  # w (n_a, n_j)
        b, i, wy = _nonzero(_spread_1d(hidden.T, self.my, len(self.oy), len(self.ay)))  # w (n_b, n_i)
        for sign in (-1.0, 1.0):
            plane_y = self.cy + sign * self.size[1] / 2.0
            keep = np.take(sign * (ey - plane_y) > 0, j)
            if keep.any():
                faces.append(("y", plane_y, a[keep], j[keep], wx[keep]))
        for sign in (-1.0, 1.0):
            plane_x = self.cx + sign * self.size[0] / 2.0
            keep = np.take(sign * (ex - plane_x) > 0, i)
            if keep.any():
                faces.append(("x", plane_x, b[keep], i[keep], wy[keep]))
        return faces

    def _counts_generic(self, hidden: np.ndarray, camera: Camera, eye: np.ndarray) -> np.ndarray:
        """Pixel counts (H * W,) float64, every distinct point projected through ``Camera.to_camera``."""
        sz, nz = self.size[2], len(self.oz)
        chunks, weights = [], []
        for kind, plane, first, second, w in self._faces(hidden, eye):
            if kind == "top":
                chunks.append(np.column_stack([self.ax[first], self.ay[second], np.full(len(first), sz)]))
                weights.append(w)
            elif kind == "y":
                chunks.append(np.column_stack([
                    np.repeat(self.ax[first], nz), np.repeat(plane[second], nz), np.tile(self.oz, len(first))]))
                weights.append(np.repeat(w, nz))
            else:
                chunks.append(np.column_stack([
                    np.repeat(plane[second], nz), np.repeat(self.ay[first], nz), np.tile(self.oz, len(first))]))
                weights.append(np.repeat(w, nz))
        return _pixel_counts(camera, np.concatenate(chunks), np.concatenate(weights).astype(np.float64))

    def _counts_x_aligned(self, hidden: np.ndarray, camera: Camera, eye: np.ndarray) -> np.ndarray:
        """Pixel counts (H * W,) float64 for a camera whose x axis is the shelf's x axis (any pitch, no yaw or
        roll: every camera built by ``camera_pose``). Then x_C = x - x_eye, and y_C, z_C depend on (y, z)
        only: image rows and depths are tabulated once per face plane and camera, and each point costs one
        division for its column. The arithmetic per point is that of ``_pixel_counts`` (same operations in
        the same order on the same values), so the counts are identical to ``_counts_generic``'s."""
        size = camera.height * camera.width
        x0 = camera.X_SC[0, 3]
        fx_ax = camera.fx * (self.ax - x0)  # fx * x_C of the lattice's x coordinates (n_a,)
        index, weights = [], []
        for kind, plane, first, second, w in self._faces(hidden, eye):
            # np.take: a gather several times faster than fancy indexing on this path
            if kind == "top":
                row, depth = self._rows(camera, "top", self.ay, np.array([self.size[2]]))
                fx_x, lattice_row = np.take(fx_ax, first)[:, None], second
            elif kind == "y":
                row, depth = self._rows(camera, ("y", float(plane[0])), plane, self.oz)
                fx_x, lattice_row = np.take(fx_ax, first)[:, None], second
            else:
                row, depth = self._rows(camera, "x", self.ay, self.oz)
                fx_x, lattice_row = np.take(camera.fx * (plane - x0), second)[:, None], first
            index.append(_pixel_index(camera, fx_x, np.take(row, lattice_row, axis=0),
                                      np.take(depth, lattice_row, axis=0)).ravel())
            weights.append(np.repeat(w.astype(np.float64), row.shape[1]))
        counts = np.bincount(np.concatenate(index), weights=np.concatenate(weights), minlength=size + 1)
        return counts[:size]  # the last bin collected the points outside the image

    def _rows(self, camera: Camera, name, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``_image_rows(camera, y, z)``, kept per camera for this lattice (the same for every scene)."""
        key = ("rows", _camera_key(camera), name)
        if key not in self._memo:
            self._remember(key, _image_rows(camera, y, z))
        return self._memo[key]


def _nonzero(w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row indices, column indices and values of the non-zero entries of a 2D array (row-major order)."""
    flat = np.flatnonzero(w)
    rows, cols = np.divmod(flat, w.shape[1])
    return rows, cols, np.take(w, flat)


def _camera_key(camera: Camera) -> tuple:
    return (camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy, camera.X_SC.tobytes())


def _x_aligned(camera: Camera) -> bool:
    R = camera.X_SC[:3, :3]
    return bool(R[0, 0] == 1.0 and R[0, 1] == 0.0 and R[0, 2] == 0.0 and R[1, 0] == 0.0 and R[2, 0] == 0.0)


def _image_rows(camera: Camera, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For an x-aligned camera: the flat index of the start of the image row, v * width (int64, or
    height * width when the row is off the image or behind the camera), and the depth z_C (float64), of the
    points (x, y[j], z[k]) for any x; both (len(y), len(z)), read-only."""
    pts = np.empty((len(y) * len(z), 3))
    pts[:, 0] = camera.X_SC[0, 3]
    pts[:, 1] = np.repeat(y, len(z))
    pts[:, 2] = np.tile(z, len(y))
    p_C = camera.to_camera(pts)  # the same transform as _pixel_counts: y_C and z_C to the last bit
    depth = p_C[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.rint(camera.fy * p_C[:, 1] / depth + camera.cy)
    inside = (v >= 0) & (v < camera.height) & (depth > 0)
    row = np.where(inside, v, camera.height).astype(np.int64) * camera.width
    shape = (len(y), len(z))
    row, depth = row.reshape(shape), np.ascontiguousarray(depth.reshape(shape))
    row.setflags(write=False)
    depth.setflags(write=False)
    return row, depth


def _pixel_index(camera: Camera, fx_x: np.ndarray, row: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Flat pixel index (int64) of points with fx * x_C ``fx_x``, image row start ``row`` and depth ``depth``
    (broadcast together); height * width for points outside the image."""
    size = camera.height * camera.width
    with np.errstate(divide="ignore", invalid="ignore"):
        u = fx_x / depth
        u += camera.cx
        np.rint(u, out=u)
        inside = (u >= 0) & (u < camera.width)  # NaN (depth 0) is outside
        index = u.astype(np.int64)
    index += row
    np.putmask(index, ~inside, size)
    np.minimum(index, size, out=index)  # rows off the image start at ``size``
    return index


def _uniform(values: np.ndarray) -> bool:
    d = np.diff(values)
    return len(d) > 0 and bool(np.allclose(d, d[0], rtol=0, atol=1e-9))
