"""The embedded default's model files, ready to run without torch.

Written by `python -m doctrpp.export.ship` from `export/weights/doctrpp_default.pt`;
`models.json` lists each file's sha256, precision, measured parity against PyTorch and
the sha256 of the weights it was made from (a test keeps them in step).
"""

from __future__ import annotations

import json
from pathlib import Path

MODELS_DIR = Path(__file__).resolve().parent
MANIFEST = "models.json"
DEFAULT_MODEL = "doctrpp_fp32.onnx"  # what `doctrpp rectify` runs without --model


class NoShippedModel(FileNotFoundError):
    """This build ships no model files (a source tree before `doctrpp.export.ship`)."""


def manifest() -> dict:
    path = MODELS_DIR / MANIFEST
    if not path.is_file():
        raise NoShippedModel(f"{path}: this build ships no model files; pass --model")
    return json.loads(path.read_text())


def shipped_model(name: str = DEFAULT_MODEL) -> Path:
    """Path of a shipped model file by name (see `manifest()["files"]`)."""
    entry = manifest()["files"].get(name)
    path = MODELS_DIR / name
    if entry is None or not path.is_file():
        raise NoShippedModel(f"{path}: not shipped with this build; pass --model")
    return path
