"""The embedded default weights (trained by us; see MODEL_CARD.md) and their record."""

from __future__ import annotations

import json
import os
from pathlib import Path

WEIGHTS_DIR = Path(__file__).resolve().parent / "weights"
DEFAULT_NAME = "doctrpp_default.pt"
ENV_OVERRIDE = "DOCTRPP_DEFAULT_WEIGHTS"  # a checkpoint path to use instead (tests, experiments)


def default_checkpoint() -> Path | None:
    """Path of the default checkpoint, or None when this build ships none."""
    override = os.environ.get(ENV_OVERRIDE)
    if override:
        return Path(override)
    path = WEIGHTS_DIR / DEFAULT_NAME
    return path if path.is_file() else None


def training_record(checkpoint: Path | None = None) -> dict:
    """The JSON record written beside the default weights (steps, data, validation, sha256)."""
    checkpoint = checkpoint or default_checkpoint()
    if checkpoint is None:
        return {}
    record = checkpoint.with_suffix(".json")
    return json.loads(record.read_text()) if record.is_file() else {}


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "doctrpp-edge"
