"""Backgrounds behind the page: tables, wood, fabric, clutter and other papers."""

from __future__ import annotations

import cv2
import numpy as np


def _smooth_noise(rng: np.random.Generator, h: int, w: int, cells: int) -> np.ndarray:
    coarse = rng.random((cells, cells)).astype(np.float32)
    return cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)


def _colour(rng: np.random.Generator, dark: bool = False) -> np.ndarray:
    """Mostly muted colours, as on desks and floors (saturated ones are rarer)."""
    top = 150 if dark else 255
    colour = rng.uniform(20, top, 3)
    grey = colour.mean()
    muted = rng.uniform(0.2, 0.7) if rng.random() < 0.8 else 1.0
    return (grey + (colour - grey) * muted).astype(np.float32)


def wood(rng, h, w):
    base = np.array([rng.uniform(20, 70), rng.uniform(50, 110), rng.uniform(90, 170)], np.float32)
    angle = rng.uniform(0, np.pi)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    across = xx * np.cos(angle) + yy * np.sin(angle)
    warp = _smooth_noise(rng, h, w, 6) * rng.uniform(10, 40)
    rings = 0.5 + 0.5 * np.sin((across + warp) * rng.uniform(0.08, 0.35))
    shade = 0.75 + 0.35 * rings[..., None]
    return base * shade


def solid(rng, h, w):
    colour = _colour(rng, dark=rng.random() < 0.5)
    grain = rng.normal(0, rng.uniform(1, 8), (h, w, 1)).astype(np.float32)
    return colour + grain + (_smooth_noise(rng, h, w, 4)[..., None] - 0.5) * 30


def fabric(rng, h, w):
    colour = _colour(rng)
    weave = rng.normal(0, 1, (h, w)).astype(np.float32)
    weave = cv2.GaussianBlur(weave, (0, 0), rng.uniform(0.6, 2.0))
    return colour * (1 + 0.25 * weave[..., None])


def gradient(rng, h, w):
    a, b = _colour(rng), _colour(rng)
    t = np.linspace(0, 1, w if rng.random() < 0.5 else h, dtype=np.float32)
    ramp = t[None, :, None] if len(t) == w else t[:, None, None]
    return np.broadcast_to(a + (b - a) * ramp, (h, w, 3)).copy()


def add_clutter(rng: np.random.Generator, image: np.ndarray) -> None:
    """Other papers, pens and objects lying around (in place)."""
    h, w = image.shape[:2]
    for _ in range(int(rng.integers(1, 7))):
        kind = rng.integers(0, 3)
        centre = (float(rng.uniform(0, w)), float(rng.uniform(0, h)))
        if kind == 0:  # another sheet of paper, maybe with lines of "text"
            size = (float(rng.uniform(0.2, 0.8) * w), float(rng.uniform(0.2, 0.8) * h))
            box = cv2.boxPoints((centre, size, float(rng.uniform(0, 180)))).astype(np.int32)
            cv2.fillPoly(image, [box], [float(c) for c in rng.uniform(190, 250, 3)], cv2.LINE_AA)
            if rng.random() < 0.6:
                for k in range(int(rng.integers(3, 12))):
                    t = k / 12
                    p0 = box[0] + (box[3] - box[0]) * t + (box[1] - box[0]) * 0.1
                    p1 = p0 + (box[1] - box[0]) * rng.uniform(0.3, 0.8)
                    cv2.line(
                        image,
                        tuple(int(c) for c in p0),
                        tuple(int(c) for c in p1),
                        (60, 60, 60),
                        1,
                        cv2.LINE_AA,
                    )
        elif kind == 1:  # a pen or cable
            angle = rng.uniform(0, np.pi)
            length = rng.uniform(0.2, 0.7) * max(h, w)
            d = np.array([np.cos(angle), np.sin(angle)]) * length / 2
            p0 = tuple(int(c) for c in centre - d)
            p1 = tuple(int(c) for c in centre + d)
            cv2.line(
                image,
                p0,
                p1,
                [float(c) for c in _colour(rng, dark=True)],
                int(rng.integers(2, max(3, h // 30))),
                cv2.LINE_AA,
            )
        else:  # a round or boxy object
            radius = int(rng.uniform(0.05, 0.25) * min(h, w)) + 1
            cv2.circle(
                image,
                (int(centre[0]), int(centre[1])),
                radius,
                [float(c) for c in _colour(rng)],
                -1,
                cv2.LINE_AA,
            )


def wood_grain(rng, h, w):
    """Fine, noise-warped grain along one direction (desks, floors)."""
    base = np.array([rng.uniform(30, 110), rng.uniform(60, 150), rng.uniform(100, 200)], np.float32)
    along = rng.random() < 0.5
    n = w if along else h
    lines = cv2.GaussianBlur(rng.standard_normal((1, n)).astype(np.float32), (0, 0), 1.5)[0]
    lines = lines / (np.abs(lines).max() + 1e-6)
    warp = _smooth_noise(rng, h, w, 5) * rng.uniform(5, 30)
    index = (np.arange(w)[None, :] if along else np.arange(h)[:, None]) + warp
    grain = lines[np.clip(index.astype(int), 0, n - 1)]
    return (
        base
        * (0.85 + 0.15 * grain[..., None])
        * (0.8 + 0.4 * _smooth_noise(rng, h, w, 3)[..., None])
    )


def carpet(rng, h, w):
    colour = _colour(rng)
    pile = rng.standard_normal((h, w, 3)).astype(np.float32) * rng.uniform(10, 35)
    return colour * (0.8 + 0.3 * _smooth_noise(rng, h, w, 6)[..., None]) + pile


def keyboard(rng, h, w):
    """Rows of keys (a laptop beside the page)."""
    dark = rng.random() < 0.6
    body = np.float32(rng.uniform(20, 60) if dark else rng.uniform(170, 220))
    image = np.full((h, w, 3), body, np.float32)
    key = max(4, int(min(h, w) * rng.uniform(0.06, 0.14)))
    gap = max(1, key // 6)
    key_colour = float(body + (25 if dark else -30))
    for row, y in enumerate(range(gap, h, key + gap)):
        shift = (row * key // 3) % (key + gap)
        for x in range(gap - shift, w, key + gap):
            cv2.rectangle(image, (x, y), (x + key, y + key), (key_colour,) * 3, -1)
    angle = rng.uniform(-30, 30)
    rotation = cv2.getRotationMatrix2D((w / 2, h / 2), angle, 1.0)
    return cv2.warpAffine(image, rotation, (w, h), borderMode=cv2.BORDER_REFLECT)


STYLES = {
    "wood": wood,
    "wood_grain": wood_grain,
    "solid": solid,
    "fabric": fabric,
    "carpet": carpet,
    "keyboard": keyboard,
    "gradient": gradient,
}
STYLE_WEIGHTS = (0.08, 0.22, 0.25, 0.13, 0.14, 0.08, 0.1)


def render_background(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A (h, w, 3) float32 BGR background in [0, 255]."""
    style = str(rng.choice(list(STYLES), p=STYLE_WEIGHTS))
    image = np.ascontiguousarray(STYLES[style](rng, h, w), dtype=np.float32)
    if rng.random() < 0.6:
        add_clutter(rng, image)
    return np.clip(image, 0, 255)
