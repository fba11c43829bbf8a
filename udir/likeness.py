"""How alike generated crops and real photos' crops look: a few image measures per kind.

Sessions tune `ranges.py` by comparing measures like these between the generator's crops
and crops cut from real photos (`photos.crops_of_each_kind`, as the training loop's real-
photo check cuts them). Measured on the 288 px crop, each a median over crops unless said:

- line pitch: distance between text lines (px) in the crop's middle half, after turning
  it to the angle (within +-15 degrees) at which its ink rows stand out most (a projection
  profile); `found` is the share of crops where a pitch was clear at all;
- edge density: share of pixels with a Sobel gradient magnitude above 80;
- sharpness: variance of the Laplacian, lower quartile (the softest quarter is what hides
  text lines);
- ink share: share of pixels darker than their neighbourhood by a margin (text strokes);
- coherence: `benchmarks.reference_free.line_coherence` of the crop turned to that angle
  (its middle three quarters): how well text lines line up across the width, so lower
  means curlier or wavier lines (or staggered columns); crops without lines are left out.

    python -m doctrpp.udir.likeness PHOTO_FOLDER [--count 48] [--seed 910000] [--json OUT]
        [--sheet OUT.png]
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from doctrpp.benchmarks.reference_free import line_coherence
from doctrpp.errors import CliError
from doctrpp.files import write_bytes_atomically
from doctrpp.progress import progress
from doctrpp.runtime.imageio import IMAGE_SUFFIXES, write_image
from doctrpp.runtime.line_alignment import ink_mask, line_pitch

from .photos import chosen_photos, crops_of_photos
from .scene import KINDS

SIZE = 288
EDGE_THRESHOLD = 80.0
DESKEW_ANGLES = np.linspace(-15.0, 15.0, 13)  # degrees


@dataclass(frozen=True)
class CropMeasures:
    line_pitch: float | None  # px at SIZE; None where no periodic rows were found
    edge_density: float
    sharpness: float  # variance of the Laplacian
    ink_share: float
    coherence: float  # deskewed full-width / band row-profile contrast; 0 = no text lines


def gray_at_size(image: np.ndarray) -> np.ndarray:
    """The crop in grey at SIZE x SIZE (squashed, as the model's input is)."""
    gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    if gray.shape != (SIZE, SIZE):
        gray = cv2.resize(gray, (SIZE, SIZE), interpolation=cv2.INTER_AREA)
    return gray


def _turned_inner(image: np.ndarray, angle: float) -> np.ndarray:
    """`image` turned by `angle` degrees about its centre, without its outer eighths
    (turning brings empty corners in)."""
    height, width = image.shape[:2]
    turn = cv2.getRotationMatrix2D((width / 2, height / 2), float(angle), 1.0)
    turned = cv2.warpAffine(image, turn, (width, height), borderMode=cv2.BORDER_REPLICATE)
    return turned[height // 8 : height - height // 8, width // 8 : width - width // 8]


def deskew_angle(ink: np.ndarray) -> float:
    """The angle in DESKEW_ANGLES at which the rows of `ink` vary most."""
    spreads = [_turned_inner(ink, angle).mean(1).var() for angle in DESKEW_ANGLES]
    return float(DESKEW_ANGLES[int(np.argmax(spreads))])


def crop_measures(image: np.ndarray) -> CropMeasures:
    """The four measures of one crop (BGR or grey, any size; measured at SIZE)."""
    gray = gray_at_size(image)
    ink = ink_mask(gray)
    quarter = SIZE // 4
    middle = ink[quarter : SIZE - quarter, quarter : SIZE - quarter]
    as_float = gray.astype(np.float32)
    gradient = np.hypot(
        cv2.Sobel(as_float, cv2.CV_32F, 1, 0), cv2.Sobel(as_float, cv2.CV_32F, 0, 1)
    )
    angle = deskew_angle(middle)
    return CropMeasures(
        line_pitch=line_pitch(_turned_inner(middle, angle).mean(1)),
        edge_density=float((gradient > EDGE_THRESHOLD).mean()),
        sharpness=float(cv2.Laplacian(gray, cv2.CV_64F).var()),
        ink_share=float(ink.mean()),
        coherence=line_coherence(_turned_inner(gray, angle)),
    )


def summarise(rows: list[CropMeasures]) -> dict[str, float]:
    """Medians (sharpness: lower quartile) and the share of crops with a line pitch."""
    if not rows:
        return {}
    pitches = [r.line_pitch for r in rows if r.line_pitch is not None]
    return {
        "line_pitch": float(np.median(pitches)) if pitches else float("nan"),
        "pitch_found": len(pitches) / len(rows),
        "edge_density": float(np.median([r.edge_density for r in rows])),
        "sharpness_q25": float(np.percentile([r.sharpness for r in rows], 25)),
        "ink_share": float(np.median([r.ink_share for r in rows])),
        "coherence": float(np.median([r.coherence for r in rows if r.coherence > 0] or [0.0])),
        "crops": float(len(rows)),
    }


def photo_crops(folder: Path, count: int, seed: int = 0) -> dict[str, list[np.ndarray]]:
    """One crop of each kind (BGR, SIZE x SIZE) from `count` photos spread over `folder`."""
    crops: dict[str, list[np.ndarray]] = {kind: [] for kind in KINDS}
    try:
        paths = chosen_photos(folder, count)
    except FileNotFoundError as exc:
        raise CliError(str(exc)) from exc
    for _, photo_crops_by_kind in progress(crops_of_photos(paths, seed), len(paths), "real crops"):
        for kind, crop in photo_crops_by_kind.items():
            crops[kind].append(cv2.resize(crop, (SIZE, SIZE), interpolation=cv2.INTER_AREA))
    return crops


def generated_crops(count: int, seed: int) -> dict[str, list[np.ndarray]]:
    """`count` generated crops of each kind (seeds seed, seed + 1, ...)."""
    from .sample import generate

    crops: dict[str, list[np.ndarray]] = {kind: [] for kind in KINDS}
    jobs = [(kind, seed + i) for kind in KINDS for i in range(count)]
    for kind, sample_seed in progress(jobs, len(jobs), "generated crops"):
        # The map is not looked at: a small one keeps generation cheap.
        crops[kind].append(generate(sample_seed, kind, size=SIZE, map_size=16).image)
    return crops


def summaries(crops: dict[str, list[np.ndarray]]) -> dict[str, dict[str, float]]:
    """`summarise` of each kind's crops."""
    return {kind: summarise([crop_measures(c) for c in images]) for kind, images in crops.items()}


def contact_sheet(
    real: dict[str, list[np.ndarray]],
    generated: dict[str, list[np.ndarray]],
    per_row: int = 8,
    tile: int = 144,
) -> np.ndarray:
    """Per kind, a row of real crops above a row of generated ones, each row labelled."""
    rows = []
    for kind in KINDS:
        for source, crops in (("real", real[kind]), ("generated", generated[kind])):
            tiles = [cv2.resize(c, (tile, tile), interpolation=cv2.INTER_AREA) for c in crops]
            tiles = (tiles + [np.zeros((tile, tile, 3), np.uint8)] * per_row)[:per_row]
            row = np.concatenate(tiles, 1)
            cv2.putText(
                row, f"{kind} {source}", (4, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 255), 1
            )
            rows.append(row)
    return np.concatenate(rows, 0)


def comparison_table(real: dict[str, dict], generated: dict[str, dict]) -> str:
    """Markdown: one row per measure and kind, real beside generated."""
    lines = ["| measure | kind | real | generated |", "|---|---|---|---|"]
    measures = (
        "line_pitch",
        "pitch_found",
        "edge_density",
        "sharpness_q25",
        "ink_share",
        "coherence",
    )
    for measure in measures:
        for kind in KINDS:
            a, b = real[kind].get(measure, float("nan")), generated[kind].get(measure, float("nan"))
            digits = 0 if measure == "sharpness_q25" else (1 if measure == "line_pitch" else 3)
            lines.append(f"| {measure} | {kind} | {a:.{digits}f} | {b:.{digits}f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m doctrpp.udir.likeness",
        description="Compare the generator's crops with crops cut from real photos "
        "(line pitch, edge density, sharpness, ink share, line coherence per kind), as a "
        "Markdown table.",
    )
    parser.add_argument("photos", type=Path, help="folder of real photos")
    parser.add_argument(
        "--count", type=int, default=48, help="photos, and generated crops per kind"
    )
    parser.add_argument("--seed", type=int, default=910000, help="first generator seed")
    parser.add_argument("--json", type=Path, help="also write the summaries here")
    parser.add_argument(
        "--sheet", type=Path, help="also write a contact sheet (8 crops per kind, real above ours)"
    )
    args = parser.parse_args(argv)
    try:
        if not args.photos.is_dir():
            raise CliError(f"{args.photos}: no such folder")
        if args.count < 1:
            raise CliError("--count must be at least 1")
        if args.sheet and args.sheet.suffix.lower() not in IMAGE_SUFFIXES:
            raise CliError(f"--sheet {args.sheet}: not an image file name (.png, .jpg, ...)")
        real_crops = photo_crops(args.photos, args.count)
        generated = generated_crops(args.count, args.seed)
    except CliError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    real, generated_summary = summaries(real_crops), summaries(generated)
    print(comparison_table(real, generated_summary))
    if args.sheet:
        write_image(args.sheet, contact_sheet(real_crops, generated))
        print(f"wrote {args.sheet}")
    if args.json:
        record = {
            "real": real,
            "generated": generated_summary,
            "count": args.count,
            "seed": args.seed,
        }
        write_bytes_atomically(args.json, json.dumps(record, indent=1).encode())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
