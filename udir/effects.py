"""Lighting and camera effects, drawn once per scene as plain parameters, applied anywhere."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from . import ranges


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
    hand_shadow: tuple[float, ...] = ()  # () or (x, y, rx, ry, angle, strength) of the crop
    fingers: tuple[float, ...] = ()  # () or (edge position 0-4, count, length, width, b, g, r)
    vignette: float = 0.0
    edge_defocus: float = 0.0  # blur sigma at the crop corners (at 288 px)


def random_look(rng: np.random.Generator) -> Look:
    light = np.array([*rng.normal(0, ranges.LIGHT_OBLIQUE_SIGMA, 2), -1.0])
    light /= np.linalg.norm(light)
    shadow: tuple[float, ...] = ()
    if rng.random() < ranges.CAST_SHADOW_SHARE:
        shadow = (
            *rng.uniform(-0.2, 1.2, 4),
            rng.uniform(*ranges.CAST_SHADOW_STRENGTH),
            rng.uniform(*ranges.CAST_SHADOW_SOFTNESS),
        )
    highlight: tuple[float, ...] = ()
    if rng.random() < ranges.HIGHLIGHT_SHARE:
        highlight = (
            *rng.uniform(0, 1, 2),
            rng.uniform(*ranges.HIGHLIGHT_RADIUS),
            rng.uniform(*ranges.HIGHLIGHT_STRENGTH),
        )
    motion: tuple[float, ...] = ()
    if rng.random() < ranges.MOTION_SHARE:
        motion = (rng.uniform(*ranges.MOTION_LENGTH), rng.uniform(0, 180))
    hand_shadow: tuple[float, ...] = ()
    if rng.random() < ranges.HAND_SHADOW_SHARE:
        hand_shadow = (
            *rng.uniform(-0.1, 1.1, 2),
            *rng.uniform(0.15, 0.5, 2),
            rng.uniform(0, 180),
            rng.uniform(*ranges.HAND_SHADOW_STRENGTH),
        )
    fingers: tuple[float, ...] = ()
    if rng.random() < ranges.FINGERS_SHARE:
        skin = rng.uniform([110, 140, 180], [180, 195, 240])
        fingers = (
            rng.uniform(0, 4),
            rng.integers(1, 5),
            rng.uniform(0.08, 0.2),
            rng.uniform(0.03, 0.05),
            *skin,
        )
    return Look(
        hand_shadow=tuple(float(c) for c in hand_shadow),
        fingers=tuple(float(c) for c in fingers),
        vignette=float(rng.uniform(*ranges.VIGNETTE)),
        edge_defocus=float(
            rng.uniform(*ranges.EDGE_DEFOCUS_SIGMA)
            if rng.random() < ranges.EDGE_DEFOCUS_SHARE
            else 0.0
        ),
        light=tuple(float(c) for c in light),
        ambient=float(rng.uniform(*ranges.AMBIENT)),
        gradient=(
            float(rng.uniform(0, 2 * np.pi)),
            float(rng.uniform(*ranges.GRADIENT_LOW)),
            float(rng.uniform(*ranges.GRADIENT_HIGH)),
        ),
        shadow=tuple(float(c) for c in shadow),
        highlight=tuple(float(c) for c in highlight),
        colour_cast=tuple(float(c) for c in rng.uniform(*ranges.WHITE_BALANCE, 3)),
        blur_sigma=float(
            rng.uniform(*ranges.BLUR_SIGMA) if rng.random() < ranges.BLUR_SHARE else 0.0
        ),
        motion=tuple(float(c) for c in motion),
        noise_sigma=float(rng.uniform(*ranges.NOISE_SIGMA)),
        jpeg_quality=(
            int(rng.integers(*ranges.JPEG_QUALITY)) if rng.random() < ranges.JPEG_SHARE else 0
        ),
    )


def shading(look: Look, normals: np.ndarray, flat_normal: np.ndarray) -> np.ndarray:
    """Lambertian shading of the page relative to the undeformed page (1 = unchanged).

    Normals face the camera (-Z) and the light direction points towards the light (also
    -Z), so a page part lit head-on has normal . light = 1. (Until session 42 the sign was
    flipped: every part clipped to the ambient term and the page showed no shading at all.)
    """
    light = np.asarray(look.light)
    lit = look.ambient + (1 - look.ambient) * np.clip(normals @ light, 0, 1)
    reference = look.ambient + (1 - look.ambient) * max(0.0, float(flat_normal @ light))
    return np.clip(lit / max(reference, 1e-3), 0.3, 1.25).astype(np.float32)


def apply_lighting(
    look: Look, image: np.ndarray, window: tuple[float, float, float, float] = (0, 0, 1, 1)
) -> np.ndarray:
    """Gradient, cast shadows, vignette and highlight (float32 in, float32 out).

    They are drawn over a frame, the whole photo the crop was cut from, and `window` is the
    crop's part of that frame (x0, y0, x1, y1 in frame fractions). A crop cut from the
    middle of a page sees only part of a shadow or a gradient, as a crop cut from a real
    photo does (until session 43 every crop saw all of them at crop scale).
    """
    h, w = image.shape[:2]
    x0, y0, x1, y1 = window
    xx, yy = np.meshgrid(
        np.linspace(x0, x1, w, dtype=np.float32), np.linspace(y0, y1, h, dtype=np.float32)
    )
    angle, low, high = look.gradient
    t = np.clip(0.5 + (xx - 0.5) * np.cos(angle) + (yy - 0.5) * np.sin(angle), 0, 1)
    factor = low + (high - low) * t
    if look.shadow:
        sx0, sy0, sx1, sy1, strength, softness = look.shadow
        # A half-plane shadow through two points, with a soft edge.
        side = (sx1 - sx0) * (yy - sy0) - (sy1 - sy0) * (xx - sx0)
        side /= np.hypot(sx1 - sx0, sy1 - sy0) + 1e-6
        inside = 0.5 * (1 + np.tanh(side / (2 * max(softness, 1e-3))))  # sigmoid, no overflow
        factor = factor * (1 - (1 - strength) * inside)
    if look.hand_shadow:
        factor = factor * _hand_shadow(look.hand_shadow, xx, yy)
    if look.vignette:
        factor = factor * (1 - look.vignette * ((xx - 0.5) ** 2 + (yy - 0.5) ** 2) * 2)
    out = image * factor[..., None]
    if look.highlight:
        hx, hy, radius, strength = look.highlight
        glare = strength * np.exp(-((xx - hx) ** 2 + (yy - hy) ** 2) / (2 * radius**2))
        out = out + glare[..., None]
    return out * np.asarray(look.colour_cast, np.float32)


def _hand_shadow(params: tuple[float, ...], xx: np.ndarray, yy: np.ndarray) -> np.ndarray:
    """A soft elliptic shadow with finger-like lobes (of a hand or a phone), as a factor at
    frame positions (xx, yy)."""
    x, y, rx, ry, angle, strength = params
    small = np.zeros((64, 64), np.float32)
    centre = (int(x * 64), int(y * 64))
    cv2.ellipse(small, centre, (int(rx * 64) + 1, int(ry * 64) + 1), angle, 0, 360, 1.0, -1)
    direction = np.deg2rad(angle)
    for k in range(4):  # fingers off one end
        offset = (k - 1.5) * ry * 64 * 0.45
        base = np.array(centre) + rx * 64 * np.array([np.cos(direction), np.sin(direction)])
        base = base + offset * np.array([-np.sin(direction), np.cos(direction)])
        tip = base + rx * 64 * 0.9 * np.array([np.cos(direction), np.sin(direction)])
        cv2.line(
            small,
            tuple(int(c) for c in base),
            tuple(int(c) for c in tip),
            1.0,
            max(1, int(ry * 64 * 0.3)),
        )
    small = cv2.GaussianBlur(small, (0, 0), 3.0)
    # The 64 px drawing spans the frame's [0, 1] (as cv2.resize to the frame would place it).
    shade = cv2.remap(
        small, xx * 64 - 0.5, yy * 64 - 0.5, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
    )
    return 1 - (1 - strength) * shade


def draw_fingers(image: np.ndarray, look: Look, base: np.ndarray, inward: np.ndarray) -> None:
    """Fingers over the page edge at `base` (pixels), pointing along `inward`; in place."""
    _, count, length, width, *skin = look.fingers
    h, w = image.shape[:2]
    size = max(h, w)
    inward = inward / (np.linalg.norm(inward) + 1e-9)
    across = np.array([-inward[1], inward[0]])
    for k in range(int(count)):
        start = base + across * (k - (count - 1) / 2) * width * size * 1.05 - inward * length * size
        tip = start + inward * length * size * (1.3 + 0.25 * np.sin(k * 1.7))
        thickness = max(2, int(width * size))
        colour = [float(c) * (0.9 + 0.05 * k % 2) for c in skin]
        p0, p1 = tuple(int(c) for c in start), tuple(int(c) for c in tip)
        cv2.line(image, p0, p1, [c * 0.7 for c in colour], thickness + 2, cv2.LINE_AA)
        cv2.line(image, p0, p1, colour, thickness, cv2.LINE_AA)


def apply_camera(look: Look, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Blur, noise and JPEG; float32 BGR in [0, 255] in, uint8 out."""
    scale = max(image.shape[:2]) / 288.0
    if look.blur_sigma > 0:
        image = cv2.GaussianBlur(image, (0, 0), look.blur_sigma * scale)
    if look.edge_defocus > 0:  # shallow depth of field: sharp centre, soft corners
        h, w = image.shape[:2]
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        weight = np.clip(((xx / w - 0.5) ** 2 + (yy / h - 0.5) ** 2) * 2, 0, 1)[..., None]
        soft = cv2.GaussianBlur(image, (0, 0), look.edge_defocus * scale)
        image = image * (1 - weight) + soft * weight
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
