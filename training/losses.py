"""Training losses on backward maps (B x 2 x H x W, pixels of the input grid)."""

from __future__ import annotations

import torch
import torch.nn.functional as F

from ..benchmarks.metrics import MS_SSIM_WEIGHTS, SSIM_K, SSIM_SIGMA, SSIM_WINDOW
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


_GRAY = (0.299, 0.587, 0.114)  # Rec. 601 on RGB, as the metric's grayscale


def _gaussian_blur(gray: torch.Tensor) -> torch.Tensor:
    """The metric's SSIM window (`SSIM_WINDOW`, `SSIM_SIGMA`), replicated borders, separably."""
    half = SSIM_WINDOW // 2
    offsets = torch.arange(SSIM_WINDOW, dtype=gray.dtype, device=gray.device) - half
    kernel = torch.exp(-(offsets**2) / (2 * SSIM_SIGMA**2))
    kernel = kernel / kernel.sum()
    padded = F.pad(gray, (half, half, half, half), mode="replicate")
    blurred = F.conv2d(padded, kernel.view(1, 1, 1, SSIM_WINDOW))
    return F.conv2d(blurred, kernel.view(1, 1, SSIM_WINDOW, 1))


def _ssim(x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """Mean SSIM per image (B,) of gray images (B x 1 x H x W) in [0, 1] (the metric's K)."""
    c1, c2 = SSIM_K[0] ** 2, SSIM_K[1] ** 2
    moments = torch.cat([x, y, x * x, y * y, x * y], 1)  # blurred in one pass
    batch, channels, height, width = moments.shape
    blurred = _gaussian_blur(moments.reshape(batch * channels, 1, height, width))
    mu_x, mu_y, xx, yy, xy = blurred.reshape(batch, channels, height, width).unbind(1)
    var_x = xx - mu_x**2
    var_y = yy - mu_y**2
    cov = xy - mu_x * mu_y
    ssim = ((2 * mu_x * mu_y + c1) * (2 * cov + c2)) / (
        (mu_x**2 + mu_y**2 + c1) * (var_x + var_y + c2)
    )
    return ssim.flatten(1).mean(1)


def rectified_image_ms_ssim(
    images: torch.Tensor, predicted: torch.Tensor, target: torch.Tensor
) -> torch.Tensor:
    """1 - MS-SSIM between the crop rectified by the predicted map and by the true one.

    Unmasked, like the held-out score: black pulled in from outside the crop counts. The
    metric's weighted sum over a 5-level pyramid, in float32 (2x2 means for pyrDown).
    """
    weights = torch.tensor(_GRAY, dtype=torch.float32, device=images.device).view(1, 3, 1, 1)
    images = images.float()
    with torch.no_grad():
        expected = (_remap(images, target.float()) * weights).sum(1, keepdim=True)
    rectified = (_remap(images, predicted.float()) * weights).sum(1, keepdim=True)
    total = torch.zeros(images.shape[0], device=images.device)
    for level, weight in enumerate(MS_SSIM_WEIGHTS):
        total = total + weight * _ssim(rectified, expected)
        if level < len(MS_SSIM_WEIGHTS) - 1:
            rectified, expected = F.avg_pool2d(rectified, 2), F.avg_pool2d(expected, 2)
    return (sum(MS_SSIM_WEIGHTS) - total).mean()


def map_loss(
    predicted: torch.Tensor,
    target: torch.Tensor,
    gradient_weight: float = 0.0,
    images: torch.Tensor | None = None,
    photometric_weight: float = 0.0,
    ms_ssim_weight: float = 0.0,
) -> torch.Tensor:
    """L1 on the map, plus `gradient_weight` times L1 on its 8-pixel differences, plus
    `photometric_weight` times `rectified_image_l1` and `ms_ssim_weight` times
    `rectified_image_ms_ssim` (both need the input `images`)."""
    loss = map_l1(predicted, target)
    if gradient_weight:
        loss = loss + gradient_weight * map_gradient_l1(predicted, target)
    if (photometric_weight or ms_ssim_weight) and images is None:
        raise ValueError("the photometric terms need the input images")
    if photometric_weight:
        loss = loss + photometric_weight * rectified_image_l1(images, predicted, target)
    if ms_ssim_weight:
        loss = loss + ms_ssim_weight * rectified_image_ms_ssim(images, predicted, target)
    return loss
