"""`python -m doctrpp.training.cross_shot`: two shots of a document, rectified, compared."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from doctrpp.benchmarks.cross_shot import agreement, paired, shot_pairs
from doctrpp.training.cross_shot import main


def _page(seed: int, size: tuple[int, int] = (240, 180)) -> np.ndarray:
    """A gray 'page' with dark text-like bars, BGR uint8."""
    rng = np.random.default_rng(seed)
    page = np.full((*size, 3), 235, np.uint8)
    for row in range(12, size[0] - 12, 14):
        start = int(rng.integers(8, 30))
        page[row : row + 5, start : size[1] - int(rng.integers(8, 40))] = 40
    return page


def test_shot_pairs_keeps_documents_with_both_shots(tmp_path):
    for name in ["a_1.png", "a_2.png", "b_1.png", "c_2.jpg", "d_3.png", "e_1.jpg", "e_2.png"]:
        cv2.imwrite(str(tmp_path / name), _page(0, (16, 16)))
    (tmp_path / "notes.txt").write_text("not an image")
    pairs = shot_pairs(tmp_path)
    assert [(p.name, q.name) for p, q in pairs] == [("a_1.png", "a_2.png"), ("e_1.jpg", "e_2.png")]


def test_identical_shots_agree_fully_and_a_shifted_shot_less():
    page = _page(1)
    same = agreement(page, page.copy())
    assert same["ms_ssim"] == pytest.approx(1.0, abs=1e-3)
    assert same["local_distortion"] == pytest.approx(0.0, abs=1e-3)
    shifted = agreement(page, np.roll(page, 5, axis=0))
    assert shifted["ms_ssim"] < 0.9
    assert shifted["local_distortion"] > 1.0


def test_paired_is_the_mean_per_document_difference_with_its_standard_error():
    reference = [
        {"ms_ssim": 0.4, "local_distortion": 30.0},
        {"ms_ssim": 0.5, "local_distortion": 20.0},
    ]
    candidate = [
        {"ms_ssim": 0.5, "local_distortion": 28.0},
        {"ms_ssim": 0.5, "local_distortion": 20.0},
    ]
    result = paired(reference, candidate)
    assert result["paired_ms_ssim"] == pytest.approx([0.05, 0.05])
    assert result["paired_local_distortion"] == pytest.approx([-1.0, 1.0])


def test_cli_scores_identity_and_weights_and_pairs_them(tmp_path, tiny_checkpoint, capsys):
    photos = tmp_path / "photos"
    photos.mkdir()
    for document in ("1", "2"):
        page = _page(int(document))
        cv2.imwrite(str(photos / f"{document}_1.png"), page)
        tilted = cv2.warpAffine(page, cv2.getRotationMatrix2D((90, 120), 4, 1.0), (180, 240))
        cv2.imwrite(str(photos / f"{document}_2.png"), tilted)
    rows = tmp_path / "rows.jsonl"
    args = [str(tiny_checkpoint), str(tiny_checkpoint), "--photos", str(photos)]
    assert main([*args, "--no-line-alignment", "--rows", str(rows)]) == 0
    lines = [json.loads(line) for line in capsys.readouterr().out.strip().splitlines()]
    assert [line["entry"] for line in lines] == ["identity", *args[:2], args[1]]
    assert all(line["pairs"] == 2 for line in lines[:3])
    assert 0 < lines[0]["cross_shot_ms_ssim"] < 1
    assert lines[3]["paired_ms_ssim"] == [0.0, 0.0]  # the same weights twice
    written = [json.loads(line) for line in rows.read_text().splitlines()]
    assert len(written) == 6 and {row["document"] for row in written} == {"1", "2"}


def test_a_model_file_is_scored_with_the_runtime(tmp_path, tiny_onnx, capsys):
    photos = tmp_path / "photos"
    photos.mkdir()
    for document in ("1", "2"):
        for shot in ("1", "2"):
            cv2.imwrite(str(photos / f"{document}_{shot}.png"), _page(int(document + shot)))
    assert main([str(tiny_onnx), "--photos", str(photos)]) == 0
    lines = [json.loads(line) for line in capsys.readouterr().out.strip().splitlines()]
    assert [line["entry"] for line in lines] == ["identity", str(tiny_onnx)]
    assert 0 < lines[1]["cross_shot_ms_ssim"] <= 1


def test_cli_refuses_a_folder_without_pairs(tmp_path, capsys):
    cv2.imwrite(str(tmp_path / "1_1.png"), _page(0, (16, 16)))
    with pytest.raises(SystemExit) as stop:
        main(["--photos", str(tmp_path)])
    assert stop.value.code == 2
    assert "fewer than two documents" in capsys.readouterr().err


def test_cli_names_an_unreadable_photo_in_one_line(tmp_path):
    for document in ("1", "2"):
        cv2.imwrite(str(tmp_path / f"{document}_1.png"), _page(0, (16, 16)))
        cv2.imwrite(str(tmp_path / f"{document}_2.png"), _page(1, (16, 16)))
    (tmp_path / "2_2.png").write_bytes(b"not a png")
    with pytest.raises(SystemExit) as stop:
        main(["--photos", str(tmp_path)])
    assert str(stop.value) == f"error: {tmp_path / '2_2.png'}: not a readable image"
