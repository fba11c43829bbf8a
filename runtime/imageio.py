"""Reading and writing photos: EXIF orientation, 8/16-bit, gray/colour, atomic writes."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from doctrpp.files import write_bytes_atomically

IMAGE_SUFFIXES = frozenset(
    {".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".jp2", ".pgm", ".ppm", ".pbm"}
)


def image_files(folder: str | Path) -> list[Path]:
    """The image files in `folder` (files with an image suffix, not recursive), sorted by
    name."""
    return sorted(
        p for p in Path(folder).iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
    )


class ImageError(ValueError):
    """An input image that cannot be used; the message is one line naming the file."""


ALPHA_SUFFIXES = frozenset({".png", ".webp", ".tif", ".tiff"})  # formats that can hold alpha


def read_image(path: str | Path) -> np.ndarray:
    """Read a photo as OpenCV does (BGR, BGRA or gray), honouring EXIF orientation.

    8- and 16-bit depths are kept. An image with an alpha channel is read as BGRA, as
    stored: OpenCV applies EXIF orientation only when it decodes without alpha, and
    such files rarely carry it.
    """
    path = Path(path)
    if not path.is_file():
        raise ImageError(f"{path}: no such file")
    if path.stat().st_size == 0:
        raise ImageError(f"{path}: file is empty")
    # np.fromfile + imdecode copes with non-ASCII paths, unlike cv2.imread on some systems.
    data = np.fromfile(str(path), dtype=np.uint8)
    if path.suffix.lower() in ALPHA_SUFFIXES and _may_have_alpha(data):
        image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
        if image is not None and image.ndim == 3 and image.shape[2] == 4:
            return image
    image = cv2.imdecode(data, cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR)
    if image is None or image.size == 0:
        raise ImageError(f"{path}: not a readable image")
    return image


def _may_have_alpha(data: np.ndarray) -> bool:
    """PNG: the header's colour type says (4 grey+alpha, 6 RGBA); other formats: maybe."""
    if data[:8].tobytes() == b"\x89PNG\r\n\x1a\n" and len(data) > 25:
        return int(data[25]) in (4, 6)
    return True


def has_alpha(image: np.ndarray) -> bool:
    return image.ndim == 3 and image.shape[2] == 4


def write_image(path: str | Path, image: np.ndarray) -> None:
    """Encode by the path's suffix and write atomically (temp file + rename)."""
    path = Path(path)
    ok, encoded = cv2.imencode(path.suffix or ".png", image)
    if not ok:
        raise ImageError(f"{path}: cannot encode an image with this suffix")
    write_bytes_atomically(path, encoded.tobytes())
