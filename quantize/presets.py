"""Quantisation recipes as frozen presets; every preset states what stays float.

Measured here (reference config, onnxruntime 1.31, 2 threads, drift vs fp32 on generated
crops, random reference weights): static-weights 0.69-0.74x fp32 latency, 0.36 px mean
drift; dynamic-linear 0.75-0.83x, 0.24 px; static-scores 0.76x (QLinearMatMul on two
activations is slower than the float kernel); static-body/static-all 1.2x and ~2.8 px
(quantising softmax probabilities for softmax(.)V ruins accuracy). Hence the default.
"""

from __future__ import annotations

from dataclasses import dataclass, replace


@dataclass(frozen=True)
class QuantPreset:
    name: str
    description: str
    mode: str  # "static" (calibrated activations) or "dynamic" (activations at run time)
    op_types: tuple[str, ...]  # op types that go int8
    per_channel: bool = True
    calibration: str = "minmax"  # minmax | entropy | percentile (static only)
    activation_type: str = "uint8"  # uint8 | int8 (static only)
    keep_float: tuple[str, ...] = ()  # node-name substrings that stay float
    # Attention's activation x activation matmuls: "int8" (both), "scores" (Q.K^T only,
    # softmax(.)V stays float) or "float" (neither).
    attention: str = "int8"
    symmetric_activations: bool = False
    quant_format: str = "qdq"  # qdq (Q/DQ pairs around float ops) | qoperator (QLinear* ops)

    def __post_init__(self) -> None:
        if self.mode not in ("static", "dynamic"):
            raise ValueError(f"mode must be static or dynamic, not {self.mode!r}")
        if self.calibration not in ("minmax", "entropy", "percentile"):
            raise ValueError(f"unknown calibration {self.calibration!r}")
        if self.attention not in ("int8", "scores", "float"):
            raise ValueError(f"attention must be int8, scores or float, not {self.attention!r}")
        if self.quant_format not in ("qdq", "qoperator"):
            raise ValueError(f"quant_format must be qdq or qoperator, not {self.quant_format!r}")
        if self.activation_type not in ("uint8", "int8"):
            raise ValueError(f"unknown activation type {self.activation_type!r}")


# The last convolutions of the flow head and of the mask feed an 8x upsampling and a
# softmax: errors there become pixel drift everywhere, so they stay float unless a preset
# says otherwise. (The heads' first 3x3 convolutions go int8: measured 0.30 vs 0.32 px
# mean drift with them float, and 3.5 MB smaller.)
HEAD = ("/update_block/mask/mask.2/", "/update_block/flow_head/conv2/", "/upsample/")

PRESETS: dict[str, QuantPreset] = {
    p.name: p
    for p in (
        QuantPreset(
            "dynamic-linear",
            "dynamic int8 linear layers (Gemm rewritten as MatMul); attention matmuls, "
            "convolutions and head float; activations quantised at run time",
            mode="dynamic",
            op_types=("MatMul",),
            per_channel=False,
            attention="float",
        ),
        QuantPreset(
            "static-all",
            "static QDQ int8 for every Conv, MatMul and Gemm (head included)",
            mode="static",
            op_types=("Conv", "MatMul", "Gemm"),
        ),
        QuantPreset(
            "static-body",
            "static QDQ int8 Conv/MatMul/Gemm; flow head and upsampling float",
            mode="static",
            op_types=("Conv", "MatMul", "Gemm"),
            keep_float=HEAD,
        ),
        QuantPreset(
            "static-weights",
            "static QDQ int8 Conv and weight MatMul/Gemm; attention matmuls and head float",
            mode="static",
            op_types=("Conv", "MatMul", "Gemm"),
            keep_float=HEAD,
            attention="float",
        ),
        QuantPreset(
            "static-scores",
            "static QDQ int8 Conv, weight MatMul/Gemm and attention scores (Q.K^T); "
            "softmax(.)V and head float",
            mode="static",
            op_types=("Conv", "MatMul", "Gemm"),
            keep_float=HEAD,
            attention="scores",
        ),
        QuantPreset(
            "static-encoder-float",
            "static QDQ int8 weight MatMul/Gemm and the down convolutions; the convolutional "
            "feature encoder (fnet), attention matmuls and head float (the trained tiny "
            "default's sensitivity: fnet causes most of the drift)",
            mode="static",
            op_types=("Conv", "MatMul", "Gemm"),
            keep_float=(*HEAD, "/fnet/"),
            attention="float",
        ),
        QuantPreset(
            "static-convs",
            "static QDQ int8 convolutions only (backbone, down layers); head float",
            mode="static",
            op_types=("Conv",),
            keep_float=HEAD,
        ),
    )
}
DEFAULT_PRESET = "static-weights"


# Variations of a preset for recipe comparisons: "static-weights+per-tensor+percentile".
VARIANTS: dict[str, dict] = {
    "per-tensor": {"per_channel": False},
    "symmetric": {"symmetric_activations": True},
    "int8-activations": {"activation_type": "int8"},
    "qoperator": {"quant_format": "qoperator"},
    "percentile": {"calibration": "percentile"},
    # onnxruntime 1.31's quantize_static hands the entropy calibrator no bin counts (128
    # histogram bins = 128 quantised bins), so it reproduces MinMax: all 282 scales of the
    # trained tiny default came out equal. Kept so the comparison table says so.
    "entropy": {"calibration": "entropy"},
}


def preset_by_name(name: str) -> QuantPreset:
    """A preset by name, optionally with variants appended: `static-weights+per-tensor`."""
    base, *variants = name.split("+")
    preset = _base_preset(base)
    for variant in variants:
        if variant not in VARIANTS:
            raise ValueError(f"unknown variant {variant!r}; choose from {', '.join(VARIANTS)}")
        preset = replace(preset, name=f"{preset.name}+{variant}", **VARIANTS[variant])
    return preset


def _base_preset(name: str) -> QuantPreset:
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown preset {name!r}; choose from {', '.join(PRESETS)}") from None
