"""Our eager PyTorch model timed against an ONNX file, interleaved (needs torch)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np


def torch_row(checkpoint: Path, onnx_model: Path, threads: int, runs: int) -> dict:
    import torch

    from doctrpp.export.checkpoint import load_model
    from doctrpp.export.model import ExportWrapper
    from doctrpp.runtime.backends import open_backend

    torch.set_num_threads(threads)
    model = ExportWrapper(load_model(checkpoint)).eval()
    backend = open_backend(onnx_model, threads)
    x = np.random.default_rng(0).random((1, 3, 288, 288), dtype=np.float32)
    tx = torch.from_numpy(x)
    torch_ms, onnx_ms = [], []
    with torch.inference_mode():
        for _ in range(2):
            model(tx)
            backend.run(x)
        for _ in range(runs):
            start = time.perf_counter()
            model(tx)
            torch_ms.append((time.perf_counter() - start) * 1000)
            start = time.perf_counter()
            backend.run(x)
            onnx_ms.append((time.perf_counter() - start) * 1000)
    return {
        "name": f"PyTorch eager ({checkpoint.name})",
        "format": "pytorch",
        "precision": "fp32",
        "threads": threads,
        "median_ms": float(np.median(torch_ms)),
        "p90_ms": float(np.percentile(torch_ms, 90)),
        "onnx_median_ms_same_rounds": float(np.median(onnx_ms)),
        "latency_ratio": float(np.median(torch_ms) / np.median(onnx_ms)),
    }
