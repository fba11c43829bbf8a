"""`Rectifier`: photo in, rectified photo out, with per-stage timings."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from doctrpp import contract

from .backends import ModelError, open_backend
from .processing import (
    MAP_SMOOTHING_SIGMA,
    applied_map,
    check_map_smoothing,
    flip_averaged_map,
    mirrored_input,
    model_input,
    photo_map,
    rectify_with_map,
)


@dataclass
class RectificationResult:
    rectified: np.ndarray  # same size, channels and dtype as the input
    backward_map: np.ndarray  # (S, S, 2) normalised, x then y, smoothed as used
    timings: dict[str, float] = field(default_factory=dict)  # seconds per stage

    def photo_map(self, out: np.ndarray | None = None) -> np.ndarray:
        """The full-resolution map in photo pixels (H, W, 2), as used for the remap.

        8 bytes per pixel: pass `out` (e.g. an np.memmap) to keep a huge one on disk.
        """
        height, width = self.rectified.shape[:2]
        return photo_map(self.backward_map, height, width, out=out)


class Rectifier:
    """Runs a DocTr++ model file (.onnx or .tflite) on photos given as OpenCV arrays
    (gray, BGR or BGRA; an alpha channel is remapped like the colour).

    `map_smoothing`: Gaussian sigma in model-grid pixels applied to the model's map before
    the remap (`processing.smooth_backward_map`); 0 reproduces the reference
    post-processing.

    `flip_average`: also run the model on the mirrored photo and use the mean of the two
    maps (`processing.flip_averaged_map`): twice the inference time, a closer map
    (MODEL_CARD.md, "Flip averaging"); False runs the model once, as the reference does.

    `line_alignment`: after smoothing, shift the map's rows so that text lines come out
    level (`line_alignment.align_text_lines`; MODEL_CARD.md, "Text-line alignment")."""

    def __init__(
        self,
        model_path: str | Path,
        threads: int | None = None,
        map_smoothing: float = MAP_SMOOTHING_SIGMA,
        flip_average: bool = True,
        line_alignment: bool = True,
    ) -> None:
        check_map_smoothing(map_smoothing)
        self.map_smoothing = map_smoothing
        self.flip_average = flip_average
        self.line_alignment = line_alignment
        self.model_path = Path(model_path)
        self.backend = open_backend(self.model_path, threads)
        self.metadata = self.backend.metadata
        self.input_size = self._input_size()
        self.config = json.loads(self.metadata.get(contract.META_CONFIG, "{}") or "{}")

    def _input_size(self) -> int:
        size = self.metadata.get(contract.META_INPUT_SIZE)
        if size is None:  # a file exported elsewhere: fall back to its static input shape
            shape = self.backend.input_shape
            size = shape[-1] if isinstance(shape[-1], int) else contract.INPUT_SIZE
        color = self.metadata.get(contract.META_COLOR_ORDER, "RGB")
        layout = self.metadata.get(contract.META_INPUT_LAYOUT, "NCHW")
        if color != "RGB" or layout != "NCHW":
            raise ModelError(f"{self.model_path}: unsupported input {layout}/{color}")
        return int(size)

    def predict_map(self, image: np.ndarray) -> np.ndarray:
        """The model's normalised backward map on its grid, (S, S, 2), x then y: one run,
        neither flip-averaged nor smoothed (what parity and drift compare)."""
        return self._infer(model_input(image, self.input_size))

    def _infer(self, batch: np.ndarray) -> np.ndarray:
        return self.backend.run(batch)[0].transpose(1, 2, 0)

    def model_map(self, batch: np.ndarray) -> np.ndarray:
        """The map the pipeline uses before smoothing: flip-averaged unless switched off."""
        backward_map = self._infer(batch)
        if self.flip_average:
            backward_map = flip_averaged_map(backward_map, self._infer(mirrored_input(batch)))
        return backward_map

    def run(self, image: np.ndarray) -> RectificationResult:
        timings: dict[str, float] = {}
        start = time.perf_counter()
        batch = model_input(image, self.input_size)
        timings["preprocess"] = time.perf_counter() - start

        start = time.perf_counter()
        backward_map = self.model_map(batch)
        timings["inference"] = time.perf_counter() - start

        start = time.perf_counter()
        backward_map = applied_map(image, backward_map, self.map_smoothing, self.line_alignment)
        timings["map"] = time.perf_counter() - start

        start = time.perf_counter()
        rectified = rectify_with_map(image, backward_map)
        timings["postprocess"] = time.perf_counter() - start
        return RectificationResult(rectified, np.ascontiguousarray(backward_map), timings)

    def rectify(self, image: np.ndarray) -> np.ndarray:
        """The rectified photo, same size, channels and dtype as `image`."""
        return self.run(image).rectified
