"""int8 quantisation: loads in the runtime, node counts match the preset, drift is bounded."""

from __future__ import annotations

import onnx
import pytest

from doctrpp.benchmarks.accuracy import drift, predict
from doctrpp.cli import main
from doctrpp.quantize.calibration import generated_inputs
from doctrpp.quantize.presets import PRESETS, QuantPreset, preset_by_name
from doctrpp.quantize.quantize import count_quantised_nodes, quantise
from doctrpp.runtime import Rectifier

# Loose: the tiny test network has random weights; real numbers live in the benchmark.
TINY_DRIFT_BOUND_PX = 5.0


@pytest.fixture(scope="module")
def calibration():
    return list(generated_inputs(6))


@pytest.mark.parametrize(
    "name",
    [
        "static-weights",
        "dynamic-linear",
        "static-scores",
        "static-weights+qoperator",
        "static-weights+per-tensor+symmetric+percentile",
    ],
)
def test_presets_quantise_tiny_model(
    name, tiny_onnx, calibration, tmp_path, document_photo, report_difference
):
    preset = preset_by_name(name)
    result = quantise(tiny_onnx, tmp_path / "int8.onnx", preset, calibration)
    assert result.expected_nodes > 0
    assert result.quantised_nodes == result.expected_nodes
    model = onnx.load(str(result.path))
    meta = {p.key: p.value for p in model.metadata_props}
    assert meta["doctrpp.precision"] == "int8" and meta["doctrpp.input_size"] == "288"
    assert count_quantised_nodes(model, preset) == result.expected_nodes
    if preset.keep_float and preset.quant_format == "qdq":
        head = [
            n
            for n in model.graph.node
            if n.op_type == "Conv" and any(k in n.name for k in ("mask.2/", "flow_head/conv2/"))
        ]
        dequantised = {n.output[0] for n in model.graph.node if n.op_type == "DequantizeLinear"}
        assert head and not any(n.input[0] in dequantised for n in head)

    rectified = Rectifier(result.path).rectify(document_photo)  # the runtime takes it unchanged
    assert rectified.shape == document_photo.shape
    held_out = list(generated_inputs(3, seed_offset=5))
    summary = drift(predict(tiny_onnx, held_out), predict(result.path, held_out))
    report_difference(
        f"{name} int8 vs fp32 (tiny, random weights): mean drift",
        summary.mean_px,
        TINY_DRIFT_BOUND_PX,
    )
    assert summary.max_px < 5 * TINY_DRIFT_BOUND_PX
    assert summary.mean_px < TINY_DRIFT_BOUND_PX


def test_preset_validation():
    with pytest.raises(ValueError, match="mode"):
        QuantPreset("x", "", mode="weird", op_types=("Conv",))
    with pytest.raises(ValueError, match="unknown preset"):
        preset_by_name("nope")
    assert all(p.op_types for p in PRESETS.values())
    varied = preset_by_name("static-weights+per-tensor+entropy")
    assert not varied.per_channel and varied.calibration == "entropy"
    assert varied.name == "static-weights+per-tensor+entropy"
    with pytest.raises(ValueError, match="unknown variant"):
        preset_by_name("static-weights+fast")
    with pytest.raises(ValueError, match="quant_format"):
        QuantPreset("x", "", mode="static", op_types=("Conv",), quant_format="qlinear")


def test_quantize_cli(tiny_onnx, tmp_path, capsys):
    out = tmp_path / "q.onnx"
    code = main(
        [
            "quantize",
            "--model",
            str(tiny_onnx),
            "--out",
            str(out),
            "--calib-synthetic",
            "3",
            "--check",
            "2",
        ]
    )
    assert code == 0 and out.is_file()
    assert "drift vs fp32" in capsys.readouterr().out
    assert main(["quantize", "--model", str(tiny_onnx), "--out", str(tiny_onnx)]) == 2
    assert main(["quantize", "--model", str(tmp_path / "absent.onnx"), "--out", str(out)]) == 2


def test_sensitivity_ranks_groups(tiny_onnx, tmp_path, capsys):
    import json

    out = tmp_path / "sens.json"
    code = main(
        [
            "quantize",
            "--model",
            str(tiny_onnx),
            "--out",
            str(tmp_path / "x.onnx"),
            "--preset",
            "static-weights",
            "--calib-synthetic",
            "2",
            "--check",
            "2",
            "--sensitivity",
            str(out),
        ]
    )
    assert code == 0
    ranking = json.loads(out.read_text())
    assert len(ranking) >= 3
    drifts = [r["drift_mean_px"] for r in ranking]
    assert drifts == sorted(drifts, reverse=True)
    assert any(r["group"].startswith("/model/fnet") for r in ranking)
