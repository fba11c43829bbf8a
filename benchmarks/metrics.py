"""The paper's metrics: MS-SSIM (and masked), local distortion (and masked), map drift, CER.

Conventions follow the DocUNet evaluation that DocTr++ reuses: grayscale; the reference
resized to 598,400 pixels keeping its aspect; the rectified image resized to the
reference; MS-SSIM is the weighted *sum* of SSIM over a 5-level Gaussian pyramid.
LD there uses Matlab SIFT-flow, which is not available here: we use OpenCV's DIS dense
optical flow, so absolute LD values differ from the paper's (trends are comparable).
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

# As published (they sum to 1.0001, so identical images score 1.0001).
MS_SSIM_WEIGHTS = (0.0448, 0.2856, 0.3001, 0.2363, 0.1333)
SSIM_WINDOW = 11  # px, Gaussian window side
SSIM_SIGMA = 1.5  # px
SSIM_K = (0.01, 0.03)  # stabilisers, times the data range
TARGET_AREA = 598_400


def to_gray(image: np.ndarray) -> np.ndarray:
    """uint8 BGR/BGRA/gray -> uint8 gray (Rec. 601 weights, like Matlab's rgb2gray)."""
    if image.dtype != np.uint8:
        raise ValueError(f"metrics take uint8 images, got {image.dtype}")
    if image.ndim == 2:
        return image
    if image.ndim == 3 and image.shape[2] in (3, 4):
        return cv2.cvtColor(image[:, :, :3], cv2.COLOR_BGR2GRAY)
    raise ValueError(f"expected a gray or BGR image, got shape {image.shape}")


def _resize(image: np.ndarray, width: int, height: int) -> np.ndarray:
    shrinking = width * height < image.shape[0] * image.shape[1]
    interpolation = cv2.INTER_AREA if shrinking else cv2.INTER_CUBIC
    return cv2.resize(image, (width, height), interpolation=interpolation)


def prepare_pair(rectified: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gray, reference at 598,400 pixels with its aspect, rectified resized to match."""
    reference = to_gray(reference)
    scale = np.sqrt(TARGET_AREA / (reference.shape[0] * reference.shape[1]))
    height = max(1, int(round(reference.shape[0] * scale)))
    width = max(1, int(round(reference.shape[1] * scale)))
    return _resize(to_gray(rectified), width, height), _resize(reference, width, height)


def ssim(x: np.ndarray, y: np.ndarray, data_range: float = 255.0) -> float:
    """Single-scale SSIM (Wang et al.): Gaussian window sigma 1.5 (11x11), K = 0.01, 0.03."""
    return float(np.mean(ssim_map(x, y, data_range)))


def ssim_map(x: np.ndarray, y: np.ndarray, data_range: float = 255.0) -> np.ndarray:
    """Per-pixel SSIM; borders use replicated pixels (as Matlab's ssim)."""
    x = x.astype(np.float64)
    y = y.astype(np.float64)
    c1, c2 = (SSIM_K[0] * data_range) ** 2, (SSIM_K[1] * data_range) ** 2

    def blur(a):
        window = (SSIM_WINDOW, SSIM_WINDOW)
        return cv2.GaussianBlur(a, window, SSIM_SIGMA, borderType=cv2.BORDER_REPLICATE)

    mu_x, mu_y = blur(x), blur(y)
    var_x = blur(x * x) - mu_x**2
    var_y = blur(y * y) - mu_y**2
    cov = blur(x * y) - mu_x * mu_y
    num = (2 * mu_x * mu_y + c1) * (2 * cov + c2)
    den = (mu_x**2 + mu_y**2 + c1) * (var_x + var_y + c2)
    return num / den


def _ms_ssim_prepared(x: np.ndarray, y: np.ndarray) -> float:
    total = 0.0
    for level, weight in enumerate(MS_SSIM_WEIGHTS):
        total += weight * ssim(x, y)
        if level < len(MS_SSIM_WEIGHTS) - 1:
            x, y = cv2.pyrDown(x), cv2.pyrDown(y)
    return total


def ms_ssim(rectified: np.ndarray, reference: np.ndarray) -> float:
    return _ms_ssim_prepared(*prepare_pair(rectified, reference))


def _black_mask(rectified_gray: np.ndarray) -> np.ndarray:
    return rectified_gray == 0


def ms_ssim_masked(rectified: np.ndarray, reference: np.ndarray) -> float:
    """MS-SSIM-M: the reference zeroed where the rectified image is black."""
    x, y = prepare_pair(rectified, reference)
    y = np.where(_black_mask(x), 0, y).astype(np.uint8)
    return _ms_ssim_prepared(x, y)


def dense_flow(reference: np.ndarray, moving: np.ndarray) -> np.ndarray:
    """(H, W, 2) displacement taking reference pixels to `moving` (OpenCV DIS flow)."""
    dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    return dis.calc(reference, moving, None)


def local_distortion(rectified: np.ndarray, reference: np.ndarray) -> float:
    """LD: mean dense-flow magnitude between reference and rectified (pixels at 598,400 px)."""
    x, y = prepare_pair(rectified, reference)
    return float(np.linalg.norm(dense_flow(y, x), axis=2).mean())


def local_distortion_masked(rectified: np.ndarray, reference: np.ndarray) -> float:
    """LD-M: LD over the pixels where the rectified image is not black."""
    x, y = prepare_pair(rectified, reference)
    keep = ~_black_mask(x)
    y = np.where(keep, y, 0).astype(np.uint8)
    magnitude = np.linalg.norm(dense_flow(y, x), axis=2)
    return float(magnitude[keep].mean()) if keep.any() else float("nan")


@dataclass(frozen=True)
class Drift:
    mean_px: float
    max_px: float


def map_drift(a: np.ndarray, b: np.ndarray) -> Drift:
    """Distance between two normalised backward maps, in pixels of their grid.

    Maps are (S, S, 2) or (2, S, S) with align_corners=True coordinates, so one unit of
    normalised distance is (S - 1) / 2 pixels.
    """
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    if a.shape != b.shape:
        raise ValueError(f"map shapes differ: {a.shape} vs {b.shape}")
    if a.shape[-1] != 2:
        a, b = np.moveaxis(a, -3, -1), np.moveaxis(b, -3, -1)
    scale = (a.shape[-2] - 1) / 2
    distance = np.linalg.norm(a - b, axis=-1) * scale
    return Drift(float(distance.mean()), float(distance.max()))


# -- character error rate -------------------------------------------------------------------
class TesseractMissing(RuntimeError):
    pass


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance (insertions, deletions, substitutions all cost 1)."""
    if len(a) < len(b):
        a, b = b, a
    previous = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        current = [i]
        for j, cb in enumerate(b, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (ca != cb)))
        previous = current
    return previous[-1]


def tesseract(image: np.ndarray, language: str = "eng", *options: str) -> str:
    """What the `tesseract` command prints for `image` (`options` e.g. "tsv");
    TesseractMissing if it is not installed."""
    binary = shutil.which("tesseract")
    if binary is None:
        raise TesseractMissing("tesseract is not installed (Debian: apt-get install tesseract-ocr)")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "page.png"
        cv2.imwrite(str(path), image)
        command = [binary, str(path), "-", "-l", language, *options]
        return subprocess.run(command, capture_output=True, text=True, check=True).stdout


def ocr_text(image: np.ndarray, language: str = "eng") -> str:
    """Text recognised by the `tesseract` command; TesseractMissing if it is not installed."""
    return " ".join(tesseract(image, language).split())


def cer(rectified: np.ndarray, reference: np.ndarray | str) -> float:
    """Character error rate of OCR on `rectified` against the reference image's OCR (or text)."""
    truth = reference if isinstance(reference, str) else ocr_text(reference)
    hypothesis = ocr_text(rectified)
    return edit_distance(hypothesis, truth) / max(len(truth), 1)


def paired_difference(
    kinds: list[str], reference: list[float], candidate: list[float]
) -> dict[str, tuple[float, float]]:
    """Per kind and overall: the mean of candidate - reference over the same crops and its
    standard error, so two weights are compared on each crop rather than by their means."""
    difference = np.asarray(candidate, float) - np.asarray(reference, float)
    kind_of = np.asarray(kinds)
    result = {}
    for kind in [*dict.fromkeys(kinds), "all"]:
        d = difference if kind == "all" else difference[kind_of == kind]
        error = float(d.std(ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("nan")
        result[kind] = (float(d.mean()), error)
    return result
