"""Deformed page surfaces and the camera: an analytic map from page (u, v) to image (x, y).

The page is the unit square in (u, v); its physical size is (aspect, 1). Every
deformation is a smooth function of (u, v), so the forward map can be evaluated at any
resolution and anywhere, which is what makes exact ground truth cheap: the backward map
of the flat target *is* this forward map.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Fold:
    angle: float  # direction of the crease line in the page plane (radians)
    offset: float  # signed distance of the crease from the page centre
    height: float  # how far the crease pushes out of the plane per unit distance
    sharpness: float  # smaller = sharper crease


@dataclass(frozen=True)
class Bump:
    u: float
    v: float
    sigma: float
    height: float


@dataclass(frozen=True)
class SurfaceParams:
    width: float  # physical page width (height is 1)
    curl_angle: float = 0.0  # direction across which the page curls
    curl_amplitude: float = 0.0
    curl_frequency: float = 1.0
    curl_phase: float = 0.0
    curl_quadratic: float = 0.0  # cylinder-like bow
    cone: float = 0.0  # curl growing along the curl axis (conical curl)
    folds: tuple[Fold, ...] = ()
    bumps: tuple[Bump, ...] = ()  # smooth crumpling
    # Camera: rotation (radians), distance and focal length in output pixels, principal point.
    tilt_x: float = 0.0
    tilt_y: float = 0.0
    roll: float = 0.0
    distance: float = 2.5
    focal: float = 400.0
    centre: tuple[float, float] = (0.0, 0.0)
    extra: dict = field(default_factory=dict, compare=False)


def _rotation(tilt_x: float, tilt_y: float, roll: float) -> np.ndarray:
    cx, sx = np.cos(tilt_x), np.sin(tilt_x)
    cy, sy = np.cos(tilt_y), np.sin(tilt_y)
    cz, sz = np.cos(roll), np.sin(roll)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def surface_points(p: SurfaceParams, u: np.ndarray, v: np.ndarray):
    """Page (u, v) -> 3-D points (X, Y, Z) of the deformed page, centred on the origin."""
    x = (u - 0.5) * p.width
    y = v - 0.5
    z = np.zeros(np.broadcast(u, v).shape)
    if p.curl_amplitude or p.curl_quadratic:
        across = x * np.cos(p.curl_angle) + y * np.sin(p.curl_angle)
        along = -x * np.sin(p.curl_angle) + y * np.cos(p.curl_angle)
        profile = p.curl_amplitude * np.sin(p.curl_frequency * across + p.curl_phase)
        profile = profile + p.curl_quadratic * across**2
        z = z + profile * (1.0 + p.cone * along)
    for f in p.folds:
        d = x * np.cos(f.angle) + y * np.sin(f.angle) - f.offset
        z = z + f.height * (np.sqrt(d * d + f.sharpness**2) - f.sharpness)
    for b in p.bumps:
        bx, by = (b.u - 0.5) * p.width, b.v - 0.5
        z = z + b.height * np.exp(-((x - bx) ** 2 + (y - by) ** 2) / (2 * b.sigma**2))
    return x, y, z


def project(p: SurfaceParams, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Page (u, v) -> image (x, y) in output pixels (pinhole camera looking down +Z)."""
    x, y, z = surface_points(p, u, v)
    r = _rotation(p.tilt_x, p.tilt_y, p.roll)
    xc = r[0, 0] * x + r[0, 1] * y + r[0, 2] * z
    yc = r[1, 0] * x + r[1, 1] * y + r[1, 2] * z
    zc = r[2, 0] * x + r[2, 1] * y + r[2, 2] * z + p.distance
    return p.focal * xc / zc + p.centre[0], p.focal * yc / zc + p.centre[1]


def surface_normals_z(p: SurfaceParams, u: np.ndarray, v: np.ndarray, eps: float = 1e-3):
    """Unit normals of the deformed page in camera coordinates, (..., 3)."""
    r = _rotation(p.tilt_x, p.tilt_y, p.roll)
    p0 = np.stack(surface_points(p, u, v), -1)
    du = np.stack(surface_points(p, u + eps, v), -1) - p0
    dv = np.stack(surface_points(p, u, v + eps), -1) - p0
    n = np.cross(du, dv) @ r.T
    n /= np.linalg.norm(n, axis=-1, keepdims=True) + 1e-12
    return np.where(n[..., 2:3] > 0, -n, n)  # facing the camera (towards -Z)


def invert(
    p: SurfaceParams, x: np.ndarray, y: np.ndarray, iterations: int = 12
) -> tuple[np.ndarray, np.ndarray]:
    """Image (x, y) -> page (u, v) by Newton's method on the forward map.

    Starts from the inverse of the undeformed page's homography; values outside the
    unit square mean "not on the page". The surfaces drawn by `random_surface` are
    kept gentle enough for the map to be one-to-one.
    """
    flat = SurfaceParams(
        width=p.width,
        tilt_x=p.tilt_x,
        tilt_y=p.tilt_y,
        roll=p.roll,
        distance=p.distance,
        focal=p.focal,
        centre=p.centre,
    )
    corners_uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)
    corners_xy = np.stack(project(flat, corners_uv[:, 0], corners_uv[:, 1]), -1)
    h = _homography(corners_xy, corners_uv)
    den = h[2, 0] * x + h[2, 1] * y + h[2, 2]
    u = (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / den
    v = (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / den
    eps = 1e-4
    for _ in range(iterations):
        fx, fy = project(p, u, v)
        fxu, fyu = project(p, u + eps, v)
        fxv, fyv = project(p, u, v + eps)
        a, b = (fxu - fx) / eps, (fxv - fx) / eps
        c, d = (fyu - fy) / eps, (fyv - fy) / eps
        det = a * d - b * c
        det = np.where(np.abs(det) < 1e-9, 1e-9, det)
        ex, ey = x - fx, y - fy
        du = (d * ex - b * ey) / det
        dv = (-c * ex + a * ey) / det
        # Damp steps far off the page, where the extrapolated surface can be steep.
        step = np.minimum(1.0, 0.25 / (np.hypot(du, dv) + 1e-12))
        u, v = u + step * du, v + step * dv
    return u, v


def _homography(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    rows = []
    for (x, y), (u, v) in zip(src, dst, strict=True):
        rows.append([x, y, 1, 0, 0, 0, -u * x, -u * y, -u])
        rows.append([0, 0, 0, x, y, 1, -v * x, -v * y, -v])
    _, _, vt = np.linalg.svd(np.array(rows))
    return vt[-1].reshape(3, 3) / vt[-1, -1]


def random_surface(
    rng: np.random.Generator, width: float, style: str | None = None
) -> SurfaceParams:
    """Plausible deformations: perspective, curl, cone, folds, crumpling, or combinations."""
    style = style or str(
        rng.choice(
            ["perspective", "curl", "cone", "fold", "crumple", "combined"],
            p=[0.1, 0.22, 0.12, 0.18, 0.13, 0.25],
        )
    )
    kw: dict = {}
    if style in ("curl", "cone", "combined"):
        kw.update(
            curl_angle=float(rng.choice([0.0, np.pi / 2]) + rng.normal(0, 0.15)),
            curl_amplitude=float(rng.uniform(0.03, 0.16)),
            curl_frequency=float(rng.uniform(1.5, 5.0)),
            curl_phase=float(rng.uniform(0, 2 * np.pi)),
            curl_quadratic=float(rng.uniform(-0.45, 0.45)),
        )
        if style == "cone" or rng.random() < 0.3:
            kw["cone"] = float(rng.uniform(-1.2, 1.2))
    if style in ("fold", "combined"):
        folds = []
        for _ in range(int(rng.integers(1, 4))):
            folds.append(
                Fold(
                    angle=float(rng.uniform(0, np.pi)),
                    offset=float(rng.uniform(-0.35, 0.35)),
                    height=float(rng.uniform(-0.25, 0.25)),
                    sharpness=float(rng.uniform(0.005, 0.04)),
                )
            )
        kw["folds"] = tuple(folds)
    if style in ("crumple", "combined"):
        n = int(rng.integers(3, 14))
        kw["bumps"] = tuple(
            Bump(
                float(rng.uniform(-0.1, 1.1)),
                float(rng.uniform(-0.1, 1.1)),
                float(rng.uniform(0.06, 0.25)),
                float(rng.normal(0, 0.03)),
            )
            for _ in range(n)
        )
    return SurfaceParams(
        width=width,
        tilt_x=float(rng.normal(0, 0.25)),
        tilt_y=float(rng.normal(0, 0.25)),
        roll=float(rng.normal(0, 0.2)),
        distance=float(rng.uniform(1.6, 5.0)),  # nearer = stronger perspective
        focal=1.0,  # image-plane units; crops are chosen in the same units
        extra={"style": style},
        **kw,
    )
