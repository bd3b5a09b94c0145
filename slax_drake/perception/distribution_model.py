"""The learned occupancy network behind the search policies' distribution-model interface.

``LearnedDistribution(target_size).distribution(scene)`` renders the believed scene's depth image at the
model's resolution (the ray caster, which equals the Drake renderer's depth to 1e-6 m) and returns the
network's 1D distribution along image x for the target's head: (W,) float64, read-only, zero outside the
predicted support, summing to one. It has the same ``name`` / ``distribution(scene)`` / ``calls`` members as
the policies' ``GroundTruthDistribution`` (duck-typed: perception does not import the later policy stage).
Results are cached per object state, as the policies evaluate the same hypothetical scenes repeatedly.
"""

from __future__ import annotations

import numpy as np

from slax_drake.perception.inference import OccupancyPredictor
from slax_drake.scene.model import Scene, state_key


class LearnedDistribution:
    """Depth image of the believed scene -> the network's 1D target occupancy distribution."""

    name = "learned"

    def __init__(self, target_size=(0.06, 0.06, 0.06), model=None, num_threads: int | None = 1,
                 cache_size: int = 4096):
        self.predictor = OccupancyPredictor(model, num_threads=num_threads)
        self.target_size = tuple(float(v) for v in target_size)
        self.head = self.predictor.head_of(self.target_size)
        self.cache_size = cache_size
        self._cache: dict = {}
        self.calls = 0  # network evaluations (cache misses)

    def depth_image(self, scene: Scene) -> np.ndarray:
        """The believed scene's depth image (H, W) float32 metres at the model's resolution (target excluded)."""
        from slax_drake.scene.raycast import SceneRaycaster

        camera = scene.camera.with_resolution(*self.predictor.resolution)
        depth, _ = SceneRaycaster(scene).render(camera)
        return np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)

    def distribution(self, scene: Scene) -> np.ndarray:
        key = state_key(scene.objects)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        p = self.predictor.predict(self.depth_image(scene), head=self.head).p1d[0].astype(np.float64)
        p.setflags(write=False)
        self.calls += 1
        if len(self._cache) >= self.cache_size:
            self._cache.clear()
        self._cache[key] = p
        return p
