"""Accuracy of one model file against another (or against ground truth), on the same inputs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doctrpp.benchmarks.metrics import map_drift
from doctrpp.runtime.backends import open_backend


@dataclass(frozen=True)
class DriftSummary:
    mean_px: float  # mean over inputs of the per-input mean drift
    max_px: float  # largest drift at any pixel of any input
    per_input_mean: tuple[float, ...]


def predict(model_path, inputs: list[np.ndarray], threads: int | None = 2) -> list[np.ndarray]:
    """(S, S, 2) normalised maps for model inputs of shape (1, 3, S, S)."""
    backend = open_backend(model_path, threads)
    return [backend.run(x)[0].transpose(1, 2, 0) for x in inputs]


def drift(maps_a: list[np.ndarray], maps_b: list[np.ndarray]) -> DriftSummary:
    drifts = [map_drift(a, b) for a, b in zip(maps_a, maps_b, strict=True)]
    return DriftSummary(
        mean_px=float(np.mean([d.mean_px for d in drifts])),
        max_px=float(max(d.max_px for d in drifts)),
        per_input_mean=tuple(d.mean_px for d in drifts),
    )
