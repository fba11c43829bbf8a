"""Widen a trained model's feed-forward layers without changing what it computes.

usage: python -m doctrpp.training.grow WEIGHTS --ffn-dim 1024 --out FILE [--seed 0]

Every attention layer's feed-forward part is relu(x W1 + b1) W2 + b2. New hidden units get
W1 rows and b1 entries drawn as `nn.Linear` draws them and W2 columns of zeros, so the
grown model's output is the old one's (up to float rounding) while the new units get
gradients from the first step: more capacity for a run that has stopped gaining, without
starting over. The file keeps the source's training record, so `doctrpp train --init
FILE` (its config is taken from the file) continues the step, stream and CPU hours.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import math
import sys
from pathlib import Path

import torch

from doctrpp.export.checkpoint import CheckpointError, read_checkpoint
from doctrpp.export.config import ModelConfig
from doctrpp.files import write_bytes_atomically

FEED_FORWARD_IN, FEED_FORWARD_OUT = ".linear1.", ".linear2."


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
            fresh = (torch.rand((added, *value.shape[1:]), generator=generator) * 2 - 1) * bound
            value = torch.cat([value, fresh])
        elif FEED_FORWARD_OUT in key and key.endswith("weight"):  # (dim, ffn): zero columns
            value = torch.cat([value, value.new_zeros(value.shape[0], added)], dim=1)
        grown[key] = value
    return grown, dataclasses.replace(config, ffn_dim=ffn_dim)


def grow_file(source: Path, out: Path, ffn_dim: int, seed: int = 0) -> ModelConfig:
    """Write the widened weights of `source` to `out` (new), with its training record."""
    if out.exists():
        raise FileExistsError(f"{out} exists; choose a new --out")
    state, config = read_checkpoint(source)
    if config is None:
        raise CheckpointError(f"{source} records no model config")
    state, config = widen_feed_forward(state, config, ffn_dim, seed)
    raw = torch.load(source, map_location="cpu", weights_only=True)
    carried = {k: raw[k] for k in ("train_state", "training_record") if k in raw}
    payload = {"model": state, "config": dataclasses.asdict(config), **carried}
    buffer = io.BytesIO()
    torch.save(payload, buffer)
    write_bytes_atomically(out, buffer.getvalue())
    return config


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m doctrpp.training.grow", description=__doc__)
    parser.add_argument("weights", type=Path, help="weights or checkpoint file with a config")
    parser.add_argument("--ffn-dim", type=int, required=True, help="new feed-forward width")
    parser.add_argument("--out", type=Path, required=True, help="file to write (new)")
    parser.add_argument("--seed", type=int, default=0, help="draws of the new units")
    args = parser.parse_args(argv)
    try:
        config = grow_file(args.weights, args.out, args.ffn_dim, args.seed)
    except (CheckpointError, ValueError, FileExistsError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}: feed-forward width {config.ffn_dim} ({config.to_json()})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
