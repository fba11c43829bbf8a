"""Inference backends, chosen by the model file's suffix. Imports happen lazily."""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import numpy as np


class ModelError(ValueError):
    """A model file that cannot be used; the message is one line."""


class Backend(Protocol):
    metadata: dict[str, str]
    input_shape: tuple[int, ...]

    def run(self, batch: np.ndarray) -> np.ndarray:
        """(1, 3, S, S) float32 -> (1, 2, S, S) float32 normalised backward map."""


class OnnxBackend:
    def __init__(self, path: Path, threads: int | None = None) -> None:
        import onnxruntime as ort

        options = ort.SessionOptions()
        if threads is not None:
            options.intra_op_num_threads = threads
            options.inter_op_num_threads = 1
        try:
            self.session = ort.InferenceSession(
                str(path), options, providers=["CPUExecutionProvider"]
            )
        except Exception as exc:  # onnxruntime raises its own exception types
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ModelError(f"{path}: cannot load ONNX model: {first}") from None
        self.metadata = dict(self.session.get_modelmeta().custom_metadata_map)
        model_input = self.session.get_inputs()[0]
        self.input_name = model_input.name
        self.input_shape = tuple(model_input.shape)

    def run(self, batch: np.ndarray) -> np.ndarray:
        return self.session.run(None, {self.input_name: batch})[0]


BACKENDS = {".onnx": OnnxBackend}


def open_backend(path: str | Path, threads: int | None = None) -> Backend:
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"model not found: {path}")
    try:
        backend_class = BACKENDS[path.suffix.lower()]
    except KeyError:
        known = ", ".join(sorted(BACKENDS))
        raise ModelError(f"{path}: unknown model format (expected {known})") from None
    return backend_class(path, threads)
