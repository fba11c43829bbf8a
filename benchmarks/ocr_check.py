"""A reference-free OCR check on real photos: how much text Tesseract reads with confidence
from the untouched photo and from its rectification by a model file, with and without
text-line alignment.

usage: python -m doctrpp.benchmarks.ocr_check [--model MODEL.onnx] --photos DIR
       [--count N] [--out rows.jsonl]

Per photo and variant: the words Tesseract (`tesseract IMAGE - tsv`, `eng`, the image
upscaled 2x: these photos' text is small) returns, the "confident" ones (confidence >= 80
and at least three letters) and their letters, and the mean word confidence. Without a
flat reference this cannot say that the text is right, only that the OCR engine is sure of
it; cropping away text lowers it (a rectification that keeps only the page reads fewer
words of the background). Needs the `tesseract` command (Debian: tesseract-ocr).
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import cv2
import numpy as np

from .metrics import tesseract

CONFIDENT = 80.0  # Tesseract word confidence (0-100) counted as read
MIN_LETTERS = 3  # shorter words are too often noise read as text
VARIANTS = ("untouched", "rectified", "aligned")


def tesseract_words(image: np.ndarray, upscale: float = 2.0) -> list[tuple[str, float]]:
    """(word, confidence) for each word Tesseract reports in `image` (BGR or gray uint8)."""
    scaled = cv2.resize(image, None, fx=upscale, fy=upscale, interpolation=cv2.INTER_CUBIC)
    return parse_tsv(tesseract(scaled, "eng", "tsv"))


def parse_tsv(tsv: str) -> list[tuple[str, float]]:
    """Tesseract's TSV output -> (word, confidence) of its word rows."""
    words = []
    for line in tsv.splitlines()[1:]:
        fields = line.split("\t")
        if len(fields) == 12 and fields[11].strip() and float(fields[10]) >= 0:
            words.append((fields[11].strip(), float(fields[10])))
    return words


def summarise_words(words: list[tuple[str, float]]) -> dict[str, float]:
    confident = [
        w for w, c in words if c >= CONFIDENT and sum(ch.isalpha() for ch in w) >= MIN_LETTERS
    ]
    return {
        "words": len(words),
        "confident_words": len(confident),
        "confident_letters": sum(len(w) for w in confident),
        "mean_confidence": float(np.mean([c for _, c in words])) if words else 0.0,
    }


def compare(rows: list[dict]) -> dict[str, dict[str, float]]:
    """Means per variant, and for each later variant on how many photos it read more / fewer
    confident letters than the variant before it."""
    table: dict[str, dict[str, float]] = {}
    for index, variant in enumerate(VARIANTS):
        values = {k: float(np.mean([r[variant][k] for r in rows])) for k in rows[0][variant]}
        if index:
            before = VARIANTS[index - 1]
            ours = np.array([r[variant]["confident_letters"] for r in rows])
            theirs = np.array([r[before]["confident_letters"] for r in rows])
            values[f"more_than_{before}"] = int((ours > theirs).sum())
            values[f"fewer_than_{before}"] = int((ours < theirs).sum())
        table[variant] = values
    return table


def main(argv: list[str] | None = None) -> int:
    from doctrpp.runtime import Rectifier, read_image
    from doctrpp.runtime.imageio import image_files
    from doctrpp.runtime.models import shipped_model

    parser = argparse.ArgumentParser(
        prog="python -m doctrpp.benchmarks.ocr_check", description=__doc__
    )
    parser.add_argument("--model", type=Path, help="model file (default: the shipped ONNX)")
    parser.add_argument("--photos", type=Path, required=True, help="folder of real photos")
    parser.add_argument("--count", type=int, default=0, help="first N photos (0: all)")
    parser.add_argument("--out", type=Path, help="also write one JSON row per photo here")
    args = parser.parse_args(argv)
    if shutil.which("tesseract") is None:
        parser.error("needs the tesseract command (Debian: apt-get install tesseract-ocr)")
    files = image_files(args.photos)
    files = files[: args.count or None]
    if not files:
        parser.error(f"{args.photos}: no images")
    model = args.model or shipped_model()
    rectifiers = {
        "rectified": Rectifier(model, line_alignment=False),
        "aligned": Rectifier(model, line_alignment=True),
    }
    rows = []
    for number, path in enumerate(files, 1):
        photo = read_image(path)
        row: dict = {"photo": path.stem, "untouched": summarise_words(tesseract_words(photo))}
        for name, rectifier in rectifiers.items():
            row[name] = summarise_words(tesseract_words(rectifier.rectify(photo)))
        rows.append(row)
        print(f"[{number}/{len(files)}] {json.dumps(row)}", flush=True)
    if args.out:
        from doctrpp.files import write_bytes_atomically

        text = "".join(json.dumps(r) + "\n" for r in rows)
        write_bytes_atomically(args.out, text.encode())
    print(json.dumps({"model": str(model), "photos": len(rows), **compare(rows)}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
