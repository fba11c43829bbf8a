"""Frozen model configurations. The default is the authors' reference network."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass


@dataclass(frozen=True)
class ModelConfig:
    """Widths and depths of the DocTr++ (GeoTr) network; the input is always 288x288."""

    hidden_dim: int = 256  # transformer width = fnet output channels
    num_heads: int = 8
    ffn_dim: int = 2048
    layers_per_block: int = 2  # attention layers in each encoder/decoder block
    backbone_widths: tuple[int, int, int] = (64, 128, 192)  # fnet layer1..layer3
    # Layers of the four blocks on the 18x18 and 9x9 grids; None: layers_per_block, as in
    # the reference. Depth there adds global context at a fraction of the 36x36 blocks' cost.
    coarse_layers_per_block: int | None = None

    def __post_init__(self) -> None:
        if self.hidden_dim % self.num_heads:
            raise ValueError(
                f"hidden_dim {self.hidden_dim} is not divisible by num_heads {self.num_heads}"
            )
        if self.hidden_dim % 4:
            raise ValueError("hidden_dim must be a multiple of 4 (sine positional encoding)")
        if self.coarse_layers_per_block is not None and self.coarse_layers_per_block < 1:
            raise ValueError("coarse_layers_per_block must be at least 1")

    @property
    def coarse_depth(self) -> int:
        """Attention layers in each block on the 18x18 and 9x9 grids."""
        if self.coarse_layers_per_block is None:
            return self.layers_per_block
        return self.coarse_layers_per_block

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), sort_keys=True)

    @classmethod
    def from_dict(cls, values: dict) -> ModelConfig:
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"unknown model config keys: {', '.join(unknown)}")
        values = dict(values)
        if "backbone_widths" in values:
            values["backbone_widths"] = tuple(values["backbone_widths"])
        return cls(**values)


REFERENCE = ModelConfig()
# Small configurations of the same architecture, for tests and CPU training experiments.
SMALL = ModelConfig(hidden_dim=128, num_heads=4, ffn_dim=512, backbone_widths=(32, 64, 96))
TINY = ModelConfig(
    hidden_dim=32, num_heads=2, ffn_dim=64, layers_per_block=1, backbone_widths=(8, 16, 24)
)

# Between tiny and small: twice tiny's widths (for longer CPU runs; see MODEL_CARD.md).
MID = ModelConfig(
    hidden_dim=64, num_heads=4, ffn_dim=256, layers_per_block=1, backbone_widths=(16, 32, 48)
)

PRESETS: dict[str, ModelConfig] = {
    "reference": REFERENCE,
    "small": SMALL,
    "mid": MID,
    "tiny": TINY,
}


def config_by_name(name: str) -> ModelConfig:
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown config {name!r}; choose from {', '.join(PRESETS)}") from None
