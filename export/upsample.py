"""Flow head and the export-friendly convex upsampling.

RAFT's convex upsampling views the mask as a 7-D tensor and gathers neighbours with
`Unfold`; neither legalises well for ONNX/TFLite. Here the 3x3 neighbourhood is
gathered by a fixed one-hot convolution, the softmax runs on a 4-D view and the 8x8
sub-pixels are placed by depth-to-space (`pixel_shuffle`). Same function, at most 4-D.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

UPSAMPLE = 8  # 36x36 coarse flow -> 288x288
NEIGHBOURS = 9  # 3x3 window, row-major (dy, dx from -1 to 1)


class FlowHead(nn.Module):
    def __init__(self, dim: int) -> None:
        super().__init__()
        self.conv1 = nn.Conv2d(dim, dim, 3, padding=1)
        self.conv2 = nn.Conv2d(dim, 2, 3, padding=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.conv2(F.relu(self.conv1(x)))


class UpdateBlock(nn.Module):
    """Predicts the coarse flow and the convex-combination mask from decoder features."""

    def __init__(self, dim: int) -> None:
        super().__init__()
        self.flow_head = FlowHead(dim)
        self.mask = nn.Sequential(
            nn.Conv2d(dim, dim, 3, padding=1),
            nn.ReLU(),
            nn.Conv2d(dim, UPSAMPLE * UPSAMPLE * NEIGHBOURS, 1),
        )

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return 0.25 * self.mask(features), self.flow_head(features)


def neighbour_kernel() -> torch.Tensor:
    """One-hot 3x3 kernels, (9, 1, 3, 3): output channel k copies neighbour k."""
    return torch.eye(NEIGHBOURS, dtype=torch.float32).reshape(NEIGHBOURS, 1, 3, 3)


class ConvexUpsample(nn.Module):
    def __init__(self) -> None:
        super().__init__()
        # Applied per flow channel (groups=2), zero padding as Unfold's.
        self.register_buffer("kernel", neighbour_kernel().repeat(2, 1, 1, 1), persistent=False)

    def forward(self, flow: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """flow (N, 2, H, W) and mask (N, 576, H, W) -> flow (N, 2, 8H, 8W)."""
        n, _, h, w = flow.shape
        sub = UPSAMPLE * UPSAMPLE
        weights = torch.softmax(mask.reshape(n, NEIGHBOURS, sub, h * w), dim=1)
        # 8.0 (a float) keeps the multiply in float for the TFLite int8 converter.
        neighbours = F.conv2d(8.0 * flow, self.kernel, padding=1, groups=2)
        neighbours = neighbours.reshape(n, 2, NEIGHBOURS, h * w)
        channels = [
            (weights * neighbours[:, c].unsqueeze(2)).sum(dim=1)  # (N, 64, H*W)
            for c in range(2)
        ]
        up = torch.cat(channels, dim=1).reshape(n, 2 * sub, h, w)
        return F.pixel_shuffle(up, UPSAMPLE)


def convex_upsample_raft(flow: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """The original RAFT formulation (Unfold, 7-D), kept as the oracle for tests."""
    n, _, h, w = flow.shape
    mask = torch.softmax(mask.view(n, 1, NEIGHBOURS, UPSAMPLE, UPSAMPLE, h, w), dim=2)
    up_flow = F.unfold(8 * flow, [3, 3], padding=1).view(n, 2, NEIGHBOURS, 1, 1, h, w)
    up_flow = torch.sum(mask * up_flow, dim=2).permute(0, 1, 4, 2, 5, 3)
    return up_flow.reshape(n, 2, UPSAMPLE * h, UPSAMPLE * w)
