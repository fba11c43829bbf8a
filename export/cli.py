"""`doctrpp export`: checkpoint -> model file (ONNX), checked against PyTorch."""

from __future__ import annotations

import argparse
from pathlib import Path

from doctrpp.errors import CliError, require

from .tflite_export import DEFAULT_KEEP_FLOAT, KEEP_FLOAT_CHOICES, PRECISIONS
from .tolerances import PARITY_TOLERANCE_PX, verdict

TFLITE_CHECK_CROPS = 6


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "export",
        help="export a checkpoint to ONNX",
        description="Export a DocTr++ checkpoint (default: the embedded trained weights) to "
        "DIR/doctrpp_fp32.onnx (opset 17, simplified, metadata inside) and check it against "
        "PyTorch.",
    )
    source = p.add_mutually_exclusive_group()
    source.add_argument(
        "--checkpoint",
        type=Path,
        help="state dict saved by the authors' code or ours (default: the embedded weights)",
    )
    source.add_argument(
        "--random-weights",
        type=int,
        metavar="SEED",
        help="export an untrained network with random weights (for smoke tests only)",
    )
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument(
        "--config", help="model config preset (default: from the checkpoint, else reference)"
    )
    p.add_argument(
        "--format",
        choices=["onnx", "tflite"],
        default="onnx",
        help="onnx (default; needs [export]) or tflite (needs [tflite-export])",
    )
    p.add_argument(
        "--precision",
        choices=PRECISIONS,
        default="fp32",
        help="tflite only (ONNX int8: `doctrpp quantize`)",
    )
    p.add_argument(
        "--keep-float",
        choices=KEEP_FLOAT_CHOICES,
        default=DEFAULT_KEEP_FLOAT,
        help="TFLite int8: modules left in float (default head+backbone+attention: on the "
        "trained mid weights a quarter of head+backbone's drift, and faster)",
    )
    calib = p.add_mutually_exclusive_group()
    calib.add_argument("--calib", type=Path, metavar="FOLDER", help="int8 calibration images")
    calib.add_argument(
        "--calib-synthetic", type=int, default=100, metavar="N", help="generated crops (100)"
    )
    p.add_argument("--no-check", action="store_true", help="skip the parity check vs PyTorch")
    p.add_argument("--verbose", action="store_true", help="show the TFLite converter's own output")
    p.set_defaults(handler=run)


def load_source(checkpoint: Path | None, random_seed: int | None, config_name: str | None):
    """(model, checkpoint sha256, note) from a checkpoint, random weights or the default."""
    import torch

    from doctrpp.files import sha256_of

    from .checkpoint import CheckpointError, load_model
    from .config import config_by_name
    from .default_weights import default_checkpoint
    from .model import DocTrPP

    try:
        config = config_by_name(config_name) if config_name else None
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if random_seed is not None:
        torch.manual_seed(random_seed)
        model = DocTrPP(config) if config else DocTrPP()
        note = f"RANDOM WEIGHTS (seed {random_seed}): not a trained model"
        print(f"WARNING: exporting {note}; its output is not a meaningful rectification.")
        return model.eval(), "", note
    if checkpoint is None:
        checkpoint = default_checkpoint()
        if checkpoint is None:
            raise CliError(
                "this build ships no trained default weights; pass --checkpoint CKPT "
                "(or --random-weights SEED for a smoke test)"
            )
        print(f"using the embedded default weights {checkpoint.name}")
    try:
        model = load_model(checkpoint, config)
    except CheckpointError as exc:
        raise CliError(str(exc)) from None
    sha256 = sha256_of(checkpoint)
    print(f"loaded {checkpoint} (sha256 {sha256[:12]}...)")
    return model, sha256, f"checkpoint {checkpoint.name}"


def export_checked(model, out_dir: Path, sha256: str, note: str, check: bool = True) -> Path:
    """Export to out_dir/doctrpp_fp32.onnx, print size and timing, and check parity."""
    import numpy as np

    from .onnx_export import export_onnx
    from .parity import parity_px

    result = export_onnx(
        model, out_dir / "doctrpp_fp32.onnx", checkpoint_sha256=sha256, checkpoint_note=note
    )
    print(
        f"wrote {result.path}: {result.size_bytes / 1e6:.1f} MB, {result.node_count} nodes, "
        f"export took {result.seconds:.1f} s"
    )
    if check:
        images = np.random.default_rng(0).random((1, 3, 288, 288), dtype=np.float32)
        worst = parity_px(model, result.path, images)
        ok = worst <= PARITY_TOLERANCE_PX
        print(
            f"parity ONNX vs PyTorch: largest difference {worst:.2e} px "
            f"(tolerance {PARITY_TOLERANCE_PX:g} px) {'ok' if ok else 'FAILED'}"
        )
        if not ok:
            raise CliError(f"exported model differs from PyTorch by {worst:.2e} px")
    return result.path


def export_tflite_checked(model, args, sha256: str, note: str) -> Path:
    """Export .tflite at args.precision and report its difference to PyTorch."""
    import numpy as np

    from .parity import drift_px
    from .tflite_export import export_tflite

    calibration = None
    if args.precision == "int8":
        from doctrpp.quantize.calibration import load_calibration

        try:
            calibration = load_calibration(args.calib, args.calib_synthetic)
        except (OSError, ValueError) as exc:
            raise CliError(str(exc)) from None
    out = args.out / f"doctrpp_{args.precision}.tflite"
    print(f"converting to {args.precision} TFLite (takes minutes; --verbose shows the converter)")
    result = export_tflite(
        model,
        out,
        args.precision,
        calibration,
        sha256,
        note,
        keep_float=args.keep_float,
        verbose=args.verbose,
    )
    print(
        f"wrote {result.path}: {result.size_bytes / 1e6:.1f} MB, export took {result.seconds:.1f} s"
    )
    if not args.no_check:
        from doctrpp.quantize.calibration import HELD_OUT_SEED_OFFSET, generated_inputs

        inputs = list(generated_inputs(TFLITE_CHECK_CROPS, HELD_OUT_SEED_OFFSET))
        drift = drift_px(model, out, inputs)
        ok, text = verdict(drift, args.precision)
        ok = ok and bool(np.isfinite(drift["max"]))
        print(f"{args.precision} TFLite vs PyTorch on {len(inputs)} held-out crops: {text}")
        if not ok and args.precision != "int8":
            raise CliError(f"exported model differs from PyTorch by {drift['max']:.2e} px")
    return out


def run(args: argparse.Namespace) -> int:
    require("torch", "onnx", "onnxslim", extra="export")
    if args.out.exists() and not args.out.is_dir():
        raise CliError(f"--out {args.out} exists and is not a folder")
    if args.format == "onnx" and args.precision != "fp32":
        raise CliError("ONNX export is fp32; make int8 with `doctrpp quantize`")
    if args.format == "tflite":
        require("litert_torch", "ai_edge_litert", extra="tflite-export")
    model, sha256, note = load_source(args.checkpoint, args.random_weights, args.config)
    if args.format == "tflite":
        export_tflite_checked(model, args, sha256, note)
    else:
        export_checked(model, args.out, sha256, note, check=not args.no_check)
    return 0
