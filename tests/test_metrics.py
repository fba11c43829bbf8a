"""The paper's metrics behave as defined."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from doctrpp.benchmarks import metrics


def textured(height: int = 748, width: int = 800, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    noise = rng.random((height // 8, width // 8)).astype(np.float32)
    image = cv2.resize(noise, (width, height), interpolation=cv2.INTER_CUBIC) * 200 + 25
    return np.clip(image, 0, 255).astype(np.uint8)


def test_identical_images():
    image = cv2.cvtColor(textured(), cv2.COLOR_GRAY2BGR)
    # The published weights sum to 1.0001, so identical images score that.
    perfect = sum(metrics.MS_SSIM_WEIGHTS)
    assert metrics.ms_ssim(image, image) == pytest.approx(perfect, abs=1e-9)
    assert metrics.ms_ssim_masked(image, image) == pytest.approx(perfect, abs=1e-9)
    assert metrics.local_distortion(image, image) < 0.05
    assert metrics.local_distortion_masked(image, image) < 0.05


def test_known_shift_gives_that_local_distortion(report_difference):
    reference = textured(748 + 20, 800 + 20)  # 748 x 800 = 598,400 pixels after the crop
    shift = 3
    ref = reference[10:-10, 10:-10]
    moved = reference[10:-10, 10 - shift : -10 - shift]
    ld = metrics.local_distortion(moved, ref)
    report_difference("LD of a 3 px shift vs 3 px", abs(ld - shift), 0.5)
    assert ld == pytest.approx(shift, abs=0.5)


def test_single_scale_ssim_matches_scikit_image(report_difference):
    structural_similarity = pytest.importorskip("skimage.metrics").structural_similarity
    x = textured(200, 240, seed=1)
    y = cv2.GaussianBlur(x, (0, 0), 1.2)
    y = np.clip(y.astype(int) + np.random.default_rng(2).integers(-9, 9, y.shape), 0, 255)
    y = y.astype(np.uint8)
    _, reference = structural_similarity(
        x,
        y,
        gaussian_weights=True,
        sigma=1.5,
        use_sample_covariance=False,
        data_range=255,
        full=True,
    )
    ours = metrics.ssim_map(x, y)
    interior = (slice(5, -5), slice(5, -5))  # scikit-image pads borders differently
    worst = float(np.abs(ours[interior] - reference[interior]).max())
    report_difference("SSIM map vs scikit-image (interior)", worst, 1e-6, unit="")
    assert worst < 1e-6


def test_ms_ssim_orders_distortions():
    reference = cv2.cvtColor(textured(seed=3), cv2.COLOR_GRAY2BGR)
    mild = cv2.GaussianBlur(reference, (0, 0), 1.0)
    strong = cv2.GaussianBlur(reference, (0, 0), 4.0)
    assert 1.0 > metrics.ms_ssim(mild, reference) > metrics.ms_ssim(strong, reference)


def test_masked_ms_ssim_ignores_black():
    reference = cv2.cvtColor(textured(seed=4), cv2.COLOR_GRAY2BGR)
    rectified = reference.copy()
    rectified[:, :200] = 0  # map pointed outside the photo there
    assert metrics.ms_ssim_masked(rectified, reference) > metrics.ms_ssim(rectified, reference)


def test_rectified_is_resized_to_reference():
    reference = textured(400, 300)
    rectified = cv2.resize(reference, (150, 200))
    assert metrics.ms_ssim(rectified, reference) > 0.8


def test_map_drift():
    g = np.linspace(-1, 1, 288, dtype=np.float32)
    x, y = np.meshgrid(g, g)
    a = np.stack([x, y], -1)
    b = a.copy()
    b[..., 0] += 2 / 287  # one pixel to the right
    drift = metrics.map_drift(a, b)
    assert drift.mean_px == pytest.approx(1.0, abs=1e-4)
    assert drift.max_px == pytest.approx(1.0, abs=1e-4)
    chw = metrics.map_drift(a.transpose(2, 0, 1), b.transpose(2, 0, 1))
    assert chw == drift
    with pytest.raises(ValueError, match="shapes differ"):
        metrics.map_drift(a, a[:10])


def test_edit_distance():
    assert metrics.edit_distance("kitten", "sitting") == 3
    assert metrics.edit_distance("", "abc") == 3
    assert metrics.edit_distance("same", "same") == 0


def test_cer_with_tesseract_or_clear_skip():
    import shutil

    if shutil.which("tesseract") is None:
        with pytest.raises(metrics.TesseractMissing, match="apt-get install tesseract-ocr"):
            metrics.ocr_text(np.zeros((10, 10), np.uint8))
        pytest.skip("tesseract not installed: CER is optional")
    page = np.full((120, 600), 255, np.uint8)
    cv2.putText(page, "HELLO WORLD 123", (10, 80), cv2.FONT_HERSHEY_SIMPLEX, 1.6, 0, 3)
    assert metrics.cer(page, "HELLO WORLD 123") < 0.2


def test_rejects_non_uint8():
    with pytest.raises(ValueError, match="uint8"):
        metrics.ms_ssim(np.zeros((10, 10), np.float32), np.zeros((10, 10), np.uint8))
