"""`doctrpp bundle --out DIR --models ...`: what a scanner app ships."""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

from doctrpp import __version__, contract
from doctrpp.errors import CliError
from doctrpp.files import sha256_of, write_bytes_atomically

DOCS = Path(__file__).resolve().parent / "docs"


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "bundle",
        help="model files + doctrpp.json contract + Android/iOS notes",
        description="Copy the chosen model files into DIR with doctrpp.json (input/output "
        "contract, exact post-processing steps and their tolerances) and docs/android.md, "
        "docs/ios.md.",
    )
    p.add_argument("--out", type=Path, required=True, help="bundle folder (created)")
    p.add_argument(
        "--models",
        type=Path,
        nargs="+",
        required=True,
        metavar="MODEL",
        help=".onnx and/or .tflite files",
    )
    p.set_defaults(handler=run)


def describe_contract() -> dict:
    return {
        "input": {
            "name": contract.INPUT_NAME,
            "shape": [1, 3, contract.INPUT_SIZE, contract.INPUT_SIZE],
            "layout": "NCHW",
            "dtype": "float32",
            "color_order": "RGB",
            "scale": "uint8 / 255, no mean/std",
            "resize": "photo (EXIF orientation applied) resized to 288x288, bilinear",
        },
        "output": {
            "name": contract.OUTPUT_NAME,
            "shape": [1, 2, contract.INPUT_SIZE, contract.INPUT_SIZE],
            "dtype": "float32",
            "meaning": contract.OUTPUT_CONVENTION,
        },
        "postprocess": [
            "flip-average (recommended; skip it for the reference's single run, at half the "
            "inference time): run the model again on the input mirrored left-right (each row "
            "of the 288 x 288 input reversed), mirror that output back (columns reversed, "
            "channel 0 negated) and average it with the first output "
            "(doctrpp.runtime.processing.flip_averaged_map; a closer map)",
            "smooth each output channel on the model grid (recommended; skip it for the "
            "reference's post-processing): extend each border by 8 px of odd reflection "
            "(2 * edge - mirror), Gaussian blur sigma 2 px with a 17 x 17 kernel, crop back "
            "to 288 x 288 (doctrpp.runtime.processing.smooth_backward_map; removes jagged text)",
            "align text lines (recommended where text matters; 30-100 ms on a laptop-class "
            "CPU, numpy/OpenCV only): render the rectified photo at 512 x 512 in gray, mark "
            "ink (darker than its 31 px median by 25), measure in 6 windows how the ink rows "
            "of 12 vertical bands shift between neighbouring bands, fit a quadratic slope "
            "across the width, and sample the map that much lower or higher per column; "
            "twice (doctrpp.runtime.line_alignment.align_text_lines, a port of which is the "
            "reference; skip it to reproduce the model's map)",
            "resize each output channel to the photo's width x height (bilinear)",
            "blur each channel with a 3x3 box filter (cv2.blur, border reflect-101)",
            "px = (x + 1) / 2 * (W - 1); py = (y + 1) / 2 * (H - 1)",
            "out = bilinear remap of the full-resolution photo at (px, py), zeros outside",
        ],
        "tolerances": {
            "remap_vs_reference_grid_sample": "<= 1 grey level (tested, OpenCV remap)",
            "onnx_fp32_vs_pytorch": "<= 1e-3 px on the 288 grid (tested; measured ~6e-5)",
            "tflite_fp32_vs_pytorch": "<= 1e-3 px on the 288 grid (tested; measured ~5e-5)",
        },
        "tested": "Python runtime on x86 CPUs only (onnxruntime, ai-edge-litert/XNNPACK)",
        "not_tested": "on-device Android/iOS runtimes and delegates",
    }


def _model_entry(path: Path) -> dict:
    from doctrpp.runtime.backends import ModelError, open_backend

    try:
        meta = open_backend(path, 1).metadata
    except ModelError as exc:
        raise CliError(str(exc)) from None
    return {
        "file": path.name,
        "format": path.suffix.lstrip("."),
        "precision": meta.get(contract.META_PRECISION, "unknown"),
        "bytes": path.stat().st_size,
        "sha256": sha256_of(path),
        "weights": meta.get(contract.META_CHECKPOINT_NOTE, ""),
    }


def run(args: argparse.Namespace) -> int:
    for model in args.models:
        if not model.is_file():
            raise CliError(f"{model}: no such model file")
        if model.suffix not in (".onnx", ".tflite"):
            raise CliError(f"{model}: expected a .onnx or .tflite file")
    if args.out.exists() and not args.out.is_dir():
        raise CliError(f"--out {args.out} exists and is not a folder")
    names = [m.name for m in args.models]
    if len(set(names)) != len(names):
        raise CliError("two models share a file name; rename one")
    entries = [_model_entry(m) for m in args.models]
    args.out.mkdir(parents=True, exist_ok=True)
    for model in args.models:
        target = args.out / model.name
        if target.resolve() != model.resolve():
            write_bytes_atomically(target, model.read_bytes())
    record = {"package_version": __version__, "models": entries, **describe_contract()}
    write_bytes_atomically(args.out / "doctrpp.json", json.dumps(record, indent=1).encode())
    docs = args.out / "docs"
    docs.mkdir(exist_ok=True)
    for name in ("android.md", "ios.md"):
        shutil.copyfile(DOCS / name, docs / name)
    print(f"wrote {args.out}: {', '.join(names)}, doctrpp.json, docs/android.md, docs/ios.md")
    return 0
