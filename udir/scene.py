"""A distorted document photographed and cropped: photo, flat target and exact backward map.

Coordinates: the camera's image plane (`surface.project`) in arbitrary units; a crop is
a rectangle (x0, y0, x1, y1) there, sampled at any resolution with align_corners
semantics (pixel j of W sits at x0 + j / (W - 1) * (x1 - x0)). The flat target is the
page rectangle `uv_box` = (u0, v0, u1, v1) holding all page content visible in the crop.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .effects import Look, apply_camera, apply_lighting, draw_fingers, shading
from .surface import SurfaceParams, invert, project, surface_normals_z

KINDS = ("complete", "partial", "none")
INVERSION_GRID = 145  # image -> page inversion on a coarse grid, then bilinear upsampling
# Newton steps at full resolution from the upsampled coarse inversion: without them the
# grid rounds the kink of a sharp crease by up to ~0.5 px in a thin band along it.
REFINE_ITERATIONS = 2
SHADING_GRID = 49  # surface normals for the shading on this grid, then bilinear upsampling


def _grid(box: tuple[float, float, float, float], h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    x0, y0, x1, y1 = box
    return np.meshgrid(np.linspace(x0, x1, w), np.linspace(y0, y1, h))


def page_outline(surface, samples: int = 64) -> np.ndarray:
    """(4 * samples, 2) points of the page's border in image-plane coordinates."""
    t = np.linspace(0, 1, samples)
    zeros, ones = np.zeros_like(t), np.ones_like(t)
    u = np.concatenate([t, ones, t[::-1], zeros])
    v = np.concatenate([zeros, t, ones, t[::-1]])
    return np.stack(project(surface, u, v), -1)


def upsample(values: np.ndarray, h: int, w: int) -> np.ndarray:
    """Bilinear upsampling with align_corners semantics (coarse corners = fine corners)."""
    gh, gw = values.shape[:2]
    if (gh, gw) == (h, w):
        return values.astype(np.float32)
    map_x = np.broadcast_to(np.linspace(0, gw - 1, w, dtype=np.float32), (h, w))
    map_y = np.broadcast_to(np.linspace(0, gh - 1, h, dtype=np.float32)[:, None], (h, w))
    return cv2.remap(
        values.astype(np.float32),
        np.ascontiguousarray(map_x),
        np.ascontiguousarray(map_y),
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_REPLICATE,
    )


@dataclass
class Scene:
    page: np.ndarray  # flat page texture, BGR uint8
    surface: SurfaceParams
    kind: str
    crop: tuple[float, float, float, float]
    uv_box: tuple[float, float, float, float]
    look: Look
    background_seed: int
    noise_seed: int

    # -- geometry -----------------------------------------------------------------
    def crop_uv(self, h: int, w: int, grid: int = INVERSION_GRID) -> tuple[np.ndarray, np.ndarray]:
        """Page (u, v) seen at each crop pixel (values outside [0, 1] = background)."""
        gh, gw = min(h, grid), min(w, grid)
        x, y = _grid(self.crop, gh, gw)
        u, v = invert(self.surface, x, y)
        if (gh, gw) == (h, w):
            return u.astype(np.float32), v.astype(np.float32)
        x, y = _grid(self.crop, h, w)
        start = upsample(u, h, w).astype(np.float64), upsample(v, h, w).astype(np.float64)
        u, v = invert(self.surface, x, y, REFINE_ITERATIONS, start=start)
        return u.astype(np.float32), v.astype(np.float32)

    def backward_map(self, h: int = 288, w: int | None = None) -> np.ndarray:
        """(h, w, 2) float32: for each flat-target pixel, where it lies in the crop.

        Normalised, align_corners=True, x then y; continuous, may point outside the crop.
        """
        w = w or h
        u, v = _grid(self.uv_box, h, w)
        x, y = project(self.surface, u, v)
        x0, y0, x1, y1 = self.crop
        gx = 2 * (x - x0) / (x1 - x0) - 1
        gy = 2 * (y - y0) / (y1 - y0) - 1
        return np.stack([gx, gy], -1).astype(np.float32)

    def _edge_point(self, position: float, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
        """A point of the page edge (position 0-4 runs round it) in crop pixels, and the
        direction from it towards the page centre."""
        side, t = int(position) % 4, position % 1
        u, v = [(t, 0.0), (1.0, t), (1 - t, 1.0), (0.0, 1 - t)][side]
        x, y = project(self.surface, np.array([u, 0.5]), np.array([v, 0.5]))
        x0, y0, x1, y1 = self.crop
        px = (x - x0) / (x1 - x0) * (w - 1)
        py = (y - y0) / (y1 - y0) * (h - 1)
        point = np.array([px[0], py[0]])
        return point, np.array([px[1], py[1]]) - point

    def lighting_window(self) -> tuple[float, float, float, float]:
        """The crop as a part of the photo's frame (the page's bounding box), in its fractions:
        lights and shadows fall on the whole scene, of which a crop sees its own part."""
        outline = page_outline(self.surface)
        (bx0, by0), (bx1, by1) = outline.min(0), outline.max(0)
        bw, bh = max(bx1 - bx0, 1e-9), max(by1 - by0, 1e-9)
        x0, y0, x1, y1 = self.crop
        return ((x0 - bx0) / bw, (y0 - by0) / bh, (x1 - bx0) / bw, (y1 - by0) / bh)

    # -- pictures -----------------------------------------------------------------
    def _texture(self, pixels_per_page: float) -> np.ndarray:
        """The page texture at a pyramid level near the needed scale (limits aliasing)."""
        texture = self.page
        while max(texture.shape[:2]) > 2 * pixels_per_page and min(texture.shape[:2]) > 32:
            texture = cv2.pyrDown(texture)
        return texture

    def flat_target(self, h: int = 288, w: int | None = None) -> np.ndarray:
        w = w or h
        u0, v0, u1, v1 = self.uv_box
        texture = self._texture(max(h / max(v1 - v0, 1e-3), w / max(u1 - u0, 1e-3)))
        th, tw = texture.shape[:2]
        u, v = _grid(self.uv_box, h, w)
        return cv2.remap(
            texture,
            (u * (tw - 1)).astype(np.float32),
            (v * (th - 1)).astype(np.float32),
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )

    def render(self, h: int = 288, w: int | None = None, photometric: bool = True) -> np.ndarray:
        """The crop as a camera would see it, BGR uint8, (h, w, 3)."""
        w = w or h
        u, v = self.crop_uv(h, w)
        visible = (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
        span = 1.0
        if visible.any():
            span = max(float(u[visible].max() - u[visible].min()), 1e-3)
        texture = self._texture(w / span)
        th, tw = texture.shape[:2]
        page = cv2.remap(
            texture, u * (tw - 1), v * (th - 1), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        ).astype(np.float32)
        # Anti-aliased page edge: coverage from the distance (in output pixels) to the border,
        # with the page's local scale (the whole crop's span of u, v overstates it where the
        # surface, extrapolated off the page, runs steep: a blurred edge several px wide).
        pixel_u = np.maximum(np.hypot(*np.gradient(u)), 1e-6)
        pixel_v = np.maximum(np.hypot(*np.gradient(v)), 1e-6)
        inside = np.minimum.reduce([u / pixel_u, (1 - u) / pixel_u, v / pixel_v, (1 - v) / pixel_v])
        coverage = np.clip(inside + 0.5, 0, 1)[..., None]
        if photometric:
            gh, gw = min(h, SHADING_GRID), min(w, SHADING_GRID)
            cu, cv = upsample(u, gh, gw), upsample(v, gh, gw)
            normals = surface_normals_z(self.surface, cu.astype(np.float64), cv.astype(np.float64))
            flat = surface_normals_z(
                SurfaceParams(
                    width=self.surface.width,
                    tilt_x=self.surface.tilt_x,
                    tilt_y=self.surface.tilt_y,
                    roll=self.surface.roll,
                ),
                np.array(0.5),
                np.array(0.5),
            )
            page *= upsample(shading(self.look, normals, flat), h, w)[..., None]
        if coverage.min() < 1:
            from .background import render_background

            background = render_background(np.random.default_rng(self.background_seed), h, w)
            image = background * (1 - coverage) + page * coverage
        else:
            image = page
        if not photometric:
            return np.clip(image + 0.5, 0, 255).astype(np.uint8)
        if self.look.fingers and self.kind != "none":
            image = np.ascontiguousarray(image, dtype=np.float32)
            draw_fingers(image, self.look, *self._edge_point(self.look.fingers[0], h, w))
        image = apply_lighting(self.look, image, self.lighting_window())
        return apply_camera(self.look, image, np.random.default_rng(self.noise_seed))
