"""TFLite / LiteRT export with litert-torch: fp32, fp16 and int8 (PT2E, calibrated).

litert-torch pins torch < 2.15 and pulls a large stack, so it lives in its own extra
(`[tflite-export]`); the runtime needs only `ai-edge-litert`. The file keeps our
input/output contract (NCHW input, as the ONNX file) and carries the same metadata as
a JSON entry named `doctrpp` in the model's metadata table.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from doctrpp import contract
from doctrpp.files import write_bytes_atomically

from .metadata import model_metadata

if TYPE_CHECKING:
    import torch

    from .model import DocTrPP

# torch is imported inside the functions: `doctrpp --help` reads the option lists below
# and must stay torch-free (the runtime CLI never imports torch).
METADATA_NAME = "doctrpp"
PRECISIONS = ("fp32", "fp16", "int8")


@dataclass(frozen=True)
class TfliteResult:
    path: Path
    seconds: float
    size_bytes: int


def add_metadata(tflite: bytes, metadata: dict[str, str]) -> bytes:
    """Append a `doctrpp` JSON entry to the model's metadata table."""
    import flatbuffers
    from ai_edge_litert import schema_py_generated as schema

    model = schema.ModelT.InitFromPackedBuf(bytearray(tflite), 0)
    for existing in model.buffers:
        # Weights stored after the flatbuffer (offset/size) would move when it is
        # repacked: bring them inline (fine below the 2 GB flatbuffer limit).
        if existing.offset > 1:
            start, end = existing.offset, existing.offset + existing.size
            existing.data = np.frombuffer(tflite[start:end], np.uint8)
            existing.offset, existing.size = 0, 0
    buffer = schema.BufferT()
    buffer.data = np.frombuffer(json.dumps(metadata, sort_keys=True).encode(), np.uint8)
    model.buffers.append(buffer)
    entry = schema.MetadataT()
    entry.name = METADATA_NAME
    entry.buffer = len(model.buffers) - 1
    model.metadata = [m for m in (model.metadata or []) if m.name != METADATA_NAME] + [entry]
    builder = flatbuffers.Builder(len(tflite) + 4096)
    builder.Finish(model.Pack(builder), file_identifier=b"TFL3")
    return bytes(builder.Output())


# int8 TFLite: which module types stay float. "head" is the flow head, the convex
# upsampling and the output normalisation (errors there become pixel drift everywhere);
# "head+backbone" also keeps the convolutional feature encoder float: on the trained tiny
# default it halved the drift (mean 0.73 -> 0.38 px, max 5.5 -> 2.0 px on 18 held-out
# crops) at the same latency. "head+backbone+attention" also keeps the attention
# (projections and softmax) float, so only the feed-forward layers and the strided convs
# are int8: on the trained mid weights (session 10) "head+backbone" drifted 0.31 / 6.2 px
# (mean / max, 12 held-out crops) and ran 1.15x the ONNX fp32 time at 2 threads; this
# drifted 0.08 / 0.80 px at 0.73x. Session 1's reference-size numbers used "head".
KEEP_FLOAT_CHOICES = ("head+backbone+attention", "head+backbone", "head")
DEFAULT_KEEP_FLOAT = "head+backbone+attention"


def keep_float_types(choice: str) -> tuple[type, ...]:
    from .backbone import FeatureEncoder
    from .model import BackwardMap, Normalise
    from .transformer import MultiheadAttention
    from .upsample import UpdateBlock

    if choice not in KEEP_FLOAT_CHOICES:
        raise ValueError(f"keep-float must be one of {', '.join(KEEP_FLOAT_CHOICES)}")
    kept = {
        "head": (UpdateBlock, BackwardMap, Normalise),
        "backbone": (FeatureEncoder,),
        "attention": (MultiheadAttention,),
    }
    return tuple(module for part in choice.split("+") for module in kept[part])


def _int8_model(
    wrapper: torch.nn.Module,
    sample: torch.Tensor,
    calibration: list[np.ndarray],
    keep_float: tuple[type, ...],
):
    """PT2E static int8, per-channel weights, calibrated on `calibration` inputs."""
    import torch
    from litert_torch.quantize.pt2e_quantizer import (
        PT2EQuantizer,
        get_symmetric_quantization_config,
    )
    from litert_torch.quantize.quant_config import QuantConfig
    from torchao.quantization.pt2e.quantize_pt2e import convert_pt2e, prepare_pt2e

    quantizer = PT2EQuantizer().set_global(
        get_symmetric_quantization_config(is_per_channel=True, is_dynamic=False)
    )
    # torch.export records module types as qualified names, so the filter takes strings.
    for module in keep_float:
        quantizer.set_module_type(f"{module.__module__}.{module.__qualname__}", None)
    exported = torch.export.export(wrapper, (sample,)).module()
    prepared = prepare_pt2e(exported, quantizer)
    with torch.no_grad():
        for batch in calibration:
            prepared(torch.from_numpy(batch))
    return convert_pt2e(prepared, fold_quantize=False), QuantConfig(pt2e_quantizer=quantizer)


def export_tflite(
    model: DocTrPP,
    out_path: str | Path,
    precision: str = "fp32",
    calibration: list[np.ndarray] | None = None,
    checkpoint_sha256: str = "",
    checkpoint_note: str = "",
    keep_float: str = DEFAULT_KEEP_FLOAT,
    verbose: bool = False,
) -> TfliteResult:
    """Convert `model` to a .tflite file; int8 keeps the `keep_float` modules in float.

    The converter's own output (dozens of lines) is shown only with `verbose`.
    """
    from doctrpp.quiet import quiet

    with quiet(not verbose):
        return _export_tflite(
            model,
            out_path,
            precision,
            calibration,
            checkpoint_sha256,
            checkpoint_note,
            keep_float,
        )


def _export_tflite(
    model, out_path, precision, calibration, checkpoint_sha256, checkpoint_note, keep_float
) -> TfliteResult:
    import litert_torch
    import torch

    from .model import ExportWrapper

    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {', '.join(PRECISIONS)}")
    start = time.perf_counter()
    wrapper = ExportWrapper(model.eval()).eval()
    sample = torch.rand(1, 3, contract.INPUT_SIZE, contract.INPUT_SIZE)
    if precision == "int8":
        if not calibration:
            raise ValueError("int8 export needs calibration inputs")
        keep = keep_float_types(keep_float)
        quantised, quant_config = _int8_model(wrapper, sample, calibration, keep)
        edge = litert_torch.convert(quantised, (sample,), quant_config=quant_config)
    elif precision == "fp16":
        from litert_torch.generative.quantize import quant_recipes

        # fp16 weights; the interpreter computes in fp32 (or fp16 where the delegate can).
        edge = litert_torch.convert(
            wrapper, (sample,), quant_config=quant_recipes.full_fp16_recipe()
        )
    else:
        edge = litert_torch.convert(wrapper, (sample,))
    out_path = Path(out_path)
    raw_path = out_path.with_name(f".{out_path.name}.raw")
    edge.export(str(raw_path))
    try:
        meta = model_metadata(model.config, checkpoint_sha256, checkpoint_note, precision)
        if precision == "int8":
            meta["doctrpp.int8_keep_float"] = keep_float
        data = add_metadata(raw_path.read_bytes(), meta)
    finally:
        raw_path.unlink(missing_ok=True)
    write_bytes_atomically(out_path, data)
    return TfliteResult(out_path, time.perf_counter() - start, len(data))
