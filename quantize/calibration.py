"""Calibration inputs: UDIR-style generated crops (three kinds) or the user's own images."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np

from doctrpp import contract
from doctrpp.progress import progress
from doctrpp.runtime.imageio import image_files, read_image
from doctrpp.runtime.processing import model_input

CALIBRATION_SEED_OFFSET = 2_000_000_000  # away from training and validation seeds
HELD_OUT_SEED_OFFSET = 2_100_000_000  # drift checks after quantisation / export


def generated_inputs(
    count: int, seed_offset: int = CALIBRATION_SEED_OFFSET
) -> Iterator[np.ndarray]:
    """Model inputs from `count` generated crops, equal thirds of the three kinds."""
    from doctrpp.udir.sample import generate, kind_for_index

    for i in range(count):
        sample = generate(seed_offset + i, kind_for_index(i))
        yield model_input(sample.image, contract.INPUT_SIZE)


def folder_inputs(folder: str | Path) -> list[np.ndarray]:
    """Model inputs from every image in `folder` (e.g. from `doctrpp crops --from-photos`)."""
    paths = image_files(folder)
    paths = [p for p in paths if not p.stem.endswith("_flat")]
    if not paths:
        raise ValueError(f"{folder}: no calibration images")
    return [model_input(read_image(p), contract.INPUT_SIZE) for p in paths]


class CalibrationReader:
    """onnxruntime's CalibrationDataReader protocol over model inputs."""

    def __init__(
        self,
        inputs: Iterable[np.ndarray],
        input_name: str = contract.INPUT_NAME,
        show_progress: bool = True,
    ):
        self.inputs = list(inputs)
        self.input_name = input_name
        self.show_progress = show_progress
        self._position = 0
        self._started = 0.0

    def get_next(self) -> dict[str, np.ndarray] | None:
        if self.show_progress and self._position:  # the previous input has been run
            self._report(self._position)
        if self._position >= len(self.inputs):
            return None
        if not self._position:
            self._started = time.perf_counter()
        batch = self.inputs[self._position]
        self._position += 1
        return {self.input_name: batch}

    def _report(self, done: int) -> None:
        total = len(self.inputs)
        if done % max(1, total // 20) and done != total:
            return
        rate = done / max(time.perf_counter() - self._started, 1e-9)
        print(
            f"calibrating: {done}/{total} inputs, {rate:.1f}/s, eta {(total - done) / rate:.0f} s",
            file=sys.stderr,
            flush=True,
        )

    def rewind(self) -> None:
        self._position = 0


def load_calibration(folder: str | Path | None, synthetic: int) -> list[np.ndarray]:
    """The user's images when `folder` is given, else `synthetic` generated crops (with a
    progress bar on stderr: generating them takes a while)."""
    if folder:
        return folder_inputs(folder)
    return list(progress(generated_inputs(synthetic), synthetic, "calibration crops"))
