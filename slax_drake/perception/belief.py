"""The camera-mode belief: what a search policy knows when it sees only the camera frame (paper Sec. V).

:class:`ObservedBelief` holds one :class:`~slax_drake.perception.observation.Observation` (depth, occluder
segmentation, target mask, camera), the estimator's object hypotheses (``known``: SceneObjects named
``segment_<id>``, what the action model checks feasibility against) and a :class:`DistributionSource`, and gives:

- ``p1d``: P_t, the 1D target occupancy distribution of the observation itself;
- ``predict(objects)``: the distribution after the hypotheses have moved as ``objects`` says (the output of
  ``apply_action`` on ``known``, one or several actions deep), computed the SLAX-RAY way: every moved segment's
  pixels are shifted in the image by its planar displacement (:func:`~slax_drake.perception.estimator.predict_observation`),
  a removed hypothesis's pixels are cleared, and the pixels a segment leaves show what the empty shelf shows there
  (the static shelf model, ``background``: the optimistic assumption that nothing stood behind it, the same
  assumption the paper's image-space prediction makes); then the same distribution source runs on the predicted
  depth image. Never from true poses.

Two distribution sources, one interface (``distribution(depth, obstacles) -> p1d``):

- :class:`DepthDistribution`: :func:`slax_drake.occupancy.from_depth.occupancy_from_depth` (the target's hidden
  placements judged from the depth image, clear of the hypotheses): the ground-truth model's definitions on
  what the camera sees;
- :class:`NetworkDistribution`: the occupancy network (:class:`~slax_drake.perception.inference.OccupancyPredictor`)
  on the depth image; the observation must then be taken at the network's resolution.

Results are cached per hypothesis state (the policies evaluate the same states repeatedly within one step).
"""

from __future__ import annotations

import numpy as np

from slax_drake.occupancy.from_depth import occupancy_from_depth
from slax_drake.perception.estimator import EstimatorConfig, Hypothesis, estimate_objects, predict_observation
from slax_drake.perception.observation import Observation
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, Shelf, state_key

SOURCES = ("depth", "network")
_MOVED = 1e-6  # m: a hypothesis displaced by less than this has not moved


class DepthDistribution:
    """P(u) from the depth image by the occupancy definitions (``occupancy_from_depth``), the hypotheses as
    obstacles; 1 cm placement lattice and target samples, like the privileged ground-truth model."""

    name = "depth"

    def __init__(self, shelf: Shelf, target_size=(0.06, 0.06, 0.06), grid_step: float = 0.01,
                 surface_spacing: float = 0.01):
        self.shelf = shelf
        self.target_size = tuple(float(v) for v in target_size)
        self.grid_step = grid_step
        self.surface_spacing = surface_spacing
        self.calls = 0

    def distribution(self, depth: np.ndarray, camera: Camera, obstacles=()) -> np.ndarray:
        self.calls += 1
        occ = occupancy_from_depth(depth, camera, self.shelf, self.target_size, self.grid_step,
                                   self.surface_spacing, obstacles=obstacles)
        return np.asarray(occ.p1d, dtype=np.float64)


class NetworkDistribution:
    """P(u) from the occupancy network on the depth image (the obstacles are not used: the network sees them)."""

    name = "network"

    def __init__(self, target_size=(0.06, 0.06, 0.06), model=None, num_threads: int | None = 1):
        from slax_drake.perception.inference import OccupancyPredictor

        self.predictor = OccupancyPredictor(model, num_threads=num_threads)
        self.head = self.predictor.head_of(target_size)
        self.calls = 0

    @property
    def resolution(self) -> tuple[int, int]:
        return self.predictor.resolution

    def distribution(self, depth: np.ndarray, camera: Camera, obstacles=()) -> np.ndarray:
        self.calls += 1
        return self.predictor.predict(depth, head=self.head).p1d[0].astype(np.float64)


def make_source(kind: str, shelf: Shelf, target_size):
    """``depth`` -> :class:`DepthDistribution`; ``network`` -> :class:`NetworkDistribution` (shipped model)."""
    if kind == "depth":
        return DepthDistribution(shelf, target_size)
    if kind == "network":
        return NetworkDistribution(target_size)
    raise ValueError(f"unknown distribution source {kind!r}; choose one of {', '.join(SOURCES)}")


def background_depth(shelf: Shelf, camera: Camera) -> np.ndarray:
    """The empty shelf's depth image (H, W) float32 metres in ``camera`` (0 where nothing is hit)."""
    from slax_drake.scene.raycast import SceneRaycaster

    empty = Scene(shelf, camera, (), None)
    depth, _ = SceneRaycaster(empty).render(camera)
    return depth


class ObservedBelief:
    """See the module docstring. ``observation``'s segment ids name the hypotheses (``segment_<id>``);
    ``hypotheses`` (default: the estimator's on ``observation``) and ``p1d`` (default: the source on the frame) may
    come from the PerceptionSystem. ``remembered``: the objects seen earlier in the trial and hidden in this frame,
    where they were last estimated (an :class:`~slax_drake.perception.tracking.ObjectTracker`'s hidden tracks,
    flagged ``remembered``); None when no tracker runs."""

    def __init__(self, observation: Observation, shelf: Shelf, source, background: np.ndarray | None = None,
                 hypotheses: list[Hypothesis] | None = None, config: EstimatorConfig = EstimatorConfig(),
                 cache_size: int = 4096, p1d: np.ndarray | None = None, remembered: tuple | None = None):
        self.observation = observation
        self.remembered = remembered
        self.shelf = shelf
        self.source = source
        self.hypotheses = estimate_objects(observation, shelf, config) if hypotheses is None else list(hypotheses)
        self.known = tuple(h.object for h in self.hypotheses)
        self._ids = {h.object.name: h.segment_id for h in self.hypotheses}
        self.background = background_depth(shelf, observation.camera) if background is None else background
        self.cache_size = cache_size
        self._cache: dict = {}
        if p1d is not None:  # P_t already computed by perception (the same source on the same frame)
            p = np.array(p1d, dtype=np.float64)
            p.setflags(write=False)
            self._cache[state_key(self.known)] = p
        self.p1d = self.predict(self.known)

    def segment_id(self, name: str) -> int:
        """The segment id of hypothesis ``name`` (``segment_<id>``)."""
        return self._ids[name]

    def predicted_observation(self, objects) -> Observation:
        """The frame expected when the hypotheses stand as ``objects`` says (see the module docstring)."""
        now = {o.name: o for o in objects}
        obs = self.observation
        for before in self.known:
            sid = self._ids[before.name]
            after = now.get(before.name)
            if after is None:
                obs = self._cleared(obs, sid)
                continue
            dx, dy = (float(v) for v in after.center[:2] - before.center[:2])
            if abs(dx) < _MOVED and abs(dy) < _MOVED:
                continue
            if sid not in obs.segment_ids:
                # An object moved earlier in this loop now covers this one wholly: it has no pixel left to move, so
                # the prediction leaves it out (an approximation: had it come out from behind, the frame would show it).
                continue
            previous = obs.segmentation == sid
            obs = predict_observation(obs, sid, dx, dy)
            left = previous & (obs.segmentation != sid) & (obs.depth <= 0)
            if left.any():
                depth = obs.depth.copy()
                depth[left] = self.background[left]
                obs = obs.replaced(depth=depth)
        return obs

    def predict(self, objects) -> np.ndarray:
        """P(u) (W,) float64, read-only, after the hypotheses moved as ``objects`` says."""
        key = state_key(tuple(objects))
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        obs = self.predicted_observation(objects)
        p = self.source.distribution(obs.depth, obs.camera, obstacles=tuple(objects))
        p.setflags(write=False)
        if len(self._cache) >= self.cache_size:
            self._cache.clear()
        self._cache[key] = p
        return p

    def _cleared(self, obs: Observation, sid: int) -> Observation:
        mask = obs.segmentation == sid
        depth = obs.depth.copy()
        depth[mask] = self.background[mask]
        labels = np.where(mask, 0, obs.segmentation)
        return obs.replaced(depth=depth, segmentation=labels, min_valid_fraction=0.0)
