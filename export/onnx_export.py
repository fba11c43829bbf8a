"""ONNX export: legacy TorchScript exporter at opset 17, simplified, metadata inside."""

from __future__ import annotations

import io
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import torch

from doctrpp import contract
from doctrpp.files import write_bytes_atomically

from .metadata import model_metadata
from .model import DocTrPP, ExportWrapper

OPSET = 17


@dataclass(frozen=True)
class ExportResult:
    path: Path
    seconds: float
    size_bytes: int
    node_count: int


def _trace_to_onnx(model: DocTrPP) -> bytes:
    wrapper = ExportWrapper(model).eval()
    dummy = torch.rand(1, 3, contract.INPUT_SIZE, contract.INPUT_SIZE)
    buffer = io.BytesIO()
    with torch.no_grad(), warnings.catch_warnings():
        # Instance norm without running stats is exactly what we want; silence the notice.
        warnings.filterwarnings("ignore", message=".*instance_norm.*")
        warnings.filterwarnings("ignore", category=torch.jit.TracerWarning)
        # The legacy exporter is chosen on purpose: silence its deprecation notices.
        warnings.filterwarnings("ignore", category=DeprecationWarning)
        warnings.filterwarnings("ignore", category=UserWarning, module="torch.onnx")
        torch.onnx.export(
            wrapper,
            (dummy,),
            buffer,
            input_names=[contract.INPUT_NAME],
            output_names=[contract.OUTPUT_NAME],
            opset_version=OPSET,
            dynamo=False,  # the dynamo exporter moves to opset 18 and writes a side file
            do_constant_folding=True,
        )
    return buffer.getvalue()


def _simplify(onnx_model):
    import onnxslim

    return onnxslim.slim(onnx_model)


def deduplicate_initializers(onnx_model) -> int:
    """Merge initializers with identical dtype, shape and bytes; returns how many went.

    The tracer inlines a buffer once per use (each positional encoding ~9 times), which
    would add ~15 MB of copies to the file.
    """
    from onnx import numpy_helper

    canonical: dict[tuple, str] = {}
    renamed: dict[str, str] = {}
    kept = []
    for init in onnx_model.graph.initializer:
        array = numpy_helper.to_array(init)
        key = (array.dtype.str, array.shape, array.tobytes())
        if key in canonical:
            renamed[init.name] = canonical[key]
        else:
            canonical[key] = init.name
            kept.append(init)
    if renamed:
        del onnx_model.graph.initializer[:]
        onnx_model.graph.initializer.extend(kept)
        for node in onnx_model.graph.node:
            for i, name in enumerate(node.input):
                if name in renamed:
                    node.input[i] = renamed[name]
    return len(renamed)


def export_onnx(
    model: DocTrPP,
    out_path: str | Path,
    *,
    checkpoint_sha256: str = "",
    checkpoint_note: str = "",
    simplify: bool = True,
) -> ExportResult:
    """Export `model` (eval mode, fp32) to `out_path`; returns timing, size and node count."""
    import onnx

    start = time.perf_counter()
    onnx_model = onnx.load_from_string(_trace_to_onnx(model.eval()))
    if simplify:
        onnx_model = _simplify(onnx_model)
    deduplicate_initializers(onnx_model)
    meta = model_metadata(model.config, checkpoint_sha256, checkpoint_note, precision="fp32")
    del onnx_model.metadata_props[:]
    for key, value in meta.items():
        onnx_model.metadata_props.add(key=key, value=value)
    onnx.checker.check_model(onnx_model)
    data = onnx_model.SerializeToString()
    out_path = Path(out_path)
    write_bytes_atomically(out_path, data)
    return ExportResult(
        path=out_path,
        seconds=time.perf_counter() - start,
        size_bytes=len(data),
        node_count=len(onnx_model.graph.node),
    )
