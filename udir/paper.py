"""Paper and print: ink on a white canvas becomes a printed sheet; photo-like pictures."""

from __future__ import annotations

import cv2
import numpy as np

from . import ranges


def smooth_noise(rng: np.random.Generator, h: int, w: int, cells: int) -> np.ndarray:
    coarse = rng.standard_normal((cells, cells)).astype(np.float32)
    return cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)


def paper_colour(rng: np.random.Generator) -> np.ndarray:
    roll = rng.random()
    if roll < ranges.PAPER_WHITE_SHARE:
        return np.array([rng.uniform(*ranges.PAPER_WHITE)] * 3) + rng.uniform(-3, 3, 3)
    if roll < (1 + ranges.PAPER_WHITE_SHARE) / 2:  # cream / recycled (BGR: less blue)
        grey = rng.uniform(205, 245)
        return np.array([grey - rng.uniform(10, 35), grey - rng.uniform(0, 12), grey])
    return rng.permutation([rng.uniform(190, 235), rng.uniform(215, 250), rng.uniform(225, 252)])


def print_on_paper(rng: np.random.Generator, canvas: np.ndarray) -> np.ndarray:
    """Ink (canvas, white = no ink) printed on textured paper; BGR uint8 out."""
    h, w = canvas.shape[:2]
    scale = max(h, w) / ranges.PAGE_LONG_SIDE
    ink = 1.0 - canvas.astype(np.float32) / 255.0  # absorbance per channel
    bleed = rng.uniform(*ranges.INK_BLEED_SIGMA) * scale
    if bleed > 0.2:
        ink = cv2.GaussianBlur(ink, (0, 0), bleed)
    density = rng.uniform(*ranges.PRINT_NOISE)
    if density > 0:
        speckle = rng.standard_normal((h // 2 + 1, w // 2 + 1)).astype(np.float32)
        ink *= np.clip(1 + density * cv2.resize(speckle, (w, h))[..., None], 0, 1.3)
    paper = np.broadcast_to(paper_colour(rng).astype(np.float32), (h, w, 3)).copy()
    fibre = rng.standard_normal((h, w)).astype(np.float32)
    fibre = cv2.GaussianBlur(fibre, (0, 0), 0.8 * scale) * rng.uniform(*ranges.PAPER_FIBRE_SIGMA)
    blotch = smooth_noise(rng, h, w, int(rng.integers(4, 12))) * rng.uniform(0, 4)
    paper += (fibre + blotch)[..., None]
    if rng.random() < 0.25:  # recycled: dark specks
        for _ in range(int(rng.integers(10, 200))):
            x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
            cv2.circle(paper, (x, y), int(rng.integers(0, 2)), (90.0, 90.0, 90.0), -1)
    if rng.random() < ranges.SHOW_THROUGH_SHARE:  # the other side, mirrored, through the paper
        other = cv2.GaussianBlur(ink.mean(-1), (0, 0), 1.5 * scale)[:, ::-1]
        other = np.roll(other, int(rng.integers(-h // 8, h // 8)), axis=0)
        paper *= 1 - rng.uniform(*ranges.SHOW_THROUGH) * other[..., None]
    return np.clip(paper * (1 - ink) + 0.5, 0, 255).astype(np.uint8)


def reversed_print(rng: np.random.Generator, page: np.ndarray) -> np.ndarray:
    """A printed page's tones reversed between a dark flood colour and light lettering, as
    in print that floods the sheet and leaves the letters paper-coloured (pictures come out
    as negatives); paper texture and print noise carry over."""
    flood = np.clip(rng.uniform(*ranges.REVERSED_FLOOD) + rng.uniform(-8, 8, 3), 0, 255)
    letters = np.clip(rng.uniform(*ranges.REVERSED_LETTERS) + rng.uniform(-6, 6, 3), 0, 255)
    tone = page.astype(np.float32) / 255.0
    out = letters.astype(np.float32) - (letters - flood).astype(np.float32) * tone
    return np.clip(out + 0.5, 0, 255).astype(np.uint8)


def _muted_colour(rng: np.random.Generator, accent: bool = False) -> np.ndarray:
    """A BGR colour (float 0-255): muted, or saturated for an accent."""
    saturation = rng.uniform(0.6, 0.95) if accent else rng.uniform(*ranges.PHOTO_SATURATION)
    hsv = np.array(
        [[[rng.uniform(0, 180), saturation * 255, rng.uniform(*ranges.PHOTO_VALUE) * 255]]]
    )
    return cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2BGR)[0, 0].astype(np.float32)


def _lit(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A brightness factor (h, w, 1) that changes linearly across the picture."""
    angle = rng.uniform(0, 2 * np.pi)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    ramp = (np.cos(angle) * xs / w + np.sin(angle) * ys / h).astype(np.float32)
    ramp -= ramp.mean()
    return (1 + rng.uniform(*ranges.PHOTO_LIGHT) * ramp)[..., None]


def _object_mask(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A filled ellipse, box or polygon (float mask 0-1, antialiased)."""
    mask = np.zeros((h, w), np.uint8)
    cx, cy = int(rng.integers(0, w)), int(rng.integers(h // 4, h))
    size = np.exp(rng.uniform(np.log(0.03), np.log(0.35)))  # many small, a few large
    ax = max(2, int(w * size * rng.uniform(0.5, 1.5)))
    ay = max(2, int(h * size * rng.uniform(0.8, 2.5)))
    shape = rng.random()
    if shape < 0.4:
        cv2.ellipse(
            mask, (cx, cy), (ax, ay), float(rng.uniform(-20, 20)), 0, 360, 255, -1, cv2.LINE_AA
        )
    elif shape < 0.8:
        cv2.rectangle(mask, (cx - ax, cy - ay), (cx + ax, cy + ay), 255, -1, cv2.LINE_AA)
    else:
        angles = np.sort(rng.uniform(0, 2 * np.pi, int(rng.integers(3, 7))))
        points = np.stack([cx + ax * np.cos(angles), cy + ay * np.sin(angles)], 1)
        cv2.fillPoly(mask, [points.astype(np.int32)], 255, cv2.LINE_AA)
    return mask.astype(np.float32)[..., None] / 255.0


def _label(rng: np.random.Generator, surface: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """`surface` with a light band across the object's middle carrying a few dark strokes."""
    ys, xs = np.nonzero(mask[..., 0] > 0.5)
    if len(ys) < 16:
        return surface
    top, bottom, left, right = ys.min(), ys.max(), xs.min(), xs.max()
    band_top = int(top + (bottom - top) * rng.uniform(0.2, 0.5))
    band_bottom = int(band_top + (bottom - top) * rng.uniform(0.15, 0.4))
    labelled = surface.copy()
    labelled[band_top:band_bottom, left:right] = _muted_colour(rng) * 0.3 + 170
    stroke = max(1, (band_bottom - band_top) // 6)
    ink = _muted_colour(rng, accent=rng.random() < 0.5) * 0.4
    for y in range(band_top + stroke, band_bottom - stroke, 2 * stroke + 1):
        end = int(left + (right - left) * rng.uniform(0.3, 0.9))
        labelled[y : y + stroke, left + stroke : end] = ink
    return labelled


def photo(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A photo-like picture: a lit backdrop (maybe over a floor or table), a few shaded
    objects with soft shadows, grain; muted colours, sometimes black and white (BGR uint8)."""
    h, w = max(h, 1), max(w, 1)
    image = np.broadcast_to(_muted_colour(rng), (h, w, 3)) * _lit(rng, h, w)
    if rng.random() < ranges.PHOTO_GROUND_SHARE:
        cut = int(h * rng.uniform(0.45, 0.8))
        image[cut:] = _muted_colour(rng) * _lit(rng, h - cut, w)
    shadow_shift = rng.uniform(-0.03, 0.03, 2) * (w, h)
    for _ in range(int(rng.integers(*ranges.PHOTO_OBJECTS))):
        mask = _object_mask(rng, h, w)
        shadow = cv2.GaussianBlur(
            np.roll(mask[..., 0], (int(shadow_shift[1]), int(shadow_shift[0])), (0, 1)),
            (0, 0),
            max(1.0, min(h, w) / 40),
        )[..., None]
        image = image * (1 - rng.uniform(0.2, 0.5) * shadow)
        accent = rng.random() < ranges.PHOTO_ACCENT_SHARE
        surface = _muted_colour(rng, accent) * _lit(rng, h, w)
        if rng.random() < ranges.PHOTO_LABEL_SHARE:  # a label or print on the object
            surface = _label(rng, surface, mask)
        image = image * (1 - mask) + surface * mask
    image = cv2.GaussianBlur(image.astype(np.float32), (0, 0), max(0.5, min(h, w) / 400))
    if rng.random() < ranges.PHOTO_GREY_SHARE:
        image = np.repeat(image.mean(-1, keepdims=True), 3, -1)
    grain = rng.standard_normal((h, w, 1)).astype(np.float32) * rng.uniform(*ranges.PHOTO_GRAIN)
    return np.clip(image + grain, 0, 255).astype(np.uint8)
