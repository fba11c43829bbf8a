"""The generator-against-real-photos measures (udir.likeness)."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from doctrpp.udir.likeness import SIZE, crop_measures, main, summarise


def ruled_page(pitch: int, angle: float) -> np.ndarray:
    """White page with dark text-like bars every `pitch` px, turned by `angle` degrees."""
    page = np.full((SIZE, SIZE, 3), 240, np.uint8)
    for y in range(-SIZE, 2 * SIZE, pitch):
        cv2.rectangle(page, (-SIZE, y), (2 * SIZE, y + pitch // 3), (30, 30, 30), -1)
    turn = cv2.getRotationMatrix2D((SIZE / 2, SIZE / 2), angle, 1.0)
    return cv2.warpAffine(page, turn, (SIZE, SIZE), borderValue=(240, 240, 240))


@pytest.mark.parametrize("angle", [0.0, 9.0, -12.0])
def test_line_pitch_of_turned_lines(angle):
    measures = crop_measures(ruled_page(12, angle))
    assert measures.line_pitch is not None
    # Read at the deskew angle nearest the true one (2.5 degree steps): within a pixel.
    assert abs(measures.line_pitch - 12) <= 1, measures
    assert 0.2 < measures.ink_share < 0.5
    assert measures.edge_density > 0.05


def test_blank_page_has_no_pitch_and_no_edges():
    measures = crop_measures(np.full((100, 80, 3), 230, np.uint8))
    assert measures.line_pitch is None
    assert measures.edge_density == 0.0
    assert measures.sharpness == 0.0
    summary = summarise([measures, crop_measures(ruled_page(10, 0.0))])
    assert summary["pitch_found"] == 0.5
    assert summary["crops"] == 2


def test_cli_compares_real_and_generated(tmp_path, document_photo, capsys):
    photos = tmp_path / "photos"
    photos.mkdir()
    cv2.imwrite(str(photos / "a.png"), document_photo)
    out, sheet = tmp_path / "likeness.json", tmp_path / "sheet.png"
    assert main([str(photos), "--count", "1", "--json", str(out), "--sheet", str(sheet)]) == 0
    table = capsys.readouterr().out
    assert "| line_pitch | none |" in table
    record = json.loads(out.read_text())
    assert set(record["real"]) == set(record["generated"]) == {"complete", "partial", "none"}
    assert record["generated"]["none"]["crops"] == 1
    # Three kinds, a real row above a generated one, eight 144 px tiles per row.
    assert cv2.imread(str(sheet)).shape == (6 * 144, 8 * 144, 3)


def test_cli_errors(tmp_path, capsys):
    assert main([str(tmp_path / "missing")]) == 2
    assert "no such folder" in capsys.readouterr().err
    assert main([str(tmp_path)]) == 2
    assert "no images" in capsys.readouterr().err
    assert main([str(tmp_path), "--sheet", str(tmp_path / "sheet.txt")]) == 2
    assert "not an image file name" in capsys.readouterr().err


def test_coherence_sees_wavy_lines():
    """Straight lines (turned or not) line up across the width; waves do not."""
    straight = crop_measures(ruled_page(12, 0.0)).coherence
    turned = crop_measures(ruled_page(12, 9.0)).coherence
    ys, xs = np.mgrid[0:SIZE, 0:SIZE].astype(np.float32)
    wave = 8.0 * np.sin(xs / SIZE * 3 * np.pi)
    wavy_page = cv2.remap(ruled_page(12, 0.0), xs, ys + wave, cv2.INTER_LINEAR)
    wavy = crop_measures(wavy_page).coherence
    print(f"coherence: straight {straight:.2f}, turned {turned:.2f}, wavy {wavy:.2f}")
    assert straight > 0.9 and turned > 0.7  # 9 degrees, read at the 10 degree step
    assert wavy < 0.6 * straight
    assert crop_measures(np.full((100, 80, 3), 230, np.uint8)).coherence == 0.0
