"""Where the unseen part of a seen object may end, as probabilities: what slax-belief's camera-mode options
``extent_prior`` and ``extent_risk`` (:class:`~slax_drake.policies.belief_options.BeliefOptions`) read.

The estimator gives each seen object an extent range (:class:`~slax_drake.perception.estimator.ExtentRange`): its
observed part and the farthest each edge may reach. How far the true edges reach along their ranges was measured on
first frames of the simulated shelf; this module holds that measurement as a tail probability, the joint draws
``extent_risk`` makes from it, and the weight of a target placement inside a range. Lengths in metres, positions
in the shelf frame S.
"""

from __future__ import annotations

import numpy as np

# extent_risk: the shares of an unseen edge's extent range an object's draw takes, with their probabilities: the
# bins of EXTENT_SHARE_TAIL below, each at its least share (below a tenth of the range: none of it; 3 % at the farthest)
EXTENT_DRAW = ((0.0, 0.60), (0.1, 0.12), (0.25, 0.15), (0.5, 0.07), (0.75, 0.03), (1.0, 0.03))
EXTENT_DRAWS = 8  # extent_risk: joint draws of every seen object's share per decision
# extent_prior and extent_risk: (share of an unseen edge's extent range, the probability that the true edge lies at
# least that far along it), linear between the points, 1 at share 0. Measured on first frames of the simulated shelf
# (6, 8 and 10 objects, 30 scenes each, 160 px, label segmentation; every edge whose range reaches more than 2 cm past
# the observed part): about 60 % of such edges end within a tenth of their range (the observed part was the whole
# object), 28 % reach a quarter of it or more, 13 % half, 0 / 1.5 / 3.4 % (6 / 8 / 10 objects) the farthest
# (`python benchmarks/extent_ranges.py --scenes 30 --tail`; docs/research/uncertain-extents.md)
EXTENT_SHARE_TAIL = ((0.0, 1.0), (0.02, 0.56), (0.05, 0.48), (0.1, 0.4), (0.25, 0.28), (0.5, 0.13), (0.75, 0.06),
                     (1.0, 0.03))


def extent_share_tail(shares: np.ndarray) -> np.ndarray:
    """P(an unseen edge reaches at least ``shares`` of its extent range), elementwise (:data:`EXTENT_SHARE_TAIL`);
    0 past share 1 (beyond the range's farthest edge)."""
    s = np.asarray(shares, dtype=float)
    xs, ps = zip(*EXTENT_SHARE_TAIL)
    return np.where(s > 1.0, 0.0, np.interp(s, xs, ps))


def extent_free_weights(placements: np.ndarray, half: tuple[float, float], extents) -> np.ndarray:
    """(K,) the chance that none of ``extents`` (:class:`~slax_drake.perception.estimator.ExtentRange`, one per seen
    object) reaches a target of half sizes ``half`` (m, shelf-aligned) at each of ``placements`` (K, 2; m, S): per
    range, the least share s* at which its rectangle, every edge s of the way from the observed part to its
    farthest, meets the target's footprint (separating axes of the range's rectangle), and 1 - tail(s*)
    (:func:`extent_share_tail`), multiplied over the ranges."""
    w = np.ones(len(placements))
    if not len(placements):
        return w
    for e in extents:
        c, s = np.cos(e.yaw), np.sin(e.yaw)
        need = np.zeros(len(placements))
        for k, (axis, reach) in enumerate(((np.array([c, s]), half[0] * abs(c) + half[1] * abs(s)),
                                           (np.array([-s, c]), half[0] * abs(s) + half[1] * abs(c)))):
            mid = placements @ axis
            lo, hi = mid - reach, mid + reach
            low_room = e.least_lo[k] - e.most_lo[k]
            high_room = e.most_hi[k] - e.least_hi[k]
            with np.errstate(divide="ignore", invalid="ignore"):
                below = np.where(low_room > 0, (e.least_lo[k] - hi) / low_room, np.inf)
                above = np.where(high_room > 0, (lo - e.least_hi[k]) / high_room, np.inf)
            axis_need = np.where(hi <= e.least_lo[k], below, np.where(lo >= e.least_hi[k], above, 0.0))
            need = np.maximum(need, axis_need)
        w *= 1.0 - extent_share_tail(need)
    return w
