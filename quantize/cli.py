"""`doctrpp quantize`: fp32 ONNX -> int8 ONNX, calibrated on UDIR-style crops."""

from __future__ import annotations

import argparse
from pathlib import Path

from doctrpp.errors import CliError, require

from .presets import DEFAULT_PRESET, PRESETS, VARIANTS


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "quantize",
        help="quantise an fp32 ONNX model to int8",
        description="Quantise with onnxruntime's tools. Static presets calibrate on generated "
        "UDIR-style crops (equal thirds of complete/partial/no boundaries) or on your own "
        "images (--calib FOLDER, e.g. from `doctrpp crops --from-photos`). Prints the map "
        "drift against the fp32 model on held-out generated crops.",
    )
    p.add_argument("--model", type=Path, required=True, help="fp32 .onnx from `doctrpp export`")
    p.add_argument("--out", type=Path, required=True, help="output .onnx path")
    source = p.add_mutually_exclusive_group()
    source.add_argument("--calib", type=Path, metavar="FOLDER", help="calibration images")
    source.add_argument(
        "--calib-synthetic",
        type=int,
        default=300,
        metavar="N",
        help="generated calibration crops (default 300)",
    )
    p.add_argument(
        "--preset",
        default=DEFAULT_PRESET,
        help=f"recipe (default {DEFAULT_PRESET}): one of {', '.join(sorted(PRESETS))}, "
        f"optionally with variants appended, e.g. {DEFAULT_PRESET}+per-tensor+percentile "
        f"(variants: {', '.join(VARIANTS)})",
    )
    p.add_argument(
        "--sensitivity",
        type=Path,
        metavar="JSON",
        help="instead of one model, rank node groups by the drift each causes alone",
    )
    p.add_argument(
        "--check",
        type=int,
        default=12,
        metavar="N",
        help="held-out crops for the drift check (0 = skip)",
    )
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    require("onnx", extra="export")
    from doctrpp.benchmarks.accuracy import drift, predict
    from doctrpp.export.tolerances import INT8_DRIFT_TARGET_PX
    from doctrpp.runtime.backends import ModelError

    from .calibration import HELD_OUT_SEED_OFFSET, generated_inputs, load_calibration
    from .presets import preset_by_name
    from .quantize import quantise

    if not args.model.is_file():
        raise CliError(f"--model {args.model}: no such file")
    if args.out.suffix != ".onnx":
        raise CliError("--out must end in .onnx")
    if args.out.resolve() == args.model.resolve():
        raise CliError("--out would overwrite the input model")
    try:
        preset = preset_by_name(args.preset)
    except ValueError as exc:
        raise CliError(f"--preset: {exc}") from None
    calibration = None
    if preset.mode == "static":
        try:
            calibration = load_calibration(args.calib, args.calib_synthetic)
        except (OSError, ValueError) as exc:
            raise CliError(str(exc)) from None
        print(f"calibrating on {len(calibration)} inputs ({args.calib or 'generated crops'})")
    if args.sensitivity:
        return _sensitivity(args, preset, calibration)
    try:
        result = quantise(args.model, args.out, preset, calibration)
    except Exception as exc:  # onnxruntime/onnx raise many types for bad models
        raise CliError(f"quantisation failed: {str(exc).splitlines()[0]}") from None
    print(
        f"wrote {result.path}: {result.size_bytes / 1e6:.1f} MB, preset {preset.name}, "
        f"{result.quantised_nodes}/{result.expected_nodes} nodes int8, "
        f"took {result.seconds:.0f} s"
    )
    if args.check:
        held_out = list(generated_inputs(args.check, seed_offset=HELD_OUT_SEED_OFFSET))
        try:
            summary = drift(predict(args.model, held_out), predict(args.out, held_out))
        except ModelError as exc:
            raise CliError(str(exc)) from None
        target = INT8_DRIFT_TARGET_PX
        ok = summary.mean_px <= target["mean"] and summary.max_px <= target["max"]
        print(
            f"drift vs fp32 on {args.check} generated crops: mean {summary.mean_px:.3f} px, "
            f"max {summary.max_px:.3f} px (target mean <= {target['mean']:g}, max <= "
            f"{target['max']:g} px): {'meets the target' if ok else 'MISSES the target'}"
        )
    return 0


def _sensitivity(args: argparse.Namespace, preset, calibration) -> int:
    import json

    from doctrpp.files import write_bytes_atomically

    from .calibration import HELD_OUT_SEED_OFFSET, generated_inputs
    from .sensitivity import rank_groups

    held_out = list(generated_inputs(max(args.check, 3), seed_offset=HELD_OUT_SEED_OFFSET))
    ranking = rank_groups(
        args.model,
        preset,
        calibration,
        held_out,
        progress=lambda i, n, g: print(f"[{i}/{n}] {g}", flush=True),
    )
    write_bytes_atomically(args.sensitivity, json.dumps(ranking, indent=1).encode())
    print(f"{'group':48s} nodes  mean px  max px")
    for row in ranking:
        print(
            f"{row['group']:48s} {row['nodes']:5d}  {row['drift_mean_px']:7.3f}  "
            f"{row['drift_max_px']:6.3f}"
        )
    print(f"wrote {args.sensitivity}")
    return 0
