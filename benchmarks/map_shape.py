"""How much of a backward map is more than a perspective: its non-projective part.

A flat page seen at an angle needs only a homography; curls, folds and creases are what is
left after the best-fitting homography is taken out. Map error alone cannot say whether a
model learned that part: a model that only de-rotates and crops already lowers the error a
lot (session 6 found the tiny default recovering none of it). These numbers can.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

GRID_STEP = 4  # map pixels between the points of the fit (72 x 72 points on a 288 map)


def _map_points(backward_map: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Output-grid points and the photo points the map sends them to, in map pixels."""
    bm = np.asarray(backward_map, np.float64)
    if bm.shape[-1] != 2:
        bm = np.moveaxis(bm, -3, -1)
    size = bm.shape[0]
    ys, xs = np.mgrid[0:size:GRID_STEP, 0:size:GRID_STEP]
    grid = np.stack([xs, ys], -1).reshape(-1, 2).astype(np.float64)
    photo = ((bm[::GRID_STEP, ::GRID_STEP] + 1.0) * 0.5 * (size - 1)).reshape(-1, 2)
    return grid, photo


def nonprojective_part(backward_map: np.ndarray) -> np.ndarray:
    """(N, 2) residual in map pixels after a least-squares homography grid -> photo."""
    grid, photo = _map_points(backward_map)
    homography, _ = cv2.findHomography(grid, photo, 0)
    if homography is None:  # degenerate map (all points on a line)
        return photo - photo.mean(0)
    return photo - cv2.perspectiveTransform(grid[None], homography)[0]


def nonprojective_px(backward_map: np.ndarray) -> float:
    """Mean length of the non-projective part, in map pixels (0 for a pure perspective)."""
    return float(np.linalg.norm(nonprojective_part(backward_map), axis=1).mean())


@dataclass(frozen=True)
class NonProjectiveRecovery:
    truth_px: float  # mean non-projective part of the true map
    predicted_px: float  # ... of the predicted map
    error_px: float  # mean distance between the two parts (truth_px when nothing recovered)
    cosine: float  # alignment of the two parts: 1 same shape, 0 unrelated

    @property
    def recovered(self) -> float:
        """1 - error / truth: 1 all recovered, 0 no better than predicting none, < 0 worse."""
        return 1.0 - self.error_px / self.truth_px if self.truth_px > 0 else float("nan")


def nonprojective_recovery(predicted: np.ndarray, truth: np.ndarray) -> NonProjectiveRecovery:
    """Compare the non-projective parts of a predicted and a true backward map."""
    part_p, part_t = nonprojective_part(predicted), nonprojective_part(truth)
    norm = np.linalg.norm(part_p) * np.linalg.norm(part_t)
    return NonProjectiveRecovery(
        truth_px=float(np.linalg.norm(part_t, axis=1).mean()),
        predicted_px=float(np.linalg.norm(part_p, axis=1).mean()),
        error_px=float(np.linalg.norm(part_p - part_t, axis=1).mean()),
        cosine=float((part_p * part_t).sum() / norm) if norm > 0 else 0.0,
    )
