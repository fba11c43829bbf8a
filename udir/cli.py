"""`doctrpp crops` (UDIR-style samples with ground truth) and `doctrpp sheet` (contact sheet)."""

from __future__ import annotations

import argparse
import json
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import cv2
import numpy as np

from doctrpp.errors import CliError
from doctrpp.files import save_npy_atomically, write_bytes_atomically
from doctrpp.progress import progress
from doctrpp.runtime.imageio import ImageError, image_files, read_image, write_image

from .scene import KINDS


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "crops",
        help="generate UDIR-style crops with exact ground truth",
        description="Write N samples: NNNNN.png (the crop), NNNNN_flat.png (flat target), "
        "NNNNN_map.npy (float32 288x288x2 normalised backward map, x then y, "
        "align_corners=True) and NNNNN.json. Sample i uses seed S+i; 'mixed' gives equal "
        "thirds of the kinds. With --from-photos, cut crops from your photos (no ground truth).",
    )
    p.add_argument("--out", type=Path, required=True, help="output folder (created)")
    p.add_argument("--n", type=int, required=True, help="number of samples")
    p.add_argument("--seed", type=int, default=0, help="sample i uses seed S+i (default 0)")
    p.add_argument(
        "--kind",
        choices=[*KINDS, "mixed"],
        default="mixed",
        help="crop kind (default mixed: equal thirds)",
    )
    p.add_argument("--size", type=int, default=288, help="crop and flat-target size in pixels")
    p.add_argument("--from-photos", type=Path, metavar="FOLDER", help="cut crops from these photos")
    p.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="generator processes (default: all cores)",
    )
    p.set_defaults(handler=run_crops)

    s = commands.add_parser(
        "sheet",
        help="contact sheet of generated crops",
        description="Write a PNG with, per sample: the crop, its flat target and the crop "
        "rectified with its ground-truth map (black = map points outside the crop).",
    )
    s.add_argument("folder", type=Path, help="a folder written by `doctrpp crops`")
    s.add_argument("-o", "--out", type=Path, required=True, help="output PNG")
    s.add_argument("--max", type=int, default=24, help="samples on the sheet")
    s.add_argument("--columns", type=int, default=3, help="samples per row")
    s.set_defaults(handler=run_sheet)


def _write_sample(job: tuple[Path, int, int, str, int]) -> str:
    from .sample import generate, kind_for_index

    out, index, seed, kind, size = job
    sample = generate(seed + index, kind_for_index(index, kind), size=size)
    stem = out / f"{index:05d}"
    write_image(stem.with_suffix(".png"), sample.image)
    write_image(stem.with_name(stem.name + "_flat.png"), sample.flat)
    save_npy_atomically(stem.with_name(stem.name + "_map.npy"), sample.backward_map)
    record = {"kind": sample.kind, "seed": sample.seed, "params": sample.params}
    write_bytes_atomically(stem.with_suffix(".json"), json.dumps(record, indent=1).encode())
    return sample.kind


def _photo_jobs(args) -> list[tuple[Path, int, Path, str, int]]:
    folder = args.from_photos
    if not folder.is_dir():
        raise CliError(f"--from-photos {folder}: no such folder")
    photos = image_files(folder)
    if not photos:
        raise CliError(f"--from-photos {folder}: no images")
    from .sample import kind_for_index

    return [
        (args.out, i, photos[i % len(photos)], kind_for_index(i, args.kind), args.seed)
        for i in range(args.n)
    ]


def _write_photo_crop(job: tuple[Path, int, Path, str, int]) -> str:
    from .photos import photo_crop_box

    out, index, photo_path, kind, seed = job
    photo = read_image(photo_path)
    box = photo_crop_box(np.random.default_rng([seed, index]), *photo.shape[:2], kind)
    x0, y0, x1, y1 = box
    stem = out / f"{index:05d}"
    write_image(stem.with_suffix(".png"), photo[y0:y1, x0:x1])
    record = {"kind": kind, "source": str(photo_path), "box": list(box)}
    write_bytes_atomically(stem.with_suffix(".json"), json.dumps(record).encode())
    return kind


def run_crops(args: argparse.Namespace) -> int:
    if args.n < 1:
        raise CliError("--n must be at least 1")
    if args.size < 16:
        raise CliError("--size must be at least 16")
    if args.out.exists() and not args.out.is_dir():
        raise CliError(f"--out {args.out} exists and is not a folder")
    if args.from_photos:
        jobs, worker = _photo_jobs(args), _write_photo_crop
    else:
        jobs = [(args.out, i, args.seed, args.kind, args.size) for i in range(args.n)]
        worker = _write_sample
    args.out.mkdir(parents=True, exist_ok=True)
    counts: dict[str, int] = {}
    failures: list[str] = []
    with ProcessPoolExecutor(max_workers=max(1, args.workers)) as pool:
        results = pool.map(_safe(worker), jobs, chunksize=4)
        for kind in progress(results, len(jobs), "crops"):
            if kind.startswith("error:"):
                failures.append(kind[6:])
            else:
                counts[kind] = counts.get(kind, 0) + 1
    summary = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
    print(f"wrote {sum(counts.values())} samples to {args.out} ({summary})")
    for line in failures:
        print(f"failed: {line}")
    return 1 if failures else 0


class _safe:
    """Picklable wrapper turning a bad input into a reported failure, not a crash."""

    def __init__(self, worker) -> None:
        self.worker = worker

    def __call__(self, job) -> str:
        try:
            return self.worker(job)
        except (ImageError, ValueError) as exc:
            return f"error:{exc}"


def _label(image: np.ndarray, text: str) -> np.ndarray:
    image = image.copy()
    cv2.putText(image, text, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 255), 1, cv2.LINE_AA)
    return image


def run_sheet(args: argparse.Namespace) -> int:
    from doctrpp.runtime.processing import rectify_with_map

    maps = sorted(args.folder.glob("*_map.npy"))[: args.max]
    if not maps:
        raise CliError(f"{args.folder}: no samples (*_map.npy) found")
    tiles = []
    for map_path in maps:
        stem = str(map_path)[: -len("_map.npy")]
        crop = cv2.resize(cv2.imread(stem + ".png"), (288, 288))
        flat = cv2.resize(cv2.imread(stem + "_flat.png"), (288, 288))
        kind = json.loads(Path(stem + ".json").read_text())["kind"]
        rectified = rectify_with_map(crop, np.load(map_path))
        tiles.append(
            np.concatenate(
                [
                    _label(crop, f"{Path(stem).name} {kind}"),
                    _label(flat, "flat target"),
                    _label(rectified, "crop rectified by GT"),
                ],
                1,
            )
        )
    columns = max(1, args.columns)
    blank = np.zeros_like(tiles[0])
    while len(tiles) % columns:
        tiles.append(blank)
    rows = [np.concatenate(tiles[i : i + columns], 1) for i in range(0, len(tiles), columns)]
    write_image(args.out, np.concatenate(rows, 0))
    print(f"wrote {args.out} ({len(maps)} samples)")
    return 0
