"""Training of the occupancy network: seeded split, AdamW with a one-cycle schedule, per-epoch validation,
checkpoints with resume, metrics JSON, a learning-curve PNG and the best model's weight file.

Output folder (``out``):
    model.pt            weights + header of the epoch with the best validation 1D support IoU
    checkpoint.pt       the last epoch's full training state (network, optimiser, schedule, history); resume reads it
    metrics.json        per-epoch history, the best epoch and its validation metrics
    learning_curve.png  training loss, validation KL and validation IoUs per epoch

Deterministic on the CPU for a given seed and thread count: Python, NumPy and torch are seeded, torch runs with
``use_deterministic_algorithms(True)``, each epoch's shuffle and flips come from a generator seeded with
(seed, epoch), so a resumed run repeats the epochs it would have run.
"""

from __future__ import annotations

import dataclasses
import io
import json
import platform
import random
import time
from pathlib import Path

import numpy as np
import torch

from slax_drake.perception.data import TrainingData
from slax_drake.errors import PerceptionDataError, WeightFileError
from slax_drake.perception.loss import masked_kl_loss, own_head_mask
from slax_drake.perception.metrics import MetricsAccumulator
from slax_drake.perception.network import NetworkConfig, OccupancyUNet
from slax_drake.perception.weights import make_header, save_weights
from slax_drake.io import write_bytes_atomic, write_text_atomic

CHECKPOINT_VERSION = 1


@dataclasses.dataclass(frozen=True)
class TrainOptions:
    """Hyper-parameters. ``val_fraction`` of the samples (a seeded choice) are held out for validation;
    ``flip`` mirrors images and distributions left-right at random (the shelf and camera are symmetric)."""

    epochs: int = 20
    batch_size: int = 16
    learning_rate: float = 3e-3
    weight_decay: float = 1e-4
    val_fraction: float = 0.1
    seed: int = 0
    device: str = "auto"
    num_threads: int | None = None
    base_channels: int = 16
    levels: int = 4
    flip: bool = True


def training_memory_bytes(samples: int, resolution: tuple[int, int], batch_size: int, base_channels: int,
                          levels: int, num_heads: int = 3) -> float:
    """Estimated bytes of training's large arrays: the samples held in memory (depth and own p2d, float32),
    the parameters with their gradients and two AdamW moments (16 bytes each), and one batch's activations
    kept for the backward pass (about 16 float32 feature maps per level and channel at each level's
    resolution, generous, plus the full-resolution input, logits and targets)."""
    w, h = resolution
    pixels = w * h
    channels = [base_channels * 2**i for i in range(levels)]
    params = 4 * base_channels * 9
    c_prev = base_channels
    for ch in channels:
        params += (c_prev * ch + ch * ch) * 9
        c_prev = ch
    for ch in reversed(channels[:-1]):
        params += ((c_prev + ch) * ch + ch * ch) * 9
        c_prev = ch
    params += c_prev * num_heads
    feature_maps = sum(16 * ch * pixels / 4 ** (i + 1) for i, ch in enumerate(channels))  # stem halves each side
    per_sample = 4.0 * (feature_maps + (6 + 4 * num_heads) * pixels)
    return 8.0 * samples * pixels + 16.0 * params + batch_size * per_sample


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed % 2**32)
    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True, warn_only=True)


def pick_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise PerceptionDataError("--device cuda asked for, but torch sees no CUDA device")
    if name not in ("cpu", "cuda"):
        raise PerceptionDataError(f"unknown device {name!r} (auto, cpu or cuda)")
    return torch.device(name)


def split_indices(n: int, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(train, validation) sample indices: a seeded permutation, at least one of each."""
    if n < 2:
        raise PerceptionDataError(f"need at least 2 samples to train with a validation split, got {n}")
    perm = np.random.default_rng([seed, 7]).permutation(n)
    n_val = min(n - 1, max(1, int(round(n * val_fraction))))
    return np.sort(perm[n_val:]), np.sort(perm[:n_val])


def batch_tensors(data: TrainingData, idx: np.ndarray, device, flip: np.ndarray | None = None):
    """(depth (B, H, W), p2d of the own head (B, H, W), own (B,)) as tensors, optionally mirrored per sample."""
    depth = data.depth[idx]
    p2d = data.p2d_own[idx]
    if flip is not None and flip.any():
        depth = depth.copy()
        p2d = p2d.copy()
        depth[flip] = depth[flip][:, :, ::-1]
        p2d[flip] = p2d[flip][:, :, ::-1]
    return (
        torch.from_numpy(np.ascontiguousarray(depth, dtype=np.float32)).to(device),
        torch.from_numpy(np.ascontiguousarray(p2d, dtype=np.float32)).to(device),
        torch.from_numpy(data.own[idx].astype(np.int64)).to(device),
    )


def full_targets(p2d_own: torch.Tensor, own: torch.Tensor, num_heads: int) -> torch.Tensor:
    """(B, H, W) own-head distributions -> (B, R, H, W) with zeros on the other heads (masked out anyway)."""
    b, h, w = p2d_own.shape
    full = p2d_own.new_zeros((b, num_heads, h, w))
    full[torch.arange(b), own] = p2d_own
    return full


@torch.no_grad()
def evaluate(network: OccupancyUNet, data: TrainingData, idx: np.ndarray, device, batch_size: int = 32) -> MetricsAccumulator:
    """Runs the network in eval mode over ``idx`` and collects metrics on each sample's own head."""
    network.eval()
    acc = MetricsAccumulator()
    for start in range(0, len(idx), batch_size):
        depth, p2d, own = batch_tensors(data, idx[start : start + batch_size], device)
        acc.add(network(depth).float().cpu(), p2d.cpu(), own.cpu())
    return acc


def train(data: TrainingData, out: str | Path, options: TrainOptions = TrainOptions(), resume: bool = False,
          progress: bool = True, log=print) -> dict:
    """Trains a network on ``data`` and writes the output folder (see the module docstring). Returns the
    content of metrics.json."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if options.num_threads:
        torch.set_num_threads(options.num_threads)
    seed_everything(options.seed)
    device = pick_device(options.device)
    n, h, w = data.depth.shape
    config = NetworkConfig(width=w, height=h, base_channels=options.base_channels, levels=options.levels)
    train_idx, val_idx = split_indices(n, options.val_fraction, options.seed)
    network = OccupancyUNet(config).to(device)
    optimizer = torch.optim.AdamW(network.parameters(), lr=options.learning_rate, weight_decay=options.weight_decay)
    steps_per_epoch = max(1, int(np.ceil(len(train_idx) / options.batch_size)))
    schedule = torch.optim.lr_scheduler.OneCycleLR(
        optimizer, max_lr=options.learning_rate, total_steps=options.epochs * steps_per_epoch, pct_start=0.15
    )
    history: list[dict] = []
    best: dict | None = None
    start_epoch = 0
    checkpoint_path = out / "checkpoint.pt"
    if not resume:
        _refuse_other_training(out, options, data)
    if resume and checkpoint_path.is_file():
        state = _load_checkpoint(checkpoint_path, options, data)
        network.load_state_dict(state["network"])
        optimizer.load_state_dict(state["optimizer"])
        schedule.load_state_dict(state["schedule"])
        history, best, start_epoch = state["history"], state["best"], state["epoch"]
        log(f"resuming from {checkpoint_path} after epoch {start_epoch}")
    elif resume:
        log(f"no checkpoint at {checkpoint_path}: starting from scratch")

    from tqdm import tqdm

    for epoch in range(start_epoch, options.epochs):
        t0 = time.perf_counter()
        network.train()
        rng = np.random.default_rng([options.seed, epoch])
        order = train_idx[rng.permutation(len(train_idx))]
        flips = rng.random(len(order)) < 0.5 if options.flip else None
        torch.manual_seed(options.seed * 1000 + epoch)
        losses = []
        bar = tqdm(range(steps_per_epoch), desc=f"epoch {epoch + 1}/{options.epochs}", disable=not progress,
                   leave=False, unit="batch")
        for step in bar:
            sl = slice(step * options.batch_size, (step + 1) * options.batch_size)
            depth, p2d, own = batch_tensors(data, order[sl], device, None if flips is None else flips[sl])
            logits = network(depth)
            loss = masked_kl_loss(logits, full_targets(p2d, own, config.num_heads), own_head_mask(own, config.num_heads))
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            optimizer.step()
            schedule.step()
            losses.append(float(loss.detach()))
            bar.set_postfix(loss=f"{np.mean(losses[-20:]):.3f}")
        bar.close()
        train_seconds = time.perf_counter() - t0
        acc = evaluate(network, data, val_idx, device)
        t1, t2 = acc.best_thresholds()
        val = acc.summary(t1, t2)
        record = {
            "epoch": epoch + 1,
            "train_loss": float(np.mean(losses)),
            "train_seconds": train_seconds,
            "train_images_per_second": len(order) / train_seconds,
            "learning_rate": float(schedule.get_last_lr()[0]),
            "val": val,
        }
        history.append(record)
        if best is None or val["iou_1d"] > best["val"]["iou_1d"]:
            best = record
            header = make_header(
                config,
                support_threshold_1d=t1,
                support_threshold_2d=t2,
                training=_training_info(data, options, len(train_idx), len(val_idx), epoch + 1, history, device),
                metrics={"validation": val},
            )
            save_weights(out / "model.pt", network, header)
        _save_checkpoint(checkpoint_path, network, optimizer, schedule, history, best, epoch + 1, options, data)
        summary = {"options": dataclasses.asdict(options), "data": data.describe(), "history": history, "best": best}
        write_text_atomic(out / "metrics.json", json.dumps(summary, indent=2) + "\n")
        save_learning_curve(history, out / "learning_curve.png")
        log(
            f"epoch {epoch + 1}/{options.epochs}: train KL {record['train_loss']:.3f}, val KL {val['kl_2d']:.3f}, "
            f"1D IoU {val['iou_1d']:.3f}, 2D IoU {val['iou_2d']:.3f}, bal.acc {val['balanced_accuracy_2d']:.3f} "
            f"({record['train_images_per_second']:.1f} img/s)"
        )
    if not history:
        raise PerceptionDataError(f"nothing to train: {options.epochs} epochs asked for, {start_epoch} done already")
    return {"options": dataclasses.asdict(options), "data": data.describe(), "history": history, "best": best}


def _training_info(data, options, n_train, n_val, epochs_done, history, device) -> dict:
    return {
        "data": data.describe(),
        "train_samples": n_train,
        "val_samples": n_val,
        "epochs": epochs_done,
        "options": dataclasses.asdict(options),
        "train_seconds": float(sum(r["train_seconds"] for r in history)),
        "hardware": f"{platform.processor() or platform.machine()}, torch {torch.__version__}, "
        f"{device.type}, {torch.get_num_threads()} threads",
    }


def _save_checkpoint(path, network, optimizer, schedule, history, best, epoch, options, data) -> None:
    buffer = io.BytesIO()
    torch.save(
        {
            "version": CHECKPOINT_VERSION,
            "network": network.state_dict(),
            "optimizer": optimizer.state_dict(),
            "schedule": schedule.state_dict(),
            "history": history,
            "best": best,
            "epoch": epoch,
            "options": json.dumps(dataclasses.asdict(options), sort_keys=True),
            "data": json.dumps(data.describe(), sort_keys=True),
        },
        buffer,
    )
    write_bytes_atomic(Path(path), buffer.getvalue())


def _refuse_other_training(out: Path, options: TrainOptions, data: TrainingData) -> None:
    """WeightFileError when ``out`` already holds the output of a training with other options or data (a run
    without resume would overwrite its model.pt, checkpoint.pt and metrics.json). A folder whose checkpoint was made
    with the same options and data is retrained from scratch to the same result, so it is let through."""
    checkpoint_path = out / "checkpoint.pt"
    if checkpoint_path.is_file():
        try:
            state = torch.load(checkpoint_path, map_location="cpu", weights_only=True)
            saved = json.loads(state["options"])
            same_data = json.loads(state["data"]) == data.describe()
        except Exception:
            raise WeightFileError(f"{checkpoint_path}: unreadable checkpoint in the output folder; use a new --out "
                                  "folder") from None
        now = dataclasses.asdict(options)
        differ = [k for k in now if k not in ("device", "num_threads") and saved.get(k) != now[k]]
        if not same_data:
            differ.append("data")
        if differ:
            was = ", ".join(f"{k} {saved[k]}" for k in differ if k in saved)
            raise WeightFileError(f"{out} already holds a model trained with other {', '.join(differ)}"
                                  f"{f' ({was})' if was else ''} that this run would overwrite; use a new --out "
                                  "folder (or --resume with the same options)")
    elif any((out / name).exists() for name in ("model.pt", "metrics.json")):
        raise WeightFileError(f"{out} already holds a model.pt or metrics.json without the checkpoint that says how "
                              "it was trained; use a new --out folder")


def _load_checkpoint(path: Path, options: TrainOptions, data: TrainingData) -> dict:
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:
        raise WeightFileError(f"{path}: unreadable checkpoint (truncated?): {' '.join(str(e).split())[:160]}") from None
    if not isinstance(state, dict) or state.get("version") != CHECKPOINT_VERSION:
        raise WeightFileError(f"{path}: not a slax-drake training checkpoint of version {CHECKPOINT_VERSION}")
    saved = json.loads(state["options"])
    now = dataclasses.asdict(options)
    differ = [k for k in now if k not in ("device", "num_threads") and saved.get(k) != now[k]]
    if differ:
        raise WeightFileError(f"{path}: checkpoint was trained with other options ({', '.join(differ)}); "
                              "use a new --out folder or the same options")
    if json.loads(state["data"]) != data.describe():
        raise WeightFileError(f"{path}: checkpoint was trained on other data; use a new --out folder")
    return state


def save_learning_curve(history: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    epochs = [r["epoch"] for r in history]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    ax1.plot(epochs, [r["train_loss"] for r in history], "o-", label="train KL (own head)")
    ax1.plot(epochs, [r["val"]["kl_2d"] for r in history], "s-", label="validation KL 2D")
    ax1.set_xlabel("epoch")
    ax1.set_ylabel("KL divergence (nats)")
    ax1.legend()
    ax1.grid(alpha=0.3)
    ax2.plot(epochs, [r["val"]["iou_1d"] for r in history], "o-", label="1D support IoU")
    ax2.plot(epochs, [r["val"]["iou_2d"] for r in history], "s-", label="2D IoU")
    ax2.plot(epochs, [r["val"]["balanced_accuracy_2d"] for r in history], "^-", label="2D balanced accuracy")
    ax2.set_xlabel("epoch")
    ax2.set_ylim(0, 1)
    ax2.legend()
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    plt.close(fig)
    write_bytes_atomic(Path(path), buffer.getvalue())
