"""The three target aspect ratios of the perception network (paper Sec. V-B), one output head each.

Sizes are [x, y, z] extents in metres (x lateral, y into the shelf, z up), in head order.
"""

from __future__ import annotations

import numpy as np

from slax_drake.errors import UserError

TARGET_SIZES: tuple[tuple[float, float, float], ...] = (
    (0.06, 0.06, 0.03),
    (0.06, 0.06, 0.06),
    (0.06, 0.06, 0.12),
)


def ratio_index(target_size, sizes=TARGET_SIZES) -> int:
    """Index of the head for a target of ``target_size`` (metres, 3 values), matched to 1 mm."""
    size = np.asarray(target_size, dtype=float).reshape(-1)
    for i, s in enumerate(sizes):
        if size.shape == (3,) and np.allclose(size, s, atol=1e-3):
            return i
    known = ", ".join("x".join(f"{v:g}" for v in s) for s in sizes)
    raise UserError(f"target size {tuple(float(v) for v in size)} m has no network head (known: {known} m)")
