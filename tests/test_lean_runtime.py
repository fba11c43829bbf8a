"""The lean runtime at any size: strip-wise post-processing, RGBA, folders in parallel,
the shipped default model, running from the repository root."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from doctrpp.cli import main
from doctrpp.runtime import Rectifier, read_image
from doctrpp.runtime.line_alignment import align_text_lines
from doctrpp.runtime.processing import (
    flip_averaged_map,
    model_input,
    photo_map,
    rectify_with_map,
    smooth_backward_map,
)

REPO = Path(__file__).resolve().parents[1]


def warp(size: int = 288) -> np.ndarray:
    g = np.linspace(-1, 1, size, dtype=np.float32)
    x, y = np.meshgrid(g, g)
    return np.stack([1.04 * x + 0.07 * np.sin(3 * y), 1.02 * y + 0.05 * np.cos(2 * x)], -1)


@pytest.mark.parametrize("shape", [(517, 389, 3), (300, 200, 4), (64, 1), (1, 64)])
def test_strip_wise_remap_equals_one_shot_exactly(shape):
    image = np.random.default_rng(1).integers(0, 256, shape, dtype=np.uint8)
    one_shot = rectify_with_map(image, warp(), strip_rows=shape[0])
    for strip_rows in (1, 7, 64):
        assert np.array_equal(rectify_with_map(image, warp(), strip_rows=strip_rows), one_shot)


def test_strip_wise_map_matches_resize_then_box_blur(report_difference):
    """The reference builds the map with cv2.resize + cv2.blur on the whole photo."""
    height, width = 731, 540
    reference = []
    for channel, size in ((0, width), (1, height)):
        resized = cv2.resize(np.ascontiguousarray(warp()[:, :, channel]), (width, height))
        reference.append((cv2.blur(resized, (3, 3)) + 1) / 2 * (size - 1))
    worst = float(np.abs(photo_map(warp(), height, width) - np.stack(reference, 2)).max())
    report_difference("strip-wise photo map vs cv2.resize + cv2.blur", worst, 1e-3)
    assert worst < 1e-3


def test_rgba_keeps_alpha_remapped_like_the_colour(tiny_onnx, document_photo, tmp_path):
    rgba = cv2.cvtColor(document_photo, cv2.COLOR_BGR2BGRA)
    rgba[:, : rgba.shape[1] // 2, 3] = 80  # a half-transparent left half
    out = Rectifier(tiny_onnx).run(rgba)
    assert out.rectified.shape == rgba.shape
    colour_only = rectify_with_map(document_photo, out.backward_map)
    assert np.array_equal(out.rectified[:, :, :3], colour_only)
    assert np.array_equal(out.rectified[:, :, 3], rectify_with_map(rgba[:, :, 3], out.backward_map))
    source, target = tmp_path / "in.png", tmp_path / "out"
    cv2.imwrite(str(source), rgba)
    assert read_image(source).shape[2] == 4
    assert main(["rectify", str(source), "--model", str(tiny_onnx), "-o", str(target)]) == 0
    written = cv2.imread(str(target / "in_rectified.png"), cv2.IMREAD_UNCHANGED)
    assert written.shape[2] == 4 and np.array_equal(written, out.rectified)


def test_jobs_give_the_same_files_as_one_at_a_time(tiny_onnx, document_photo, tmp_path):
    folder = tmp_path / "photos"
    folder.mkdir()
    for i in range(5):
        cv2.imwrite(str(folder / f"p{i}.png"), np.roll(document_photo, 7 * i, axis=1))
    for jobs in ("1", "3"):
        args = ["rectify", str(folder), "--model", str(tiny_onnx), "-o", str(tmp_path / jobs)]
        assert main([*args, "--jobs", jobs, "--threads", "1"]) == 0
    for i in range(5):
        a = cv2.imread(str(tmp_path / "1" / f"p{i}_rectified.png"))
        assert np.array_equal(a, cv2.imread(str(tmp_path / "3" / f"p{i}_rectified.png")))


@pytest.mark.parametrize(
    "flag, value",
    [
        *[(f, v) for f in ("--threads", "--jobs") for v in ("0", "-3", "two")],
        ("--map-smoothing", "-1"),
        ("--map-smoothing", "nan"),
        ("--map-smoothing", "soft"),
    ],
)
def test_counts_must_be_positive(flag, value, tiny_onnx, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["rectify", str(tmp_path), "--model", str(tiny_onnx), "-o", "o", flag, value])
    assert stop.value.code == 2
    assert flag in capsys.readouterr().err


def test_one_run_and_no_smoothing_is_the_reference_post_processing(
    tiny_onnx, document_photo, tmp_path
):
    source = tmp_path / "p.png"
    cv2.imwrite(str(source), document_photo)
    args = ["rectify", str(source), "--model", str(tiny_onnx), "-o"]
    raw_args = ["--map-smoothing", "0", "--no-flip-average", "--no-line-alignment"]
    assert main([*args, str(tmp_path / "raw.png"), *raw_args]) == 0
    assert main([*args, str(tmp_path / "default.png")]) == 0
    rectifier = Rectifier(tiny_onnx)
    raw = rectify_with_map(document_photo, rectifier.predict_map(document_photo))
    assert np.array_equal(cv2.imread(str(tmp_path / "raw.png")), raw)
    # The default flip-averages, smooths and aligns the text lines of the map it uses.
    result = rectifier.run(document_photo)
    batch = model_input(document_photo, rectifier.input_size)
    mirrored = rectifier.predict_map(document_photo[:, ::-1])
    averaged = flip_averaged_map(rectifier.predict_map(document_photo), mirrored)
    assert np.abs(rectifier.model_map(batch) - averaged).max() < 1e-5  # resize is symmetric
    smoothed = smooth_backward_map(rectifier.model_map(batch))
    assert np.array_equal(result.backward_map, align_text_lines(document_photo, smoothed))
    assert np.array_equal(cv2.imread(str(tmp_path / "default.png")), result.rectified)


def test_saved_map_is_the_remap_map(tiny_onnx, document_photo, tmp_path):
    source = tmp_path / "p.png"
    cv2.imwrite(str(source), document_photo)
    out = tmp_path / "o"
    assert (
        main(["rectify", str(source), "--model", str(tiny_onnx), "-o", str(out), "--save-map"]) == 0
    )
    saved = np.load(out / "p_map.npy")
    expected = Rectifier(tiny_onnx).run(document_photo).photo_map()
    assert saved.dtype == np.float32 and np.array_equal(saved, expected)
    assert not list(out.glob(".*tmp"))


def test_works_from_the_repository_root():
    """The source folder doctrpp/ must not hide the stage packages (export/, runtime/, ...)."""
    code = "import doctrpp.runtime, doctrpp.benchmarks, doctrpp.udir; print('ok')"
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True)
    assert done.returncode == 0 and "ok" in done.stdout, done.stderr
    done = subprocess.run(
        [sys.executable, "-m", "doctrpp", "--help"], cwd=REPO, capture_output=True, text=True
    )
    assert done.returncode == 0 and "rectify" in done.stdout, done.stderr


def test_every_option_has_help_and_the_readme_lists_every_command():
    from doctrpp.cli import build_parser

    parser = build_parser()
    readme = (REPO / "README.md").read_text()
    commands = parser._subparsers._group_actions[0].choices
    for name, sub in commands.items():
        assert f"doctrpp {name}" in readme, f"README does not list `doctrpp {name}`"
        for action in sub._actions:
            if action.option_strings and action.dest != "help":
                assert action.help, f"doctrpp {name} {action.option_strings[0]} has no help"
        sub.format_help()  # no stray %% or format errors
        assert "%%" not in sub.format_help()
