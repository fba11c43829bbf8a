"""The realistic generator: TrueType documents, paper, capture effects, page reuse, and
flat targets of partial/none crops that stay inside the crop (no black ring)."""

from __future__ import annotations

import numpy as np
import pytest

from doctrpp.udir import ranges
from doctrpp.udir.documents import DOCUMENTS, render_page
from doctrpp.udir.effects import random_look
from doctrpp.udir.page import Style, Writer
from doctrpp.udir.sample import OUTSIDE_SHARE_MAX, generate, make_scene
from doctrpp.udir.typeset import FAMILIES, STYLES, draw_text, font


def test_every_font_of_every_family_loads_and_draws_ink():
    for family in FAMILIES:
        for style in STYLES:
            canvas = np.full((40, 200, 3), 255, np.uint8)
            width = draw_text(canvas, 2, 30, "Rectify 123", font(family, style, 20), (0, 0, 0))
            assert width > 50, (family, style)
            assert (canvas < 128).mean() > 0.02, (family, style)  # antialiased glyphs drawn


@pytest.mark.parametrize("kind", sorted(DOCUMENTS))
def test_every_document_type_fills_a_page(kind):
    rng = np.random.default_rng(3)
    canvas = np.full((700, 500, 3), 255, np.uint8)
    style = Style("times", 12, 16, (20, 20, 20), (40, 90, 160), justify=True)
    DOCUMENTS[kind](canvas, rng, style, 30, 30)
    ink = (canvas.mean(-1) < 200).mean()
    print(f"{kind}: ink covers {ink:.1%} of the page")
    assert 0.01 < ink < 0.8


def test_writer_stays_inside_its_column():
    canvas = np.full((400, 400, 3), 255, np.uint8)
    style = Style("sans", 11, 15, (0, 0, 0), (200, 0, 0), justify=False)
    writer = Writer(canvas, np.random.default_rng(0), style, 100, 200, 50, 350)
    writer.fill({"paragraph": 1.0})
    outside = np.ones(canvas.shape[:2], bool)
    outside[40:360, 95:305] = False
    assert (canvas[outside] == 255).all()


def test_pages_are_deterministic_and_varied():
    a = render_page(np.random.default_rng(5))
    b = render_page(np.random.default_rng(5))
    assert np.array_equal(a, b)
    assert max(a.shape[:2]) == ranges.PAGE_LONG_SIDE
    shapes = {render_page(np.random.default_rng(s)).shape for s in range(8)}
    assert len(shapes) > 1


def test_page_reuse_shares_the_page_not_the_scene():
    first, second = make_scene(40, "complete", page_reuse=4), make_scene(41, "none", page_reuse=4)
    assert first.page is second.page
    assert first.crop != second.crop
    assert make_scene(44, "complete", page_reuse=4).page is not first.page
    assert not first.page.flags.writeable  # shared: nobody may draw on it


@pytest.mark.parametrize("kind", ["partial", "none"])
def test_flat_target_lies_inside_the_crop(kind):
    """A crop without page edges must not be shrunk into a patch ringed by black."""
    shares = []
    for seed in range(6):
        backward_map = generate(300 + seed, kind, photometric=False).backward_map
        shares.append(float((np.abs(backward_map) > 1).any(-1).mean()))
    print(f"{kind}: ground-truth black share max {max(shares):.4f}")
    assert max(shares) <= OUTSIDE_SHARE_MAX + 0.005


def test_capture_effects_are_drawn_with_their_shares():
    looks = [random_look(np.random.default_rng(s)) for s in range(400)]
    for field, share in (
        ("hand_shadow", ranges.HAND_SHADOW_SHARE),
        ("fingers", ranges.FINGERS_SHARE),
    ):
        seen = np.mean([bool(getattr(look, field)) for look in looks])
        assert abs(seen - share) < 0.07, field


def test_fingers_are_drawn_over_the_page():
    for seed in range(200):
        scene = make_scene(seed, "complete")
        if scene.look.fingers:
            break
    plain = make_scene(seed, "complete")
    image = scene.render(288, 288)
    without = type(scene.look)(**{**scene.look.__dict__, "fingers": ()})
    plain.look = without
    assert np.abs(image.astype(int) - plain.render(288, 288).astype(int)).max() > 40


def test_some_pages_are_printed_light_on_dark():
    """REVERSED_PRINT_SHARE of the pages: a dark flood with light lettering; the choice has
    its own random stream, so every other page is drawn as before."""
    from doctrpp.udir.sample import page_for, reversal

    chosen = [seed for seed in range(1000) if reversal(seed) is not None]
    assert 0.5 * ranges.REVERSED_PRINT_SHARE < len(chosen) / 1000 < 2 * ranges.REVERSED_PRINT_SHARE
    page = page_for(chosen[0]).mean(-1)
    background = float(np.median(page))
    assert background < ranges.REVERSED_FLOOD[1] + 30  # a dark page ...
    assert float(np.quantile(page, 0.995)) > background + 60  # ... with light lettering
    normal = page_for(chosen[0] + 1).mean(-1)
    assert float(np.median(normal)) > 150  # its neighbour is printed as usual


def test_pictures_are_muted_and_have_sharp_objects():
    """Pictures on pages (session 35): muted colours as in real pages' photos, not
    saturated rainbow fields; objects with edges; deterministic per seed."""
    import cv2

    from doctrpp.udir.paper import photo

    pictures = [photo(np.random.default_rng(seed), 120, 160) for seed in range(24)]
    assert all(p.shape == (120, 160, 3) and p.dtype == np.uint8 for p in pictures)
    assert np.array_equal(photo(np.random.default_rng(3), 120, 160), pictures[3])
    saturation = [np.median(cv2.cvtColor(p, cv2.COLOR_BGR2HSV)[..., 1]) for p in pictures]
    print(f"median HSV saturation of pictures: {np.median(saturation):.0f} / 255")
    assert np.median(saturation) < 0.45 * 255
    edges = [np.mean(cv2.Canny(cv2.GaussianBlur(p, (5, 5), 0), 40, 120) > 0) for p in pictures]
    assert np.mean([e > 0.002 for e in edges]) > 0.75
