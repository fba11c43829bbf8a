"""Crops of the three kinds cut from a user's own photos (no ground truth), for calibration.

Without a document mask the kinds are heuristics on a photo that shows one document
roughly centred: 'complete' keeps the whole frame (a small random trim), 'partial' cuts
a window off one side, 'none' takes a window from the middle of the frame.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .scene import KINDS


def photo_crop_box(rng: np.random.Generator, height: int, width: int, kind: str):
    """(x0, y0, x1, y1) in pixels for a crop of `kind` from a height x width photo."""
    if kind not in KINDS:
        raise ValueError(f"unknown crop kind {kind!r}")
    if kind == "complete":
        trim = rng.uniform(0, 0.04, 4)
        return (
            int(trim[0] * width),
            int(trim[1] * height),
            int(width * (1 - trim[2])),
            int(height * (1 - trim[3])),
        )
    if kind == "none":
        fw, fh = rng.uniform(0.3, 0.5, 2)
        cx, cy = rng.uniform(0.4, 0.6, 2)
    else:
        fw, fh = rng.uniform(0.45, 0.8, 2)
        side = rng.integers(0, 4)
        cx, cy = [(fw / 2, 0.5), (1 - fw / 2, 0.5), (0.5, fh / 2), (0.5, 1 - fh / 2)][side]
        cx, cy = cx + rng.uniform(-0.1, 0.1), cy + rng.uniform(-0.1, 0.1)
    x0 = int(np.clip((cx - fw / 2) * width, 0, width - 2))
    y0 = int(np.clip((cy - fh / 2) * height, 0, height - 2))
    x1 = int(np.clip((cx + fw / 2) * width, x0 + 2, width))
    y1 = int(np.clip((cy + fh / 2) * height, y0 + 2, height))
    return x0, y0, x1, y1


def spread(paths: list, count: int) -> list:
    """`count` of `paths` (sorted by the caller) evenly spread over them."""
    if not paths:
        return []
    return [paths[i] for i in np.linspace(0, len(paths) - 1, min(count, len(paths))).astype(int)]


def crops_of_each_kind(photo: np.ndarray, seed: int, index: int) -> dict[str, np.ndarray]:
    """One crop of each kind from `photo` (the `index`-th photo of a set), deterministic."""
    crops = {}
    for kind in KINDS:
        rng = np.random.default_rng([seed, index, KINDS.index(kind)])
        x0, y0, x1, y1 = photo_crop_box(rng, photo.shape[0], photo.shape[1], kind)
        crops[kind] = photo[y0:y1, x0:x1]
    return crops


def chosen_photos(folder: Path, photos: int) -> list[Path]:
    """`photos` image files spread evenly over `folder` (sorted by name; fewer if it holds
    fewer). FileNotFoundError: no images."""
    from doctrpp.runtime.imageio import image_files

    files = image_files(folder)
    if not files:
        raise FileNotFoundError(f"{folder}: no images")
    return spread(files, photos)


def crops_of_photos(
    paths: list[Path], seed: int = 0
) -> Iterator[tuple[Path, dict[str, np.ndarray]]]:
    """Each path with one crop of each kind of its photo (`crops_of_each_kind`, the photo's
    place in `paths` as its index; BGR, at the photo's resolution)."""
    from doctrpp.runtime.imageio import read_image

    for index, path in enumerate(paths):
        yield path, crops_of_each_kind(read_image(path)[:, :, :3], seed, index)
