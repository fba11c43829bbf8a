"""Quantisation recipes as frozen presets. Which one is the default is decided by measurement
(see benchmarks/README or the closing notes); every preset states what stays float."""

from __future__ import annotations

from dataclasses import dataclass


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
    matmul_weights_only: bool = False  # only MatMuls with a constant B (no attention matmuls)
    symmetric_activations: bool = False

    def __post_init__(self) -> None:
        if self.mode not in ("static", "dynamic"):
            raise ValueError(f"mode must be static or dynamic, not {self.mode!r}")
        if self.calibration not in ("minmax", "entropy", "percentile"):
            raise ValueError(f"unknown calibration {self.calibration!r}")
        if self.activation_type not in ("uint8", "int8"):
            raise ValueError(f"unknown activation type {self.activation_type!r}")


# The flow head and mask feed a softmax and an 8x upsampling: small errors there become
# pixel drift everywhere, so they stay float unless a preset says otherwise.
HEAD = ("/update_block/", "/upsample/")

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
            matmul_weights_only=True,
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
            matmul_weights_only=True,
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
DEFAULT_PRESET = "static-body"


def preset_by_name(name: str) -> QuantPreset:
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown preset {name!r}; choose from {', '.join(PRESETS)}") from None
