"""ONNX export: parity with PyTorch, graph constraints, metadata."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import onnx
import pytest
import torch

from doctrpp import contract
from doctrpp.export.checkpoint import unwrap_state_dict
from doctrpp.export.config import REFERENCE, TINY
from doctrpp.export.model import DocTrPP
from doctrpp.export.onnx_export import OPSET, export_onnx
from doctrpp.export.parity import parity_px

PARITY_TOLERANCE_PX = 1e-3


def _max_rank(model: onnx.ModelProto) -> int:
    inferred = onnx.shape_inference.infer_shapes(model)
    values = list(inferred.graph.value_info) + list(inferred.graph.output)
    return max(len(v.type.tensor_type.shape.dim) for v in values)


def test_tiny_export_parity_and_graph(tiny_model, tiny_onnx, report_difference):
    images = np.random.default_rng(1).random((2, 3, 288, 288), dtype=np.float32)
    worst = parity_px(tiny_model, tiny_onnx, images)
    report_difference("ONNX vs PyTorch (tiny config)", worst, PARITY_TOLERANCE_PX)
    assert worst <= PARITY_TOLERANCE_PX

    model = onnx.load(str(tiny_onnx))
    assert model.opset_import[0].version == OPSET
    ops = {n.op_type for n in model.graph.node}
    assert not ops & {"Col2Im", "Im2Col", "If", "Loop"}
    assert _max_rank(model) <= 4
    (graph_input,) = model.graph.input
    (graph_output,) = model.graph.output
    dims = lambda v: [d.dim_value for d in v.type.tensor_type.shape.dim]  # noqa: E731
    assert (graph_input.name, dims(graph_input)) == (contract.INPUT_NAME, [1, 3, 288, 288])
    assert (graph_output.name, dims(graph_output)) == (contract.OUTPUT_NAME, [1, 2, 288, 288])


def test_deeper_coarse_blocks_export_with_parity(tmp_path, report_difference):
    """A config with more layers in the 18/9-grid blocks (training.grow --coarse-layers)."""
    torch.manual_seed(3)
    config = dataclasses.replace(TINY, coarse_layers_per_block=2)
    model = DocTrPP(config).eval()
    path = tmp_path / "deep.onnx"
    export_onnx(model, path, checkpoint_sha256="0" * 64, checkpoint_note="deeper coarse blocks")
    images = np.random.default_rng(2).random((1, 3, 288, 288), dtype=np.float32)
    worst = parity_px(model, path, images)
    report_difference("ONNX vs PyTorch (tiny, coarse blocks 2 layers)", worst, PARITY_TOLERANCE_PX)
    assert worst <= PARITY_TOLERANCE_PX
    meta = {p.key: p.value for p in onnx.load(str(path)).metadata_props}
    assert json.loads(meta[contract.META_CONFIG])["coarse_layers_per_block"] == 2


def test_metadata_inside_the_file(tiny_onnx):
    meta = {p.key: p.value for p in onnx.load(str(tiny_onnx)).metadata_props}
    assert meta[contract.META_INPUT_SIZE] == "288"
    assert meta[contract.META_COLOR_ORDER] == "RGB"
    assert meta[contract.META_INPUT_SCALE] == "1/255"
    assert meta[contract.META_INPUT_LAYOUT] == "NCHW"
    assert "align_corners=True" in meta[contract.META_OUTPUT_CONVENTION]
    assert json.loads(meta[contract.META_CONFIG]) == json.loads(TINY.to_json())
    assert meta[contract.META_CHECKPOINT_SHA256] == "0" * 64
    assert meta[contract.META_VERSION]


def test_output_normalisation_in_graph(tiny_model, tiny_onnx):
    import onnxruntime as ort

    x = np.random.default_rng(2).random((1, 3, 288, 288), dtype=np.float32)
    session = ort.InferenceSession(str(tiny_onnx), providers=["CPUExecutionProvider"])
    normalised = session.run(None, {contract.INPUT_NAME: x})[0]
    with torch.no_grad():
        pixels = tiny_model(torch.from_numpy(x)).numpy()
    expected = (2 * (pixels / 286.8) - 1) * 0.99
    assert np.abs(normalised - expected).max() < 1e-5


def test_reference_export_matches_official(
    reference_state, shared_reference, tmp_path, report_difference
):
    model = DocTrPP(REFERENCE).eval()
    model.load_state_dict(unwrap_state_dict(reference_state))
    result = export_onnx(model, tmp_path / "doctrpp_fp32.onnx")
    expected = np.load(shared_reference / "official_seed0.npz")
    import onnxruntime as ort

    session = ort.InferenceSession(str(result.path), providers=["CPUExecutionProvider"])
    worst = 0.0
    for image, bm_pixels in zip(expected["input"], expected["bm_pixels"], strict=True):
        out = session.run(None, {contract.INPUT_NAME: image[None]})[0][0]
        worst = max(worst, float(np.abs(contract.normalised_to_pixels(out) - bm_pixels).max()))
    report_difference(
        "ONNX (reference config) vs official_seed0 bm_pixels", worst, PARITY_TOLERANCE_PX
    )
    assert worst <= PARITY_TOLERANCE_PX
    assert result.size_bytes < 100e6  # no duplicated constants


@pytest.mark.parametrize("bad", ["missing"])
def test_export_refuses_a_file_as_folder(bad, tmp_path):
    from doctrpp.cli import main

    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["export", "--random-weights", "0", "--config", "tiny", "--out", str(blocker)]) == 2
