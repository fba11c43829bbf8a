"""`doctrpp export`: checkpoint -> model file (ONNX), checked against PyTorch."""

from __future__ import annotations

import argparse
from pathlib import Path

from doctrpp.errors import CliError, require

PARITY_TOLERANCE_PX = 1e-3


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "export",
        help="export a checkpoint to ONNX",
        description="Export a DocTr++ checkpoint to DIR/doctrpp_fp32.onnx (opset 17, "
        "simplified, metadata inside) and check it against PyTorch.",
    )
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "--checkpoint", type=Path, help="state dict saved by the authors' code or ours"
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
    p.add_argument("--no-check", action="store_true", help="skip the ONNX vs PyTorch parity check")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    require("torch", "onnx", "onnxslim", extra="export")
    import numpy as np
    import torch

    from .checkpoint import CheckpointError, load_model, sha256_of
    from .config import config_by_name
    from .model import DocTrPP
    from .onnx_export import export_onnx, onnx_parity_px

    try:
        config = config_by_name(args.config) if args.config else None
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if args.out.exists() and not args.out.is_dir():
        raise CliError(f"--out {args.out} exists and is not a folder")

    if args.checkpoint is not None:
        try:
            model = load_model(args.checkpoint, config)
        except CheckpointError as exc:
            raise CliError(str(exc)) from None
        sha256, note = sha256_of(args.checkpoint), f"checkpoint {args.checkpoint.name}"
        print(f"loaded {args.checkpoint} (sha256 {sha256[:12]}...)")
    else:
        torch.manual_seed(args.random_weights)
        model = DocTrPP(config) if config else DocTrPP()
        model.eval()
        sha256 = ""
        note = f"RANDOM WEIGHTS (seed {args.random_weights}): not a trained model"
        print(f"WARNING: exporting {note}; its output is not a meaningful rectification.")

    out_path = args.out / "doctrpp_fp32.onnx"
    result = export_onnx(model, out_path, checkpoint_sha256=sha256, checkpoint_note=note)
    print(
        f"wrote {result.path}: {result.size_bytes / 1e6:.1f} MB, {result.node_count} nodes, "
        f"export took {result.seconds:.1f} s"
    )
    if not args.no_check:
        images = np.random.default_rng(0).random((1, 3, 288, 288), dtype=np.float32)
        worst = onnx_parity_px(model, result.path, images)
        status = "ok" if worst <= PARITY_TOLERANCE_PX else "FAILED"
        print(
            f"parity ONNX vs PyTorch: largest difference {worst:.2e} px "
            f"(tolerance {PARITY_TOLERANCE_PX:g} px) {status}"
        )
        if worst > PARITY_TOLERANCE_PX:
            return 1
    return 0
