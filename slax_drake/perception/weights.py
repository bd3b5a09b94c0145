"""The weight file: a torch state dict plus a JSON-able header that is checked on load.

File layout (``torch.save`` of a dict, read back with ``weights_only=True``, so loading never runs code)::

    {"header": {"format": "slax-drake-perception", "version": 1, "architecture": "OccupancyUNet",
                "network": NetworkConfig fields (resolution, heads, channels, depth normalisation),
                "target_sizes": [[x, y, z], ...] metres, one per head,
                "support_threshold_1d": t1, "support_threshold_2d": t2,   # multiples of the uniform mass
                "training": {...}, "metrics": {...}},
     "state_dict": {...}}

A missing, truncated, foreign or mismatched file, or one holding a NaN or infinite weight, raises :class:`WeightFileError` with one line naming the file.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
from pathlib import Path

import torch

from slax_drake.config import REPO_ROOT
from slax_drake.errors import ImageSizeError, WeightFileError
from slax_drake.perception.network import NetworkConfig, OccupancyUNet
from slax_drake.perception.shipped_model import DEFAULT_MODEL
from slax_drake.perception.targets import TARGET_SIZES
from slax_drake.io import write_bytes_atomic

FORMAT = "slax-drake-perception"
VERSION = 1
ARCHITECTURE = "OccupancyUNet"


@dataclasses.dataclass
class LoadedModel:
    """A network in eval mode with the header it was saved with."""

    network: OccupancyUNet
    header: dict
    path: Path

    @property
    def config(self) -> NetworkConfig:
        return self.network.config

    @property
    def target_sizes(self) -> list[list[float]]:
        return self.header["target_sizes"]

    @property
    def support_threshold_1d(self) -> float:
        return float(self.header.get("support_threshold_1d", 0.1))

    @property
    def support_threshold_2d(self) -> float:
        return float(self.header.get("support_threshold_2d", 0.1))


def make_header(config: NetworkConfig, **extra) -> dict:
    header = {
        "format": FORMAT,
        "version": VERSION,
        "architecture": ARCHITECTURE,
        "network": config.to_dict(),
        "target_sizes": [list(s) for s in TARGET_SIZES[: config.num_heads]],
        "support_threshold_1d": 0.1,
        "support_threshold_2d": 0.1,
    }
    header.update(extra)
    json.dumps(header)  # the header must stay JSON-able: fail here, not when someone reads it
    return header


def save_weights(path: str | Path, network: OccupancyUNet, header: dict) -> None:
    """Writes the network's weights and ``header`` (see :func:`make_header`) atomically."""
    state = {k: v.detach().cpu().clone() for k, v in network.state_dict().items()}
    buffer = io.BytesIO()
    torch.save({"header": header, "state_dict": state}, buffer)
    write_bytes_atomic(Path(path), buffer.getvalue())


def resolve_model_path(path: str | Path | None) -> Path:
    """The given path, or the shipped default; a relative path not found here is tried in the repository."""
    path = Path(path if path is not None else DEFAULT_MODEL)
    if path.is_dir():
        path = path / "model.pt"
    if not path.exists() and not path.is_absolute() and (REPO_ROOT / path).exists():
        path = REPO_ROOT / path
        if path.is_dir():
            path = path / "model.pt"
    return path


def load_weights(path: str | Path | None = None, expected_resolution: tuple[int, int] | None = None) -> LoadedModel:
    """Loads a weight file (default: the shipped model) into a network in eval mode on the CPU.

    ``expected_resolution`` (width, height), when given, must match the model's input size."""
    path = resolve_model_path(path)
    if not path.is_file():
        raise WeightFileError(f"{path}: no such weight file (train one with `slax-drake train`)")
    try:
        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # truncated zip, not a torch file, pickled code, ...
        # torch's own text here is advice about `weights_only`, which misleads more than it helps.
        raise WeightFileError(
            f"{path}: not a readable weight file (truncated or corrupt? torch.load raised {type(e).__name__})"
        ) from None
    if not isinstance(blob, dict) or not isinstance(blob.get("header"), dict) or "state_dict" not in blob:
        raise WeightFileError(f"{path}: not a slax-drake perception weight file (no header/state_dict)")
    header = blob["header"]
    if header.get("format") != FORMAT:
        raise WeightFileError(f"{path}: format {header.get('format')!r}, expected {FORMAT!r}")
    if header.get("version") != VERSION:
        raise WeightFileError(f"{path}: weight file version {header.get('version')!r}, this code reads {VERSION}")
    if header.get("architecture") != ARCHITECTURE:
        raise WeightFileError(f"{path}: architecture {header.get('architecture')!r}, expected {ARCHITECTURE!r}")
    try:
        config = NetworkConfig(**header["network"])
    except (TypeError, KeyError, ImageSizeError) as e:
        raise WeightFileError(f"{path}: bad network description in header: {e}") from None
    sizes = header.get("target_sizes")
    if not isinstance(sizes, list) or len(sizes) != config.num_heads:
        raise WeightFileError(f"{path}: header lists {sizes!r} target sizes for {config.num_heads} heads")
    network = OccupancyUNet(config)
    try:
        network.load_state_dict(blob["state_dict"], strict=True)
    except Exception as e:
        reason = " ".join(str(e).split())[:200]
        raise WeightFileError(f"{path}: weights do not match the header's network: {reason}") from None
    for name, tensor in blob["state_dict"].items():
        if isinstance(tensor, torch.Tensor) and tensor.is_floating_point() and not bool(torch.isfinite(tensor).all()):
            bad = int((~torch.isfinite(tensor)).sum())
            raise WeightFileError(f"{path}: tensor '{name}' holds {bad} non-finite values (NaN or inf) of "
                                  f"{tensor.numel()}: the weights are unusable (did the training diverge?)")
    for key in ("support_threshold_1d", "support_threshold_2d"):
        value = header.get(key, 0.1)
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) or value < 0:
            raise WeightFileError(f"{path}: header '{key}' = {value!r} must be a finite number >= 0")
    if expected_resolution is not None and tuple(expected_resolution) != (config.width, config.height):
        w, h = expected_resolution
        raise WeightFileError(
            f"{path}: model takes {config.width}x{config.height} depth images, but {w}x{h} images are given"
        )
    network.eval()
    return LoadedModel(network=network, header=header, path=path)
