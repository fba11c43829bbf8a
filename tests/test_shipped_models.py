"""The model files the package ships match the shipped weights (so they cannot drift apart)."""

from __future__ import annotations

import json

import pytest

from doctrpp.export.default_weights import default_checkpoint
from doctrpp.export.tolerances import verdict
from doctrpp.files import sha256_of
from doctrpp.runtime.models import MODELS_DIR, manifest, shipped_model


def test_manifest_names_the_shipped_weights_and_files():
    record = manifest()
    assert record["weights_sha256"] == sha256_of(default_checkpoint()), (
        "runtime/models was made from other weights: run python -m doctrpp.export.ship"
    )
    for name, entry in record["files"].items():
        assert sha256_of(MODELS_DIR / name) == entry["sha256"], name
    assert shipped_model().name == record["default"]


@pytest.mark.parametrize(
    "name", sorted(json.loads((MODELS_DIR / "models.json").read_text())["files"])
)
def test_shipped_file_matches_the_weights_within_its_tolerance(name, report_difference):
    entry = manifest()["files"][name]
    if entry["format"] == "tflite":
        pytest.importorskip("ai_edge_litert", reason="needs the [tflite] extra")
    from doctrpp.export.checkpoint import load_model
    from doctrpp.export.parity import drift_px
    from doctrpp.export.ship import parity_inputs

    drift = drift_px(load_model(default_checkpoint()), MODELS_DIR / name, parity_inputs(3))
    ok, text = verdict(drift, entry["precision"])
    report_difference(f"shipped {name} vs PyTorch", drift["max"], entry["tolerance_px"]["max"])
    assert ok, text
