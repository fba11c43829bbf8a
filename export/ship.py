"""Make the model files the package ships, from the embedded default weights.

usage: python -m doctrpp.export.ship [--skip-tflite]

Writes runtime/models/: doctrpp_fp32.onnx, doctrpp_fp16.tflite and doctrpp_int8.tflite
(the formats `bundle` and phones use) and models.json (sha256, precision, parity against
PyTorch on held-out generated crops, the weights' sha256). Rerun after publishing new
default weights; tests/test_shipped_models.py fails until the files match the weights.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

from doctrpp.files import sha256_of, write_bytes_atomically
from doctrpp.runtime.models import DEFAULT_MODEL, MANIFEST, MODELS_DIR

from .default_weights import WEIGHTS_DIR, default_checkpoint
from .tolerances import TOLERANCE_PX, verdict

PARITY_CROPS = 6


def parity_inputs(count: int = PARITY_CROPS) -> list[np.ndarray]:
    from doctrpp.quantize.calibration import HELD_OUT_SEED_OFFSET, generated_inputs

    return list(generated_inputs(count, HELD_OUT_SEED_OFFSET))


def ship(out_dir: Path = MODELS_DIR, tflite: bool = True) -> dict:
    from .checkpoint import load_model
    from .onnx_export import export_onnx
    from .parity import drift_px
    from .tflite_export import DEFAULT_KEEP_FLOAT, export_tflite

    checkpoint = default_checkpoint()
    if checkpoint is None:
        raise SystemExit("no default weights in export/weights; publish some first")
    model = load_model(checkpoint)
    weights_sha = sha256_of(checkpoint)
    note = f"checkpoint {checkpoint.name}"
    inputs = parity_inputs()
    files: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        onnx = export_onnx(
            model, Path(tmp) / DEFAULT_MODEL, checkpoint_sha256=weights_sha, checkpoint_note=note
        )
        made = [("onnx", "fp32", onnx)]
        if tflite:
            from doctrpp.quantize.calibration import load_calibration

            for precision in ("fp16", "int8"):
                calibration = load_calibration(None, 100) if precision == "int8" else None
                path = Path(tmp) / f"doctrpp_{precision}.tflite"
                result = export_tflite(
                    model,
                    path,
                    precision,
                    calibration,
                    weights_sha,
                    note,
                    keep_float=DEFAULT_KEEP_FLOAT,
                    verbose=False,
                )
                made.append(("tflite", precision, result))
        for fmt, precision, result in made:
            drift = drift_px(model, result.path, inputs)
            ok, text = verdict(drift, precision)
            print(f"{result.path.name}: {result.size_bytes / 1e6:.2f} MB; vs PyTorch {text}")
            if not ok:
                raise SystemExit(f"{result.path.name} misses its tolerance; nothing written")
            files[result.path.name] = {
                "format": fmt,
                "precision": precision,
                "bytes": result.size_bytes,
                "sha256": sha256_of(result.path),
                "vs_pytorch_px": drift,
                "tolerance_px": TOLERANCE_PX[precision],
            }
        for name in files:
            write_bytes_atomically(out_dir / name, (Path(tmp) / name).read_bytes())
    record = json.loads((WEIGHTS_DIR / "doctrpp_default.json").read_text())
    manifest = {
        "weights": checkpoint.name,
        "weights_sha256": weights_sha,
        "config": record.get("config"),
        "parity_inputs": f"{PARITY_CROPS} held-out generated crops (all kinds)",
        "default": DEFAULT_MODEL,
        "files": files,
    }
    text = json.dumps(manifest, indent=1, sort_keys=True) + "\n"
    write_bytes_atomically(out_dir / MANIFEST, text.encode())
    return manifest


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m doctrpp.export.ship", description=__doc__)
    parser.add_argument("--skip-tflite", action="store_true", help="ONNX only (no converter)")
    args = parser.parse_args(argv)
    manifest = ship(tflite=not args.skip_tflite)
    print(f"wrote {MODELS_DIR}: {', '.join(manifest['files'])}, {MANIFEST}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
