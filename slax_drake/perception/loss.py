"""The training loss: KL divergence of the predicted 2D distribution from the true one, on chosen heads only.

As in the paper (Sec. V-B), each training sample supervises only the head of its own target ratio; ``mask``
(B, R) says which (sample, head) pairs carry a loss. KL(p || q) = sum p (log p - log q) over the H*W pixels, in
nats; it is zero exactly when the prediction equals the truth, so a net that fits its data drives it to zero.
"""

from __future__ import annotations

import torch

from slax_drake.perception.network import log_distributions_2d


def own_head_mask(own: torch.Tensor, num_heads: int) -> torch.Tensor:
    """(B,) head index of each sample's own target ratio -> (B, R) bool mask selecting that head only."""
    return torch.nn.functional.one_hot(own.long(), num_heads).bool()


def kl_per_head(logits: torch.Tensor, p_true: torch.Tensor) -> torch.Tensor:
    """KL(p_true || softmax(logits)) for every sample and head: (B, R, H, W) twice -> (B, R) nats."""
    log_q = log_distributions_2d(logits)
    p = p_true.clamp_min(0)
    log_p = torch.log(torch.where(p > 0, p, torch.ones_like(p)))
    return (p * (log_p - log_q)).flatten(-2).sum(-1)


def masked_kl_loss(logits: torch.Tensor, p_true: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Mean KL over the (sample, head) pairs where ``mask`` is true; heads outside the mask get no gradient.

    Pairs whose true distribution is empty (no hidden placement for that ratio) are skipped as well."""
    has_mass = p_true.flatten(-2).sum(-1) > 0.5
    mask = mask & has_mass
    if not bool(mask.any()):
        return logits.sum() * 0.0
    return kl_per_head(logits, p_true)[mask].mean()
