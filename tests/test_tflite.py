"""TFLite export (litert-torch) and the LiteRT runtime backend; skipped without them."""

from __future__ import annotations

import numpy as np
import pytest
import torch

litert_torch = pytest.importorskip("litert_torch", reason="the [tflite-export] extra is absent")

from doctrpp.export.model import ExportWrapper  # noqa: E402
from doctrpp.export.tflite_export import export_tflite  # noqa: E402
from doctrpp.runtime import Rectifier  # noqa: E402

PARITY_TOLERANCE_PX = 1e-3


@pytest.fixture(scope="module")
def tiny_tflite(tiny_model, tmp_path_factory):
    path = tmp_path_factory.mktemp("tfl") / "doctrpp_fp32.tflite"
    return export_tflite(tiny_model, path, "fp32", checkpoint_note="tiny test model").path


def test_fp32_tflite_parity_with_pytorch(tiny_model, tiny_tflite, report_difference):
    rectifier = Rectifier(tiny_tflite, threads=2)
    assert rectifier.metadata["doctrpp.precision"] == "fp32"
    assert rectifier.metadata["doctrpp.input_layout"] == "NCHW"
    x = np.random.default_rng(3).random((1, 3, 288, 288), dtype=np.float32)
    with torch.no_grad():
        expected = ExportWrapper(tiny_model)(torch.from_numpy(x)).numpy()
    got = rectifier.backend.run(x)
    worst = float(np.abs(got - expected).max()) * 286.8 / (2 * 0.99)
    report_difference("TFLite fp32 vs PyTorch (tiny config)", worst, PARITY_TOLERANCE_PX)
    assert worst <= PARITY_TOLERANCE_PX


def test_tflite_runs_in_the_rectifier(tiny_tflite, document_photo):
    out = Rectifier(tiny_tflite).rectify(document_photo)
    assert out.shape == document_photo.shape


@pytest.mark.parametrize("precision", ["fp16", "int8"])
def test_reduced_precision_tflite(precision, tiny_model, tmp_path, report_difference):
    from doctrpp.quantize.calibration import generated_inputs

    calibration = list(generated_inputs(3)) if precision == "int8" else None
    path = export_tflite(
        tiny_model, tmp_path / f"m_{precision}.tflite", precision, calibration
    ).path
    backend = Rectifier(path).backend
    assert backend.output["dtype"] == np.float32  # the head and output stay float
    x = list(generated_inputs(1, seed_offset=9))[0]
    with torch.no_grad():
        expected = ExportWrapper(tiny_model)(torch.from_numpy(x)).numpy()
    worst = float(np.abs(backend.run(x) - expected).max()) * 286.8 / (2 * 0.99)
    report_difference(f"TFLite {precision} vs PyTorch (tiny, random weights)", worst, 3.0)
    assert worst < 3.0


def test_keep_float_choices_name_module_types():
    from doctrpp.export.backbone import FeatureEncoder
    from doctrpp.export.tflite_export import (
        DEFAULT_KEEP_FLOAT,
        KEEP_FLOAT_CHOICES,
        keep_float_types,
    )
    from doctrpp.export.transformer import MultiheadAttention

    assert DEFAULT_KEEP_FLOAT in KEEP_FLOAT_CHOICES
    head = set(keep_float_types("head"))
    assert FeatureEncoder not in head and MultiheadAttention not in head
    assert set(keep_float_types("head+backbone")) == head | {FeatureEncoder}
    assert set(keep_float_types("head+backbone+attention")) == head | {
        FeatureEncoder,
        MultiheadAttention,
    }
    with pytest.raises(ValueError, match="keep-float must be one of"):
        keep_float_types("attention")
