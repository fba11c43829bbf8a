"""Our implementation of the DocTr++ (GeoTr) network; see shared/reference/MODEL_SPEC.md."""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

from doctrpp.contract import INPUT_SIZE, pixels_to_normalised

from .backbone import FeatureEncoder
from .config import REFERENCE, ModelConfig
from .transformer import AttentionBlock
from .upsample import UPSAMPLE, ConvexUpsample, UpdateBlock

FEATURE_GRID = INPUT_SIZE // UPSAMPLE  # 36


def pixel_grid(size: int) -> torch.Tensor:
    """(1, 2, size, size) pixel coordinates: channel 0 = x, channel 1 = y."""
    ys, xs = torch.meshgrid(
        torch.arange(size, dtype=torch.float32),
        torch.arange(size, dtype=torch.float32),
        indexing="ij",
    )
    return torch.stack((xs, ys)).unsqueeze(0)


class BackwardMap(nn.Module):
    """Coarse flow + convex-combination mask -> backward map in pixels of the 288 grid.

    A module of its own so that converters can keep it float by type.
    """

    def __init__(self) -> None:
        super().__init__()
        self.upsample = ConvexUpsample()
        self.register_buffer("grid", pixel_grid(INPUT_SIZE), persistent=False)

    def forward(self, flow: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        return self.grid + self.upsample(flow, mask)


class Normalise(nn.Module):
    """Pixels of the 288 grid -> grid_sample coordinates, as the reference script does."""

    def forward(self, backward_map: torch.Tensor) -> torch.Tensor:
        return pixels_to_normalised(backward_map)


# The attention blocks on the 18x18 and 9x9 grids: their depth is `config.coarse_depth`.
COARSE_BLOCKS = ("encoder_block1", "encoder_block2", "decoder_block0", "decoder_block1")


class DocTrPP(nn.Module):
    """image (N, 3, 288, 288) RGB in [0, 1] -> backward map (N, 2, 288, 288) in pixels."""

    def __init__(self, config: ModelConfig = REFERENCE) -> None:
        super().__init__()
        self.config = config
        dim, heads, ffn, depth = (
            config.hidden_dim,
            config.num_heads,
            config.ffn_dim,
            config.layers_per_block,
        )
        grids = (FEATURE_GRID, FEATURE_GRID // 2, FEATURE_GRID // 4)  # 36, 18, 9
        self.fnet = FeatureEncoder(config.backbone_widths, dim)

        def block(name: str, grid: int) -> AttentionBlock:
            layers = config.coarse_depth if name in COARSE_BLOCKS else depth
            return AttentionBlock(dim, heads, ffn, layers, grid)

        self.encoder_block0 = block("encoder_block0", grids[0])
        self.encoder_block1 = block("encoder_block1", grids[1])
        self.encoder_block2 = block("encoder_block2", grids[2])
        self.down_layer0 = nn.Conv2d(dim, dim, 3, stride=2, padding=1)
        self.down_layer1 = nn.Conv2d(dim, dim, 3, stride=2, padding=1)
        self.decoder_block0 = block("decoder_block0", grids[2])
        self.decoder_block1 = block("decoder_block1", grids[1])
        self.decoder_block2 = block("decoder_block2", grids[0])
        self.query_embed = nn.Embedding(grids[2] * grids[2], dim)
        self.update_block = UpdateBlock(dim)
        self.backward_map = BackwardMap()

    @staticmethod
    def _tokens(x: torch.Tensor) -> torch.Tensor:
        return x.flatten(2).transpose(1, 2)  # (N, C, H, W) -> (N, H*W, C)

    @staticmethod
    def _image(tokens: torch.Tensor, grid: int) -> torch.Tensor:
        n, _, c = tokens.shape
        return tokens.transpose(1, 2).reshape(n, c, grid, grid)

    def _up2(self, tokens: torch.Tensor, grid: int) -> torch.Tensor:
        image = F.interpolate(
            self._image(tokens, grid), scale_factor=2.0, mode="bilinear", align_corners=True
        )
        return self._tokens(image)

    def forward(self, image: torch.Tensor) -> torch.Tensor:
        feat = F.relu(self.fnet(image))
        e1 = self.encoder_block0.encode(self._tokens(feat))
        g1, g2, g3 = self.encoder_block0.grid, self.encoder_block1.grid, self.encoder_block2.grid
        e2 = self.encoder_block1.encode(self._tokens(self.down_layer0(self._image(e1, g1))))
        e3 = self.encoder_block2.encode(self._tokens(self.down_layer1(self._image(e2, g2))))
        query = self.query_embed.weight.unsqueeze(0).expand(image.shape[0], -1, -1)
        d3 = self.decoder_block0.decode(e3, query)
        d2 = self.decoder_block1.decode(e2, self._up2(d3, g3))
        d1 = self.decoder_block2.decode(e1, self._up2(d2, g2))
        mask, flow = self.update_block(self._image(d1, g1))
        return self.backward_map(flow, mask)


class ExportWrapper(nn.Module):
    """What goes into a model file: the network plus the output normalisation."""

    def __init__(self, model: DocTrPP) -> None:
        super().__init__()
        self.model = model
        self.normalise = Normalise()

    def forward(self, image: torch.Tensor) -> torch.Tensor:
        return self.normalise(self.model(image))
