"""The RAFT-style feature encoder `fnet` (instance norm), as in the reference."""

from __future__ import annotations

import torch
from torch import nn


def _instance_norm(channels: int) -> nn.InstanceNorm2d:
    # No affine parameters and no running statistics: the reference state has none.
    return nn.InstanceNorm2d(channels)


class ResidualBlock(nn.Module):
    def __init__(self, in_planes: int, planes: int, stride: int = 1) -> None:
        super().__init__()
        self.conv1 = nn.Conv2d(in_planes, planes, 3, padding=1, stride=stride)
        self.conv2 = nn.Conv2d(planes, planes, 3, padding=1)
        self.norm1 = _instance_norm(planes)
        self.norm2 = _instance_norm(planes)
        self.relu = nn.ReLU()
        self.downsample: nn.Module | None = None
        if stride != 1:
            self.downsample = nn.Sequential(
                nn.Conv2d(in_planes, planes, 1, stride=stride), _instance_norm(planes)
            )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.relu(self.norm1(self.conv1(x)))
        y = self.relu(self.norm2(self.conv2(y)))
        shortcut = x if self.downsample is None else self.downsample(x)
        return self.relu(shortcut + y)


class FeatureEncoder(nn.Module):
    """288x288x3 -> 36x36 x output_dim (overall stride 8)."""

    def __init__(self, widths: tuple[int, int, int], output_dim: int) -> None:
        super().__init__()
        w1, w2, w3 = widths
        self.conv1 = nn.Conv2d(3, w1, 7, stride=2, padding=3)
        self.norm1 = _instance_norm(w1)
        self.relu1 = nn.ReLU()
        self.layer1 = nn.Sequential(ResidualBlock(w1, w1), ResidualBlock(w1, w1))
        self.layer2 = nn.Sequential(ResidualBlock(w1, w2, stride=2), ResidualBlock(w2, w2))
        self.layer3 = nn.Sequential(ResidualBlock(w2, w3, stride=2), ResidualBlock(w3, w3))
        self.conv2 = nn.Conv2d(w3, output_dim, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = self.relu1(self.norm1(self.conv1(x)))
        x = self.layer3(self.layer2(self.layer1(x)))
        return self.conv2(x)
