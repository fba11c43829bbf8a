"""The trainer's checkpoint files (last.pth, best.pth, snapshots): written atomically, read
back with one-line errors. Kept apart from the loop so that publishing and averaging do not
import the trainer."""

from __future__ import annotations

import io
from collections.abc import Iterable
from pathlib import Path

import torch

from doctrpp.errors import CliError
from doctrpp.export.checkpoint import CheckpointError, read_checkpoint_payload
from doctrpp.files import write_bytes_atomically

TRAINING_KEYS = ("model", "config", "train_state")
RESUME_KEYS = (*TRAINING_KEYS, "optimizer", "scheduler")


def save_checkpoint(path: Path, payload: dict) -> None:
    buffer = io.BytesIO()
    torch.save(payload, buffer)
    write_bytes_atomically(path, buffer.getvalue())


def read_training_checkpoint(path: Path, required: Iterable[str] = TRAINING_KEYS) -> dict:
    """A checkpoint `save_checkpoint` wrote (by default one with model, config and
    train_state; `required` names the keys needed); anything else is a one-line CliError."""
    try:
        checkpoint = read_checkpoint_payload(path)
    except CheckpointError as exc:
        raise CliError(str(exc)) from None
    problem = missing_keys(path, checkpoint, required)
    if problem:
        raise CliError(problem)
    return checkpoint


def missing_keys(path: Path, checkpoint: object, required: Iterable[str]) -> str | None:
    """What a loaded checkpoint lacks of `required`, as one line; None when nothing."""
    keys = set(checkpoint) if isinstance(checkpoint, dict) else set()
    missing = set(required) - keys
    if not missing:
        return None
    return f"{path}: not a training checkpoint (no {', '.join(sorted(missing))})"
