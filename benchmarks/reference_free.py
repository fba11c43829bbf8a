"""Reference-free scores of a rectification (real photos have no flat scan to compare with).

- `black_share`: share of the output sampled from outside the photo (black in the result).
- `line_straightness`: how straight and level text lines are, from projection profiles:
  in narrow vertical bands, straight horizontal lines of text give a row profile of ink
  with sharp peaks and empty gaps (high contrast); tilted or curved lines smear it.
  Compared with the untouched photo's, the ratio says whether rectification helped.
  It cannot see content that was cut away, page edges, or distortions along lines
  (horizontal stretching); it is only meaningful on pages with text lines.
- `line_coherence`: how well text lines line up across the whole width: the ink row
  profile of the full width against the mean of the narrow bands' profiles (contrast
  ratio, 1 = every band's lines sit at the same heights). Narrow bands only see local
  tilt; curved or wavy lines that are locally straight still smear the full-width
  profile, so this is the one that sees curls (on generated crops the ground-truth
  rectification raises it in 30 of 40, by 28% on average; straightness by 14%).
  Multi-column pages with staggered baselines score lower even when flat: compare
  ratios to the untouched crop, not absolute values.
- `kept_share`: share of the photo that the output samples (a rectification of a crop
  without page edges should keep nearly all of it).
"""

from __future__ import annotations

import cv2
import numpy as np

from doctrpp.runtime.line_alignment import PROFILE_SMOOTHING, ink_mask

from .map_shape import nonprojective_px

SCORE_SIZE = 576  # images are scored at this square size
BANDS = 8  # vertical bands for projection profiles


def black_share(backward_map: np.ndarray) -> float:
    """Share of output pixels whose (normalised, align_corners) source lies outside."""
    outside = (np.abs(backward_map[..., 0]) > 1) | (np.abs(backward_map[..., 1]) > 1)
    return float(outside.mean())


def kept_share(backward_map: np.ndarray, grid: int = 96) -> float:
    """Share of the photo (on a grid x grid raster) that some output pixel samples."""
    points = (backward_map.reshape(-1, 2) + 1) / 2 * (grid - 1)
    inside = np.all((points >= 0) & (points <= grid - 1), axis=1)
    cells = np.zeros((grid, grid), np.uint8)
    xy = np.round(points[inside]).astype(int)
    cells[xy[:, 1], xy[:, 0]] = 1
    cells = cv2.morphologyEx(cells, cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
    return float(cells.mean())


def _ink(image: np.ndarray) -> np.ndarray:
    gray = image if image.ndim == 2 else cv2.cvtColor(image[:, :, :3], cv2.COLOR_BGR2GRAY)
    return ink_mask(cv2.resize(gray, (SCORE_SIZE, SCORE_SIZE), interpolation=cv2.INTER_AREA))


def _profile_contrast(profile: np.ndarray) -> float:
    profile = np.convolve(profile, PROFILE_SMOOTHING, mode="same")
    return float(profile.std() / (profile.mean() + 1e-6))


def _band_contrasts(ink: np.ndarray) -> list[float]:
    width = SCORE_SIZE // BANDS
    bands = [ink[:, b * width : (b + 1) * width].mean(axis=1) for b in range(BANDS)]
    return [_profile_contrast(p) for p in bands if p.mean() >= 0.01]  # bands with text


def line_straightness(image: np.ndarray) -> float:
    """Mean over vertical bands of the row-profile contrast of ink (0 = no lines)."""
    scores = _band_contrasts(_ink(image))
    return float(np.mean(scores)) if scores else 0.0


def line_coherence(image: np.ndarray) -> float:
    """Full-width row-profile contrast / mean band contrast (0 = no lines)."""
    ink = _ink(image)
    bands = _band_contrasts(ink)
    if not bands:
        return 0.0
    return _profile_contrast(ink.mean(axis=1)) / max(float(np.mean(bands)), 1e-6)


LINE_SCORES = {"straightness": line_straightness, "coherence": line_coherence}


def line_scores(image: np.ndarray) -> dict[str, float]:
    return {name: score(image) for name, score in LINE_SCORES.items()}


def rectification_scores(
    rectified: np.ndarray, backward_map: np.ndarray, untouched_lines: dict[str, float]
) -> dict[str, float]:
    """One rectified crop: black and kept share, the map's non-projective part (px of its
    grid: how much it does beyond a perspective), and each line score beside the untouched
    crop's (`line_scores` of it, computed once by the caller)."""
    scores = {
        "black_share": black_share(backward_map),
        "kept_share": kept_share(backward_map),
        "nonprojective_px": nonprojective_px(backward_map),
    }
    for name, value in line_scores(rectified).items():
        scores[name] = value
        scores[f"untouched_{name}"] = untouched_lines[name]
    return scores


def summarise(rows: list[dict[str, float]]) -> dict[str, float]:
    """Means over crops; each line score as a ratio of means, result over untouched crop."""
    means = {key: float(np.mean([row[key] for row in rows])) for key in rows[0]}
    for name in LINE_SCORES:
        if name in means:
            untouched = means.pop(f"untouched_{name}")
            means[f"{name}_ratio"] = means.pop(name) / max(untouched, 1e-6)
    return means
