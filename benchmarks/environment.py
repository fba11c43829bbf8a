"""What a benchmark ran on: machine, library versions, allocator setting."""

from __future__ import annotations

import os
import platform
from importlib.metadata import PackageNotFoundError, version

PACKAGES = (
    "doctrpp-edge",
    "numpy",
    "opencv-python-headless",
    "onnxruntime",
    "onnx",
    "torch",
    "ai-edge-litert",
    "litert-torch",
)
ALLOCATOR_VARIABLES = (
    "MALLOC_MMAP_THRESHOLD_",
    "MALLOC_TRIM_THRESHOLD_",
    "MALLOC_ARENA_MAX",
    "LD_PRELOAD",
)


def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def environment() -> dict:
    versions = {}
    for name in PACKAGES:
        try:
            versions[name] = version(name)
        except PackageNotFoundError:
            continue
    allocator = {k: os.environ[k] for k in ALLOCATOR_VARIABLES if k in os.environ}
    return {
        "platform": platform.platform(),
        "python": platform.python_version(),
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "packages": versions,
        "allocator": allocator or "glibc malloc defaults (no MALLOC_* variables set)",
    }


def load_average() -> float | None:
    """1-minute load average (other work on the machine makes timings noisy)."""
    try:
        return os.getloadavg()[0]
    except OSError:
        return None
