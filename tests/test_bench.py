"""`doctrpp bench` writes a complete report (tiny models, few runs)."""

from __future__ import annotations

import json

from doctrpp.cli import main
from doctrpp.quantize.calibration import generated_inputs
from doctrpp.quantize.presets import preset_by_name
from doctrpp.quantize.quantize import quantise


def test_bench_report(tiny_onnx, tmp_path):
    int8 = tmp_path / "tiny_int8.onnx"
    quantise(tiny_onnx, int8, preset_by_name("static-weights"), list(generated_inputs(3)))
    out = tmp_path / "report"
    code = main(
        [
            "bench",
            "--models",
            str(tiny_onnx),
            str(int8),
            "--out",
            str(out),
            "--runs",
            "2",
            "--per-kind",
            "1",
        ]
    )
    assert code == 0
    report = json.loads((out / "report.json").read_text())
    fp32, q = report["models"]
    assert fp32["precision"] == "fp32" and q["precision"] == "int8"
    assert set(fp32["latency"]) == {"1", "2"} and fp32["latency_ratio"] == 1.0
    assert fp32["accuracy"]["partial"]["drift_max_px"] == 0.0
    assert "gt_map_error_px" in q["accuracy"]["none"]
    assert q["peak_rss_mb"] > 10
    assert report["environment"]["allocator"]
    checks = {t["check"] for t in report["targets"]}
    assert {"max drift px (generated crops)", "latency vs reference, 1 thread", "file MB"} <= checks
    assert set(report["untouched"]) == {"complete", "partial", "none"}
    markdown = (out / "report.md").read_text()
    assert "| tiny_int8.onnx | onnx | int8 |" in markdown
    assert "allocator" in markdown
    assert "| untouched input | none |" in markdown
    assert "- phone:" in markdown and "- CPU server:" in markdown
    assert (out / "latency.png").is_file() and (out / "drift_vs_latency.png").is_file()


def test_bench_errors(tmp_path):
    assert main(["bench", "--models", str(tmp_path / "absent.onnx"), "--out", str(tmp_path)]) == 2
