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


def attention_role(model: onnx.ModelProto) -> dict[str, str]:
    """MatMuls of two activations: "values" if one input comes from a Softmax, else "scores"."""
    constants = _initializers(model)
    producer = {out: node.op_type for node in model.graph.node for out in node.output}
    roles = {}
    for node in model.graph.node:
        if node.op_type == "MatMul" and node.input[1] not in constants:
            from_softmax = any(producer.get(name) == "Softmax" for name in node.input)
            roles[node.name] = "values" if from_softmax else "scores"
    return roles


def eligible_nodes(model: onnx.ModelProto, preset: QuantPreset) -> list[str]:
    """Names of the nodes the preset puts in int8."""
    roles = attention_role(model)
    allowed_roles = {"int8": {"scores", "values"}, "scores": {"scores"}, "float": set()}
    weights_only = preset.mode == "dynamic"  # dynamic mode quantises constant-B MatMuls only
    names = []
    for node in model.graph.node:
        if node.op_type not in preset.op_types:
            continue
        if any(pattern in node.name for pattern in preset.keep_float):
            continue
        role = roles.get(node.name)
        if role and (weights_only or role not in allowed_roles[preset.attention]):
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
    if preset.quant_format == "qoperator":
        return sum(n.op_type in ("QLinearConv", "QLinearMatMul", "QGemm") for n in model.graph.node)
    dequantised = {n.output[0] for n in model.graph.node if n.op_type == "DequantizeLinear"}
    return sum(n.op_type in preset.op_types and n.input[0] in dequantised for n in model.graph.node)


def gemm_to_matmul(model: onnx.ModelProto) -> int:
    """Rewrite Gemm(x, W, b, transB=1) with constant W as MatMul(x, W^T) + b, in place.

    onnxruntime's dynamic quantisation only handles MatMul; the exporter writes the
    transformer's linear layers as Gemm. Returns how many were rewritten.
    """
    from onnx import helper, numpy_helper

    weights = {i.name: i for i in model.graph.initializer}
    rewritten = 0
    nodes = []
    for node in model.graph.node:
        attrs = {a.name: helper.get_attribute_value(a) for a in node.attribute}
        plain = attrs.get("alpha", 1.0) == 1.0 and attrs.get("beta", 1.0) == 1.0
        if (
            node.op_type != "Gemm"
            or not plain
            or attrs.get("transA", 0)
            or node.input[1] not in weights
        ):
            nodes.append(node)
            continue
        weight = numpy_helper.to_array(weights[node.input[1]])
        if attrs.get("transB", 0):
            weight = weight.T
        name = node.input[1] + "_matmul"
        model.graph.initializer.append(numpy_helper.from_array(np.ascontiguousarray(weight), name))
        product = node.output[0] + "_matmul" if len(node.input) > 2 else node.output[0]
        nodes.append(helper.make_node("MatMul", [node.input[0], name], [product], name=node.name))
        if len(node.input) > 2:
            nodes.append(
                helper.make_node(
                    "Add", [product, node.input[2]], [node.output[0]], name=node.name + "_bias"
                )
            )
        rewritten += 1
    del model.graph.node[:]
    model.graph.node.extend(nodes)
    used = {name for node in model.graph.node for name in node.input}
    kept = [i for i in model.graph.initializer if i.name in used]
    del model.graph.initializer[:]
    model.graph.initializer.extend(kept)
    return rewritten


def _preprocess(source: Path, target: Path) -> None:
    from onnxruntime.quantization.shape_inference import quant_pre_process

    quant_pre_process(str(source), str(target), skip_symbolic_shape=True)


def quantise(
    fp32_path: str | Path,
    out_path: str | Path,
    preset: QuantPreset,
    calibration: list[np.ndarray] | None = None,
    only_nodes: list[str] | None = None,
) -> QuantResult:
    """Quantise `fp32_path` into `out_path` (written atomically); metadata is carried over."""
    from onnxruntime.quantization import (
        CalibrationMethod,
        QuantFormat,
        QuantType,
        quantize_dynamic,
        quantize_static,
    )

    from doctrpp.files import write_bytes_atomically

    start = time.perf_counter()
    fp32_path, out_path = Path(fp32_path), Path(out_path)
    metadata = {
        p.key: p.value for p in onnx.load(str(fp32_path), load_external_data=False).metadata_props
    }
    with tempfile.TemporaryDirectory() as folder:
        prepared = Path(folder) / "prepared.onnx"
        _preprocess(fp32_path, prepared)
        prepared_model = onnx.load(str(prepared))
        if preset.mode == "dynamic" and gemm_to_matmul(prepared_model):
            onnx.save(prepared_model, str(prepared))
        chosen = eligible_nodes(prepared_model, preset)
        if only_nodes is not None:  # a subset, e.g. for the sensitivity ranking
            subset = set(only_nodes)
            chosen = [name for name in chosen if name in subset]
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
                quant_format=QuantFormat.QDQ
                if preset.quant_format == "qdq"
                else QuantFormat.QOperator,
                op_types_to_quantize=list(preset.op_types),
                per_channel=preset.per_channel,
                activation_type=QuantType.QUInt8
                if preset.activation_type == "uint8"
                else QuantType.QInt8,
                weight_type=QuantType.QInt8,
                nodes_to_quantize=chosen,
                calibrate_method=method,
                extra_options={
                    # No CalibMaxIntermediateOutputs: in onnxruntime 1.31 MinMax drops the
                    # chunks it clears. MinMax keeps only per-tensor min/max per input anyway.
                    "ActivationSymmetric": preset.symmetric_activations,
                },
            )
        model = onnx.load(str(quantised_path))
    from doctrpp.export.onnx_export import deduplicate_initializers

    deduplicate_initializers(model)  # shared scales and zero points
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
