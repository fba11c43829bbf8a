"""The lean runtime: reference post-processing, input kinds, errors, no torch."""

from __future__ import annotations

import subprocess
import sys

import cv2
import numpy as np
import pytest
import torch
import torch.nn.functional as F

from doctrpp.runtime import ImageError, ModelError, Rectifier, read_image
from doctrpp.runtime.processing import (
    flip_averaged_map,
    model_input,
    photo_map,
    rectify_with_map,
    remap,
    smooth_backward_map,
    unmirror_map,
)


def reference_rectify(photo_bgr: np.ndarray, backward_map: np.ndarray) -> np.ndarray:
    """The authors' inference script: resize + box blur the map, grid_sample, truncate."""
    h, w = photo_bgr.shape[:2]
    bx = cv2.blur(cv2.resize(backward_map[:, :, 0], (w, h)), (3, 3))
    by = cv2.blur(cv2.resize(backward_map[:, :, 1], (w, h)), (3, 3))
    grid = torch.from_numpy(np.stack([bx, by], axis=2)).unsqueeze(0)
    photo = torch.from_numpy(photo_bgr[:, :, ::-1] / 255.0).permute(2, 0, 1)[None].float()
    out = F.grid_sample(photo, grid, align_corners=True)
    return (out[0] * 255).permute(1, 2, 0).numpy()[:, :, ::-1].astype(np.uint8)


def smooth_map(size: int = 288, seed: int = 0) -> np.ndarray:
    """A plausible normalised backward map: identity plus a smooth warp, partly outside."""
    rng = np.random.default_rng(seed)
    g = np.linspace(-1, 1, size, dtype=np.float32)
    x, y = np.meshgrid(g, g)
    bx = 1.05 * x + 0.08 * np.sin(3 * y + rng.random()) + 0.02
    by = 1.03 * y + 0.06 * np.cos(2 * x + rng.random())
    return np.stack([bx, by], axis=2).astype(np.float32)


def test_postprocess_equals_reference_grid_sample(document_photo, report_difference):
    backward_map = smooth_map()
    ours = remap(document_photo, photo_map(backward_map, *document_photo.shape[:2]))
    reference = reference_rectify(document_photo, backward_map)
    worst = int(np.abs(ours.astype(int) - reference.astype(int)).max())
    report_difference("runtime remap vs reference grid_sample", worst, 1, unit="grey levels")
    assert worst <= 1


def test_model_input_matches_reference_preprocessing(document_photo, report_difference):
    """We resize in the photo's depth, the reference resizes a float copy: < 1 grey level."""
    noisy = np.random.default_rng(0).integers(0, 256, (1200, 900, 3), dtype=np.uint8)
    for photo in (document_photo, noisy, noisy.astype(np.uint16) * 257):
        scale = 65535.0 if photo.dtype == np.uint16 else 255.0
        reference = cv2.resize(photo[:, :, ::-1] / scale, (288, 288)).transpose(2, 0, 1)
        ours = model_input(photo, 288)[0]
        assert ours.dtype == np.float32
        worst = float(np.abs(ours - reference).max() * 255)
        report_difference(
            f"model input vs float-first resize ({photo.dtype})", worst, 1.0, unit="grey levels"
        )
        assert worst < 1.0


def test_rectifier_on_tiny_model(tiny_onnx, tiny_model, document_photo):
    rectifier = Rectifier(tiny_onnx, threads=1)
    backward_map = rectifier.predict_map(document_photo)
    assert backward_map.shape == (288, 288, 2)
    with torch.no_grad():
        expected = tiny_model(torch.from_numpy(model_input(document_photo, 288))).numpy()[0]
    expected = ((2 * (expected / 286.8) - 1) * 0.99).transpose(1, 2, 0)
    assert np.abs(backward_map - expected).max() < 1e-5
    result = rectifier.run(document_photo)
    assert result.rectified.shape == document_photo.shape
    assert result.rectified.dtype == np.uint8
    assert set(result.timings) == {"preprocess", "inference", "map", "postprocess"}
    assert result.photo_map().shape == (300, 240, 2)


def test_input_kinds_keep_size_channels_and_depth(tiny_onnx, document_photo, convert_photo):
    image = convert_photo(document_photo)
    rectifier = Rectifier(tiny_onnx)
    out = rectifier.rectify(image)
    assert out.shape == image.shape and out.dtype == image.dtype
    # All kinds feed the model input of the 8-bit BGR photo, within one grey level (each is
    # resized in its own depth).
    base = model_input(document_photo, 288)
    if image.ndim == 3:
        assert np.abs(model_input(image, 288) - base).max() < 1 / 255


def test_bad_arrays_rejected(tiny_onnx):
    rectifier = Rectifier(tiny_onnx)
    with pytest.raises(ValueError, match="dtype"):
        rectifier.rectify(np.zeros((10, 10, 3), np.int32))
    with pytest.raises(ValueError, match="shape"):
        rectifier.rectify(np.zeros((10, 10, 2), np.uint8))


def test_exif_orientation_honoured(tmp_path):
    from PIL import Image

    pixels = np.zeros((40, 80, 3), np.uint8)
    pixels[:, :20] = 255
    image = Image.fromarray(pixels)
    exif = image.getexif()
    exif[0x0112] = 6  # rotate 90 degrees clockwise to display
    path = tmp_path / "rotated.jpg"
    image.save(path, exif=exif)
    loaded = read_image(path)
    assert loaded.shape[:2] == (80, 40)
    assert loaded[:20].mean() > 200 and loaded[-20:].mean() < 50  # white band now on top


def test_unreadable_files(tmp_path):
    (tmp_path / "empty.png").write_bytes(b"")
    (tmp_path / "text.jpg").write_text("hello")
    for name, message in [
        ("empty.png", "empty"),
        ("text.jpg", "not a readable image"),
        ("absent.png", "no such file"),
    ]:
        with pytest.raises(ImageError, match=message) as info:
            read_image(tmp_path / name)
        assert "\n" not in str(info.value)


def test_bad_model_files(tmp_path):
    junk = tmp_path / "junk.onnx"
    junk.write_bytes(b"junk")
    with pytest.raises(ModelError, match="cannot load ONNX model"):
        Rectifier(junk)
    with pytest.raises(ModelError, match="unknown model format"):
        Rectifier(_touch(tmp_path / "m.pt"))
    with pytest.raises(ModelError, match="not found"):
        Rectifier(tmp_path / "absent.onnx")


def _touch(path):
    path.write_bytes(b"x")
    return path


def test_runtime_never_imports_torch(tiny_onnx):
    code = (
        "import sys, numpy as np\n"
        "import doctrpp, doctrpp.runtime, doctrpp.cli\n"
        f"r = doctrpp.runtime.Rectifier({str(tiny_onnx)!r})\n"
        "r.rectify(np.zeros((50, 40, 3), np.uint8))\n"
        "doctrpp.cli.build_parser()\n"
        "assert 'torch' not in sys.modules, 'torch was imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=tiny_onnx.parent)


def test_outputs_get_the_usual_file_mode(tmp_path):
    import os
    import stat

    from doctrpp.files import write_bytes_atomically

    target = tmp_path / "x.bin"
    write_bytes_atomically(target, b"data")
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~mask


def _jagged(size: int = 288, seed: int = 1) -> np.ndarray:
    """A smooth map plus the block-wise jitter our models' convex upsampling leaves."""
    rng = np.random.default_rng(seed)
    jitter = rng.normal(0, 1.0, (size // 8, size // 8, 2)).astype(np.float32)
    jitter = np.repeat(np.repeat(jitter, 8, 0), 8, 1) * (2 / (size - 1))  # ~1 grid px
    return smooth_map(size) + jitter


def _roughness_px(backward_map: np.ndarray) -> float:
    """p99 of the map's Laplacian, in grid pixels."""
    px = (backward_map + 1) * 0.5 * (backward_map.shape[0] - 1)
    lap = px[2:, 1:-1] + px[:-2, 1:-1] + px[1:-1, 2:] + px[1:-1, :-2] - 4 * px[1:-1, 1:-1]
    return float(np.quantile(np.abs(lap), 0.99))


def test_map_smoothing_keeps_smooth_maps_and_removes_jitter(report_difference):
    from doctrpp.contract import identity_map

    identity = identity_map()
    assert np.abs(smooth_backward_map(identity) - identity).max() < 1e-6
    smooth = smooth_map()
    moved = float(np.abs(smooth_backward_map(smooth) - smooth).max() * 143.5)
    report_difference("smooth map, smoothed vs not (grid px)", moved, 0.1)
    assert moved < 0.1
    jagged = _jagged()
    before, after = _roughness_px(jagged), _roughness_px(smooth_backward_map(jagged))
    assert after < before / 5, (before, after)
    assert np.array_equal(smooth_backward_map(jagged, 0), jagged)
    with pytest.raises(ValueError, match="sigma"):
        smooth_backward_map(jagged, -1)


def test_unmirrored_map_rectifies_the_mirrored_photo_as_the_mirror_image(document_photo):
    """unmirror_map is the map of the mirrored photo: rectifying the mirrored photo with it
    gives the mirror image of the rectified photo (exactly, up to interpolation)."""
    backward_map = smooth_map()
    mirrored_map = unmirror_map(backward_map)
    assert np.array_equal(unmirror_map(mirrored_map), backward_map)  # an involution
    rectified = rectify_with_map(document_photo, backward_map).astype(int)
    mirrored = rectify_with_map(np.ascontiguousarray(document_photo[:, ::-1]), mirrored_map)
    assert np.abs(mirrored[:, ::-1].astype(int) - rectified).max() <= 1


def test_flip_average_keeps_a_mirror_consistent_answer(report_difference):
    from doctrpp.contract import identity_map

    identity = identity_map()
    assert np.abs(unmirror_map(identity) - identity).max() < 1e-6
    backward_map = smooth_map()
    # A model that answers the mirrored photo with the mirrored map: nothing changes.
    same = flip_averaged_map(backward_map, unmirror_map(backward_map))
    moved = float(np.abs(same - backward_map).max() * 143.5)
    report_difference("flip average of a mirror-consistent answer (grid px)", moved, 1e-4)
    assert moved < 1e-4
    other = smooth_map(seed=1)
    expected = (backward_map + other) / 2
    assert np.abs(flip_averaged_map(backward_map, unmirror_map(other)) - expected).max() < 1e-6


def test_image_files_lists_image_files_sorted(tmp_path):
    from doctrpp.runtime.imageio import image_files

    for name in ("b.PNG", "a.jpg", "notes.txt"):
        (tmp_path / name).write_bytes(b"x")
    (tmp_path / "folder.png").mkdir()  # a folder named like an image is not one
    assert [p.name for p in image_files(tmp_path)] == ["a.jpg", "b.PNG"]
