"""`doctrpp rectify`: photos (files or folders) -> rectified photos."""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path

from doctrpp import contract
from doctrpp.errors import CliError
from doctrpp.progress import progress

from .backends import ModelError
from .imageio import IMAGE_SUFFIXES, ImageError, has_alpha, image_files, read_image, write_image
from .processing import MAP_SMOOTHING_SIGMA


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "rectify",
        help="rectify document photos",
        description="Rectify photos. INPUT is an image file or a folder of images. OUT is a "
        "folder (created; writes <stem>_rectified.png) or, with exactly one input file, an "
        "image path. Inputs are never overwritten.",
    )
    p.add_argument("inputs", nargs="+", type=Path, metavar="INPUT", help="image files or folders")
    p.add_argument(
        "--model",
        type=Path,
        help="model file (.onnx, or .tflite with the [tflite] extra); default: the shipped "
        "default model (doctrpp_fp32.onnx inside the package)",
    )
    p.add_argument("-o", "--out", type=Path, required=True, help="output folder or image path")
    p.add_argument(
        "--save-map",
        action="store_true",
        help="also write <stem>_map.npy: float32 HxWx2 sampling positions in photo pixels "
        "(x, y); 8 bytes per pixel (864 MB for 108 MP), written strip by strip",
    )
    p.add_argument(
        "--threads",
        type=positive_int,
        default=None,
        help="inference threads per image (default: onnxruntime's choice, all cores)",
    )
    p.add_argument(
        "--map-smoothing",
        type=non_negative_float,
        default=MAP_SMOOTHING_SIGMA,
        metavar="SIGMA",
        help="Gaussian sigma (model-grid pixels) for the model's map before the remap; removes "
        f"jagged text (default {MAP_SMOOTHING_SIGMA:g}; 0 = the reference post-processing)",
    )
    p.add_argument(
        "--no-flip-average",
        dest="flip_average",
        action="store_false",
        help="run the model once per photo instead of also on its mirror image and "
        "averaging the two maps (half the inference time; the map is less accurate)",
    )
    p.add_argument(
        "--no-line-alignment",
        dest="line_alignment",
        action="store_false",
        help="keep the model's map as it is instead of shifting its rows so that text "
        "lines come out level (30-100 ms per photo)",
    )
    p.add_argument(
        "--jobs",
        type=positive_int,
        default=1,
        help="images in flight at once: decode, inference, remap and encode overlap "
        "(default 1; memory grows with it)",
    )
    p.set_defaults(handler=run)


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def non_negative_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return value


def collect_inputs(inputs: list[Path]) -> list[Path]:
    """Expand folders (their image files, sorted, not recursive); files are kept as given."""
    files: list[Path] = []
    for item in inputs:
        if item.is_dir():
            found = image_files(item)
            if not found:
                raise CliError(f"{item}: folder holds no images")
            files.extend(found)
        elif item.exists():
            files.append(item)
        else:
            raise CliError(f"{item}: no such file or folder")
    return files


def plan_outputs(files: list[Path], out: Path, single_target: bool) -> list[Path]:
    """Output image path per input; distinct names even when stems repeat."""
    if single_target:
        return [out]
    outputs, used = [], set()
    for f in files:
        name = f"{f.stem}_rectified.png"
        if name in used:  # a.jpg and a.png in one run
            name = f"{f.stem}_{f.suffix.lstrip('.').lower()}_rectified.png"
        index = 2
        while name in used:
            name = f"{f.stem}_{index}_rectified.png"
            index += 1
        used.add(name)
        outputs.append(out / name)
    return outputs


def run(args: argparse.Namespace) -> int:
    from .rectifier import Rectifier

    files = collect_inputs(args.inputs)
    single_target = args.out.suffix.lower() in IMAGE_SUFFIXES and not args.out.is_dir()
    if single_target and (len(files) != 1 or args.inputs[0].is_dir()):
        raise CliError("an image path as --out needs exactly one input file; give a folder")
    if not single_target and args.out.exists() and not args.out.is_dir():
        raise CliError(f"--out {args.out} exists and is not a folder")
    outputs = plan_outputs(files, args.out, single_target)
    resolved_inputs = {f.resolve() for f in files}
    for target in outputs:
        if target.resolve() in resolved_inputs:
            raise CliError(f"output {target} would overwrite an input")

    if args.model is None:
        from .models import NoShippedModel, shipped_model

        try:
            args.model = shipped_model()
        except NoShippedModel as exc:
            raise CliError(str(exc)) from None
    try:
        rectifier = Rectifier(
            args.model,
            threads=args.threads,
            map_smoothing=args.map_smoothing,
            flip_average=args.flip_average,
            line_alignment=args.line_alignment,
        )
    except ModelError as exc:
        raise CliError(str(exc)) from None
    note = rectifier.metadata.get(contract.META_CHECKPOINT_NOTE, "")
    if "RANDOM" in note.upper():
        print(f"WARNING: {args.model} holds {note}", file=sys.stderr)

    pairs = list(zip(files, outputs, strict=True))
    job = partial(rectify_file, rectifier, save_map=args.save_map)
    failures: list[str] = []
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:  # OpenCV and onnxruntime
        results = pool.map(job, pairs)  # release the GIL, so threads overlap for real
        for (source, _target), (message, line, notes) in progress(
            zip(pairs, results, strict=True), len(pairs), "rectify", enabled=len(pairs) > 1
        ):
            if message:
                failures.append(message)
            elif len(pairs) == 1:
                print(line)
            for note in notes:
                print(f"note: {source}: {note}", file=sys.stderr)
    if len(pairs) > 1:
        print(f"rectified {len(pairs) - len(failures)} of {len(pairs)} images into {args.out}")
    if failures:
        print(f"{len(failures)} failed:", file=sys.stderr)
        for line in failures:
            print(f"  {line}", file=sys.stderr)
        return 1
    return 0


NO_ALPHA_SUFFIXES = frozenset({".jpg", ".jpeg", ".bmp", ".jp2", ".pgm", ".ppm", ".pbm"})
BIG_MAP_BYTES = 256 * 2**20


def rectify_file(rectifier, pair: tuple[Path, Path], save_map: bool) -> tuple[str, str, list[str]]:
    """Read, rectify, write one photo: (error message or "", summary line, notes)."""
    source, target = pair
    notes: list[str] = []
    try:
        image = read_image(source)
        result = rectifier.run(image)
        rectified = result.rectified
        if has_alpha(rectified) and target.suffix.lower() in NO_ALPHA_SUFFIXES:
            notes.append(f"alpha dropped: {target.suffix} holds none")
            rectified = rectified[:, :, :3]
        write_image(target, rectified)
        if save_map:
            map_path = target.with_name(target.stem.removesuffix("_rectified") + "_map.npy")
            size = save_photo_map(map_path, result)
            if size > BIG_MAP_BYTES:
                notes.append(f"map {map_path} is {size / 2**20:.0f} MB")
    except (ImageError, ValueError, OSError) as exc:
        return (str(exc) if str(source) in str(exc) else f"{source}: {exc}"), "", notes
    t = result.timings
    line = (
        f"wrote {target} ({image.shape[1]}x{image.shape[0]}; preprocess "
        f"{t['preprocess'] * 1e3:.0f} ms, inference {t['inference'] * 1e3:.0f} ms, "
        f"map {t['map'] * 1e3:.0f} ms, remap {t['postprocess'] * 1e3:.0f} ms)"
    )
    return "", line, notes


def save_photo_map(path: Path, result) -> int:
    """The full-resolution map as .npy, written strip by strip to a temp file and renamed
    into place: atomic, and never all in memory (8 bytes per pixel on disk)."""
    import numpy as np

    from .processing import photo_map_strips

    height, width = result.rectified.shape[:2]
    temporary = path.with_name(f".{path.name}.tmp")
    header = {"descr": "<f4", "fortran_order": False, "shape": (height, width, 2)}
    try:
        with open(temporary, "wb") as f:
            np.lib.format.write_array_header_1_0(f, header)
            for _, strip in photo_map_strips(result.backward_map, height, width):
                f.write(np.ascontiguousarray(strip, dtype="<f4").tobytes())
        temporary.replace(path)
    finally:
        temporary.unlink(missing_ok=True)
    return path.stat().st_size
