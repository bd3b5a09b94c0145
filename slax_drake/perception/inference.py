"""Inference: depth images (metres) -> 2D and 1D target occupancy distributions for a chosen target ratio.

The network's softmax is positive everywhere; the predicted support is where the mass reaches the model's
calibrated thresholds (``support_threshold_2d / (H*W)`` per pixel, ``support_threshold_1d / W`` per column of the
1D distribution, both stored in the weight file). Mass below them is set to zero and the rest renormalised, so
``p1d > 0`` is the predicted support that the search policies reduce (paper Sec. V-C).
"""

from __future__ import annotations

import copy
import dataclasses
from pathlib import Path

import numpy as np
import torch

from slax_drake.errors import ImageSizeError
from slax_drake.perception.network import distributions_2d
from slax_drake.perception.targets import ratio_index
from slax_drake.perception.weights import LoadedModel, load_weights


@dataclasses.dataclass(frozen=True)
class PredictedOccupancy:
    """Predicted distributions of one batch: ``p2d`` (B, H, W) and ``p1d`` (B, W), float32, each summing to
    one per image (zero outside the predicted support); ``raw_p2d`` is the untruncated softmax."""

    p2d: np.ndarray
    p1d: np.ndarray
    raw_p2d: np.ndarray


class OccupancyPredictor:
    """Runs a loaded model on depth images; thread count fixed at construction (one core by default).

    ``device`` ("cpu", "cuda", ...) is where the network runs; inputs and outputs stay numpy on the CPU."""

    def __init__(self, model: LoadedModel | str | Path | None = None, num_threads: int | None = 1,
                 batch_size: int = 32, device: str = "cpu"):
        self.model = model if isinstance(model, LoadedModel) else load_weights(model)
        self.num_threads = num_threads
        self.batch_size = batch_size
        self.device = torch.device(device)
        self._network = self.model.network if self.device.type == "cpu" else \
            copy.deepcopy(self.model.network).to(self.device)

    @property
    def resolution(self) -> tuple[int, int]:
        """(width, height) of the depth images the model takes."""
        return self.model.config.width, self.model.config.height

    def head_of(self, target_size) -> int:
        """The head index for a target of ``target_size`` [x, y, z] metres."""
        return ratio_index(target_size, [tuple(s) for s in self.model.target_sizes])

    def predict(self, depth: np.ndarray, target_size=(0.06, 0.06, 0.06), head: int | None = None,
                truncate: bool = True) -> PredictedOccupancy:
        """Depth (H, W) or (B, H, W) in metres -> distributions for the head of ``target_size`` (or ``head``).

        A single image gives a batch of one. ``truncate=False`` keeps the softmax's full support."""
        head = self.head_of(target_size) if head is None else int(head)
        if not 0 <= head < self.model.config.num_heads:
            raise ImageSizeError(f"head {head} does not exist; the model has {self.model.config.num_heads} heads")
        depth = np.asarray(depth, dtype=np.float32)
        if depth.ndim == 2:
            depth = depth[None]
        w, h = self.resolution
        if depth.ndim != 3 or depth.shape[1:] != (h, w):
            raise ImageSizeError(
                f"depth image of shape {depth.shape[-2:] if depth.ndim >= 2 else depth.shape} (rows, columns) "
                f"given; model {self.model.path.name} takes {w}x{h} images, i.e. shape ({h}, {w})"
            )
        previous = torch.get_num_threads()
        if self.num_threads:
            torch.set_num_threads(self.num_threads)
        try:
            with torch.inference_mode():
                raw = []
                for start in range(0, len(depth), self.batch_size):
                    batch = torch.from_numpy(depth[start : start + self.batch_size]).to(self.device)
                    logits = self._network(batch)
                    raw.append(distributions_2d(logits[:, head].double()).cpu().numpy())
                raw_p2d = np.concatenate(raw) if raw else np.zeros((0, h, w))
        finally:
            torch.set_num_threads(previous)
        p2d, p1d = truncate_support(raw_p2d, self.model.support_threshold_2d, self.model.support_threshold_1d) \
            if truncate else (raw_p2d, raw_p2d.sum(1))
        return PredictedOccupancy(p2d=p2d.astype(np.float32), p1d=p1d.astype(np.float32),
                                  raw_p2d=raw_p2d.astype(np.float32))


def truncate_support(p2d: np.ndarray, t2: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
    """Zeros 2D mass below t2/(H*W) and 1D mass below t1/W, renormalising each (B, H, W) / (B, W) result.

    The 1D distribution is the row sum of the untruncated 2D one, truncated on its own. An image whose mass all
    falls below a threshold keeps its largest entry, so every output still sums to one."""
    b, h, w = p2d.shape
    q2 = np.where(p2d >= t2 / (h * w), p2d, 0.0)
    q1_raw = p2d.sum(1)
    q1 = np.where(q1_raw >= t1 / w, q1_raw, 0.0)
    for q, raw in ((q2.reshape(b, -1), p2d.reshape(b, -1)), (q1, q1_raw)):
        empty = q.sum(1) <= 0
        if empty.any():
            rows = np.flatnonzero(empty)
            cols = raw[rows].argmax(1)
            q[rows, cols] = raw[rows, cols]
        q /= q.sum(1, keepdims=True)
    return q2, q1
