"""Pre- and post-processing exactly as the reference inference script does them."""

from __future__ import annotations

import cv2
import numpy as np


def to_unit_rgb(image: np.ndarray) -> np.ndarray:
    """BGR/BGRA/gray uint8, uint16 or float in [0, 1] -> float32 RGB in [0, 1], HxWx3."""
    if image.ndim == 2:
        image = image[:, :, None]
    if image.ndim != 3 or image.shape[2] not in (1, 3, 4) or min(image.shape[:2]) < 1:
        raise ValueError(f"expected an HxW, HxWx3 or HxWx4 image, got shape {image.shape}")
    if image.dtype == np.uint8:
        scaled = image.astype(np.float32) / 255.0
    elif image.dtype == np.uint16:
        scaled = image.astype(np.float32) / 65535.0
    elif image.dtype in (np.float32, np.float64):
        scaled = image.astype(np.float32)
    else:
        raise ValueError(f"unsupported image dtype {image.dtype} (use uint8, uint16 or float)")
    if scaled.shape[2] == 1:
        return np.repeat(scaled, 3, axis=2)
    return np.ascontiguousarray(scaled[:, :, 2::-1])  # BGR(A) -> RGB


def model_input(image: np.ndarray, size: int) -> np.ndarray:
    """Photo -> (1, 3, size, size) float32, RGB in [0, 1], resized bilinearly.

    The reference resizes the float image (not the uint8 one); so do we.
    """
    rgb = cv2.resize(to_unit_rgb(image), (size, size), interpolation=cv2.INTER_LINEAR)
    return np.ascontiguousarray(rgb.transpose(2, 0, 1)[None])


def photo_map(backward_map: np.ndarray, height: int, width: int) -> np.ndarray:
    """(h, w, 2) normalised backward map -> (height, width, 2) map in photo pixels.

    Resize each channel bilinearly to the photo, blur with a 3x3 box, then convert
    from align_corners=True coordinates to pixel positions.
    """
    channels = []
    for c, size in ((0, width), (1, height)):
        resized = cv2.resize(
            np.ascontiguousarray(backward_map[:, :, c], dtype=np.float32),
            (width, height),
            interpolation=cv2.INTER_LINEAR,
        )
        blurred = cv2.blur(resized, (3, 3))
        channels.append((blurred + 1.0) * 0.5 * (size - 1))
    return np.stack(channels, axis=2)


def rectify_with_map(image: np.ndarray, backward_map: np.ndarray) -> np.ndarray:
    """The reference post-processing: the model-grid map applied to the full photo."""
    return remap(image, photo_map(backward_map, image.shape[0], image.shape[1]))


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
