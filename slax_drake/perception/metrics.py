"""Held-out metrics of predicted occupancy distributions against the true ones (own head of each sample).

- ``kl_2d`` / ``kl_1d``: KL(true || predicted) in nats, of the 2D distributions and of the 1D ones (along image x).
- ``iou_1d``: IoU of the predicted and true 1D supports. The true support is where the true 1D distribution is
  positive; the predicted one is where the predicted 1D mass reaches ``t1 / W`` (t1 times the uniform mass).
- ``balanced_accuracy_2d`` / ``iou_2d``: X-RAY's metrics of the 2D support mask thresholded at ``t2 / (H*W)``,
  (true positive rate + true negative rate) / 2 and intersection over union, per image, averaged.

The thresholds t1 and t2 are chosen on the validation split (best mean IoU over ``THRESHOLDS``) and stored in
the weight file; they are what turns a softmax (positive everywhere) into a support with zeros.
"""

from __future__ import annotations

import numpy as np
import torch

from slax_drake.perception.network import distributions_2d, log_distributions_2d

# Candidate support thresholds, as multiples of the uniform probability mass per pixel (or per column).
THRESHOLDS = np.round(np.geomspace(0.01, 10.0, 31), 5)
TRUE_SUPPORT_EPS = 1e-9


class MetricsAccumulator:
    """Collects per-sample metrics over batches for every candidate threshold; ``summary()`` averages them."""

    def __init__(self, thresholds=THRESHOLDS):
        self.thresholds = np.asarray(thresholds, dtype=np.float64)
        self.kl_2d: list[np.ndarray] = []
        self.kl_1d: list[np.ndarray] = []
        self.iou_1d: list[np.ndarray] = []  # (B, T) per batch
        self.iou_2d: list[np.ndarray] = []
        self.bacc_2d: list[np.ndarray] = []

    @torch.no_grad()
    def add(self, logits: torch.Tensor, p2d_own: torch.Tensor, own: torch.Tensor) -> None:
        """logits (B, R, H, W); p2d_own (B, H, W) the true 2D distribution of each sample's own target ratio,
        whose head index is own (B,); only that head is scored."""
        idx = torch.arange(logits.shape[0])
        lg = logits[idx, own].double()
        p = p2d_own.double().clamp_min(0)
        p = p / p.flatten(-2).sum(-1).clamp_min(1e-30)[:, None, None]
        q = distributions_2d(lg)
        log_q = log_distributions_2d(lg)
        self.kl_2d.append(_kl(p.flatten(-2), log_q.flatten(-2)).numpy())
        p1, q1 = p.sum(-2), q.sum(-2)
        self.kl_1d.append(_kl(p1, torch.log(q1.clamp_min(1e-300))).numpy())
        h, w = p.shape[-2:]
        t = torch.as_tensor(self.thresholds)
        true1 = (p1 > TRUE_SUPPORT_EPS)[:, None, :]
        pred1 = q1[:, None, :] >= (t / w)[None, :, None]
        self.iou_1d.append(_iou(pred1, true1).numpy())
        true2 = (p.flatten(-2) > TRUE_SUPPORT_EPS)[:, None, :]
        pred2 = q.flatten(-2)[:, None, :] >= (t / (h * w))[None, :, None]
        self.iou_2d.append(_iou(pred2, true2).numpy())
        tp = (pred2 & true2).sum(-1).double()
        tn = (~pred2 & ~true2).sum(-1).double()
        pos = true2.sum(-1).double().clamp_min(1)
        neg = (~true2).sum(-1).double().clamp_min(1)
        self.bacc_2d.append((0.5 * (tp / pos + tn / neg)).numpy())

    def __len__(self) -> int:
        return int(sum(len(k) for k in self.kl_2d))

    def best_thresholds(self) -> tuple[float, float]:
        """(t1, t2): the thresholds with the best mean 1D and 2D support IoU on the collected samples."""
        i1 = int(np.argmax(np.concatenate(self.iou_1d).mean(0)))
        i2 = int(np.argmax(np.concatenate(self.iou_2d).mean(0)))
        return float(self.thresholds[i1]), float(self.thresholds[i2])

    def summary(self, t1: float, t2: float) -> dict:
        """Mean metrics with the 1D support threshold t1 and the 2D one t2 (both must be in ``thresholds``)."""
        i1 = int(np.argmin(np.abs(self.thresholds - t1)))
        i2 = int(np.argmin(np.abs(self.thresholds - t2)))
        return {
            "samples": len(self),
            "kl_2d": float(np.concatenate(self.kl_2d).mean()),
            "kl_1d": float(np.concatenate(self.kl_1d).mean()),
            "iou_1d": float(np.concatenate(self.iou_1d)[:, i1].mean()),
            "iou_2d": float(np.concatenate(self.iou_2d)[:, i2].mean()),
            "balanced_accuracy_2d": float(np.concatenate(self.bacc_2d)[:, i2].mean()),
            "support_threshold_1d": float(self.thresholds[i1]),
            "support_threshold_2d": float(self.thresholds[i2]),
        }


def _kl(p: torch.Tensor, log_q: torch.Tensor) -> torch.Tensor:
    log_p = torch.log(torch.where(p > 0, p, torch.ones_like(p)))
    return (p * (log_p - log_q)).sum(-1)


def _iou(pred: torch.Tensor, true: torch.Tensor) -> torch.Tensor:
    inter = (pred & true).sum(-1).double()
    union = (pred | true).sum(-1).double()
    return torch.where(union > 0, inter / union.clamp_min(1), torch.ones_like(union))
