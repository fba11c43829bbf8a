"""How far an exported model file (.onnx or .tflite) is from our PyTorch model."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from doctrpp import contract
from doctrpp.runtime.backends import open_backend

from .model import DocTrPP, ExportWrapper


def drift_px(
    model: DocTrPP, model_path: str | Path, images: np.ndarray, threads: int = 2
) -> dict[str, float]:
    """Mean and largest distance between the file's and PyTorch's backward maps over
    `images` ((N, 3, 288, 288) or a list of (1, 3, 288, 288)), in pixels of the 288 grid."""
    backend = open_backend(model_path, threads)
    wrapper = ExportWrapper(model.eval())
    distances = []
    for image in images:
        batch = np.asarray(image, np.float32).reshape(1, 3, *np.shape(image)[-2:])
        with torch.no_grad():
            expected = wrapper(torch.from_numpy(batch)).numpy()
        difference = contract.normalised_to_pixels(backend.run(batch)) - (
            contract.normalised_to_pixels(expected)
        )
        distances.append(np.sqrt((difference**2).sum(axis=1)).ravel())
    everything = np.concatenate(distances)
    return {"mean": float(everything.mean()), "max": float(everything.max())}


def parity_px(
    model: DocTrPP, model_path: str | Path, images: np.ndarray, threads: int = 2
) -> float:
    """Largest distance (px of the 288 grid) between the file's and PyTorch's maps."""
    return drift_px(model, model_path, images, threads)["max"]
