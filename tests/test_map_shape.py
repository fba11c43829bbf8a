"""The non-projective part of a map: zero for a perspective, found for a curl."""

from __future__ import annotations

import cv2
import numpy as np

from doctrpp.benchmarks.map_shape import nonprojective_px, nonprojective_recovery
from doctrpp.contract import identity_map

SIZE = 288


def perspective_map() -> np.ndarray:
    corners = np.float32([[0, 0], [SIZE - 1, 0], [SIZE - 1, SIZE - 1], [0, SIZE - 1]])
    seen = np.float32([[20, 10], [270, 30], [250, 280], [5, 260]])
    homography = cv2.getPerspectiveTransform(corners, seen)
    ys, xs = np.mgrid[0:SIZE, 0:SIZE].astype(np.float32)
    points = cv2.perspectiveTransform(np.stack([xs, ys], -1).reshape(1, -1, 2), homography)
    return points.reshape(SIZE, SIZE, 2) / (SIZE - 1) * 2 - 1


def curled_map(amplitude_px: float = 6.0) -> np.ndarray:
    bm = identity_map(SIZE).copy()
    x = np.linspace(0, 2 * np.pi, SIZE)
    bm[..., 1] += (amplitude_px * np.sin(x) / ((SIZE - 1) / 2))[None, :]
    return bm


def test_perspective_has_no_nonprojective_part():
    assert nonprojective_px(identity_map(SIZE)) < 1e-4
    assert nonprojective_px(perspective_map()) < 1e-3


def test_curl_is_found_at_its_size():
    # A sine of amplitude A has mean |sin| 2A/pi; a homography takes out little of it.
    assert 0.5 * 6 * 2 / np.pi < nonprojective_px(curled_map(6.0)) < 6.0


def test_recovery_scale():
    truth = curled_map()
    assert nonprojective_recovery(truth, truth).recovered > 0.999
    only_perspective = nonprojective_recovery(perspective_map(), truth)
    assert abs(only_perspective.recovered) < 0.01  # no better than predicting none
    assert abs(only_perspective.cosine) < 0.05
    half = nonprojective_recovery((identity_map(SIZE) + truth) / 2, truth)
    assert 0.45 < half.recovered < 0.55 and half.cosine > 0.99


def test_validation_scores_report_recovered_bending():
    from doctrpp.training.validate import identity_scores, score_maps, validation_set

    items = validation_set(3)
    perfect = score_maps(items, [item.backward_map for item in items])
    assert perfect["nonprojective_recovered/all"] > 0.999
    assert abs(identity_scores(items)["nonprojective_recovered/all"]) < 1e-6
