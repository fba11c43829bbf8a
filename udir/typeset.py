"""TrueType text on numpy pages: fonts that matplotlib ships, English-like words, drawing.

Fonts come from matplotlib's data folder (DejaVu Sans/Serif/Sans Mono and STIX, each
regular, bold, italic and bold italic), found without importing matplotlib. Text is drawn
antialiased by Pillow into a small coverage mask and blended into the page in place.
"""

from __future__ import annotations

import importlib.util
from functools import lru_cache
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

FAMILIES: dict[str, tuple[str, str, str, str]] = {  # regular, bold, italic, bold italic
    "sans": ("DejaVuSans", "DejaVuSans-Bold", "DejaVuSans-Oblique", "DejaVuSans-BoldOblique"),
    "serif": ("DejaVuSerif", "DejaVuSerif-Bold", "DejaVuSerif-Italic", "DejaVuSerif-BoldItalic"),
    "times": ("STIXGeneral", "STIXGeneralBol", "STIXGeneralItalic", "STIXGeneralBolIta"),
    "mono": (
        "DejaVuSansMono",
        "DejaVuSansMono-Bold",
        "DejaVuSansMono-Oblique",
        "DejaVuSansMono-BoldOblique",
    ),
}
STYLES = ("regular", "bold", "italic", "bold-italic")

_COMMON_WORDS = (  # common English words, space-separated
    "the of and to in is that for it as was with be by on not he this are or his from at "
    "which but have an they you were her she there been one all we their has would when "
    "more will if no out so said what up its about than into them can only other new some "
    "could time these two may then do first any my now such like our over man me even most "
    "made after also did many before must through back years where much your way well down "
    "should because each just those people how too little state good very make world still "
    "own see men work long get here between both life being under never day same another "
    "know while last might us great old year off come since against go came right used "
    "take three states himself few house use during without again place around however "
    "home small found thought went say part once general high upon school every does got "
    "united left number course war until always away something fact though water less "
    "public put think almost hand enough far took head yet government system better set "
    "told nothing night end why called didn eyes find going look asked later knew point "
    "next program city business give group toward young days let room president side "
    "social given present several order national possible rather second face per among "
    "form important often things looked early white case john become large big need four "
    "within felt along children saw best church ever least power development light thing "
    "seemed family interest want members mind country area others done turned although "
    "open problem god service certain kind different thus began door help means sense "
    "whole matter perhaps itself york times law human line above name example action "
    "company hands local show whether five history gave today either act feet across taken "
    "past quite anyone having seen death experience body word half really week total "
    "amount invoice date payment account tax price item quantity customer order address "
    "phone email report results data analysis method study table figure section "
)
WORDS = tuple(_COMMON_WORDS.split())


def font_folder() -> Path:
    spec = importlib.util.find_spec("matplotlib")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("the crop generator needs matplotlib's fonts: pip install matplotlib")
    return Path(list(spec.submodule_search_locations)[0]) / "mpl-data" / "fonts" / "ttf"


@lru_cache(maxsize=512)
def font(family: str, style: str, size: int) -> ImageFont.FreeTypeFont:
    name = FAMILIES[family][STYLES.index(style)]
    return ImageFont.truetype(str(font_folder() / f"{name}.ttf"), max(4, int(size)))


def word(rng: np.random.Generator) -> str:
    roll = rng.random()
    if roll < 0.05:
        return str(int(rng.integers(1, 2100)))
    if roll < 0.07:
        return f"{rng.uniform(1, 999):.2f}"
    text = str(rng.choice(WORDS))
    roll = rng.random()
    if roll < 0.1:
        text = text.capitalize()
    elif roll < 0.12:
        text = text.upper()
    if rng.random() < 0.08:
        text += str(rng.choice([",", ".", ";", ":", ".", ","]))
    return text


def text_width(text: str, face: ImageFont.FreeTypeFont) -> float:
    return face.getlength(text)


def fill_line(rng: np.random.Generator, width: float, face: ImageFont.FreeTypeFont) -> str:
    """Words up to `width` pixels (at least one word)."""
    words: list[str] = []
    space = face.getlength(" ")
    used = 0.0
    while True:
        candidate = word(rng)
        extra = face.getlength(candidate) + (space if words else 0)
        if used + extra > width:
            return " ".join(words) if words else candidate
        words.append(candidate)
        used += extra


def sentence(rng: np.random.Generator, words: int) -> str:
    text = " ".join(word(rng) for _ in range(max(1, words)))
    return text[:1].upper() + text[1:]


def draw_text(
    page: np.ndarray,
    x: float,
    baseline: float,
    text: str,
    face: ImageFont.FreeTypeFont,
    ink: tuple[float, float, float],
    justify_to: float | None = None,
) -> float:
    """Draws `text` with its baseline at `baseline`, in place; returns the drawn width.

    `justify_to`: stretch the spaces so the line spans that many pixels (justified text).
    """
    if not text.strip():
        return 0.0
    words = text.split(" ")
    if justify_to and len(words) > 1:
        gap = (justify_to - sum(face.getlength(w) for w in words)) / (len(words) - 1)
        cursor = x
        for w in words:
            _blend_text(page, cursor, baseline, w, face, ink)
            cursor += face.getlength(w) + gap
        return justify_to
    _blend_text(page, x, baseline, text, face, ink)
    return face.getlength(text)


def _blend_text(page, x, baseline, text, face, ink) -> None:
    left, top, right, bottom = face.getbbox(text, anchor="ls")
    w, h = int(right - left) + 3, int(bottom - top) + 3
    if w <= 3 or h <= 3:
        return
    mask_image = Image.new("L", (w, h), 0)
    ox, oy = int(x) + int(left) - 1, int(baseline) + int(top) - 1
    ImageDraw.Draw(mask_image).text((x - ox, baseline - oy), text, font=face, fill=255, anchor="ls")
    blend_mask(page, np.asarray(mask_image, np.float32) / 255.0, ox, oy, ink)


def blend_mask(page: np.ndarray, mask: np.ndarray, ox: int, oy: int, ink) -> None:
    """page = page * (1 - mask) + ink * mask over the mask's rectangle (clipped), in place."""
    ph, pw = page.shape[:2]
    h, w = mask.shape
    x0, y0, x1, y1 = max(ox, 0), max(oy, 0), min(ox + w, pw), min(oy + h, ph)
    if x0 >= x1 or y0 >= y1:
        return
    m = mask[y0 - oy : y1 - oy, x0 - ox : x1 - ox, None]
    region = page[y0:y1, x0:x1].astype(np.float32)
    page[y0:y1, x0:x1] = region * (1 - m) + np.asarray(ink, np.float32) * m
