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


def _tflite_interpreter_class():
    try:
        from ai_edge_litert.interpreter import Interpreter
    except ImportError:
        try:  # frozen at 2.14 and broken with numpy 2; accepted only as a fallback
            from tflite_runtime.interpreter import Interpreter
        except ImportError:
            raise ModelError(
                "running .tflite models needs the [tflite] extra: pip install "
                "'doctrpp-edge[tflite]'"
            ) from None
    return Interpreter


def read_tflite_metadata(data: bytes) -> dict[str, str]:
    """The `doctrpp` JSON entry of a .tflite file's metadata table ({} if absent)."""
    import json

    try:
        from ai_edge_litert import schema_py_generated as schema
    except ImportError:
        return {}
    model = schema.Model.GetRootAs(data, 0)
    for i in range(model.MetadataLength()):
        entry = model.Metadata(i)
        if entry.Name() == b"doctrpp":
            buffer = model.Buffers(entry.Buffer())
            return json.loads(buffer.DataAsNumpy().tobytes().decode())
    return {}


class TfliteBackend:
    """LiteRT interpreter (XNNPACK delegate by default on CPU) for .tflite files."""

    def __init__(self, path: Path, threads: int | None = None) -> None:
        interpreter_class = _tflite_interpreter_class()
        data = path.read_bytes()
        try:
            self.interpreter = interpreter_class(model_content=data, num_threads=threads)
            self.interpreter.allocate_tensors()
        except (ValueError, RuntimeError) as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ModelError(f"{path}: cannot load TFLite model: {first}") from None
        self.metadata = read_tflite_metadata(data)
        self.input = self.interpreter.get_input_details()[0]
        self.output = self.interpreter.get_output_details()[0]
        self.input_shape = tuple(int(d) for d in self.input["shape"])

    def run(self, batch: np.ndarray) -> np.ndarray:
        dtype = self.input["dtype"]
        if dtype != np.float32:  # a fully quantised model: quantise the input ourselves
            scale, zero_point = self.input["quantization"]
            info = np.iinfo(dtype)
            batch = np.clip(np.round(batch / scale) + zero_point, info.min, info.max)
        self.interpreter.set_tensor(self.input["index"], batch.astype(dtype))
        self.interpreter.invoke()
        out = self.interpreter.get_tensor(self.output["index"])
        if out.dtype != np.float32:
            scale, zero_point = self.output["quantization"]
            out = (out.astype(np.float32) - zero_point) * scale
        return out.copy()


BACKENDS[".tflite"] = TfliteBackend
