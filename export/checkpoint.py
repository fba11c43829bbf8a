"""Loading checkpoints saved by the authors' code (or by us) into `DocTrPP`."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import torch

from .config import REFERENCE, ModelConfig
from .model import DocTrPP

WRAPPER_KEYS = ("state_dict", "model", "model_state_dict", "net")
PREFIXES = ("module.", "model.")
# Present in every reference layer, never used in its forward pass.
UNUSED_MARKERS = (".multihead_attn_list.1.", ".norm2_list.1.")


class CheckpointError(ValueError):
    """A checkpoint that does not fit the model; the message says why in one line."""


def unwrap_state_dict(obj: object) -> dict[str, torch.Tensor]:
    """Find the state dict in what `torch.load` returned and normalise its key names."""
    if isinstance(obj, Mapping):
        for key in WRAPPER_KEYS:
            if key in obj and isinstance(obj[key], Mapping):
                obj = obj[key]
                break
    if not isinstance(obj, Mapping) or not all(isinstance(v, torch.Tensor) for v in obj.values()):
        raise CheckpointError("checkpoint holds no state dict of tensors")
    state: dict[str, torch.Tensor] = {}
    for key, value in obj.items():
        for prefix in PREFIXES:
            if key.startswith(prefix):
                key = key[len(prefix) :]
                break
        if any(marker in "." + key for marker in UNUSED_MARKERS):
            continue
        state[key] = value
    return state


def _preview(items: list[str], limit: int = 3) -> str:
    shown = ", ".join(items[:limit])
    return shown + (f" (+{len(items) - limit} more)" if len(items) > limit else "")


def check_state_dict(model: torch.nn.Module, state: Mapping[str, torch.Tensor]) -> None:
    """Raise CheckpointError naming missing/unexpected keys and shape mismatches."""
    expected = model.state_dict()
    missing = [k for k in expected if k not in state]
    unexpected = [k for k in state if k not in expected]
    mismatched = [
        f"{k} {tuple(state[k].shape)} vs {tuple(v.shape)}"
        for k, v in expected.items()
        if k in state and tuple(state[k].shape) != tuple(v.shape)
    ]
    problems = []
    if missing:
        problems.append(f"missing keys: {_preview(missing)}")
    if unexpected:
        problems.append(f"unexpected keys: {_preview(unexpected)}")
    if mismatched:
        problems.append(f"shape mismatches (checkpoint vs model): {_preview(mismatched)}")
    if problems:
        raise CheckpointError("checkpoint does not fit the model: " + "; ".join(problems))


def read_checkpoint(path: str | Path) -> tuple[dict[str, torch.Tensor], ModelConfig | None]:
    """Read a checkpoint file; returns its state dict and the config it records, if any."""
    return split_checkpoint(read_checkpoint_payload(path))


def split_checkpoint(obj: object) -> tuple[dict[str, torch.Tensor], ModelConfig | None]:
    """The state dict and recorded config of what `read_checkpoint_payload` returned."""
    config = None
    if isinstance(obj, Mapping) and isinstance(obj.get("config"), Mapping):
        config = ModelConfig.from_dict(dict(obj["config"]))
    return unwrap_state_dict(obj), config


def read_checkpoint_payload(path: str | Path) -> object:
    """Load a checkpoint file as saved (state dict or a dict with training extras)."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"checkpoint not found: {path}")
    if not looks_like_torch_file(path):
        raise CheckpointError(
            f"{path} is not a PyTorch checkpoint (expected a file written by torch.save: "
            ".pth/.pt, a zip archive or a legacy pickle)"
        )
    try:
        obj = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises several types for corrupt or pickled files
        first_line = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise CheckpointError(f"cannot read checkpoint {path}: {first_line}") from None
    return obj


def looks_like_torch_file(path: Path) -> bool:
    """torch.save writes a zip archive (PK) or, in the legacy format, a pickle (0x80)."""
    with open(path, "rb") as f:
        head = f.read(2)
    return head == b"PK" or head[:1] == b"\x80"


def load_model(path: str | Path, config: ModelConfig | None = None) -> DocTrPP:
    """Build the model (config from the file, else `config`, else the reference) and load it."""
    state, recorded = read_checkpoint(path)
    model = DocTrPP(config or recorded or REFERENCE)
    check_state_dict(model, state)
    model.load_state_dict({k: v.float() for k, v in state.items()})
    return model.eval()
