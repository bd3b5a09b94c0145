"""Where a blade push leaves a box: quasi-static pushing with the blade's flat face (planar, shelf frame S, m, rad).

The first-order model of the paper translates a pushed object by d along x. A real flat pusher turns a box it meets
at a corner, or along only part of a face, until the box's face lies flush against it (Mason 1986; Lynch, Maekawa
and Tanie 1992): measured in the Drake station (``research/push_contact.py``), a lone box turned 15 or 30 deg
and pushed 0.10 m ends turned by about that much and 1-3 cm off the straight line, and a box 16 cm deep pushed
by a blade meeting only the front 3 cm of its side turns 40 deg. This module predicts that motion.

Model. The box rests on the floor on its four bottom corners (as the station's boxes do); its friction with
the floor is approximated by an ellipsoidal limit surface, under which a force f = (f_x, f_y) applied at p (from the
centre) moves the box with the twist (v_x, v_y, w) proportional to (f_x, f_y, (p x f) / c^2), c the ratio of the
largest friction moment to the largest friction force (Lee and Cutkosky 1991; :func:`characteristic_length`). The blade is a segment of the line
x = x_b (its face), ``y_lo`` to ``y_hi``, advancing along n = (sign, 0); the force it applies at a contact lies
in the friction cone of half-angle atan(``mu``) about n. With one contact point the box sticks to the blade
when the pusher's velocity lies in the cone of contact velocities the cone's forces give, and slides along
it at the cone's edge otherwise (the motion cone). With two (a face flush on the blade) the box translates when
the foot of its centre on the face lies between them, and turns about the contact nearer to it otherwise.
The blade advances in steps of ``STEP``; its travel after the first contact is d, as in the first-order model.

Discs (cylinders) are pushed through their centre and translate; so does a box whose contact's lever about its
centre is nil. A box that turns off the blade's end stays where it was left. Neighbours are not modelled: the action model keeps the pushed object's way free.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from slax_drake.scene.footprint import Footprint

STEP = 0.002  # m of blade travel per integration step
TOUCH = 1e-4  # m: points of the box this close to the blade's face touch it
# The blade on packaging (Coulomb mu). research/push_contact.py: 0.3 to 1.0 change no case's verdict against Drake.
BLADE_OBJECT_FRICTION = 0.5


def characteristic_length(half_x: float, half_y: float) -> float:
    """c (m) of a box standing on its four bottom corners: their distance from its centre (the ratio of the
    largest friction moment to the largest friction force). The Drake station's boxes stand on spheres at their
    corners (:mod:`slax_drake.station.scene_world`); a uniform pressure over the rectangle (c about half of
    this) turns them 1.5-2x too fast against the station (research/push_contact.py: 34 of 58 pushes predicted
    against 50 of 58)."""
    return math.hypot(half_x, half_y)


def _twist(p: np.ndarray, f: np.ndarray, c2: float) -> np.ndarray:
    """The box's twist (v_x, v_y, w), up to scale, under the force f at p (from its centre)."""
    return np.array([f[0], f[1], (p[0] * f[1] - p[1] * f[0]) / c2])


def _point_velocity(v: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The velocity of the box's point p (from its centre) under the twist v."""
    return np.array([v[0] - v[2] * p[1], v[1] + v[2] * p[0]])


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def point_push_twist(p: np.ndarray, sign: float, mu: float, c2: float) -> np.ndarray:
    """The box's twist per metre of blade travel when the blade's face (normal (sign, 0)) pushes it at its
    point p alone (from its centre): sticking inside the motion cone, sliding along the blade at its edge."""
    n = np.array([sign, 0.0])
    t = np.array([0.0, 1.0])
    pusher = n  # the blade moves along its normal
    edges = [n + mu * t, n - mu * t]
    twists = [_twist(p, f, c2) for f in edges]
    vels = [_point_velocity(v, p) for v in twists]
    a, b = vels
    if abs(_cross(a, b)) < 1e-12:  # a degenerate cone (no lever): the box moves with the blade
        return np.array([sign, 0.0, 0.0])
    inside = _cross(a, pusher) * _cross(a, b) >= 0.0 and _cross(pusher, b) * _cross(a, b) >= 0.0
    if inside:  # sticking: the contact point moves with the blade; the force in the cone that does it
        m = np.column_stack([a, b])
        weights = np.linalg.solve(m, pusher)
        return weights[0] * twists[0] + weights[1] * twists[1]
    # sliding: the twist of the cone's edge nearer to the pusher's velocity, scaled to keep up with the blade
    k = 0 if abs(_cross(a, pusher)) < abs(_cross(b, pusher)) else 1
    normal_speed = float(np.dot(vels[k], n))
    return twists[k] / normal_speed


def _contacts(corners: np.ndarray, x_b: float, sign: float, y_lo: float, y_hi: float):
    """The points where the box's rectangle meets the blade's face: the points of its outline within the
    blade's y-range that lie farthest toward the blade (within TOUCH), as (points (K, 2), gap), the gap the
    signed distance (m) from the face to the nearest such point along the push (negative: inside)."""
    pts = [c for c in corners if y_lo <= c[1] <= y_hi]
    for k in range(4):  # the outline's crossings of the blade's ends
        a, b = corners[k], corners[(k + 1) % 4]
        for y in (y_lo, y_hi):
            if (a[1] - y) * (b[1] - y) < 0.0:
                s = (y - a[1]) / (b[1] - a[1])
                pts.append(a + s * (b - a))
    if not pts:
        return np.zeros((0, 2)), math.inf
    pts = np.array(pts)
    gaps = sign * (pts[:, 0] - x_b)
    gap = float(gaps.min())
    return pts[gaps <= gap + TOUCH], gap


@functools.lru_cache(maxsize=65536)
def push_pose(fp: Footprint, sign: float, d: float, y_lo: float, y_hi: float,
              mu: float = BLADE_OBJECT_FRICTION) -> tuple[float, float, float]:
    """(x, y, yaw) of the footprint ``fp`` after the blade's face, spanning y in [``y_lo``, ``y_hi``] and
    advancing along (``sign``, 0), has travelled ``d`` (m, >= 0) past the first contact. A disc translates."""
    if fp.shape == "cylinder" or d <= 0.0:
        return fp.x + sign * d, fp.y, fp.yaw
    c2 = characteristic_length(fp.half_x, fp.half_y) ** 2
    centre, yaw = np.array([fp.x, fp.y]), fp.yaw
    corners = fp.corners()
    # the blade's face starts at the box's point nearest to it within its span (the contacts with the face at 0)
    in_range, _ = _contacts(corners, 0.0, sign, y_lo, y_hi)
    if len(in_range) == 0:
        return fp.x + sign * d, fp.y, fp.yaw  # the blade misses the box: the model's straight push
    x_b = float(in_range[0][0])
    travelled = 0.0
    while travelled < d - 1e-12:
        step = min(STEP, d - travelled)
        points, gap = _contacts(corners, x_b, sign, y_lo, y_hi)
        if len(points) == 0 or gap > STEP:  # turned off the blade's end: the blade passes it, it stays
            break
        offsets = points - centre
        if len(points) >= 2 and np.ptp(points[:, 1]) > TOUCH:
            lo, hi = float(points[:, 1].min()), float(points[:, 1].max())
            if lo <= centre[1] <= hi:  # flush, the centre's foot between the contacts: it translates
                twist = np.array([sign, 0.0, 0.0])
            else:  # turns about the contact nearer its centre
                nearest = offsets[np.argmin(np.abs(offsets[:, 1]))]
                twist = point_push_twist(nearest, sign, mu, c2)
        else:
            twist = point_push_twist(offsets[0], sign, mu, c2)
        centre = centre + twist[:2] * step
        yaw += twist[2] * step
        x_b += sign * step
        # keep the box on the blade's face (the integration's drift, and a corner turned into it)
        corners = Footprint(fp.shape, centre[0], centre[1], yaw, fp.half_x, fp.half_y).corners()
        _, gap = _contacts(corners, x_b, sign, y_lo, y_hi)
        if gap < 0.0:
            centre[0] -= sign * gap
            corners = Footprint(fp.shape, centre[0], centre[1], yaw, fp.half_x, fp.half_y).corners()
        travelled += step
    return float(centre[0]), float(centre[1]), float(yaw)
