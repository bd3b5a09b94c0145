"""The occupancy network: a compact U-Net from one depth image to one 2D occupancy head per target ratio.

Input: depth images (B, H, W) in metres along the optical axis (float32; 0, NaN or inf mark pixels without a
return). Output: logits (B, R, H, W), one channel per target ratio (see ``targets.TARGET_SIZES``); the 2D
occupancy distribution of head r is the softmax of its logits over all H*W pixels, so it sums to one, and the
1D distribution along image x is its sum over image rows (paper Sec. V-B, P_t(x) = sum_y p_t(x, y)).

The network sees four channels at the input resolution: the normalised depth, a validity mask and the pixel's
(x, y) position in [-1, 1] (the distribution depends on where in the shelf an occluder stands, not only on its
shape). A stride-2 stem halves the resolution before the U-Net proper, whose logits are upsampled back, so a
128x96 image costs about the same as a 64x48 one; ``base_channels`` and ``levels`` scale it up for a GPU.
"""

from __future__ import annotations

import dataclasses

import torch
from torch import nn
from torch.nn import functional as F

from slax_drake.errors import ImageSizeError


@dataclasses.dataclass(frozen=True)
class NetworkConfig:
    """Everything that fixes the network's shape; stored in the weight file's header and checked on load.

    ``width``/``height``: the depth image's size in pixels. ``max_depth`` (metres): farther or invalid returns
    are clipped to it; depths are normalised as (depth - depth_offset) / depth_scale.
    """

    width: int = 128
    height: int = 96
    num_heads: int = 3
    base_channels: int = 16
    levels: int = 4
    max_depth: float = 2.0
    depth_offset: float = 1.0
    depth_scale: float = 0.5

    def __post_init__(self):
        divisor = 2**self.levels  # stem stride 2, then levels - 1 poolings of 2
        if self.width % divisor or self.height % divisor:
            raise ImageSizeError(
                f"image size {self.width}x{self.height} must be divisible by {divisor} for a {self.levels}-level network"
            )

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _conv_block(c_in: int, c_out: int) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(c_in, c_out, 3, padding=1, bias=False),
        nn.BatchNorm2d(c_out),
        nn.ReLU(inplace=True),
        nn.Conv2d(c_out, c_out, 3, padding=1, bias=False),
        nn.BatchNorm2d(c_out),
        nn.ReLU(inplace=True),
    )


class OccupancyUNet(nn.Module):
    """Depth image (B, H, W) metres -> occupancy logits (B, num_heads, H, W)."""

    def __init__(self, config: NetworkConfig):
        super().__init__()
        self.config = config
        c = config.base_channels
        channels = [c * 2**i for i in range(config.levels)]
        self.stem = nn.Sequential(
            nn.Conv2d(4, c, 3, stride=2, padding=1, bias=False), nn.BatchNorm2d(c), nn.ReLU(inplace=True)
        )
        self.encoders = nn.ModuleList()
        c_prev = c
        for ch in channels:
            self.encoders.append(_conv_block(c_prev, ch))
            c_prev = ch
        self.decoders = nn.ModuleList()
        for ch in reversed(channels[:-1]):
            self.decoders.append(_conv_block(c_prev + ch, ch))
            c_prev = ch
        self.head = nn.Conv2d(c_prev, config.num_heads, 1)
        h, w = config.height, config.width
        ys = torch.linspace(-1.0, 1.0, h).view(1, 1, h, 1).expand(1, 1, h, w)
        xs = torch.linspace(-1.0, 1.0, w).view(1, 1, 1, w).expand(1, 1, h, w)
        self.register_buffer("coords", torch.cat([xs, ys], dim=1).contiguous(), persistent=False)

    def input_channels(self, depth: torch.Tensor) -> torch.Tensor:
        """The four input channels (B, 4, H, W) from depth images (B, H, W) in metres."""
        cfg = self.config
        if depth.dim() != 3 or tuple(depth.shape[1:]) != (cfg.height, cfg.width):
            raise ImageSizeError(
                f"depth images of shape {tuple(depth.shape)} given; this model takes (batch, {cfg.height}, "
                f"{cfg.width}), i.e. {cfg.width}x{cfg.height} pixels"
            )
        valid = torch.isfinite(depth) & (depth > 0)
        d = torch.where(valid, depth, torch.full_like(depth, cfg.max_depth)).clamp(max=cfg.max_depth)
        d = (d - cfg.depth_offset) / cfg.depth_scale
        coords = self.coords.expand(depth.shape[0], -1, -1, -1)
        return torch.cat([d.unsqueeze(1), valid.unsqueeze(1).to(d.dtype), coords], dim=1)

    def forward(self, depth: torch.Tensor) -> torch.Tensor:
        x = self.stem(self.input_channels(depth))
        skips = []
        for i, encoder in enumerate(self.encoders):
            if i > 0:
                x = F.max_pool2d(x, 2)
            x = encoder(x)
            skips.append(x)
        for decoder, skip in zip(self.decoders, reversed(skips[:-1])):
            x = F.interpolate(x, size=skip.shape[-2:], mode="nearest")
            x = decoder(torch.cat([x, skip], dim=1))
        logits = self.head(x)
        return F.interpolate(logits, size=(self.config.height, self.config.width), mode="bilinear", align_corners=False)


def distributions_2d(logits: torch.Tensor) -> torch.Tensor:
    """Spatial softmax: logits (..., H, W) -> 2D distributions (..., H, W) that each sum to one."""
    shape = logits.shape
    return torch.softmax(logits.flatten(-2), dim=-1).view(shape)


def log_distributions_2d(logits: torch.Tensor) -> torch.Tensor:
    """Log of :func:`distributions_2d`, computed stably."""
    shape = logits.shape
    return torch.log_softmax(logits.flatten(-2), dim=-1).view(shape)
