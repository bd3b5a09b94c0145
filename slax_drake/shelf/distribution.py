"""Target occupancy distributions for the policies: one interface for ground truth and the network.

A :class:`DistributionModel` maps what the policy believes the shelf looks like to a 1D distribution P(u)
over the columns u of a coarse image (paper Sec. V-B: P(x) = sum_y p(x, y)). The belief is a :class:`Scene`
holding only the objects the policy has seen, moved as hypothetical actions say; for the current state of the
simulator it is the true scene. ``GroundTruthDistribution`` runs :func:`slax_drake.occupancy.compute_occupancy`
on it at coarse settings; the learned model (:class:`slax_drake.perception.distribution_model.LearnedDistribution`)
renders the same scene's depth image and runs the network, behind the same ``distribution(scene)`` call.

History encoding and the policies' scores: P'_t = min(P_t, P'_{t-1}); support r = |{u : P'(u) > 0}|;
entropy of P' normalised to sum 1.
"""

from __future__ import annotations

import numpy as np

from slax_drake.scene.model import Scene, state_key

PERCEPTION_MODES = ("ground-truth", "learned")


class DistributionModel:
    """Maps a believed scene to the 1D target occupancy distribution (columns of a coarse image)."""

    name = "abstract"

    def distribution(self, scene: Scene) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError


class GroundTruthDistribution(DistributionModel):
    """``compute_occupancy`` on the believed scene, at coarse settings, cached per state.

    Defaults: a 1 cm placement lattice, 1 cm target surface samples, the scene's camera imaged 160 px wide
    (benchmarks/bench_policies.py measures how this agrees with the fine 5 mm / 640 px result)."""

    name = "ground-truth"

    def __init__(self, target_size=(0.06, 0.06, 0.06), grid_step: float = 0.01, surface_spacing: float = 0.01,
                 image_width: int = 160, cache_size: int = 4096):
        self.target_size = tuple(float(v) for v in target_size)
        self.grid_step = grid_step
        self.surface_spacing = surface_spacing
        self.image_width = image_width
        self.cache_size = cache_size
        self._cache: dict = {}
        self._hidden: dict = {}  # state key -> number of hidden placements (the unseen space, in lattice cells)
        self.calls = 0  # distributions actually computed (cache misses)

    def hidden_count(self, scene: Scene) -> int:
        """The number of hidden target placements on the lattice in ``scene`` (the unseen space P is spread over;
        computed with, and cached beside, :meth:`distribution`)."""
        key = state_key(scene.objects)
        if key not in self._hidden:
            self.distribution(scene)
        return self._hidden[key]

    def distribution(self, scene: Scene) -> np.ndarray:
        key = state_key(scene.objects)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        from slax_drake.occupancy import compute_occupancy

        cam = scene.camera
        height = max(1, int(round(cam.height * self.image_width / cam.width)))
        occ = compute_occupancy(
            scene.with_objects(scene.objects), target_size=self.target_size, grid_step=self.grid_step,
            camera=cam.with_resolution(self.image_width, height), surface_spacing=self.surface_spacing,
        )
        p = np.asarray(occ.p1d, dtype=np.float64)
        p.setflags(write=False)
        self.calls += 1
        if len(self._cache) >= self.cache_size:
            self._cache.clear()
            self._hidden.clear()
        self._cache[key] = p
        self._hidden[key] = int(occ.num_hidden)
        return p


def make_distribution_model(perception: str, target_size) -> DistributionModel:
    """The policies' distribution model: ``ground-truth`` (compute_occupancy on the believed scene) or ``learned``
    (the shipped perception network on the believed scene's depth image)."""
    if perception == "ground-truth":
        return GroundTruthDistribution(target_size)
    if perception == "learned":
        from slax_drake.perception.distribution_model import LearnedDistribution

        return LearnedDistribution(target_size)
    from slax_drake.errors import UserError

    raise UserError(f"unknown perception '{perception}' (known: {', '.join(PERCEPTION_MODES)})")


def history_min(p: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """P'_t = min(P_t, P'_{t-1}) (P'_0 = P_0)."""
    return np.asarray(p, dtype=float) if previous is None else np.minimum(p, previous)


def support(p: np.ndarray) -> int:
    """r = |{u : P(u) > 0}|."""
    return int(np.count_nonzero(np.asarray(p) > 0))


def entropy(p: np.ndarray) -> float:
    """Shannon entropy (nats) of P normalised to sum 1; 0 for an empty distribution."""
    p = np.asarray(p, dtype=float)
    total = p.sum()
    if total <= 0:
        return 0.0
    q = p[p > 0] / total
    return float(-(q * np.log(q)).sum())
