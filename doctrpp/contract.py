"""The model file's input/output contract, shared by the exporter and the runtime.

Kept free of torch and onnxruntime so that both sides can import it.
"""

from __future__ import annotations

INPUT_NAME = "image"
OUTPUT_NAME = "backward_map"
INPUT_SIZE = 288

# The reference inference script maps the backward map from pixels of the 288 grid to
# grid_sample coordinates with these two constants (not 287 and 1.0).
BM_DIVISOR = 286.8
BM_SHRINK = 0.99

# Keys of the ONNX `metadata_props` (and of the TFLite metadata) written by the exporter.
META_INPUT_SIZE = "doctrpp.input_size"  # "288"
META_INPUT_LAYOUT = "doctrpp.input_layout"  # "NCHW"
META_COLOR_ORDER = "doctrpp.color_order"  # "RGB"
META_INPUT_SCALE = "doctrpp.input_scale"  # "1/255": float = uint8 / 255, no mean/std
META_INPUT_RESIZE = "doctrpp.input_resize"  # "bilinear"
META_OUTPUT_CONVENTION = "doctrpp.output_convention"
META_OUTPUT_LAYOUT = "doctrpp.output_layout"  # "NCHW"
META_CONFIG = "doctrpp.model_config"  # JSON
META_VERSION = "doctrpp.package_version"
META_CHECKPOINT_SHA256 = "doctrpp.checkpoint_sha256"
META_CHECKPOINT_NOTE = "doctrpp.checkpoint_note"
META_PRECISION = "doctrpp.precision"

OUTPUT_CONVENTION = (
    "normalised backward map, channel 0 = x, channel 1 = y, in [-1, 1] with "
    "grid_sample(align_corners=True) semantics: pixel = (g + 1) / 2 * (size - 1); "
    "resize to the photo (bilinear), 3x3 box blur, bilinear remap with zeros outside"
)


def pixels_to_normalised(bm_pixels):
    """Backward map in pixels of the 288 grid -> grid_sample coordinates (arrays or tensors)."""
    return (2.0 * (bm_pixels / BM_DIVISOR) - 1.0) * BM_SHRINK


def normalised_to_pixels(bm_normalised):
    """Inverse of `pixels_to_normalised`."""
    return (bm_normalised / BM_SHRINK + 1.0) / 2.0 * BM_DIVISOR


def identity_map(size: int = INPUT_SIZE):
    """The backward map that leaves a photo as it is: (size, size, 2) normalised, x then y."""
    import numpy as np

    g = np.linspace(-1, 1, size, dtype=np.float32)
    x, y = np.meshgrid(g, g)
    return np.stack([x, y], -1)
