"""Collision-free joint paths in free space (no contact allowed): the straight line, or a bidirectional RRT.

The planner's free segments (from the start configuration to an action's first waypoint, and from its last
waypoint back to the observation pose) are straight lines in joint space when the straight line is free. With
robot self-collision checked, a straight line often sweeps the forearm through the torso; then
:func:`free_path` grows two trees (RRT-Connect, Kuffner and LaValle 2000) from both ends in the planned joints'
space, inside the position limits less the IK margin (continuous joints: within half a turn beyond the two
ends), and shortens the path found by trying to join non-consecutive nodes directly. Every edge is checked
densely with the planning world's collision checker (environment and self-collision). The search is seeded:
the same ends in the same world give the same path.
"""

from __future__ import annotations

import numpy as np

MAX_ITERATIONS = 600
SEARCH_STEP = 0.02  # rad (m) between configurations checked while the trees grow; the path found is then
# checked densely (PlanningWorld.edge_free), and searched again with dense checks if that fails
STEP = 0.35  # rad (m for the torso) of the largest joint change per tree extension
SHORTCUT_TRIES = 40


def _bounds(limits, qa, qb, margin):
    lo = np.where(np.isfinite(limits.position_lower), limits.position_lower + margin, np.minimum(qa, qb) - np.pi)
    hi = np.where(np.isfinite(limits.position_upper), limits.position_upper - margin, np.maximum(qa, qb) + np.pi)
    return lo, hi


def _toward(q_from, q_to, step):
    d = q_to - q_from
    n = float(np.max(np.abs(d)))
    return q_to.copy() if n <= step else q_from + d * (step / n)


def free_path(world, qa, qb, limits, margin: float, seed: int = 0, max_iterations: int = MAX_ITERATIONS):
    """Configurations [qa, ..., qb] joined by collision-free straight segments, or None if none was found in
    ``max_iterations`` extensions. ``world``: a PlanningWorld (its tool-contact filter as the caller set it).
    The trees grow with configurations ``SEARCH_STEP`` apart checked; every segment of the path returned is
    checked densely, and when one fails the search runs again with dense checks."""
    qa = np.asarray(qa, float)
    qb = np.asarray(qb, float)
    if world.edge_free(qa, qb):
        return [qa, qb]
    coarse = _search(world, qa, qb, limits, margin, seed, max_iterations,
                     lambda a, b: world.edge_free_coarse(a, b, SEARCH_STEP))
    if coarse is None:
        return None
    if all(world.edge_free(a, b) for a, b in zip(coarse[:-1], coarse[1:])):
        return coarse
    return _search(world, qa, qb, limits, margin, seed, max_iterations, world.edge_free)


def _search(world, qa, qb, limits, margin, seed, max_iterations, edge_free):
    """RRT-Connect from qa and qb with ``edge_free`` as the edge test; the shortened path, or None."""
    rng = np.random.default_rng(seed)
    lo, hi = _bounds(limits, qa, qb, margin)
    trees = [([qa], [-1]), ([qb], [-1])]  # (nodes, parent index) grown from qa and from qb

    def nearest(tree, q):
        nodes = np.asarray(tree[0])
        return int(np.argmin(np.max(np.abs(nodes - q), axis=1)))

    def extend(tree, q_target):
        """One step of ``tree`` toward q_target; the new node's index, or None when blocked."""
        i = nearest(tree, q_target)
        q_new = _toward(tree[0][i], q_target, STEP)
        if not edge_free(tree[0][i], q_new):
            return None
        tree[0].append(q_new)
        tree[1].append(i)
        return len(tree[0]) - 1

    def path_to_root(tree, i):
        out = []
        while i >= 0:
            out.append(tree[0][i])
            i = tree[1][i]
        return out

    for iteration in range(max_iterations):
        grow, other = (trees[0], trees[1]) if iteration % 2 == 0 else (trees[1], trees[0])
        q_rand = rng.uniform(lo, hi)
        i_new = extend(grow, q_rand)
        if i_new is None:
            continue
        q_new = grow[0][i_new]
        while True:  # connect: the other tree steps toward the new node until it reaches it or is blocked
            j = extend(other, q_new)
            if j is None:
                break
            if np.array_equal(other[0][j], q_new):
                a_side = path_to_root(trees[0], i_new if grow is trees[0] else j)[::-1]
                b_side = path_to_root(trees[1], j if grow is trees[0] else i_new)
                return _shortcut(edge_free, a_side + b_side[1:], rng)
    return None


def _shortcut(edge_free, path, rng):
    """Removes intermediate nodes where two nodes can be joined directly (seeded random pairs, then greedy)."""
    path = list(path)
    for _ in range(SHORTCUT_TRIES):
        if len(path) <= 2:
            break
        i, j = sorted(rng.choice(len(path), size=2, replace=False))
        if j - i >= 2 and edge_free(path[i], path[j]):
            path = path[:i + 1] + path[j:]
    return path
