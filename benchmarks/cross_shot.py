"""Cross-shot agreement: a real-photo score that reads like issue #10's held-out check.

docunet_dev holds two photos of each document (`<document>_1.jpg`, `<document>_2.jpg`),
curled, folded and framed differently, and no flat scan. A perfect rectifier turns both
into the same flat page, so its two outputs agree: their unmasked MS-SSIM (gray, at
598,400 px, the held-out check's measure) rises toward 1 and the local distortion between
them (mean dense-flow magnitude, px) falls toward 0. Both shots' errors count, so the
numbers sit below a comparison with the flat page; the ranking is what they are for.

What it cannot see: an error both shots share (the same wrong aspect, the same margin cut
away, blur) counts as agreement, and the pairs are full pages only (a partial crop of one
shot has no known counterpart in the other).

Torch-free: `doctrpp bench` scores model files with it; `python -m
doctrpp.training.cross_shot` adds weights files and the trainer's in-loop check.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from doctrpp.benchmarks.metrics import local_distortion, ms_ssim, paired_difference
from doctrpp.files import write_bytes_atomically
from doctrpp.progress import progress
from doctrpp.runtime.imageio import image_files, read_image

Rectify = Callable[[np.ndarray], np.ndarray]
MEASURES = ("ms_ssim", "local_distortion")
UNTOUCHED = "untouched photos"  # the entry of the photos as they are


def shot_pairs(folder: Path) -> list[tuple[Path, Path]]:
    """Each document's first and second shot (`<document>_1.*`, `<document>_2.*`), in
    the folder's sorted order; documents with one shot are left out."""
    shots: dict[str, dict[str, Path]] = {}
    for path in image_files(Path(folder)):
        document, _, shot = path.stem.rpartition("_")
        if document and shot in ("1", "2"):
            shots.setdefault(document, {})[shot] = path
    return [(s["1"], s["2"]) for s in shots.values() if len(s) == 2]


def agreement(first: np.ndarray, second: np.ndarray) -> dict[str, float]:
    """MS-SSIM and local distortion between two rectified shots, each the mean of both
    directions (the measures resize one image to the other's aspect)."""
    return {
        "ms_ssim": (ms_ssim(first, second) + ms_ssim(second, first)) / 2,
        "local_distortion": (local_distortion(first, second) + local_distortion(second, first)) / 2,
    }


def pair_rows(
    rectify: Rectify, pairs: Sequence[tuple[Path, Path]], label: str = "pairs", bar: bool = True
) -> list[dict]:
    """`agreement` of each pair's two shots after `rectify`, a row per document."""
    rows = []
    for first, second in progress(pairs, len(pairs), label, enabled=bar):
        scores = agreement(rectify(read_image(first)), rectify(read_image(second)))
        rows.append({"document": first.stem.rpartition("_")[0], **scores})
    return rows


def summary(rows: list[dict]) -> dict[str, float]:
    return {f"cross_shot_{m}": round(float(np.mean([r[m] for r in rows])), 4) for m in MEASURES}


def paired(reference: list[dict], candidate: list[dict]) -> dict[str, list[float]]:
    """Per-document difference candidate - reference: [mean, standard error]."""
    result = {}
    for measure in MEASURES:
        kinds = ["complete"] * len(reference)
        mean, error = paired_difference(
            kinds, [r[measure] for r in reference], [r[measure] for r in candidate]
        )["all"]
        result[f"paired_{measure}"] = [round(mean, 5), round(error, 5)]
    return result


def write_rows(path: Path, names: list[str], rows: list[list[dict]]) -> None:
    lines = [
        json.dumps({"entry": name, **row})
        for name, entry_rows in zip(names, rows, strict=True)
        for row in entry_rows
    ]
    write_bytes_atomically(path, ("\n".join(lines) + "\n").encode())


def report_entries(
    entries: Sequence[tuple[str, Rectify]],
    pairs: Sequence[tuple[Path, Path]],
    reference: str | None = None,
    status: Callable[[str], None] | None = None,
) -> list[dict]:
    """`doctrpp bench`'s section: a record per entry (name, means, and with `reference`
    naming one of the entries, each other entry's per-document difference from it)."""
    rows: dict[str, list[dict]] = {}
    for name, rectify in entries:
        if status:
            status(f"cross-shot agreement: {name} ({len(pairs)} documents)")
        rows[name] = pair_rows(rectify, pairs, f"  {name}")
    records = []
    for name, entry_rows in rows.items():
        record = {"name": name, "pairs": len(entry_rows), **summary(entry_rows)}
        if reference in rows and name != reference:
            record |= {"paired_against": reference, **paired(rows[reference], entry_rows)}
        records.append(record)
    return records
