"""The embedded default weights (trained by us; see MODEL_CARD.md) and their record."""

from __future__ import annotations

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
