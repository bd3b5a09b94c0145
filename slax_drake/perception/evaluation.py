"""Held-out evaluation of a trained model on a dataset folder, a PNG grid of examples, and the mean IoU of the
depth-only instance segmentation against the renderer's label images.

The metrics use the support thresholds stored in the weight file (chosen on the training run's validation
split), so evaluating the shipped model on the held-out set reproduces the numbers in its model card.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import torch

from slax_drake.perception.data import TrainingData
from slax_drake.perception.metrics import MetricsAccumulator
from slax_drake.perception.weights import LoadedModel
from slax_drake.io import write_bytes_atomic


def evaluate_model(model: LoadedModel, data: TrainingData, batch_size: int = 32, num_threads: int | None = None,
                   progress: bool = False) -> tuple[dict, np.ndarray]:
    """Metrics (see ``metrics.py``) of ``model`` on every sample of ``data`` at the model's stored thresholds,
    and the predicted 2D distributions of the samples' own heads (N, H, W)."""
    from tqdm import tqdm

    cfg = model.config
    if data.resolution != (cfg.width, cfg.height):
        from slax_drake.errors import ImageSizeError

        w, h = data.resolution
        raise ImageSizeError(f"{data.source}: {w}x{h} images, but model {model.path} takes {cfg.width}x{cfg.height} "
                             f"(make the dataset with --resolution {cfg.width}x{cfg.height})")
    if num_threads:
        torch.set_num_threads(num_threads)
    acc = MetricsAccumulator(thresholds=[model.support_threshold_1d, model.support_threshold_2d])
    predictions = np.empty(data.depth.shape, np.float32)
    with torch.inference_mode():
        for start in tqdm(range(0, len(data), batch_size), disable=not progress, leave=False, desc="evaluating"):
            sl = slice(start, start + batch_size)
            logits = model.network(torch.from_numpy(data.depth[sl]))
            own = torch.from_numpy(data.own[sl])
            acc.add(logits, torch.from_numpy(data.p2d_own[sl]), own)
            idx = torch.arange(len(own))
            predictions[sl] = torch.softmax(logits[idx, own].flatten(-2).double(), -1).view(-1, cfg.height, cfg.width)
    return acc.summary(model.support_threshold_1d, model.support_threshold_2d), predictions


def segmentation_mean_iou(folder: str | Path, limit: int | None = None, min_true_pixels: int | None = None) -> dict:
    """Mean instance IoU of :func:`segmentation.segment_depth` on a dataset's depth images against its label
    images (objects only; shelf, nothing and the hidden target are background). Two figures: over every
    visible object, and over objects with at least ``min_true_pixels`` visible pixels (default: the
    segmenter's own minimum instance size)."""
    from slax_drake.dataset.shards import DatasetReader
    from slax_drake.perception.segmentation import instance_mean_iou, segment_depth
    from slax_drake.scene.io import scene_from_dict

    reader = DatasetReader(folder)
    n = len(reader) if limit is None else min(limit, len(reader))
    all_ious, big_ious = [], []
    try:
        for i in range(n):
            sample = reader[i]
            scene = scene_from_dict(json.loads(reader.scene_json(i)))
            depth = sample["depth"][0]
            h, w = depth.shape
            camera = scene.camera.with_resolution(w, h)
            label = sample["label"]
            truth = np.where((label > 0) & (label <= len(scene.objects)), label, 0)
            pred = segment_depth(depth, camera, scene.shelf)
            small = max(4, int(round(depth.size * 2e-4))) if min_true_pixels is None else min_true_pixels
            all_ious.append(instance_mean_iou(pred, truth))
            big_ious.append(instance_mean_iou(pred, truth, min_true_pixels=small))
    finally:
        reader.close()
    return {
        "images": n,
        "mean_iou_all_objects": float(np.mean(all_ious)),
        "mean_iou_objects_min_pixels": float(np.mean(big_ious)),
        "min_pixels": small,
    }


def save_example_grid(data: TrainingData, predictions: np.ndarray, model: LoadedModel, path: str | Path,
                      count: int = 6) -> None:
    """A PNG with one row per sample: depth image, true and predicted 2D distributions, true and predicted 1D
    distributions (the predicted support shaded)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from slax_drake.perception.inference import truncate_support

    count = min(count, len(data))
    pick = np.linspace(0, len(data) - 1, count).round().astype(int)
    fig, axes = plt.subplots(count, 4, figsize=(14, 2.4 * count), squeeze=False)
    sizes = model.target_sizes
    for row, i in enumerate(pick):
        ax_d, ax_t, ax_p, ax_1 = axes[row]
        d = np.where(data.depth[i] > 0, data.depth[i], np.nan)
        ax_d.imshow(d, cmap="viridis")
        size = "x".join(f"{v:g}" for v in sizes[int(data.own[i])])
        ax_d.set_title(f"sample {i}: depth (m), target {size}", fontsize=8)
        vmax = float(max(data.p2d_own[i].max(), predictions[i].max()))
        ax_t.imshow(data.p2d_own[i], cmap="magma", vmin=0, vmax=vmax)
        ax_t.set_title("true 2D distribution", fontsize=8)
        ax_p.imshow(predictions[i], cmap="magma", vmin=0, vmax=vmax)
        ax_p.set_title("predicted 2D distribution", fontsize=8)
        _, q1 = truncate_support(predictions[i][None].astype(np.float64), model.support_threshold_2d,
                                 model.support_threshold_1d)
        x = np.arange(data.depth.shape[2])
        ax_1.plot(x, data.p2d_own[i].sum(0), label="true 1D")
        ax_1.plot(x, predictions[i].sum(0), label="predicted 1D")
        ax_1.fill_between(x, 0, q1[0] > 0, step="mid", alpha=0.15, color="C1", transform=ax_1.get_xaxis_transform(),
                          label="predicted support")
        ax_1.set_xlim(0, len(x) - 1)
        ax_1.legend(fontsize=6)
        ax_1.set_title("1D along image x", fontsize=8)
        for ax in (ax_d, ax_t, ax_p):
            ax.set_xticks([])
            ax.set_yticks([])
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=80)
    plt.close(fig)
    write_bytes_atomic(Path(path), buffer.getvalue())
