"""The `doctrpp` command line, end to end on a tiny model."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
import pytest

from doctrpp import __version__
from doctrpp.cli import main


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    # Run outside the source tree, so the installed package is what gets imported.
    return subprocess.run(
        [sys.executable, "-m", "doctrpp", *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd or tempfile.gettempdir(),
    )


def test_version_and_help():
    assert __version__ in run_cli("--version").stdout
    help_text = run_cli("--help").stdout
    assert "export" in help_text and "rectify" in help_text


def test_export_random_tiny_says_so(tmp_path):
    done = run_cli("export", "--random-weights", "0", "--config", "tiny", "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert "RANDOM WEIGHTS" in done.stdout
    assert "parity ONNX vs PyTorch: largest difference" in done.stdout
    assert (tmp_path / "doctrpp_fp32.onnx").is_file()


def test_export_bad_checkpoint_one_line(tmp_path):
    ckpt = tmp_path / "bad.pth"
    ckpt.write_bytes(b"garbage")
    done = run_cli("export", "--checkpoint", str(ckpt), "--out", str(tmp_path / "o"))
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0
    assert "not a PyTorch checkpoint" in done.stderr


@pytest.fixture
def photos(tmp_path, document_photo):
    folder = tmp_path / "photos"
    folder.mkdir()
    cv2.imwrite(str(folder / "a.jpg"), document_photo)
    cv2.imwrite(str(folder / "a.png"), document_photo)
    cv2.imwrite(str(folder / "gray.png"), cv2.cvtColor(document_photo, cv2.COLOR_BGR2GRAY))
    (folder / "broken.jpg").write_bytes(b"not an image")
    (folder / "notes.txt").write_text("ignored")
    return folder


def test_rectify_folder_continues_past_bad_file(tiny_onnx, photos, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["rectify", str(photos), "--model", str(tiny_onnx), "-o", str(out), "--save-map"])
    captured = capsys.readouterr()
    assert code == 1
    assert "broken.jpg: not a readable image" in captured.err
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "a_map.npy",
        "a_png_map.npy",
        "a_png_rectified.png",
        "a_rectified.png",
        "gray_map.npy",
        "gray_rectified.png",
    ]
    gray = cv2.imread(str(out / "gray_rectified.png"), cv2.IMREAD_UNCHANGED)
    assert gray.shape == (300, 240)
    full_map = np.load(out / "gray_map.npy")
    assert full_map.shape == (300, 240, 2) and full_map.dtype == np.float32


def test_rectify_single_file_to_image_path(tiny_onnx, photos, tmp_path):
    target = tmp_path / "result.png"
    code = main(["rectify", str(photos / "a.jpg"), "--model", str(tiny_onnx), "-o", str(target)])
    assert code == 0 and target.is_file()


def test_rectify_never_overwrites_input(tiny_onnx, photos, capsys):
    before = (photos / "a.png").read_bytes()
    code = main(
        ["rectify", str(photos / "a.png"), "--model", str(tiny_onnx), "-o", str(photos / "a.png")]
    )
    assert code == 2
    assert "would overwrite an input" in capsys.readouterr().err
    assert (photos / "a.png").read_bytes() == before


def test_rectify_errors(tiny_onnx, photos, tmp_path, capsys):
    assert (
        main(
            [
                "rectify",
                str(tmp_path / "absent.jpg"),
                "--model",
                str(tiny_onnx),
                "-o",
                str(tmp_path / "o"),
            ]
        )
        == 2
    )
    assert (
        main(
            [
                "rectify",
                str(photos / "a.jpg"),
                "--model",
                str(tmp_path / "absent.onnx"),
                "-o",
                str(tmp_path / "o"),
            ]
        )
        == 2
    )
    assert (
        main(["rectify", str(photos), "--model", str(tiny_onnx), "-o", str(tmp_path / "one.png")])
        == 2
    )
    err = capsys.readouterr().err
    assert "no such file or folder" in err and "model not found" in err


def test_embedded_default_used_without_checkpoint_or_model(
    tiny_checkpoint, photos, tmp_path, monkeypatch, capsys
):
    monkeypatch.setenv("DOCTRPP_DEFAULT_WEIGHTS", str(tiny_checkpoint))
    assert main(["export", "--out", str(tmp_path / "exported")]) == 0
    assert "embedded default" in capsys.readouterr().out
    out = tmp_path / "r.png"
    assert main(["rectify", str(photos / "a.jpg"), "-o", str(out)]) == 0  # the shipped file
    assert out.is_file()


def test_no_default_weights_is_a_clear_error(monkeypatch, tmp_path, capsys):
    from doctrpp.export import default_weights

    monkeypatch.delenv("DOCTRPP_DEFAULT_WEIGHTS", raising=False)
    monkeypatch.setattr(default_weights, "WEIGHTS_DIR", tmp_path)
    assert main(["export", "--out", str(tmp_path / "o")]) == 2
    assert "no trained default weights" in capsys.readouterr().err
