"""Lighting and camera effects, drawn once per scene as plain parameters, applied anywhere."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Look:
    light: tuple[float, float, float]  # direction towards the light (camera coordinates)
    ambient: float
    gradient: tuple[float, float, float]  # multiplicative ramp: angle, low, high
    shadow: tuple[float, ...]  # () or (x0, y0, x1, y1 in [0,1] of the crop, strength, softness)
    highlight: tuple[float, ...]  # () or (x, y, radius, strength)
    colour_cast: tuple[float, float, float]
    blur_sigma: float  # at 288 px; scaled with the output size
    motion: tuple[float, ...]  # () or (length at 288 px, angle)
    noise_sigma: float
    jpeg_quality: int  # 0 = no JPEG


def random_look(rng: np.random.Generator) -> Look:
    light = np.array([rng.normal(0, 0.5), rng.normal(0, 0.5), -1.0])
    light /= np.linalg.norm(light)
    shadow: tuple[float, ...] = ()
    if rng.random() < 0.35:
        shadow = (*rng.uniform(-0.2, 1.2, 4), rng.uniform(0.45, 0.85), rng.uniform(0.01, 0.12))
    highlight: tuple[float, ...] = ()
    if rng.random() < 0.2:
        highlight = (*rng.uniform(0, 1, 2), rng.uniform(0.1, 0.5), rng.uniform(20, 80))
    motion: tuple[float, ...] = ()
    if rng.random() < 0.12:
        motion = (rng.uniform(2, 7), rng.uniform(0, 180))
    return Look(
        light=tuple(float(c) for c in light),
        ambient=float(rng.uniform(0.45, 0.85)),
        gradient=(
            float(rng.uniform(0, 2 * np.pi)),
            float(rng.uniform(0.7, 1.0)),
            float(rng.uniform(1.0, 1.12)),
        ),
        shadow=tuple(float(c) for c in shadow),
        highlight=tuple(float(c) for c in highlight),
        colour_cast=tuple(float(c) for c in rng.uniform(0.88, 1.1, 3)),
        blur_sigma=float(rng.uniform(0.3, 1.4) if rng.random() < 0.45 else 0.0),
        motion=tuple(float(c) for c in motion),
        noise_sigma=float(rng.uniform(0.5, 7.0)),
        jpeg_quality=int(rng.integers(35, 96)) if rng.random() < 0.6 else 0,
    )


def shading(look: Look, normals: np.ndarray, flat_normal: np.ndarray) -> np.ndarray:
    """Lambertian shading of the page relative to the undeformed page (1 = unchanged)."""
    light = np.asarray(look.light)
    lit = look.ambient + (1 - look.ambient) * np.clip(-(normals @ light), 0, 1)
    reference = look.ambient + (1 - look.ambient) * max(0.0, float(-(flat_normal @ light)))
    return np.clip(lit / max(reference, 1e-3), 0.3, 1.25).astype(np.float32)


def apply_lighting(look: Look, image: np.ndarray) -> np.ndarray:
    """Gradient, cast shadow and highlight over the whole crop (float32 in, float32 out)."""
    h, w = image.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    xx /= max(w - 1, 1)
    yy /= max(h - 1, 1)
    angle, low, high = look.gradient
    t = np.clip(0.5 + (xx - 0.5) * np.cos(angle) + (yy - 0.5) * np.sin(angle), 0, 1)
    factor = low + (high - low) * t
    if look.shadow:
        x0, y0, x1, y1, strength, softness = look.shadow
        # A half-plane shadow through two points, with a soft edge.
        side = (x1 - x0) * (yy - y0) - (y1 - y0) * (xx - x0)
        side /= np.hypot(x1 - x0, y1 - y0) + 1e-6
        inside = 0.5 * (1 + np.tanh(side / (2 * max(softness, 1e-3))))  # sigmoid, no overflow
        factor = factor * (1 - (1 - strength) * inside)
    out = image * factor[..., None]
    if look.highlight:
        x, y, radius, strength = look.highlight
        glare = strength * np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * radius**2))
        out = out + glare[..., None]
    return out * np.asarray(look.colour_cast, np.float32)


def apply_camera(look: Look, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Blur, noise and JPEG; float32 BGR in [0, 255] in, uint8 out."""
    scale = max(image.shape[:2]) / 288.0
    if look.blur_sigma > 0:
        image = cv2.GaussianBlur(image, (0, 0), look.blur_sigma * scale)
    if look.motion:
        length, angle = look.motion
        size = max(3, int(length * scale) | 1)
        kernel = np.zeros((size, size), np.float32)
        kernel[size // 2, :] = 1.0
        rotation = cv2.getRotationMatrix2D((size / 2 - 0.5, size / 2 - 0.5), angle, 1.0)
        kernel = cv2.warpAffine(kernel, rotation, (size, size))
        image = cv2.filter2D(image, -1, kernel / max(kernel.sum(), 1e-6))
    if look.noise_sigma > 0:
        image = image + rng.normal(0, look.noise_sigma, image.shape).astype(np.float32)
    out = np.clip(image + 0.5, 0, 255).astype(np.uint8)
    if look.jpeg_quality:
        ok, data = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, look.jpeg_quality])
        if ok:
            out = cv2.imdecode(data, cv2.IMREAD_COLOR)
    return out
