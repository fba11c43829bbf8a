"""Drawing scenes from a seed, choosing crops of the three kinds, and packing samples."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import ranges
from .documents import render_page
from .effects import random_look
from .paper import reversed_print
from .scene import KINDS, Scene, page_outline
from .surface import folds_over, invert, project, random_surface


class CropError(RuntimeError):
    """No crop of the asked kind could be found for this scene (the caller redraws)."""


def _page_fraction(surface, box, grid: int = 24) -> float:
    x, y = np.meshgrid(np.linspace(box[0], box[2], grid), np.linspace(box[1], box[3], grid))
    u, v = invert(surface, x, y)
    return float(np.mean((u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)))


def _box_around(rng, centre, width, height):
    cx, cy = centre
    return (cx - width / 2, cy - height / 2, cx + width / 2, cy + height / 2)


def choose_crop(rng: np.random.Generator, surface, kind: str) -> tuple[float, float, float, float]:
    outline = page_outline(surface)
    (bx0, by0), (bx1, by1) = outline.min(0), outline.max(0)
    bw, bh = bx1 - bx0, by1 - by0
    if kind == "complete":
        m = rng.uniform(*ranges.COMPLETE_MARGIN, 4)
        return (bx0 - m[0] * bw, by0 - m[1] * bh, bx1 + m[2] * bw, by1 + m[3] * bh)
    for _ in range(40):
        if kind == "none":
            cu, cv = rng.uniform(0.25, 0.75, 2)
            size = rng.uniform(*ranges.NONE_CROP_SIZE) * min(bw, bh)
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
            low, high = ranges.PARTIAL_CROP_SIZE
            box = _box_around(rng, centre, rng.uniform(low, high) * bw, rng.uniform(low, high) * bh)
            if (
                ranges.PARTIAL_PAGE_SHARE[0]
                <= _page_fraction(surface, box)
                <= ranges.PARTIAL_PAGE_SHARE[1]
            ):
                return box
    raise CropError(f"no {kind} crop found")


@lru_cache(maxsize=4)
def page_for(page_seed: int, long_side: int = ranges.PAGE_LONG_SIDE) -> np.ndarray:
    """The flat page of `page_seed` (cached: training reuses a page for a few scenes)."""
    page = render_page(np.random.default_rng([page_seed, 0x9A6E]), long_side)
    stream = reversal(page_seed)
    if stream is not None:
        page = reversed_print(stream, page)
    page.setflags(write=False)
    return page


def reversal(page_seed: int) -> np.random.Generator | None:
    """The random stream that prints page `page_seed` light on dark, or None for the
    REVERSED_PRINT_SHARE-complement printed as usual. Its own stream, so that adding it
    left every other page as it was."""
    stream = np.random.default_rng([page_seed, 0xDA2C])
    return stream if stream.random() < ranges.REVERSED_PRINT_SHARE else None


def make_scene(seed: int, kind: str, page_reuse: int = 1) -> Scene:
    """A scene drawn deterministically from `seed`, with a crop of `kind`.

    `page_reuse` > 1: seeds that agree in `seed // page_reuse` share the page (not the
    deformation, crop, background or look), which makes training data cheaper to generate.
    """
    if kind not in KINDS:
        raise ValueError(f"unknown crop kind {kind!r}; choose from {', '.join(KINDS)}")
    rng = np.random.default_rng([seed, KINDS.index(kind)])
    page = page_for(seed // max(page_reuse, 1))
    for _ in range(20):
        surface = random_surface(rng, width=page.shape[1] / page.shape[0])
        if folds_over(surface):
            continue
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
    """The flat target of a partial/none crop: a page rectangle (u0, v0, u1, v1) that lies
    in the crop but for at most `OUTSIDE_SHARE_MAX` of its area.

    Starts from the bounding box of the visible page content and moves in, one grid row or
    column at a time, the side whose edge lies most outside the crop. (The bounding box
    itself would make the model shrink crops without page edges into a patch ringed by
    black: the corners of the box lie outside the photo.)
    """
    u, v = scene.crop_uv(grid, grid, grid=grid)
    visible = (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
    u, v = np.clip(u[visible], 0, 1), np.clip(v[visible], 0, 1)
    box = (float(u.min()), float(v.min()), float(u.max()), float(v.max()))
    return inscribed_uv_box(scene, box)


OUTSIDE_SHARE_MAX = 0.01  # of the flat target allowed to map outside the crop (black)


def inscribed_uv_box(
    scene: Scene, box: tuple[float, float, float, float], grid: int = 97
) -> tuple[float, float, float, float]:
    u0, v0, u1, v1 = box
    us, vs = np.linspace(u0, u1, grid), np.linspace(v0, v1, grid)
    uu, vv = np.meshgrid(us, vs)
    x, y = project(scene.surface, uu, vv)
    cx0, cy0, cx1, cy1 = scene.crop
    outside = ~((x >= cx0) & (x <= cx1) & (y >= cy0) & (y <= cy1))
    top, bottom, left, right = 0, grid - 1, 0, grid - 1
    while bottom - top > grid // 4 and right - left > grid // 4:
        window = outside[top : bottom + 1, left : right + 1]
        if window.mean() <= OUTSIDE_SHARE_MAX:
            break
        edges = [window[0].mean(), window[-1].mean(), window[:, 0].mean(), window[:, -1].mean()]
        side = int(np.argmax(edges))
        if side == 0:
            top += 1
        elif side == 1:
            bottom -= 1
        elif side == 2:
            left += 1
        else:
            right -= 1
    return (float(us[left]), float(vs[top]), float(us[right]), float(vs[bottom]))


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
    seed: int,
    kind: str,
    size: int = 288,
    map_size: int = 288,
    photometric: bool = True,
    page_reuse: int = 1,
) -> Sample:
    scene = make_scene(seed, kind, page_reuse)
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
