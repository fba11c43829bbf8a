"""Widen or deepen a trained model without changing what it computes.

usage: python -m doctrpp.training.grow WEIGHTS [--ffn-dim 1024] [--backbone-widths 24 48 72]
       [--coarse-layers 3] --out FILE [--seed 0]

Feed-forward parts (`--ffn-dim`): every attention layer's relu(x W1 + b1) W2 + b2 gets new
hidden units with W1 rows and b1 entries drawn as `nn.Linear` draws them and W2 columns of
zeros.

Feature encoder (`--backbone-widths`): every convolution that writes a stage's feature map
gets new output filters drawn as `nn.Conv2d` draws them, and every convolution that reads
it gets zero weights from the new channels into its old outputs. Instance norm, relu and
the residual sums act channel by channel, so the old channels never see the new ones.

Coarse attention blocks (`--coarse-layers`): the four blocks on the 18x18 and 9x9 grids
get new attention layers after their last one, each with zero output projections and a
zero second feed-forward matrix, so its residual sums add nothing. The layers are post-norm,
so the old last layer's final norm hands its scale and shift to the last new layer and
outputs unit-normalised tokens, which the new layers' plain norms pass on unchanged.

Every way the grown model's output is the old one's (up to float rounding) while the new
units get gradients from the first step: more capacity for a run that has stopped gaining,
without starting over. The file keeps the source's training record, so `doctrpp train
--init FILE` (its config is taken from the file) continues the step, stream and CPU hours.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import math
import re
import sys
from pathlib import Path

import torch

from doctrpp.export.checkpoint import (
    CheckpointError,
    read_checkpoint_payload,
    split_checkpoint,
)
from doctrpp.export.config import ModelConfig
from doctrpp.export.model import COARSE_BLOCKS
from doctrpp.files import write_bytes_atomically

FEED_FORWARD_IN, FEED_FORWARD_OUT = ".linear1.", ".linear2."
# fnet.layerN.B.PART: block B of stage N (1-3); its first block may change the width.
_RESIDUAL_KEY = re.compile(r"^fnet\.layer(\d)\.(\d)\.(conv1|conv2|downsample\.0)\.")


def _drawn_uniform(shape: tuple[int, ...], bound: float, generator) -> torch.Tensor:
    """Uniform in [-bound, bound], as `nn.Linear` and `nn.Conv2d` initialise."""
    return (torch.rand(shape, generator=generator) * 2 - 1) * bound


def widen_feed_forward(
    state: dict[str, torch.Tensor], config: ModelConfig, ffn_dim: int, seed: int = 0
) -> tuple[dict[str, torch.Tensor], ModelConfig]:
    """The state dict and config with `ffn_dim` hidden units in every feed-forward part."""
    if ffn_dim <= config.ffn_dim:
        raise ValueError(f"--ffn-dim {ffn_dim} must exceed the model's {config.ffn_dim}")
    generator = torch.Generator().manual_seed(seed)
    added = ffn_dim - config.ffn_dim
    bound = 1.0 / math.sqrt(config.hidden_dim)  # nn.Linear's default range for fan-in `dim`
    grown = {}
    for key, value in state.items():
        value = value.float()
        if FEED_FORWARD_IN in key:  # weight (ffn, dim) or bias (ffn,): new rows
            value = torch.cat([value, _drawn_uniform((added, *value.shape[1:]), bound, generator)])
        elif FEED_FORWARD_OUT in key and key.endswith("weight"):  # (dim, ffn): zero columns
            value = torch.cat([value, value.new_zeros(value.shape[0], added)], dim=1)
        grown[key] = value
    return grown, dataclasses.replace(config, ffn_dim=ffn_dim)


def backbone_stages(key: str) -> tuple[int | None, int | None]:
    """(stage read, stage written) by an fnet convolution: 0-2 index `backbone_widths`,
    None the image (3 channels) or the transformer's `hidden_dim`."""
    if key.startswith("fnet.conv1."):
        return None, 0
    if key.startswith("fnet.conv2."):
        return 2, None
    match = _RESIDUAL_KEY.match(key)
    if match is None:
        raise ValueError(f"unexpected feature-encoder key {key}")
    stage, block, part = int(match[1]) - 1, int(match[2]), match[3]
    reads_previous_stage = block == 0 and part != "conv2" and stage > 0
    return (stage - 1 if reads_previous_stage else stage), stage


def _widen_convolution(
    weight: torch.Tensor, bias: torch.Tensor, added_in: int, added_out: int, generator
) -> tuple[torch.Tensor, torch.Tensor]:
    """New input channels feed only new output filters; new filters are drawn fresh."""
    out_channels, in_channels, height, width = weight.shape
    fan_in = (in_channels + added_in) * height * width
    bound = 1.0 / math.sqrt(fan_in)  # nn.Conv2d's default range for weight and bias
    weight = torch.cat([weight, weight.new_zeros(out_channels, added_in, height, width)], 1)
    fresh = _drawn_uniform((added_out, in_channels + added_in, height, width), bound, generator)
    weight = torch.cat([weight, fresh])
    return weight, torch.cat([bias, _drawn_uniform((added_out,), bound, generator)])


def widen_backbone(
    state: dict[str, torch.Tensor],
    config: ModelConfig,
    widths: tuple[int, int, int],
    seed: int = 0,
) -> tuple[dict[str, torch.Tensor], ModelConfig]:
    """The state dict and config with feature-encoder stages `widths` channels wide."""
    widths = tuple(int(w) for w in widths)
    old = config.backbone_widths
    too_narrow = len(widths) != 3 or any(new < was for new, was in zip(widths, old, strict=True))
    if too_narrow or widths == old:
        raise ValueError(
            f"--backbone-widths {' '.join(map(str, widths))} must be 3 widths, none below "
            f"the model's {' '.join(map(str, old))} and at least one above"
        )
    added = [new - was for new, was in zip(widths, old, strict=True)]
    generator = torch.Generator().manual_seed(seed)
    grown = {key: value.float() for key, value in state.items()}
    for key in [k for k in state if k.startswith("fnet.") and k.endswith(".weight")]:
        reads, writes = backbone_stages(key)
        bias_key = key[: -len("weight")] + "bias"
        grown[key], grown[bias_key] = _widen_convolution(
            grown[key],
            grown[bias_key],
            0 if reads is None else added[reads],
            0 if writes is None else added[writes],
            generator,
        )
    return grown, dataclasses.replace(config, backbone_widths=widths)


def _new_attention(prefix: str, dim: int, generator) -> dict[str, torch.Tensor]:
    """Projections as `MultiheadAttention` draws them, with a zero output projection."""
    return {
        f"{prefix}.in_proj_weight": _drawn_uniform((3 * dim, dim), math.sqrt(1.5 / dim), generator),
        f"{prefix}.in_proj_bias": torch.zeros(3 * dim),
        f"{prefix}.out_proj.weight": torch.zeros(dim, dim),
        f"{prefix}.out_proj.bias": torch.zeros(dim),
    }


def _new_layer(prefix: str, config: ModelConfig, generator) -> dict[str, torch.Tensor]:
    """An attention layer whose residual sums add nothing and whose norms are plain."""
    dim, ffn = config.hidden_dim, config.ffn_dim
    bound = 1.0 / math.sqrt(dim)  # nn.Linear's range for linear1
    layer = {
        **_new_attention(f"{prefix}.self_attn", dim, generator),
        **_new_attention(f"{prefix}.multihead_attn_list.0", dim, generator),
        f"{prefix}.linear1.weight": _drawn_uniform((ffn, dim), bound, generator),
        f"{prefix}.linear1.bias": _drawn_uniform((ffn,), bound, generator),
        f"{prefix}.linear2.weight": torch.zeros(dim, ffn),
        f"{prefix}.linear2.bias": torch.zeros(dim),
    }
    for norm in ("norm1", "norm2_list.0", "norm3"):
        layer[f"{prefix}.{norm}.weight"] = torch.ones(dim)
        layer[f"{prefix}.{norm}.bias"] = torch.zeros(dim)
    return layer


def deepen_coarse_blocks(
    state: dict[str, torch.Tensor], config: ModelConfig, layers: int, seed: int = 0
) -> tuple[dict[str, torch.Tensor], ModelConfig]:
    """The state dict and config with `layers` attention layers in each coarse block."""
    old = config.coarse_depth
    if layers <= old:
        raise ValueError(f"--coarse-layers {layers} must exceed the model's {old}")
    generator = torch.Generator().manual_seed(seed)
    grown = {key: value.float() for key, value in state.items()}
    for block in COARSE_BLOCKS:
        for index in range(old, layers):
            grown.update(_new_layer(f"{block}.layers.{index}", config, generator))
        # Post-norm: the last layer's final scale and shift move to the new last layer,
        # which starts plain (1, 0); the two swap.
        last, new_last = (f"{block}.layers.{i}.norm3." for i in (old - 1, layers - 1))
        for part in ("weight", "bias"):
            grown[last + part], grown[new_last + part] = grown[new_last + part], grown[last + part]
    return grown, dataclasses.replace(config, coarse_layers_per_block=layers)


def grow_file(
    source: Path,
    out: Path,
    ffn_dim: int | None = None,
    seed: int = 0,
    backbone_widths: tuple[int, int, int] | None = None,
    coarse_layers: int | None = None,
) -> ModelConfig:
    """Write the grown weights of `source` to `out` (new), with its training record."""
    if ffn_dim is None and backbone_widths is None and coarse_layers is None:
        raise ValueError(
            "nothing to grow: give --ffn-dim, --backbone-widths and/or --coarse-layers"
        )
    if out.exists():
        raise FileExistsError(f"{out} exists; choose a new --out")
    raw = read_checkpoint_payload(source)
    state, config = split_checkpoint(raw)
    if config is None:
        raise CheckpointError(f"{source} records no model config")
    if ffn_dim is not None:
        state, config = widen_feed_forward(state, config, ffn_dim, seed)
    if backbone_widths is not None:
        state, config = widen_backbone(state, config, backbone_widths, seed)
    if coarse_layers is not None:
        state, config = deepen_coarse_blocks(state, config, coarse_layers, seed)
    carried = {k: raw[k] for k in ("train_state", "training_record") if k in raw}
    payload = {"model": state, "config": dataclasses.asdict(config), **carried}
    buffer = io.BytesIO()
    torch.save(payload, buffer)
    write_bytes_atomically(out, buffer.getvalue())
    return config


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m doctrpp.training.grow", description=__doc__)
    parser.add_argument("weights", type=Path, help="weights or checkpoint file with a config")
    parser.add_argument("--ffn-dim", type=int, help="new feed-forward width")
    parser.add_argument(
        "--backbone-widths", type=int, nargs=3, metavar="W", help="new feature-encoder widths"
    )
    parser.add_argument(
        "--coarse-layers", type=int, metavar="N", help="attention layers per 18/9-grid block"
    )
    parser.add_argument("--out", type=Path, required=True, help="file to write (new)")
    parser.add_argument("--seed", type=int, default=0, help="draws of the new units")
    args = parser.parse_args(argv)
    widths = None if args.backbone_widths is None else tuple(args.backbone_widths)
    try:
        config = grow_file(
            args.weights, args.out, args.ffn_dim, args.seed, widths, args.coarse_layers
        )
    except (CheckpointError, ValueError, FileExistsError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(
        f"wrote {args.out}: feed-forward width {config.ffn_dim}, feature-encoder widths "
        f"{' '.join(map(str, config.backbone_widths))}, coarse-block layers "
        f"{config.coarse_depth} ({config.to_json()})"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
