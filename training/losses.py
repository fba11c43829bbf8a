"""Training losses on backward maps (B x 2 x H x W, pixels of the input grid)."""

from __future__ import annotations

import torch


def map_l1(predicted: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """The paper's loss: mean absolute difference of the maps, in pixels."""
    return (predicted - target).abs().mean()


def map_gradient_l1(predicted: torch.Tensor, target: torch.Tensor, stride: int = 8) -> torch.Tensor:
    """Mean absolute difference of the maps' finite differences over `stride` pixels.

    Blind to where the page sits (a shift of the whole map cancels), so it weighs the
    page's local shape (bending, local stretch) that the plain L1 lets placement swamp.
    """
    error = predicted - target
    down = error[:, :, stride:, :] - error[:, :, :-stride, :]
    across = error[:, :, :, stride:] - error[:, :, :, :-stride]
    return 0.5 * (down.abs().mean() + across.abs().mean())


def map_loss(
    predicted: torch.Tensor, target: torch.Tensor, gradient_weight: float = 0.0
) -> torch.Tensor:
    """L1 on the map plus `gradient_weight` times L1 on its 8-pixel differences."""
    loss = map_l1(predicted, target)
    if gradient_weight:
        loss = loss + gradient_weight * map_gradient_l1(predicted, target)
    return loss
