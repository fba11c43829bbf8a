"""Text-line alignment: a post-processing step that levels the text lines the model's map
leaves wavy, by shifting the map's rows (MODEL_CARD.md, "Text-line alignment").

The model's maps get the page's position and perspective roughly right but leave part of
the bending: text lines come out bowed or stepped. The rectified result is rendered small
and cut into vertical bands and horizontal windows; in each window, each pair of
neighbouring bands' ink row profiles is cross-correlated (within 0.4 line pitch, so no
line is ever matched to the next), which gives how much the lines climb from one band to
the next. A low-order polynomial of that slope across the width, integrated, is the
vertical offset of the lines in each band; the map samples each column that much
lower or higher. Only neighbours are compared, so columns with staggered baselines are
never forced level with each other; bands without text give no slope, and the offset is
held level beyond the measured span. Pages without text lines come out unchanged.

It can only correct vertical offsets that vary smoothly across the width (bowed,
tilted, folded lines), not stretching along the lines.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

PROFILE_SMOOTHING = np.array([0.25, 0.5, 0.25])  # of row profiles (antialiasing, JPEG)
OUTLIER_PX = 1.0  # a slope this far (px per band) from the first fit may be an outlier


@dataclass(frozen=True)
class LineAlignment:
    """Parameters of `align_text_lines`; the defaults are the runtime's."""

    render_size: int = 512  # px of the square rendering the lines are measured on
    bands: int = 12  # vertical bands across the width
    windows: int = 6  # horizontal windows down the height (overlapping by half)
    iterations: int = 2  # measure and correct again on the corrected rendering
    min_ink: float = 0.02  # share of ink pixels a band needs to be measured
    min_correlation: float = 0.5  # of neighbouring bands' profiles, to count a slope
    degree: int = 2  # of the polynomial fitted to the slope across the width
    max_offset: float = 0.04  # largest offset, share of the height

    def __post_init__(self) -> None:
        if self.render_size < 64 or self.bands < self.degree + 3 or self.windows < 1:
            raise ValueError(f"invalid line alignment parameters: {self}")
        if self.iterations < 0 or not 0 < self.max_offset < 0.5:
            raise ValueError(f"invalid line alignment parameters: {self}")


def gray_uint8(image: np.ndarray, max_side: int) -> np.ndarray:
    """Gray uint8 copy of a photo (gray, BGR or BGRA; uint8, uint16 or float in [0, 1]),
    area-downscaled first so that its longer side is at most `max_side`."""
    height, width = image.shape[:2]
    scale = min(1.0, max_side / max(height, width))
    if scale < 1:
        size = (max(1, round(width * scale)), max(1, round(height * scale)))
        image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
    if image.ndim == 3:
        image = image[:, :, 0] if image.shape[2] == 1 else image[:, :, :3]
    if image.ndim == 3:
        image = cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_BGR2GRAY)
    if image.dtype == np.uint8:
        return image
    top = 65535.0 if image.dtype == np.uint16 else 1.0
    return np.clip(image.astype(np.float32) * (255.0 / top) + 0.5, 0, 255).astype(np.uint8)


def render_gray(gray: np.ndarray, backward_map: np.ndarray, size: int) -> np.ndarray:
    """The rectified gray photo at size x size (bilinear, edges replicated)."""
    height, width = gray.shape
    grid = cv2.resize(np.asarray(backward_map, np.float32), (size, size))
    map_x = (grid[:, :, 0] + 1) * np.float32((width - 1) / 2)
    map_y = (grid[:, :, 1] + 1) * np.float32((height - 1) / 2)
    return cv2.remap(gray, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def ink_mask(gray: np.ndarray) -> np.ndarray:
    """Dark text strokes (float 0/1): darker than the local background by a margin."""
    background = cv2.medianBlur(gray, 31)
    return ((background.astype(np.int16) - gray) > 25).astype(np.float32)


def line_pitch(profile: np.ndarray, shortest: int = 4, longest: int = 80) -> float | None:
    """Distance between text lines: the first clear autocorrelation peak of a row profile
    (the first, not the highest: multiples of the pitch correlate as well), or None where
    there is no periodic structure."""
    centred = profile - profile.mean()
    energy = float(centred @ centred)
    longest = min(longest, len(centred) - 2)
    if energy < 1e-9 or longest <= shortest:
        return None
    lags = np.arange(shortest - 1, longest + 1)
    correlation = np.array([centred[lag:] @ centred[:-lag] for lag in lags]) / energy
    peaks = (correlation[1:-1] > correlation[:-2]) & (correlation[1:-1] >= correlation[2:])
    clear = np.flatnonzero(peaks & (correlation[1:-1] > 0.3))
    return float(lags[clear[0] + 1]) if len(clear) else None


def profile_offset(profile: np.ndarray, reference: np.ndarray, reach: int) -> tuple[float, float]:
    """(d, peak): the shift d in [-reach, reach] (subpixel) for which profile(y + d) best
    matches reference(y), and the normalised correlation there."""
    profile = profile - profile.mean()
    reference = reference - reference.mean()
    n = len(profile)
    scores = np.empty(2 * reach + 1)
    for index, shift in enumerate(range(-reach, reach + 1)):
        moved = profile[shift:] if shift >= 0 else profile[: n + shift]
        still = reference[: n - shift] if shift >= 0 else reference[-shift:]
        norm = np.sqrt(float(moved @ moved) * float(still @ still)) + 1e-9
        scores[index] = float(moved @ still) / norm
    best = int(np.argmax(scores))
    offset = float(best - reach)
    if 0 < best < len(scores) - 1:  # parabola through the peak and its neighbours
        left, peak, right = scores[best - 1 : best + 2]
        curvature = left - 2 * peak + right
        if curvature < 0:
            offset += float(0.5 * (left - right) / curvature)
    return offset, float(scores[best])


def window_offsets(ink: np.ndarray, params: LineAlignment) -> np.ndarray:
    """(bands,) vertical offsets of the text lines in each band of one window (px of the
    rendering, mean 0): band b's lines sit that much lower than the window's mean."""
    width = ink.shape[1] // params.bands
    profiles = [
        np.convolve(ink[:, b * width : (b + 1) * width].mean(axis=1), PROFILE_SMOOTHING, "same")
        for b in range(params.bands)
    ]
    centres = (np.arange(params.bands) + 0.5) / params.bands * 2 - 1  # x in [-1, 1]
    inked = [p.mean() >= params.min_ink for p in profiles]
    pitches = [line_pitch(p) for p, ink_enough in zip(profiles, inked, strict=True) if ink_enough]
    pitches = [p for p in pitches if p is not None]
    if not pitches:
        return np.zeros(params.bands)
    reach = max(1, int(0.4 * float(np.median(pitches))))  # never as far as the next line
    xs, slopes, weights = [], [], []
    for b in range(params.bands - 1):
        if not (inked[b] and inked[b + 1]):
            continue
        step, correlation = profile_offset(profiles[b + 1], profiles[b], reach)
        if correlation >= params.min_correlation:
            xs.append((centres[b] + centres[b + 1]) / 2)
            slopes.append(step)
            weights.append(correlation)
    if len(xs) < params.degree + 2:
        return np.zeros(params.bands)
    xs_arr, slopes_arr, weights_arr = np.asarray(xs), np.asarray(slopes), np.asarray(weights)
    polynomial = np.polynomial.polynomial
    coefficients = polynomial.polyfit(xs_arr, slopes_arr, params.degree, w=weights_arr)
    # A pair that straddles two columns with staggered baselines gives a slope unlike its
    # neighbours': drop the outliers of the fit and fit again, twice.
    inliers = np.ones(len(xs_arr), bool)
    for _ in range(2):
        fit = np.polynomial.polynomial.polyval(xs_arr, coefficients)
        residuals = np.abs(slopes_arr - fit)
        inliers = residuals <= max(OUTLIER_PX, 3 * float(np.median(residuals[inliers])))
        if inliers.sum() < params.degree + 2:
            return np.zeros(params.bands)
        coefficients = np.polynomial.polynomial.polyfit(
            xs_arr[inliers], slopes_arr[inliers], params.degree, w=weights_arr[inliers]
        )
    fine = np.linspace(-1, 1, 201)
    # the slope (px per band) is held beyond the measured span rather than extrapolated
    slope = np.polynomial.polynomial.polyval(
        np.clip(fine, xs_arr.min(), xs_arr.max()), coefficients
    )
    offset = np.concatenate([[0.0], np.cumsum((slope[1:] + slope[:-1]) / 2 * np.diff(fine))])
    offsets = np.interp(centres, fine, offset * params.bands / 2)
    offsets -= offsets.mean()
    limit = params.max_offset * ink.shape[0]
    return np.clip(offsets, -limit, limit)


def offset_field(ink: np.ndarray, params: LineAlignment) -> np.ndarray:
    """(windows, bands) offsets, one row per window (windows overlap by half)."""
    height = 2 * ink.shape[0] // (params.windows + 1)
    return np.stack(
        [
            window_offsets(ink[t * height // 2 : t * height // 2 + height], params)
            for t in range(params.windows)
        ]
    )


def field_on_grid(field: np.ndarray, size: int, render_size: int) -> np.ndarray:
    """(windows, bands) offsets in px of the rendering -> (size, size) normalised offsets,
    interpolated linearly between window and band centres, held beyond them."""
    windows, bands = field.shape
    window_centres = (np.arange(windows) + 1) / (windows + 1)
    band_centres = (np.arange(bands) + 0.5) / bands
    positions = (np.arange(size) + 0.5) / size
    across = np.stack([np.interp(positions, band_centres, row) for row in field])
    grid = np.stack([np.interp(positions, window_centres, column) for column in across.T], axis=1)
    return (grid * (2 / (render_size - 1))).astype(np.float32)


def shift_rows(backward_map: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """new(x, y) = map(x, y + offset(x, y)): `offsets` normalised, (S, S). The map is
    extended beyond its top and bottom by odd reflection, which continues it smoothly."""
    size = backward_map.shape[0]
    pad = size // 4
    padded = np.pad(
        np.asarray(backward_map, np.float32),
        ((pad, pad), (0, 0), (0, 0)),
        "reflect",
        reflect_type="odd",
    )
    columns, rows = np.meshgrid(
        np.arange(size, dtype=np.float32), np.arange(size, dtype=np.float32)
    )
    rows = rows + offsets * np.float32((size - 1) / 2) + np.float32(pad)
    return cv2.remap(padded, columns, rows, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def align_text_lines(
    image: np.ndarray, backward_map: np.ndarray, params: LineAlignment | None = None
) -> np.ndarray:
    """The backward map (S, S, 2, normalised) with its rows shifted so that the text lines
    of the rectified `image` come out level (unchanged where no lines are found)."""
    params = params or LineAlignment()
    backward_map = np.asarray(backward_map, np.float32)
    gray = gray_uint8(image, 2 * params.render_size)
    for _ in range(params.iterations):
        ink = ink_mask(render_gray(gray, backward_map, params.render_size))
        field = offset_field(ink, params)
        if not field.any():
            break
        offsets = field_on_grid(field, backward_map.shape[0], params.render_size)
        backward_map = shift_rows(backward_map, offsets)
    return np.ascontiguousarray(backward_map)
