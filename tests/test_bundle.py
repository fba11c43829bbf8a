"""`doctrpp bundle` writes what an app ships."""

from __future__ import annotations

import json

from doctrpp.cli import main


def test_bundle(tiny_onnx, tmp_path):
    out = tmp_path / "bundle"
    assert main(["bundle", "--out", str(out), "--models", str(tiny_onnx)]) == 0
    record = json.loads((out / "doctrpp.json").read_text())
    assert record["input"]["shape"] == [1, 3, 288, 288] and record["input"]["layout"] == "NCHW"
    assert record["models"][0]["precision"] == "fp32"
    assert len(record["models"][0]["sha256"]) == 64
    assert any("3x3 box" in step for step in record["postprocess"])
    assert "mirrored left-right" in record["postprocess"][0]
    assert "Gaussian blur sigma 2 px" in record["postprocess"][1]
    assert "align text lines" in record["postprocess"][2]
    assert "not_tested" in record
    assert (out / "doctrpp_fp32.onnx").read_bytes() == tiny_onnx.read_bytes()
    assert "What was tested" in (out / "docs" / "android.md").read_text()
    assert (out / "docs" / "ios.md").is_file()


def test_bundle_errors(tmp_path):
    bad = tmp_path / "m.pt"
    bad.write_text("x")
    assert main(["bundle", "--out", str(tmp_path / "b"), "--models", str(bad)]) == 2
    assert (
        main(["bundle", "--out", str(tmp_path / "b"), "--models", str(tmp_path / "no.onnx")]) == 2
    )
