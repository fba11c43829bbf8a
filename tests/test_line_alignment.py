"""Text-line alignment (runtime.line_alignment): levels wavy lines, leaves the rest alone."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from doctrpp.contract import identity_map
from doctrpp.runtime.line_alignment import LineAlignment, align_text_lines, gray_uint8

WORDS = [
    "alpha",
    "beta",
    "gamma",
    "delta",
    "epsilon",
    "zeta",
    "eta",
    "theta",
    "iota",
    "kappa",
    "lambda",
    "omicron",
]


def text_page(size: int = 640, columns: int = 1, stagger: int = 0, seed: int = 0) -> np.ndarray:
    """A flat white page of text lines (18 px pitch); column c's baselines drop c * stagger."""
    rng = np.random.default_rng(seed)
    page = np.full((size, size, 3), 235, np.uint8)
    width = (size - 40) // columns
    for column in range(columns):
        left = 20 + column * width
        for baseline in range(40 + column * stagger, size - 20, 18):
            line = " ".join(rng.choice(WORDS, 12))
            cv2.putText(page, line, (left, baseline), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (20,) * 3)
            page[:, left + width - 12 : left + width] = 235  # a gutter between columns
    return page


def wavy_map(amplitude: float, size: int = 288) -> np.ndarray:
    """Identity, with each column sampling `amplitude * sin(pi x)` lower (normalised)."""
    backward_map = identity_map(size)
    backward_map[:, :, 1] += amplitude * np.sin(np.pi * backward_map[:, :, 0])
    return backward_map


def level_error_px(backward_map: np.ndarray) -> float:
    """Mean |vertical deviation from a row-wise constant| of the map, px of its grid,
    over the middle of the page (where there are lines above and below)."""
    y = backward_map[36:-36, :, 1] * (backward_map.shape[0] - 1) / 2
    return float(np.abs(y - y.mean(axis=1, keepdims=True)).mean())


def test_wavy_lines_come_out_level(report_difference):
    page, wavy = text_page(), wavy_map(0.03)  # lines bow by 4.3 px of the 288 grid
    aligned = align_text_lines(page, wavy)
    before, after = level_error_px(wavy), level_error_px(aligned)
    report_difference("waviness left of 2.75 px", after, 0.25 * before)
    assert after < 0.25 * before
    assert np.abs(aligned[:, :, 0] - wavy[:, :, 0]).max() < 1e-6  # only rows move


def test_level_lines_and_blank_pages_stay_as_they_are(report_difference):
    flat = identity_map(288)
    blank = np.full((400, 300, 3), 230, np.uint8)
    assert np.array_equal(align_text_lines(blank, flat), flat)
    staggered = text_page(columns=2, stagger=7)  # baselines half a pitch apart: not a bend
    moved = np.abs(align_text_lines(staggered, flat) - flat).max() * 287 / 2
    report_difference("flat staggered columns moved", moved, 1.0)
    assert moved < 1.0  # a fifth of what the wavy test corrects


def test_every_photo_kind_gives_the_same_alignment(convert_photo):
    page, wavy = text_page(), wavy_map(0.03)
    assert np.array_equal(gray_uint8(convert_photo(page), 1024), gray_uint8(page, 1024))
    assert np.allclose(align_text_lines(convert_photo(page), wavy), align_text_lines(page, wavy))


def test_no_iterations_is_the_identity_and_bad_parameters_are_refused():
    wavy = wavy_map(0.03)
    unchanged = align_text_lines(text_page(), wavy, LineAlignment(iterations=0))
    assert np.array_equal(unchanged, wavy)
    for bad in ({"render_size": 16}, {"bands": 3}, {"windows": 0}, {"max_offset": 0.0}):
        with pytest.raises(ValueError, match="line alignment"):
            LineAlignment(**bad)


def test_score_runs_the_pipeline_on_larger_crops(tiny_checkpoint, capsys):
    from doctrpp.training.score import main as score

    assert (
        score(
            [
                str(tiny_checkpoint),
                "--validation-size",
                "3",
                "--crop-size",
                "576",
                "--flip-average",
                "--line-alignment",
            ]
        )
        == 0
    )
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2 and "map_error_px/all" in lines[1]
