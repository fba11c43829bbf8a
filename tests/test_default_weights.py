"""The embedded default weights: loadable, their record consistent, the bar met."""

from __future__ import annotations

import json

import pytest

from doctrpp.export.checkpoint import load_model
from doctrpp.export.config import ModelConfig
from doctrpp.export.default_weights import DEFAULT_NAME, WEIGHTS_DIR
from doctrpp.files import sha256_of

WEIGHTS = WEIGHTS_DIR / DEFAULT_NAME
pytestmark = pytest.mark.skipif(not WEIGHTS.is_file(), reason="this build ships no default")


def _record() -> dict:
    return json.loads(WEIGHTS.with_suffix(".json").read_text())


def test_record_matches_the_weights_file():
    record = _record()
    assert record["sha256"] == sha256_of(WEIGHTS)
    assert WEIGHTS.stat().st_size <= 60e6
    for key in ("step", "samples_seen", "cpu_hours", "date", "validation", "identity"):
        assert key in record
    model = load_model(WEIGHTS)
    assert model.config == ModelConfig.from_dict(record["config"])


def test_default_beats_identity_on_every_crop_kind():
    record = _record()
    for kind in ("complete", "partial", "none"):
        ours = record["validation"][f"map_error_px/{kind}"]
        identity = record["identity"][f"map_error_px/{kind}"]
        print(f"{kind}: {ours:.1f} px vs identity {identity:.1f} px")
        assert ours < identity


def test_record_reproduces_on_the_validation_set(report_difference):
    """Re-score the shipped weights (fp32 compute, fp16 storage) on the trainer's fixed
    validation set: the record must still describe them (and the generator)."""
    from doctrpp.training.validate import predict_maps, score_maps, validation_set

    record = _record()
    items = validation_set(48)
    scores = score_maps(items, predict_maps(load_model(WEIGHTS), items))
    worst = max(
        abs(scores[f"map_error_px/{kind}"] - record["validation"][f"map_error_px/{kind}"])
        for kind in ("complete", "partial", "none", "all")
    )
    report_difference("default weights: validation vs record (per-kind mean px)", worst, 0.5)
    assert worst <= 0.5
