"""int8 quantisation of an exported fp32 ONNX model with onnxruntime's tools."""

from __future__ import annotations

import json
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import onnx

from doctrpp import contract

from .calibration import CalibrationReader
from .presets import QuantPreset

DYNAMIC_OPS = ("MatMulInteger", "ConvInteger", "DynamicQuantizeMatMul", "DynamicQuantizeLinear")


@dataclass(frozen=True)
class QuantResult:
    path: Path
    seconds: float
    size_bytes: int
    quantised_nodes: int
    expected_nodes: int


def _initializers(model: onnx.ModelProto) -> set[str]:
    return {i.name for i in model.graph.initializer}


def eligible_nodes(model: onnx.ModelProto, preset: QuantPreset) -> list[str]:
    """Names of the nodes the preset puts in int8."""
    constants = _initializers(model)
    names = []
    for node in model.graph.node:
        if node.op_type not in preset.op_types:
            continue
        if any(pattern in node.name for pattern in preset.keep_float):
            continue
        if (
            node.op_type == "MatMul"
            and preset.matmul_weights_only
            and node.input[1] not in constants
        ):
            continue
        names.append(node.name)
    return names


def count_quantised_nodes(model: onnx.ModelProto, preset: QuantPreset) -> int:
    """Nodes that compute in int8: QDQ-wrapped ops (static) or integer ops (dynamic)."""
    if preset.mode == "dynamic":
        return sum(
            n.op_type in ("MatMulInteger", "ConvInteger", "DynamicQuantizeMatMul")
            for n in model.graph.node
        )
    dequantised = {n.output[0] for n in model.graph.node if n.op_type == "DequantizeLinear"}
    return sum(n.op_type in preset.op_types and n.input[0] in dequantised for n in model.graph.node)


def _preprocess(source: Path, target: Path) -> None:
    from onnxruntime.quantization.shape_inference import quant_pre_process

    quant_pre_process(str(source), str(target), skip_symbolic_shape=True)


def quantise(
    fp32_path: str | Path,
    out_path: str | Path,
    preset: QuantPreset,
    calibration: list[np.ndarray] | None = None,
) -> QuantResult:
    """Quantise `fp32_path` into `out_path` (written atomically); metadata is carried over."""
    from onnxruntime.quantization import (
        CalibrationMethod,
        QuantFormat,
        QuantType,
        quantize_dynamic,
        quantize_static,
    )

    from doctrpp.runtime.imageio import write_bytes_atomically

    start = time.perf_counter()
    fp32_path, out_path = Path(fp32_path), Path(out_path)
    metadata = {
        p.key: p.value for p in onnx.load(str(fp32_path), load_external_data=False).metadata_props
    }
    with tempfile.TemporaryDirectory() as folder:
        prepared = Path(folder) / "prepared.onnx"
        _preprocess(fp32_path, prepared)
        prepared_model = onnx.load(str(prepared))
        chosen = eligible_nodes(prepared_model, preset)
        quantised_path = Path(folder) / "int8.onnx"
        if preset.mode == "dynamic":
            quantize_dynamic(
                prepared,
                quantised_path,
                op_types_to_quantize=list(preset.op_types),
                per_channel=preset.per_channel,
                weight_type=QuantType.QInt8,
                nodes_to_quantize=chosen,
            )
        else:
            if not calibration:
                raise ValueError("static quantisation needs calibration inputs")
            method = {
                "minmax": CalibrationMethod.MinMax,
                "entropy": CalibrationMethod.Entropy,
                "percentile": CalibrationMethod.Percentile,
            }[preset.calibration]
            quantize_static(
                prepared,
                quantised_path,
                CalibrationReader(calibration),
                quant_format=QuantFormat.QDQ,
                op_types_to_quantize=list(preset.op_types),
                per_channel=preset.per_channel,
                activation_type=QuantType.QUInt8
                if preset.activation_type == "uint8"
                else QuantType.QInt8,
                weight_type=QuantType.QInt8,
                nodes_to_quantize=chosen,
                calibrate_method=method,
                extra_options={
                    "CalibMaxIntermediateOutputs": 4,  # bounded memory on 300+ inputs
                    "ActivationSymmetric": preset.symmetric_activations,
                    "MatMulConstBOnly": preset.matmul_weights_only,
                },
            )
        model = onnx.load(str(quantised_path))
    metadata[contract.META_PRECISION] = "int8"
    metadata["doctrpp.quant_preset"] = json.dumps(asdict(preset), sort_keys=True)
    del model.metadata_props[:]
    for key, value in metadata.items():
        model.metadata_props.add(key=key, value=value)
    data = model.SerializeToString()
    write_bytes_atomically(out_path, data)
    return QuantResult(
        path=out_path,
        seconds=time.perf_counter() - start,
        size_bytes=len(data),
        quantised_nodes=count_quantised_nodes(model, preset),
        expected_nodes=len(chosen),
    )
