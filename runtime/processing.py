"""Pre- and post-processing as the reference inference script does them, in bounded memory,
plus our smoothing of the model's map (`smooth_backward_map`; 0 skips it) and the mean of
the maps of the photo and its mirror image (`flip_averaged_map`).

Pre-processing resizes the photo in its own depth and converts only the 288x288 result to
float (the reference converts the full photo first; the difference is under one grey
level, tested). Post-processing builds the full-resolution map and remaps the photo in
strips of rows, so memory grows with the output image, not with float copies of it; a
pixel's value does not depend on the strip size (tested: strip-wise equals one-shot).
"""

from __future__ import annotations

from collections.abc import Iterator

import cv2
import numpy as np

from .line_alignment import align_text_lines

STRIP_ROWS = 256  # rows of the full-resolution map held at once
# Gaussian sigma, in model-grid pixels, for the model's map before it is resized (0: the
# reference post-processing). Our trained models leave about 1 px of jitter on the 288
# grid (p99 of the map's Laplacian 0.8-1.9 px against 0.01 for true maps), which a
# full-resolution photo magnifies into jagged, broken text; sigma 2 cuts it tenfold and
# moves the map error by under 0.02 px (MODEL_CARD.md, "Map smoothing").
MAP_SMOOTHING_SIGMA = 2.0


def to_unit_rgb(image: np.ndarray) -> np.ndarray:
    """BGR/BGRA/gray uint8, uint16 or float in [0, 1] -> float32 RGB in [0, 1], HxWx3."""
    check_image(image)
    if image.ndim == 2:
        image = image[:, :, None]
    if image.dtype == np.uint8:
        scaled = image.astype(np.float32) / 255.0
    elif image.dtype == np.uint16:
        scaled = image.astype(np.float32) / 65535.0
    else:
        scaled = image.astype(np.float32)
    if scaled.shape[2] == 1:
        return np.repeat(scaled, 3, axis=2)
    return np.ascontiguousarray(scaled[:, :, 2::-1])  # BGR(A) -> RGB


def check_image(image: np.ndarray) -> None:
    shape_ok = image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (1, 3, 4))
    if not shape_ok or min(image.shape[:2]) < 1:
        raise ValueError(f"expected an HxW, HxWx3 or HxWx4 image, got shape {image.shape}")
    if image.dtype not in (np.uint8, np.uint16, np.float32, np.float64):
        raise ValueError(f"unsupported image dtype {image.dtype} (use uint8, uint16 or float)")


def model_input(image: np.ndarray, size: int) -> np.ndarray:
    """Photo -> (1, 3, size, size) float32, RGB in [0, 1], resized bilinearly.

    Resized in the photo's own depth, then converted: no full-resolution float copy.
    """
    check_image(image)
    source = image if image.ndim == 2 or image.shape[2] != 1 else image[:, :, 0]
    if source.ndim == 3 and source.shape[2] == 4:
        source = source[:, :, :3]  # alpha does not reach the model
    small = cv2.resize(source, (size, size), interpolation=cv2.INTER_LINEAR)
    rgb = to_unit_rgb(small)
    return np.ascontiguousarray(rgb.transpose(2, 0, 1)[None])


def mirrored_input(batch: np.ndarray) -> np.ndarray:
    """(1, 3, S, S) model input -> the same photo mirrored left-right."""
    return np.ascontiguousarray(batch[..., ::-1])


def unmirror_map(mirrored_map: np.ndarray) -> np.ndarray:
    """The map predicted for a mirrored input, (S, S, 2) normalised -> the map of the
    original photo: columns reversed and x negated (align-corners coordinates mirror
    exactly about 0)."""
    backward_map = np.array(mirrored_map[:, ::-1], np.float32)
    backward_map[:, :, 0] *= -1
    return backward_map


def flip_averaged_map(backward_map: np.ndarray, mirrored_map: np.ndarray) -> np.ndarray:
    """Mean of the photo's map and the unmirrored map of its mirror image. The model is not
    exactly mirror-symmetric; its two answers err partly independently, and their mean
    is closer to the truth (MODEL_CARD.md, "Flip averaging")."""
    return (np.asarray(backward_map, np.float32) + unmirror_map(mirrored_map)) / np.float32(2)


def _reflect101(index: np.ndarray, n: int) -> np.ndarray:
    """OpenCV's BORDER_REFLECT_101 index mapping (…, 2, 1 | 0, 1, …, n-1 | n-2, …)."""
    if n == 1:
        return np.zeros_like(index)
    index = np.abs(index)
    return np.where(index >= n, 2 * (n - 1) - index, index)


def _rows_of_resized(across: np.ndarray, rows: np.ndarray, height: int) -> np.ndarray:
    """Rows `rows` of `across` (S, W, 2) resized bilinearly to `height` rows (cv2 convention:
    half-pixel centres, clamped at the borders)."""
    s = across.shape[0]
    source = np.clip((rows + 0.5) * (s / height) - 0.5, 0, s - 1)
    low = np.floor(source).astype(int)
    high = np.minimum(low + 1, s - 1)
    weight = (source - low).astype(np.float32)[:, None, None]
    return across[low] * (1 - weight) + across[high] * weight


def _box3(block: np.ndarray, width: int) -> np.ndarray:
    """3x3 mean of the interior rows of `block` (n + 2 rows, halo included), reflect-101
    across columns; a fixed summation order, so every pixel is the same in any strip."""
    vertical = block[:-2] + block[1:-1] + block[2:]
    columns = _reflect101(np.arange(-1, width + 1), width)
    padded = vertical[:, columns]
    return (padded[:, :-2] + padded[:, 1:-1] + padded[:, 2:]) / np.float32(9)


def check_map_smoothing(sigma: float) -> None:
    if not sigma >= 0:
        raise ValueError(f"map smoothing sigma must be >= 0, got {sigma}")


def smooth_backward_map(backward_map: np.ndarray, sigma: float = MAP_SMOOTHING_SIGMA) -> np.ndarray:
    """(S, S, 2) normalised map -> the same, Gaussian-smoothed (`sigma` in grid pixels,
    kernel radius ceil(4 sigma)). The borders are extended by odd reflection
    (2 * edge - mirror image), which continues a ramp exactly: the identity and any affine
    map come out unchanged, and the map is not pulled inwards at the borders."""
    check_map_smoothing(sigma)
    backward_map = np.asarray(backward_map, np.float32)
    if sigma == 0:
        return backward_map
    radius = int(np.ceil(4 * sigma))
    padded = np.pad(
        backward_map,
        ((radius, radius), (radius, radius), (0, 0)),
        mode="reflect",
        reflect_type="odd",
    )
    smoothed = cv2.GaussianBlur(padded, (2 * radius + 1, 2 * radius + 1), sigma)
    return np.ascontiguousarray(smoothed[radius:-radius, radius:-radius])


def applied_map(
    image: np.ndarray,
    backward_map: np.ndarray,
    sigma: float = MAP_SMOOTHING_SIGMA,
    line_alignment: bool = True,
) -> np.ndarray:
    """The model's map as the pipeline applies it to `image`: smoothed (`sigma`), then,
    unless switched off, its rows shifted so that text lines come out level
    (`line_alignment.align_text_lines`)."""
    backward_map = smooth_backward_map(backward_map, sigma)
    return align_text_lines(image, backward_map) if line_alignment else backward_map


def photo_map_strips(
    backward_map: np.ndarray, height: int, width: int, strip_rows: int = STRIP_ROWS
) -> Iterator[tuple[int, np.ndarray]]:
    """(first row, (rows, width, 2) map in photo pixels) for consecutive strips of rows.

    Each channel of the model-grid map is resized bilinearly to width x height, blurred
    with a 3x3 box (reflect-101 borders, as cv2.blur) and converted from align_corners
    coordinates to pixel positions.
    """
    across = cv2.resize(
        np.ascontiguousarray(backward_map, dtype=np.float32),
        (width, backward_map.shape[0]),
        interpolation=cv2.INTER_LINEAR,
    )  # (S, width, 2): columns resized once, rows resized per strip
    scale = np.array([(width - 1) / 2, (height - 1) / 2], np.float32)
    for top in range(0, height, strip_rows):
        bottom = min(top + strip_rows, height)
        rows = _reflect101(np.arange(top - 1, bottom + 1), height)
        block = _rows_of_resized(across, rows, height)
        yield top, (_box3(block, width) + np.float32(1)) * scale


def photo_map(backward_map: np.ndarray, height: int, width: int, out=None) -> np.ndarray:
    """(h, w, 2) normalised backward map -> (height, width, 2) float32 map in photo pixels.

    `out`: an array (or np.memmap) of that shape to fill, e.g. to write a huge map to disk.
    """
    if out is None:
        out = np.empty((height, width, 2), np.float32)
    for top, strip in photo_map_strips(backward_map, height, width):
        out[top : top + len(strip)] = strip
    return out


def rectify_with_map(
    image: np.ndarray, backward_map: np.ndarray, strip_rows: int = STRIP_ROWS
) -> np.ndarray:
    """The reference post-processing, strip by strip: same size, channels and dtype; an
    alpha channel is remapped like the colour (transparent outside the photo)."""
    height, width = image.shape[:2]
    out = np.empty_like(image)
    for top, strip in photo_map_strips(backward_map, height, width, strip_rows):
        out[top : top + len(strip)] = remap(image, strip).reshape(out[top : top + len(strip)].shape)
    return out


def remap(image: np.ndarray, pixel_map: np.ndarray) -> np.ndarray:
    """Sample `image` at `pixel_map` (H, W, 2): bilinear, zeros outside; keeps dtype."""
    return cv2.remap(
        image,
        np.ascontiguousarray(pixel_map[:, :, 0]),
        np.ascontiguousarray(pixel_map[:, :, 1]),
        interpolation=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=0,
    )
