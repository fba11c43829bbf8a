"""Lean inference: numpy + OpenCV + onnxruntime. Never imports torch."""

from .backends import ModelError
from .imageio import ImageError, read_image, write_image
from .rectifier import RectificationResult, Rectifier

__all__ = [
    "ImageError",
    "ModelError",
    "RectificationResult",
    "Rectifier",
    "read_image",
    "write_image",
]
