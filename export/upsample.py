"""Flow head and the export-friendly convex upsampling.

RAFT's convex upsampling views the mask as a 7-D tensor and gathers neighbours with
`Unfold`; neither legalises well for ONNX/TFLite. Here the 3x3 neighbourhood is
gathered by nine shifted slices of the zero-padded flow (a fixed one-hot convolution
computes the same but trips the TFLite int8 converter's same-scale rule), the softmax
runs on a 4-D view and the 8x8 sub-pixels are placed by depth-to-space
(`pixel_shuffle`). Same function, at most 4-D.
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


def neighbours_3x3(x: torch.Tensor) -> torch.Tensor:
    """(N, 1, H, W) -> (N, 9, H, W): the 3x3 neighbours (zero outside), row-major."""
    h, w = x.shape[-2:]
    padded = F.pad(x, (1, 1, 1, 1))
    return torch.cat(
        [padded[:, :, dy : dy + h, dx : dx + w] for dy in range(3) for dx in range(3)], dim=1
    )


class ConvexUpsample(nn.Module):
    def forward(self, flow: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """flow (N, 2, H, W) and mask (N, 576, H, W) -> flow (N, 2, 8H, 8W)."""
        n, _, h, w = flow.shape
        sub = UPSAMPLE * UPSAMPLE
        weights = torch.softmax(mask.reshape(n, NEIGHBOURS, sub, h * w), dim=1)
        # 8.0 (a float) keeps the multiply in float for the TFLite int8 converter.
        scaled = 8.0 * flow
        channels = []
        for c in range(2):
            neighbours = neighbours_3x3(scaled[:, c : c + 1]).reshape(n, NEIGHBOURS, 1, h * w)
            channels.append((weights * neighbours).sum(dim=1))  # (N, 64, H*W)
        up = torch.cat(channels, dim=1).reshape(n, 2 * sub, h, w)
        return F.pixel_shuffle(up, UPSAMPLE)


def convex_upsample_raft(flow: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """The original RAFT formulation (Unfold, 7-D), kept as the oracle for tests."""
    n, _, h, w = flow.shape
    mask = torch.softmax(mask.view(n, 1, NEIGHBOURS, UPSAMPLE, UPSAMPLE, h, w), dim=2)
    up_flow = F.unfold(8 * flow, [3, 3], padding=1).view(n, 2, NEIGHBOURS, 1, 1, h, w)
    up_flow = torch.sum(mask * up_flow, dim=2).permute(0, 1, 4, 2, 5, 3)
    return up_flow.reshape(n, 2, UPSAMPLE * h, UPSAMPLE * w)
