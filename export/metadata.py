"""Metadata written into every model file: enough for a runtime to use it unaided."""

from __future__ import annotations

from doctrpp import __version__, contract

from .config import ModelConfig


def model_metadata(
    config: ModelConfig, checkpoint_sha256: str, checkpoint_note: str, precision: str
) -> dict[str, str]:
    return {
        contract.META_INPUT_SIZE: str(contract.INPUT_SIZE),
        contract.META_INPUT_LAYOUT: "NCHW",
        contract.META_COLOR_ORDER: "RGB",
        contract.META_INPUT_SCALE: "1/255",
        contract.META_INPUT_RESIZE: "bilinear",
        contract.META_OUTPUT_LAYOUT: "NCHW",
        contract.META_OUTPUT_CONVENTION: contract.OUTPUT_CONVENTION,
        contract.META_CONFIG: config.to_json(),
        contract.META_VERSION: __version__,
        contract.META_CHECKPOINT_SHA256: checkpoint_sha256,
        contract.META_CHECKPOINT_NOTE: checkpoint_note,
        contract.META_PRECISION: precision,
    }
