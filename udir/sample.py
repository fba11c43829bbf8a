"""Drawing scenes from a seed, choosing crops of the three kinds, and packing samples."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .effects import random_look
from .page import render_page
from .scene import KINDS, Scene
from .surface import invert, project, random_surface


class CropError(RuntimeError):
    """No crop of the asked kind could be found for this scene (the caller redraws)."""


def _page_outline(surface, samples: int = 64) -> np.ndarray:
    t = np.linspace(0, 1, samples)
    zeros, ones = np.zeros_like(t), np.ones_like(t)
    u = np.concatenate([t, ones, t[::-1], zeros])
    v = np.concatenate([zeros, t, ones, t[::-1]])
    return np.stack(project(surface, u, v), -1)


def _page_fraction(surface, box, grid: int = 24) -> float:
    x, y = np.meshgrid(np.linspace(box[0], box[2], grid), np.linspace(box[1], box[3], grid))
    u, v = invert(surface, x, y)
    return float(np.mean((u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)))


def _box_around(rng, centre, width, height):
    cx, cy = centre
    return (cx - width / 2, cy - height / 2, cx + width / 2, cy + height / 2)


def choose_crop(rng: np.random.Generator, surface, kind: str) -> tuple[float, float, float, float]:
    outline = _page_outline(surface)
    (bx0, by0), (bx1, by1) = outline.min(0), outline.max(0)
    bw, bh = bx1 - bx0, by1 - by0
    if kind == "complete":
        m = rng.uniform(0.02, 0.22, 4)
        return (bx0 - m[0] * bw, by0 - m[1] * bh, bx1 + m[2] * bw, by1 + m[3] * bh)
    for _ in range(40):
        if kind == "none":
            cu, cv = rng.uniform(0.25, 0.75, 2)
            size = rng.uniform(0.3, 0.7) * min(bw, bh)
            aspect = rng.uniform(0.7, 1.4)
            centre = np.array(project(surface, np.array(cu), np.array(cv))).ravel()
            box = _box_around(rng, centre, size * aspect, size / aspect)
            for _ in range(8):
                if _page_fraction(surface, box, grid=16) >= 1.0:
                    return box
                box = _box_around(rng, centre, (box[2] - box[0]) * 0.8, (box[3] - box[1]) * 0.8)
        else:  # partial: part of the page and some background, some boundaries visible
            edge = rng.integers(0, 4)
            along = rng.uniform(-0.1, 1.1)
            across = rng.uniform(-0.1, 0.3)
            cu, cv = [(across, along), (1 - across, along), (along, across), (along, 1 - across)][
                edge
            ]
            centre = np.array(project(surface, np.array(cu), np.array(cv))).ravel()
            box = _box_around(rng, centre, rng.uniform(0.4, 0.9) * bw, rng.uniform(0.4, 0.9) * bh)
            if 0.3 <= _page_fraction(surface, box) <= 0.9:
                return box
    raise CropError(f"no {kind} crop found")


def make_scene(seed: int, kind: str, long_side: int = 768) -> Scene:
    """A scene drawn deterministically from `seed`, with a crop of `kind`."""
    if kind not in KINDS:
        raise ValueError(f"unknown crop kind {kind!r}; choose from {', '.join(KINDS)}")
    rng = np.random.default_rng([seed, KINDS.index(kind)])
    for _ in range(20):
        page = render_page(rng, long_side)
        surface = random_surface(rng, width=page.shape[1] / page.shape[0])
        try:
            crop = choose_crop(rng, surface, kind)
        except CropError:
            continue
        break
    else:  # pragma: no cover - practically unreachable
        raise CropError(f"seed {seed}: no {kind} crop after 20 scenes")
    scene = Scene(
        page=page,
        surface=surface,
        kind=kind,
        crop=crop,
        uv_box=(0.0, 0.0, 1.0, 1.0),
        look=random_look(rng),
        background_seed=int(rng.integers(2**31)),
        noise_seed=int(rng.integers(2**31)),
    )
    if kind != "complete":
        scene.uv_box = visible_uv_box(scene)
    return scene


def visible_uv_box(scene: Scene, grid: int = 129) -> tuple[float, float, float, float]:
    """Bounding box in (u, v) of the page content visible in the crop."""
    u, v = scene.crop_uv(grid, grid, grid=grid)
    visible = (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
    u, v = np.clip(u[visible], 0, 1), np.clip(v[visible], 0, 1)
    return (float(u.min()), float(v.min()), float(u.max()), float(v.max()))


@dataclass
class Sample:
    image: np.ndarray  # the crop, BGR uint8
    flat: np.ndarray  # the flat target, BGR uint8
    backward_map: np.ndarray  # (S, S, 2) float32 normalised, x then y
    kind: str
    seed: int
    params: dict


def kind_for_index(index: int, kind: str = "mixed") -> str:
    """Equal thirds for 'mixed'; otherwise the asked kind."""
    return KINDS[index % 3] if kind == "mixed" else kind


def generate(
    seed: int, kind: str, size: int = 288, map_size: int = 288, photometric: bool = True
) -> Sample:
    scene = make_scene(seed, kind)
    return Sample(
        image=scene.render(size, size, photometric=photometric),
        flat=scene.flat_target(size, size),
        backward_map=scene.backward_map(map_size, map_size),
        kind=kind,
        seed=seed,
        params=scene_params(scene),
    )


def scene_params(scene: Scene) -> dict:
    surface = dataclasses.asdict(scene.surface)
    return {
        "kind": scene.kind,
        "crop": list(scene.crop),
        "uv_box": list(scene.uv_box),
        "page_size": list(scene.page.shape[:2]),
        "surface": surface,
        "look": dataclasses.asdict(scene.look),
    }
