"""A raster of the shelf's support surface: object footprints and the 2D shadows they cast from the camera.

The action model uses it for one rule only, the paper's "nothing is moved into space hidden behind other
objects": a floor cell is *hidden* when the segment from the camera's (x, y) to the cell's centre crosses an
object's footprint (the overhead 2D visibility of paper Sec. V-A, objects taken as infinitely tall, which is
conservative: anything the camera cannot see in 3D lies in this 2D shadow). Collisions are never decided on
this raster; they use the exact footprint tests of :mod:`slax_drake.scene.footprint`.

Cells are ``cell`` metres square; row r, column c has its centre at
(x, y) = (-width/2 + (c + 0.5) cell, -depth/2 + (r + 0.5) cell) in the shelf frame S (rows run into the shelf).
"""

from __future__ import annotations

import functools
import math

import cv2

import numpy as np

from slax_drake.scene.footprint import Footprint, clear_of
from slax_drake.scene.model import Shelf

NOT_FOUND = 1 << 20


class FloorGrid:
    """Cell centres of the bay's floor, and footprint / shadow masks (rows along y, columns along x)."""

    def __init__(self, shelf: Shelf, cell: float = 0.005):
        self.shelf = shelf
        self.cell = cell
        self.nx = int(round(shelf.width / cell))
        self.ny = int(round(shelf.depth / cell))
        xs = -shelf.width / 2 + (np.arange(self.nx) + 0.5) * cell
        ys = -shelf.depth / 2 + (np.arange(self.ny) + 0.5) * cell
        gx, gy = np.meshgrid(xs, ys)
        self.centers = np.column_stack([gx.ravel(), gy.ravel()])

    def footprint_mask(self, fp: Footprint) -> np.ndarray:
        """Cells (ny, nx) whose centre lies inside the footprint."""
        inside = ~clear_of("cylinder", self.centers, 0.0, (0.0, 0.0), fp, 1e-9)
        return inside.reshape(self.ny, self.nx)

    def shadow_mask(self, fp: Footprint, eye_xy: np.ndarray, height: float | None = None,
                    eye_z: float | None = None, probe_z: float = 0.0) -> np.ndarray:
        """Cells (ny, nx) hidden by the footprint from ``eye_xy``: the segment eye -> centre meets it
        (the footprint's own cells included).

        Overhead (``height`` None): the object is taken as infinitely tall. 3D (``height`` and ``eye_z``
        given): the segment from the eye (at ``eye_z``) to the point ``probe_z`` above the cell's centre must
        meet the object's solid of height ``height``: the segment descends, so it does exactly when its height
        where it leaves the footprint's outline is at most ``height``."""
        e = np.asarray(eye_xy, dtype=float)[:2]
        p = self.centers
        solid = height is not None and eye_z is not None and eye_z > height
        if fp.shape == "cylinder":
            c = np.array([fp.x, fp.y])
            d = p - e
            dd = np.einsum("ij,ij->i", d, d)
            t_c = ((c - e) @ d.T) / dd
            t = np.clip(t_c, 0.0, 1.0)
            closest = e + t[:, None] * d
            dist = np.hypot(closest[:, 0] - c[0], closest[:, 1] - c[1])
            hit = dist <= fp.half_x
            if solid:
                dist_line = np.hypot(*(e + t_c[:, None] * d - c).T)
                half_chord = np.sqrt(np.maximum(fp.half_x ** 2 - dist_line ** 2, 0.0) / dd)
                t_out = np.clip(t_c + half_chord, 0.0, 1.0)
                hit &= eye_z + t_out * (probe_z - eye_z) <= height
            return hit.reshape(self.ny, self.nx)
        cos, sin = math.cos(fp.yaw), math.sin(fp.yaw)
        R = np.array([[cos, -sin], [sin, cos]])
        e_l = (e - (fp.x, fp.y)) @ R
        p_l = (p - (fp.x, fp.y)) @ R
        d = p_l - e_l
        t_lo = np.zeros(len(p))
        t_hi = np.ones(len(p))
        for axis, half in ((0, fp.half_x), (1, fp.half_y)):
            da = d[:, axis]
            small = np.abs(da) < 1e-12
            with np.errstate(divide="ignore", invalid="ignore"):
                t1 = (-half - e_l[axis]) / da
                t2 = (half - e_l[axis]) / da
            lo = np.where(small, -np.inf, np.minimum(t1, t2))
            hi = np.where(small, np.inf, np.maximum(t1, t2))
            outside = small & (abs(e_l[axis]) > half)
            t_lo = np.maximum(t_lo, lo)
            t_hi = np.where(outside, -1.0, np.minimum(t_hi, hi))
        hit = t_lo <= t_hi
        if solid:
            hit &= eye_z + np.clip(t_hi, 0.0, 1.0) * (probe_z - eye_z) <= height
        return hit.reshape(self.ny, self.nx)


def erode(mask: np.ndarray) -> np.ndarray:
    """One-cell erosion (4-neighbourhood) that absorbs the raster's edge noise."""
    out = mask.copy()
    out[1:, :] &= mask[:-1, :]
    out[:-1, :] &= mask[1:, :]
    out[:, 1:] &= mask[:, :-1]
    out[:, :-1] &= mask[:, 1:]
    return out


def free_push_cells(footprint: np.ndarray, hidden: np.ndarray, sign: int) -> int:
    """How many cells a footprint mask can move along x (sign +1 right, -1 left) before any cell it newly
    covers is hidden; NOT_FOUND when nothing hidden lies in its way."""
    rows = np.flatnonzero(footprint.any(axis=1))
    if len(rows) == 0:
        return NOT_FOUND
    f = footprint[rows]
    h = hidden[rows]
    nx = f.shape[1]
    cols = np.arange(nx)
    if sign > 0:
        edge = nx - 1 - np.argmax(f[:, ::-1], axis=1)  # last covered column per row
        ahead = h & (cols[None, :] > edge[:, None])
        first = np.where(ahead.any(axis=1), np.argmax(ahead, axis=1), NOT_FOUND)
        gaps = first - edge - 1
    else:
        edge = np.argmax(f, axis=1)  # first covered column per row
        ahead = h & (cols[None, :] < edge[:, None])
        last = np.where(ahead.any(axis=1), nx - 1 - np.argmax(ahead[:, ::-1], axis=1), -NOT_FOUND)
        gaps = edge - last - 1
    return int(min(gaps.min(), NOT_FOUND))


def push_end_hidden(footprint: np.ndarray, hidden: np.ndarray, sign: int, steps: int) -> np.ndarray:
    """Per step k = 1 .. ``steps`` (cells along x, sign +1 right, -1 left), whether the footprint mask moved by k
    newly covers a hidden cell where it comes to rest (bool (steps,)); cells moved past the raster's edge do not
    count (the walls stop the push first). The ``push_hidden_extent`` "end" reading; :func:`free_push_cells` is
    the "path" one."""
    out = np.zeros(max(0, int(steps)), dtype=bool)
    rows = np.flatnonzero(footprint.any(axis=1))
    if len(rows) == 0 or len(out) == 0:
        return out
    f, h = footprint[rows], hidden[rows]
    nx = f.shape[1]
    for k in range(1, min(len(out), nx - 1) + 1):
        moved = np.zeros_like(f)
        if sign > 0:
            moved[:, k:] = f[:, :nx - k]
        else:
            moved[:, :nx - k] = f[:, k:]
        out[k - 1] = bool((moved & ~f & h).any())
    return out


def column_extents(footprint: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns the footprint covers, and per such column its first and last covered row."""
    cols = np.flatnonzero(footprint.any(axis=0))
    f = footprint[:, cols]
    ny = f.shape[0]
    first = np.argmax(f, axis=0)
    last = ny - 1 - np.argmax(f[::-1, :], axis=0)
    return cols, first, last


def first_hidden_row(hidden: np.ndarray) -> np.ndarray:
    """Per column, the first (front-most) hidden row; NOT_FOUND where the column is clear."""
    return np.where(hidden.any(axis=0), np.argmax(hidden, axis=0), NOT_FOUND)


def disc_offsets(radius_cells: int) -> list[tuple[int, int]]:
    """(row, column) offsets of the cells whose centres lie within ``radius_cells`` of a cell's centre."""
    r = int(radius_cells)
    return [(dr, dc) for dr in range(-r, r + 1) for dc in range(-r, r + 1) if dr * dr + dc * dc <= r * r]


@functools.lru_cache(maxsize=8)
def disc_kernel(radius_cells: int) -> np.ndarray:
    """The disc of :func:`disc_offsets` as a (2r+1, 2r+1) uint8 structuring element. (cached: read only)."""
    r = int(radius_cells)
    kernel = np.zeros((2 * r + 1, 2 * r + 1), dtype=np.uint8)
    for dr, dc in disc_offsets(r):
        kernel[dr + r, dc + r] = 1
    return kernel


def open_with_disc(mask: np.ndarray, radius_cells: int) -> np.ndarray:
    """Morphological opening by a disc: the cells covered by some disc of ``radius_cells`` lying entirely in
    ``mask`` (cells outside the raster count as outside the mask). Where no such disc fits, no object whose
    footprint contains that disc can stand unseen.

    OpenCV's erosion then dilation with the disc kernel, both with a zero border (the disc is symmetric, so
    the kernel needs no reflection); equal to shifting the mask by every disc offset (tested)."""
    if radius_cells <= 0 or not mask.any():
        return mask.copy()
    kernel = disc_kernel(radius_cells)
    m = mask.astype(np.uint8)
    centres = cv2.erode(m, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    if not centres.any():
        return np.zeros_like(mask)
    return cv2.dilate(centres, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0).astype(bool)


def band_crosses_hidden(grid: FloorGrid, hidden: np.ndarray, y_lo: float, y_hi: float, x_lo, x_hi) -> np.ndarray:
    """Whether the floor rectangle x_lo <= x <= x_hi, y_lo <= y <= y_hi (m, S) holds the centre of a ``hidden`` cell
    (bool (ny, nx) on ``grid``), for each of the arrays ``x_lo`` and ``x_hi`` (same shape; the result has it): the
    test of an object carried across the shelf at one depth, its bounding box swept along x (a carried way that
    crosses space the camera has not seen). A band wholly in front of the bay holds no cell."""
    x_lo, x_hi = np.asarray(x_lo, float), np.asarray(x_hi, float)
    r0 = max(0, int(math.ceil((y_lo + grid.shelf.depth / 2.0) / grid.cell - 0.5 - 1e-9)))
    r1 = min(grid.ny - 1, int(math.floor((y_hi + grid.shelf.depth / 2.0) / grid.cell - 0.5 + 1e-9)))
    if r1 < r0:
        return np.zeros(x_lo.shape, dtype=bool)
    columns = hidden[r0:r1 + 1].any(axis=0)
    counts = np.concatenate([[0], np.cumsum(columns)])
    c0 = np.clip(np.ceil((x_lo + grid.shelf.width / 2.0) / grid.cell - 0.5 - 1e-9), 0, grid.nx).astype(int)
    c1 = np.clip(np.floor((x_hi + grid.shelf.width / 2.0) / grid.cell - 0.5 + 1e-9), -1, grid.nx - 1).astype(int)
    return (c1 >= c0) & (counts[np.maximum(c1 + 1, 0)] - counts[np.minimum(c0, grid.nx)] > 0)
