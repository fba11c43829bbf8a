"""Deformed page surfaces and the camera: an analytic map from page (u, v) to image (x, y).

The page is the unit square in (u, v); its physical size is (aspect, 1). Every
deformation is a smooth function of (u, v), so the forward map can be evaluated at any
resolution and anywhere, which is what makes exact ground truth cheap: the backward map
of the flat target *is* this forward map.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from . import ranges as R

# Paper does not stretch: bends are applied along the page's arc length (tabulated).
ARC_RANGE = 4.0  # |position| covered by the table, page heights
ARC_SAMPLES = 8001
NEWTON_TOLERANCE = 1e-9  # page units; outputs stayed bit-identical to 12 full iterations


@dataclass(frozen=True)
class Fold:
    angle: float  # direction across the crease, along which the paper bends (radians)
    offset: float  # signed distance of the crease from the page centre
    height: float  # how far the crease pushes out of the plane per unit distance
    sharpness: float  # smaller = sharper crease


@dataclass(frozen=True)
class Lift:
    """An edge or corner bending up towards the camera (z grows like t^2 past `start`)."""

    angle: float  # direction from the page centre towards the lifted edge (radians)
    start: float  # signed distance from the page centre where the bend starts
    strength: float  # z = strength * t^2 (smoothed) at t past the start


@dataclass(frozen=True)
class Bump:
    u: float
    v: float
    sigma: float
    height: float


@dataclass(frozen=True)
class LocalCrease:
    """A crease of crumpled paper that fades out along and across its line: the paper
    bends sharply at the line and is pulled in towards it (text foreshortens and kinks
    there), as a fold would, but only within a window around the crease's centre."""

    x: float  # centre, page units from the page centre (x across the width, y down)
    y: float
    angle: float  # direction of the crease line itself (a Fold's angle runs across it)
    length: float  # window sigma along the line
    width: float  # window sigma across the line
    slope: float  # signed height gained per unit distance from the line
    sharpness: float  # rounding of the crease (smaller = sharper)


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
    lifts: tuple[Lift, ...] = ()
    bumps: tuple[Bump, ...] = ()  # smooth crumpling
    creases: tuple[LocalCrease, ...] = ()  # sharp crumpling
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


def _profile(shape: tuple, c: np.ndarray) -> np.ndarray:
    """Height of a 1-D bend at position c across it (c = 0 at the page centre)."""
    kind, *q = shape
    if kind == "curl":
        amplitude, frequency, phase, quadratic = q
        return amplitude * np.sin(frequency * c + phase) + quadratic * c**2
    if kind == "fold":
        offset, height, sharpness = q
        d = c - offset
        return height * (np.sqrt(d * d + sharpness**2) - sharpness)
    start, strength = q  # lift: a smooth ramp t -> t^2 past the start
    t = c - start
    ramp = 0.5 * (t + np.sqrt(t * t + 1e-4))
    return strength * ramp**2


@lru_cache(maxsize=512)
def _arc_table(shape: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Arc length along the bent profile (0 at the centre) and the position it reaches."""
    c = np.linspace(-ARC_RANGE, ARC_RANGE, ARC_SAMPLES)
    slope = np.gradient(_profile(shape, c), c)
    step = np.sqrt(1.0 + slope**2)
    arc = np.concatenate([[0.0], np.cumsum(0.5 * (step[1:] + step[:-1]) * np.diff(c))])
    arc -= np.interp(0.0, c, arc)
    return arc, c


def _bend(shape: tuple, flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Flat position -> (position across the bend, height): the paper keeps its length."""
    arc, c = _arc_table(shape)
    inside = np.clip(flat, arc[0], arc[-1])
    across = np.interp(inside, arc, c) + (flat - inside)  # straight beyond the table
    return across, _profile(shape, across)


def surface_points(p: SurfaceParams, u: np.ndarray, v: np.ndarray):
    """Page (u, v) -> 3-D points (X, Y, Z) of the deformed page, centred on the origin.

    Curls, folds and lifts are 1-D bends: each pulls the page in along its direction by
    what the bend takes up, so text foreshortens where the paper turns away as on real
    paper. Bumps (crumpling) are small height offsets.
    """
    x0 = (u - 0.5) * p.width
    y0 = v - 0.5
    x, y = x0 + 0.0, y0 + 0.0
    z = np.zeros(np.broadcast(u, v).shape)
    bends: list[tuple[float, tuple, float]] = []  # (direction, shape, scale of the height)
    if p.curl_amplitude or p.curl_quadratic:
        along = -x0 * np.sin(p.curl_angle) + y0 * np.cos(p.curl_angle)
        shape = ("curl", p.curl_amplitude, p.curl_frequency, p.curl_phase, p.curl_quadratic)
        bends.append((p.curl_angle, shape, 1.0 + p.cone * along))
    bends += [(f.angle, ("fold", f.offset, f.height, f.sharpness), 1.0) for f in p.folds]
    bends += [(lift.angle, ("lift", lift.start, lift.strength), 1.0) for lift in p.lifts]
    for angle, shape, scale in bends:
        cos, sin = np.cos(angle), np.sin(angle)
        flat = x0 * cos + y0 * sin
        across, height = _bend(shape, flat)
        x, y = x + (across - flat) * cos, y + (across - flat) * sin
        z = z + height * scale
    for crease in p.creases:
        x, y, z = _local_crease(crease, x0, y0, x, y, z)
    for b in p.bumps:
        bx, by = (b.u - 0.5) * p.width, b.v - 0.5
        z = z + b.height * np.exp(-((x0 - bx) ** 2 + (y0 - by) ** 2) / (2 * b.sigma**2))
    return x, y, z


def _local_crease(crease: LocalCrease, x0, y0, x, y, z):
    """Add a windowed fold about the crease line to the points (x, y, z) of flat (x0, y0)."""
    cos, sin = np.cos(crease.angle), np.sin(crease.angle)
    dx, dy = x0 - crease.x, y0 - crease.y
    along = dx * cos + dy * sin
    flat = -dx * sin + dy * cos  # signed distance from the line
    window = np.exp(-0.5 * ((along / crease.length) ** 2 + (flat / crease.width) ** 2))
    across, height = _bend(("fold", 0.0, crease.slope, crease.sharpness), flat)
    pull = (across - flat) * window
    return x - pull * sin, y + pull * cos, z + height * window


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


def image_jacobian(p: SurfaceParams, u: np.ndarray, v: np.ndarray, eps: float = 1e-4):
    """Image position (x, y) of page (u, v) and the forward map's Jacobian there, by forward
    differences: x, y, dx/du, dx/dv, dy/du, dy/dv."""
    x, y = project(p, u, v)
    xu, yu = project(p, u + eps, v)
    xv, yv = project(p, u, v + eps)
    return x, y, (xu - x) / eps, (xv - x) / eps, (yu - y) / eps, (yv - y) / eps


def invert(
    p: SurfaceParams,
    x: np.ndarray,
    y: np.ndarray,
    iterations: int = 12,
    start: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Image (x, y) -> page (u, v) by Newton's method on the forward map.

    Starts from `start` (a close guess, e.g. a coarser inversion upsampled) or else from
    the inverse of the undeformed page's homography; values outside the unit square mean
    "not on the page". The surfaces drawn by `random_surface` are kept gentle enough for
    the map to be one-to-one.
    """
    if start is not None:
        return _newton(p, x, y, *start, iterations)
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
    return _newton(p, x, y, u, v, iterations)


def _newton(
    p: SurfaceParams, x: np.ndarray, y: np.ndarray, u: np.ndarray, v: np.ndarray, iterations: int
) -> tuple[np.ndarray, np.ndarray]:
    """Up to `iterations` Newton steps per point; a point stops once its step is below
    NEWTON_TOLERANCE (most converge to rounding in 4-7 of the 12: stepping them on was
    half of the generator's time)."""
    x, y, u, v = (np.array(a, np.float64) for a in np.broadcast_arrays(x, y, u, v))
    shape = x.shape
    x, y, u, v = x.ravel(), y.ravel(), u.ravel(), v.ravel()
    active = np.arange(x.size)
    for _ in range(iterations):
        if active.size == 0:
            break
        ua, va = u[active], v[active]
        fx, fy, a, b, c, d = image_jacobian(p, ua, va)
        det = a * d - b * c
        det = np.where(np.abs(det) < 1e-9, 1e-9, det)
        ex, ey = x[active] - fx, y[active] - fy
        du = (d * ex - b * ey) / det
        dv = (-c * ex + a * ey) / det
        # Damp steps far off the page, where the extrapolated surface can be steep.
        step = np.minimum(1.0, 0.25 / (np.hypot(du, dv) + 1e-12))
        u[active], v[active] = ua + step * du, va + step * dv
        active = active[step * np.hypot(du, dv) > NEWTON_TOLERANCE]
    return u.reshape(shape), v.reshape(shape)


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
    """Plausible deformations: perspective, curl, cone, folds, lifted edges, crumpling, or
    combinations (ranges in ranges.py)."""
    style = style or str(rng.choice(list(R.SURFACE_STYLES), p=list(R.SURFACE_STYLES.values())))
    kw: dict = {}
    if style in ("curl", "cone", "combined"):
        kw.update(
            curl_angle=float(rng.choice([0.0, np.pi / 2]) + rng.normal(0, 0.15)),
            curl_amplitude=float(rng.uniform(*R.CURL_AMPLITUDE)),
            curl_frequency=float(rng.uniform(*R.CURL_FREQUENCY)),
            curl_phase=float(rng.uniform(0, 2 * np.pi)),
            curl_quadratic=float(rng.uniform(-R.CURL_BOW, R.CURL_BOW)),
        )
        if style == "cone" or rng.random() < 0.3:
            kw["cone"] = float(rng.uniform(-R.CONE, R.CONE))
    folds: list[Fold] = []
    if style in ("fold", "combined"):
        folds += [_random_fold(rng) for _ in range(int(rng.integers(1, R.FOLDS_MAX + 1)))]
    if style == "crumple" or (style == "combined" and rng.random() < 0.5):
        folds += [_random_crease(rng) for _ in range(int(rng.integers(*R.CREASES)))]
        count = int(rng.integers(*R.LOCAL_CREASES))
        kw["creases"] = tuple(_random_local_crease(rng, width) for _ in range(count))
    if folds:
        kw["folds"] = tuple(folds)
    if style == "lift" or (style == "combined" and rng.random() < R.LIFT_IN_COMBINED):
        kw["lifts"] = tuple(_random_lift(rng, width) for _ in range(int(rng.integers(1, 3))))
    if style in ("crumple", "combined"):
        kw["bumps"] = tuple(
            Bump(
                float(rng.uniform(-0.1, 1.1)),
                float(rng.uniform(-0.1, 1.1)),
                float(rng.uniform(*R.BUMP_SIGMA)),
                float(rng.normal(0, R.BUMP_HEIGHT)),
            )
            for _ in range(int(rng.integers(*R.BUMPS)))
        )
    aligned = bool(rng.random() < R.ALIGNED_CAMERA_SHARE)
    tilt, roll, distance = (
        (R.ALIGNED_TILT_SIGMA, R.ALIGNED_ROLL_SIGMA, R.ALIGNED_CAMERA_DISTANCE)
        if aligned
        else (R.TILT_SIGMA, R.ROLL_SIGMA, R.CAMERA_DISTANCE)
    )
    return SurfaceParams(
        width=width,
        tilt_x=float(rng.normal(0, tilt)),
        tilt_y=float(rng.normal(0, tilt)),
        roll=float(rng.normal(0, roll)),
        distance=float(rng.uniform(*distance)),  # nearer = stronger perspective
        focal=1.0,  # image-plane units; crops are chosen in the same units
        extra={"style": style, "camera": "aligned" if aligned else "handheld"},
        **kw,
    )


def _random_fold(rng: np.random.Generator) -> Fold:
    """A fold across the page; most run parallel to a side, as when paper is folded."""
    if rng.random() < R.FOLD_ALONG_AXES:
        angle = float(rng.choice([0.0, np.pi / 2]) + rng.normal(0, 0.05))
    else:
        angle = float(rng.uniform(0, np.pi))
    return Fold(
        angle=angle,
        offset=float(rng.uniform(-R.FOLD_OFFSET, R.FOLD_OFFSET)),
        height=float(rng.uniform(-R.FOLD_SLOPE, R.FOLD_SLOPE)),
        sharpness=float(rng.uniform(*R.FOLD_SHARPNESS)),
    )


def _random_crease(rng: np.random.Generator) -> Fold:
    """A small crease of crumpled paper: any angle, anywhere, shallow and sharp."""
    return Fold(
        angle=float(rng.uniform(0, np.pi)),
        offset=float(rng.uniform(-R.CREASE_OFFSET, R.CREASE_OFFSET)),
        height=float(rng.choice([-1.0, 1.0]) * rng.uniform(*R.CREASE_SLOPE)),
        sharpness=float(rng.uniform(*R.CREASE_SHARPNESS)),
    )


def _random_local_crease(rng: np.random.Generator, width: float) -> LocalCrease:
    length = float(rng.uniform(*R.LOCAL_CREASE_LENGTH))
    return LocalCrease(
        x=float(rng.uniform(-0.5, 0.5) * width),
        y=float(rng.uniform(-0.5, 0.5)),
        angle=float(rng.uniform(0, np.pi)),
        length=length,
        width=length * float(rng.uniform(*R.LOCAL_CREASE_WIDTH)),
        slope=float(rng.choice([-1.0, 1.0]) * rng.uniform(*R.LOCAL_CREASE_SLOPE)),
        sharpness=float(rng.uniform(*R.LOCAL_CREASE_SHARPNESS)),
    )


def folds_over(p: SurfaceParams, grid: int = 41) -> bool:
    """Whether the camera sees part of the page folded over another part, turned almost
    edge-on (local image area below `MIN_AREA_SCALE` of the median) or reaching towards the
    camera plane (above `MAX_AREA_SCALE`): the image of the page would not be one-to-one,
    the crop would show that part too thinly to rectify, or the page's image would run off
    so far that a full-page crop shows a sliver of it."""
    u, v = np.meshgrid(np.linspace(0, 1, grid), np.linspace(0, 1, grid))
    _, _, a, b, c, d = image_jacobian(p, u, v)
    area = a * d - b * c  # local image area per unit page area
    area = area * np.sign(np.median(area))
    median = np.median(area)
    return bool(area.min() < R.MIN_AREA_SCALE * median or area.max() > R.MAX_AREA_SCALE * median)


def _random_lift(rng: np.random.Generator, width: float) -> Lift:
    """An edge or corner bent up: the slope it reaches at the page edge is drawn."""
    angle = float(rng.uniform(0, 2 * np.pi))
    # Distance from the centre to the page edge in that direction.
    reach = min(0.5 * width / max(abs(np.cos(angle)), 1e-6), 0.5 / max(abs(np.sin(angle)), 1e-6))
    start = float(rng.uniform(*R.LIFT_START)) * reach
    slope = float(rng.uniform(*R.LIFT_EDGE_SLOPE))
    sign = -1.0 if rng.random() < R.LIFT_TOWARDS_CAMERA else 1.0  # -z is towards the camera
    return Lift(angle=angle, start=start, strength=sign * slope / (2 * (reach - start)))
