"""Publishing a run's weights as the embedded default (fp16, with its record) and re-scoring it."""

from __future__ import annotations

import dataclasses

import pytest
import torch

from doctrpp.errors import CliError
from doctrpp.export.checkpoint import load_model
from doctrpp.export.config import TINY


def test_publish_writes_fp16_default_with_record(tmp_path):
    import json

    from doctrpp.export.model import DocTrPP
    from doctrpp.files import sha256_of
    from doctrpp.training.publish import publish

    run = tmp_path / "run"
    run.mkdir()
    model = DocTrPP(TINY)
    state = {"step": 5, "samples_seen": 40, "cpu_seconds": 36.0, "wall_seconds": 20.0}
    ckpt = {"model": model.state_dict(), "config": dataclasses.asdict(TINY), "train_state": state}
    torch.save(ckpt, run / "best.pth")
    lines = [
        {"step": 0, "identity": True, "map_error_px/all": 48.0},
        {"step": 5, "samples_seen": 40, "map_error_px/all": 30.0},
    ]
    (run / "validation.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    (run / "snapshots").mkdir()
    torch.save(ckpt, run / "snapshots" / "step0000005.pt")  # a snapshot publishes alike
    snapshot = publish(run / "snapshots" / "step0000005.pt", tmp_path / "from_snapshot", "test")
    assert json.loads(snapshot.with_suffix(".json").read_text())["run"] == "run"
    weights = publish(run / "best.pth", tmp_path / "weights", note="test")
    record = json.loads(weights.with_suffix(".json").read_text())
    assert record["sha256"] == sha256_of(weights)
    assert record["validation"] == {"map_error_px/all": 30.0}
    assert record["identity"] == {"map_error_px/all": 48.0}
    assert record["samples_seen"] == 40 and record["cpu_hours"] == 0.01
    stored = torch.load(weights, weights_only=True)["model"]
    assert all(v.dtype == torch.float16 for v in stored.values() if v.is_floating_point())
    loaded = load_model(weights)
    assert loaded.config == TINY
    x = torch.rand(1, 3, 288, 288)
    with torch.no_grad():
        worst = float((loaded(x) - model.eval()(x)).abs().max())
    print(f"fp16 storage vs fp32 weights (tiny, random): largest difference {worst:.3g} px")
    assert worst < 0.5


def test_publish_rescore_replaces_generated_scores_only(tmp_path):
    """After a generator change the published record is re-scored on the new validation set:
    generated scores replaced (the old ones kept), real-photo scores and weights untouched."""
    import json

    from doctrpp.export.model import DocTrPP
    from doctrpp.files import sha256_of
    from doctrpp.training.publish import publish, rescore

    run = tmp_path / "run"
    run.mkdir()
    state = {"step": 5, "samples_seen": 40, "cpu_seconds": 36.0, "wall_seconds": 20.0}
    ckpt = {"model": DocTrPP(TINY).state_dict(), "config": dataclasses.asdict(TINY)}
    torch.save({**ckpt, "train_state": state}, run / "best.pth")
    lines = [
        {"step": 0, "identity": True, "map_error_px/all": 48.0, "real/kept_share/none": 1.0},
        {"step": 5, "map_error_px/all": 1.0, "real/kept_share/none": 0.9},
    ]
    (run / "validation.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    weights = publish(run / "best.pth", tmp_path / "weights", note="test")
    digest = sha256_of(weights)
    record = rescore(tmp_path / "weights", validation_size=3)
    assert json.loads(weights.with_suffix(".json").read_text()) == record
    assert sha256_of(weights) == digest == record["sha256"]
    assert record["validation"]["real/kept_share/none"] == 0.9
    assert record["validation"]["map_error_px/all"] > 1.0  # random weights, really scored
    assert set(record["identity"]) > {"map_error_px/complete", "map_error_px/all"}
    assert record["validation_before_rescore"]["validation"] == {"map_error_px/all": 1.0}
    with pytest.raises(CliError, match="no published default"):
        rescore(tmp_path / "nothing")
