"""Training losses on backward maps (B x 2 x H x W, pixels of the input grid)."""

from __future__ import annotations

import torch
import torch.nn.functional as F

from ..contract import pixels_to_normalised


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


def _remap(images: torch.Tensor, backward_map: torch.Tensor) -> torch.Tensor:
    """The crops as `rectify` samples them through a map in pixels (zeros outside)."""
    grid = pixels_to_normalised(backward_map).permute(0, 2, 3, 1)
    return F.grid_sample(images, grid, mode="bilinear", padding_mode="zeros", align_corners=True)


def rectified_image_l1(
    images: torch.Tensor,
    predicted: torch.Tensor,
    target: torch.Tensor,
    blurs: tuple[int, ...] = (1, 5, 15),
) -> torch.Tensor:
    """Mean L1 between the crop rectified by the predicted map and by the true one.

    What the held-out scores compare is the rectified image, so this weighs a map error by
    the print it moves (text, rules, edges) rather than by the pixels alone. The crop is
    box-blurred at a few widths first: thin strokes give a gradient only within a pixel of
    their edges, the blurred copies pull from further away.
    """
    losses = []
    for width in blurs:
        source = images
        if width > 1:
            source = F.avg_pool2d(
                images, width, stride=1, padding=width // 2, count_include_pad=False
            )
        with torch.no_grad():
            expected = _remap(source, target)
        losses.append((_remap(source, predicted) - expected).abs().mean())
    return torch.stack(losses).mean()


def map_loss(
    predicted: torch.Tensor,
    target: torch.Tensor,
    gradient_weight: float = 0.0,
    images: torch.Tensor | None = None,
    photometric_weight: float = 0.0,
) -> torch.Tensor:
    """L1 on the map, plus `gradient_weight` times L1 on its 8-pixel differences, plus
    `photometric_weight` times `rectified_image_l1` (which needs the input `images`)."""
    loss = map_l1(predicted, target)
    if gradient_weight:
        loss = loss + gradient_weight * map_gradient_l1(predicted, target)
    if photometric_weight:
        if images is None:
            raise ValueError("the photometric term needs the input images")
        loss = loss + photometric_weight * rectified_image_l1(images, predicted, target)
    return loss
