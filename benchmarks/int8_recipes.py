"""Compare int8 recipes on trained weights: TFLite (calibration set x what stays float) and
ONNX (onnxruntime presets and their variants x calibration set).

usage: python -m doctrpp.benchmarks.int8_recipes --checkpoint W.pt --photos DIR --out DIR
       [--calib-count 96] [--recipes generated:head+backbone real:head+backbone ...
        onnx/static-weights+per-tensor:mixed onnx/dynamic-linear ...]

TFLite recipes are `CALIBRATION:KEEP_FLOAT`; ONNX recipes are `onnx/PRESET[+VARIANT...]`
with `:CALIBRATION` for static presets (variants: quantize.presets.VARIANTS).

Calibration sets: `generated` (UDIR-style crops of the three kinds), `real` (crops of the
three kinds cut from the even-numbered photos of DIR), `mixed` (half each). Drift against
the PyTorch model is measured on held-out generated crops and on crops cut from the *other*
photos (odd-numbered: never calibrated on); latency at 1 and 2 threads, interleaved with
the ONNX fp32 export of the same weights. Writes DIR/int8_recipes.json and .md.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

from doctrpp import contract
from doctrpp.files import write_bytes_atomically
from doctrpp.runtime.imageio import image_files, read_image
from doctrpp.runtime.processing import model_input
from doctrpp.udir.photos import photo_crop_box
from doctrpp.udir.scene import KINDS

DEFAULT_RECIPES = (
    "generated:head+backbone",
    "real:head+backbone",
    "mixed:head+backbone",
    "mixed:head",
)


def photo_crop_inputs(photos: list[Path], count: int, seed: int) -> list[np.ndarray]:
    """`count` model inputs: crops of the three kinds in turn, cycling over `photos`."""
    inputs = []
    for i in range(count):
        photo = read_image(photos[i % len(photos)])[:, :, :3]
        kind = KINDS[i % 3]
        x0, y0, x1, y1 = photo_crop_box(np.random.default_rng([seed, i]), *photo.shape[:2], kind)
        inputs.append(model_input(photo[y0:y1, x0:x1], contract.INPUT_SIZE))
    return inputs


def calibration_set(name: str, photos: list[Path], count: int) -> list[np.ndarray]:
    from doctrpp.quantize.calibration import generated_inputs

    if name == "generated":
        return list(generated_inputs(count))
    if name == "real":
        return photo_crop_inputs(photos, count, seed=1)
    if name == "mixed":
        return list(generated_inputs(count // 2)) + photo_crop_inputs(photos, count // 2, 1)
    raise ValueError(f"unknown calibration set {name!r}")


def _onnx_recipe(
    recipe: str, fp32: Path, calib_photos: list[Path], count: int, index: int
) -> tuple[Path, int]:
    """Quantise the fp32 ONNX file with `onnx/PRESET[+VARIANT...][:CALIBRATION]`."""
    from doctrpp.quantize.presets import preset_by_name
    from doctrpp.quantize.quantize import quantise

    name, _, calib_name = recipe.removeprefix("onnx/").partition(":")
    preset = preset_by_name(name)
    calibration = None
    if preset.mode == "static":
        calib_name = calib_name or "mixed"
        print(f"{recipe}: calibrating on {count} {calib_name} inputs", flush=True)
        calibration = calibration_set(calib_name, calib_photos, count)
    path = fp32.with_name(f"int8_{index}.onnx")
    return path, quantise(fp32, path, preset, calibration).size_bytes


def main(argv: list[str] | None = None) -> int:
    from doctrpp.benchmarks.timing import interleaved_latency
    from doctrpp.export.checkpoint import load_model
    from doctrpp.export.onnx_export import export_onnx
    from doctrpp.export.parity import drift_px
    from doctrpp.export.tflite_export import export_tflite
    from doctrpp.quantize.calibration import HELD_OUT_SEED_OFFSET, generated_inputs

    parser = argparse.ArgumentParser(
        prog="python -m doctrpp.benchmarks.int8_recipes", description=__doc__
    )
    parser.add_argument("--checkpoint", type=Path, required=True)
    parser.add_argument("--photos", type=Path, required=True, help="folder of real photos")
    parser.add_argument("--out", type=Path, required=True, help="folder for the table")
    parser.add_argument("--calib-count", type=int, default=96)
    parser.add_argument("--recipes", nargs="+", default=list(DEFAULT_RECIPES))
    parser.add_argument("--runs", type=int, default=30, help="timed runs per model and threads")
    args = parser.parse_args(argv)

    photos = image_files(args.photos)
    calib_photos, eval_photos = photos[0::2], photos[1::2]
    model = load_model(args.checkpoint).eval()
    held_out = {
        "generated": list(generated_inputs(18, HELD_OUT_SEED_OFFSET)),
        "real": photo_crop_inputs(eval_photos[:: max(1, len(eval_photos) // 12)], 36, seed=2),
    }
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        fp32 = export_onnx(model, Path(tmp) / "fp32.onnx").path
        files = [fp32]
        for index, recipe in enumerate(args.recipes):
            if recipe.startswith("onnx/"):
                path, size = _onnx_recipe(recipe, fp32, calib_photos, args.calib_count, index)
            else:
                calib_name, keep_float = recipe.split(":")
                print(f"{recipe}: calibrating on {args.calib_count} {calib_name} inputs")
                calibration = calibration_set(calib_name, calib_photos, args.calib_count)
                path = Path(tmp) / f"int8_{index}.tflite"
                size = export_tflite(
                    model, path, "int8", calibration, keep_float=keep_float
                ).size_bytes
            row = {"recipe": recipe, "file": path.name, "mb": size / 1e6}
            for name, inputs in held_out.items():
                drift = drift_px(model, path, inputs)
                row[f"{name}_mean_px"], row[f"{name}_max_px"] = drift["mean"], drift["max"]
            print(json.dumps(row), flush=True)
            rows.append(row)
            files.append(path)
        latency = interleaved_latency(files, (1, 2), args.runs)
        for row, path in zip(rows, files[1:], strict=True):
            for threads in (1, 2):
                ratio = (
                    latency[(str(path), threads)].median_ms
                    / latency[(str(fp32), threads)].median_ms
                )
                row[f"vs_onnx_fp32_{threads}t"] = ratio
                row[f"ms_{threads}t"] = latency[(str(path), threads)].median_ms
    fp32_ms = {t: latency[(str(fp32), t)].median_ms for t in (1, 2)}
    table = {"checkpoint": str(args.checkpoint), "onnx_fp32_ms": fp32_ms, "rows": rows}
    args.out.mkdir(parents=True, exist_ok=True)
    write_bytes_atomically(args.out / "int8_recipes.json", json.dumps(table, indent=1).encode())
    lines = [
        "| recipe (calibration:float) | MB | generated mean / max px | real-photo mean / max px "
        "| 1 thread ms (x ONNX fp32) | 2 threads ms (x ONNX fp32) |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['recipe']} | {r['mb']:.2f} | {r['generated_mean_px']:.2f} / "
            f"{r['generated_max_px']:.2f} | {r['real_mean_px']:.2f} / {r['real_max_px']:.2f} | "
            f"{r['ms_1t']:.1f} ({r['vs_onnx_fp32_1t']:.2f}x) | {r['ms_2t']:.1f} "
            f"({r['vs_onnx_fp32_2t']:.2f}x) |"
        )
    lines.append(f"\nONNX fp32: {fp32_ms[1]:.1f} ms at 1 thread, {fp32_ms[2]:.1f} ms at 2 threads.")
    write_bytes_atomically(args.out / "int8_recipes.md", ("\n".join(lines) + "\n").encode())
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
