"""`doctrpp rectify`: photos (files or folders) -> rectified photos."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from doctrpp import contract
from doctrpp.errors import CliError
from doctrpp.files import save_npy_atomically
from doctrpp.progress import progress

from .backends import ModelError
from .imageio import IMAGE_SUFFIXES, ImageError, read_image, write_image


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "rectify",
        help="rectify document photos",
        description="Rectify photos. INPUT is an image file or a folder of images. OUT is a "
        "folder (created; writes <stem>_rectified.png) or, with exactly one input file, an "
        "image path. Inputs are never overwritten.",
    )
    p.add_argument("inputs", nargs="+", type=Path, metavar="INPUT")
    p.add_argument(
        "--model",
        type=Path,
        help="model file (.onnx); default: the embedded weights, exported once to a cache "
        "folder (needs the [export] extra)",
    )
    p.add_argument("-o", "--out", type=Path, required=True, help="output folder or image path")
    p.add_argument(
        "--save-map",
        action="store_true",
        help="also write <stem>_map.npy: float32 HxWx2 sampling positions in photo pixels (x, y)",
    )
    p.add_argument("--threads", type=int, default=None, help="inference threads (default: all)")
    p.set_defaults(handler=run)


def collect_inputs(inputs: list[Path]) -> list[Path]:
    """Expand folders (their image files, sorted, not recursive); files are kept as given."""
    files: list[Path] = []
    for item in inputs:
        if item.is_dir():
            found = sorted(
                p for p in item.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
            )
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
        from doctrpp.export.cli import default_onnx

        args.model = default_onnx()
    try:
        rectifier = Rectifier(args.model, threads=args.threads)
    except ModelError as exc:
        raise CliError(str(exc)) from None
    note = rectifier.metadata.get(contract.META_CHECKPOINT_NOTE, "")
    if "RANDOM" in note.upper():
        print(f"WARNING: {args.model} holds {note}", file=sys.stderr)

    failures: list[str] = []
    pairs = list(zip(files, outputs, strict=True))
    for source, target in progress(pairs, len(pairs), "rectify", enabled=len(pairs) > 1):
        try:
            image = read_image(source)
            result = rectifier.run(image)
            write_image(target, result.rectified)
            if args.save_map:
                map_path = target.with_name(target.stem.removesuffix("_rectified") + "_map.npy")
                save_npy_atomically(map_path, result.photo_map().astype("float32"))
        except (ImageError, ValueError) as exc:
            failures.append(str(exc) if str(source) in str(exc) else f"{source}: {exc}")
            continue
        if len(pairs) == 1:
            t = result.timings
            print(
                f"wrote {target} ({image.shape[1]}x{image.shape[0]}; preprocess "
                f"{t['preprocess'] * 1e3:.0f} ms, inference {t['inference'] * 1e3:.0f} ms, "
                f"postprocess {t['postprocess'] * 1e3:.0f} ms)"
            )
    if len(pairs) > 1:
        print(f"rectified {len(pairs) - len(failures)} of {len(pairs)} images into {args.out}")
    if failures:
        print(f"{len(failures)} failed:", file=sys.stderr)
        for line in failures:
            print(f"  {line}", file=sys.stderr)
        return 1
    return 0
