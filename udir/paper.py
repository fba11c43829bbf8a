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


def photo(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A photo-like picture: smooth colour regions, objects, texture (BGR uint8)."""
    h, w = max(h, 1), max(w, 1)
    field = rng.uniform(0, 255, (int(rng.integers(2, 5)), int(rng.integers(2, 5)), 3))
    image = cv2.resize(field.astype(np.float32), (w, h), interpolation=cv2.INTER_CUBIC)
    if rng.random() < 0.5:  # horizon: sky over ground
        cut = int(h * rng.uniform(0.3, 0.7))
        image[:cut] = image[:cut] * 0.5 + rng.uniform(120, 255, 3).astype(np.float32) * 0.5
    for _ in range(int(rng.integers(1, 7))):
        centre = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        axes = (int(rng.integers(3, w // 2 + 4)), int(rng.integers(3, h // 2 + 4)))
        colour = [float(c) for c in rng.uniform(0, 255, 3)]
        cv2.ellipse(
            image, centre, axes, float(rng.uniform(0, 180)), 0, 360, colour, -1, cv2.LINE_AA
        )
    texture = rng.standard_normal((h, w, 1)).astype(np.float32) * rng.uniform(2, 14)
    image = cv2.GaussianBlur(image, (0, 0), max(1.0, min(h, w) / 60)) + texture
    return np.clip(image, 0, 255).astype(np.uint8)
