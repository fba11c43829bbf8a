"""Stated tolerances of exported files against our PyTorch model (px of the 288 grid).

fp32 and fp16 are parity checks (the largest difference); int8 is the drift target
(mean and largest difference over held-out crops) that an int8 file must meet.
"""

from __future__ import annotations

# 2e-3, not 1e-3: the trained default's fp32 ONNX differs from PyTorch by 0.78e-3 px on an
# AVX-512 CPU and 1.07e-3 px on an AVX2 one (float32 summation order in the kernels).
PARITY_TOLERANCE_PX = 2e-3
INT8_DRIFT_TARGET_PX = {"mean": 0.5, "max": 3.0}
TOLERANCE_PX: dict[str, dict[str, float]] = {
    "fp32": {"max": PARITY_TOLERANCE_PX},
    "fp16": {"max": 0.05},
    "int8": INT8_DRIFT_TARGET_PX,
}


def verdict(drift: dict[str, float], precision: str) -> tuple[bool, str]:
    """(within tolerance, one-line description) for a {mean, max} drift."""
    stated = TOLERANCE_PX[precision]
    ok = all(drift[k] <= v for k, v in stated.items())
    limits = ", ".join(f"{k} {v:g}" for k, v in stated.items())
    text = (
        f"mean {drift['mean']:.2e} px, largest difference {drift['max']:.2e} px "
        f"(tolerance {limits} px): {'ok' if ok else 'MISSES the tolerance'}"
    )
    return ok, text
