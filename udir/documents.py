"""Documents: the layouts of real documents, typeset with `page.Writer`, printed on paper.

`render_page` draws one of `DOCUMENTS` (book/article pages, magazine pages, letters,
invoices, receipts, forms, slides) as ink on a white canvas with TrueType fonts
(`typeset`), then prints it on paper (`paper.print_on_paper`: texture, tint, show-through,
ink bleed). Every random range is in `udir/ranges.py`.
"""

from __future__ import annotations

import cv2
import numpy as np

from . import ranges
from .page import Style, Writer, pick, random_colour
from .paper import photo, print_on_paper
from .typeset import draw_text, fill_line, font, sentence, word


def _columns(canvas, rng, style, margin_x, top, bottom, count, weights) -> None:
    width = canvas.shape[1]
    gutter = int(width * rng.uniform(0.025, 0.05))
    col_w = (width - 2 * margin_x - (count - 1) * gutter) // count
    for c in range(count):
        x0 = margin_x + c * (col_w + gutter)
        Writer(canvas, rng, style, x0, col_w, top, bottom).fill(weights)


def _logo(canvas, rng, style, x, y, size) -> int:
    """A coloured mark and a bold name; returns the bottom row."""
    colour = tuple(int(c) for c in style.accent)
    if rng.random() < 0.5:
        cv2.circle(canvas, (x + size // 2, y + size // 2), size // 2, colour, -1, cv2.LINE_AA)
    else:
        cv2.rectangle(canvas, (x, y), (x + size, y + size), colour, -1)
    face = font(style.family, "bold", int(size * 0.6))
    name = " ".join(word(rng).capitalize() for _ in range(int(rng.integers(1, 3))))
    draw_text(canvas, x + size * 1.3, y + size * 0.75, name, face, colour)
    return y + size


def article(canvas, rng, style, m_x, m_y) -> None:
    h, w = canvas.shape[:2]
    top = m_y
    if rng.random() < 0.5:  # running header with a rule
        face = font(style.family, "italic", int(style.body * 0.85))
        draw_text(canvas, m_x, top + style.line_h * 0.7, sentence(rng, 4), face, style.ink)
        top += style.line_h
        cv2.line(canvas, (m_x, top), (w - m_x, top), tuple(int(c) for c in style.ink), 1)
        top += style.line_h // 2
    if rng.random() < 0.5:
        writer = Writer(canvas, rng, style, m_x, w - 2 * m_x, top, h - m_y)
        writer.heading(float(rng.uniform(1.6, 2.6)))
        top = writer.y
    count = int(rng.choice([1, 2, 2, 3])) if w < h else int(rng.choice([2, 3]))
    weights = {
        "paragraph": 0.62,
        "heading": 0.1,
        "figure": 0.08,
        "table": 0.07,
        "bullets": 0.08,
        "box": 0.05,
    }
    _columns(canvas, rng, style, m_x, top, h - m_y - style.line_h, count, weights)
    face = font(style.family, "regular", int(style.body * 0.85))
    draw_text(canvas, w / 2, h - m_y * 0.6, str(int(rng.integers(1, 600))), face, style.ink)


def magazine(canvas, rng, style, m_x, m_y) -> None:
    h, w = canvas.shape[:2]
    top = m_y
    if rng.random() < 0.5:  # a photo across the top
        ph = int(h * rng.uniform(0.15, 0.4))
        canvas[top : top + ph, m_x : w - m_x] = photo(rng, ph, w - 2 * m_x)
        top += ph + style.line_h
    writer = Writer(canvas, rng, style, m_x, w - 2 * m_x, top, h - m_y)
    writer.heading(float(rng.uniform(2.2, 4.0)), colour=style.accent)
    weights = {"paragraph": 0.45, "heading": 0.1, "figure": 0.2, "box": 0.15, "bullets": 0.1}
    _columns(canvas, rng, style, m_x, writer.y, h - m_y, int(rng.choice([2, 3, 3])), weights)


def letter(canvas, rng, style, m_x, m_y) -> None:
    h, w = canvas.shape[:2]
    top = (
        _logo(canvas, rng, style, m_x, m_y, int(style.line_h * rng.uniform(1.5, 3))) + style.line_h
    )
    writer = Writer(canvas, rng, style, m_x, int((w - 2 * m_x) * 0.5), top, h - m_y)
    face = writer.face()
    for _ in range(int(rng.integers(3, 6))):  # address block
        writer.line(sentence(rng, int(rng.integers(2, 5))), face)
    writer.y += style.line_h
    writer.width = w - 2 * m_x
    writer.line(f"{rng.integers(1, 29)} {word(rng).capitalize()} {rng.integers(1990, 2027)}", face)
    writer.y += style.line_h
    for _ in range(int(rng.integers(2, 6))):
        writer.paragraph()
    writer.handwriting()


def invoice(canvas, rng, style, m_x, m_y) -> None:
    h, w = canvas.shape[:2]
    top = _logo(canvas, rng, style, m_x, m_y, int(style.line_h * rng.uniform(1.5, 3)))
    writer = Writer(canvas, rng, style, m_x, w - 2 * m_x, top + style.line_h, h - m_y)
    writer.heading(2.0)
    face = writer.face()
    for _ in range(int(rng.integers(2, 5))):
        writer.line(f"{word(rng).capitalize()}: {word(rng)} {rng.integers(100, 99999)}", face)
    writer.y += style.line_h
    writer.table(numeric=True)
    bold = writer.face(style="bold")
    for label in ("Subtotal", "Tax", "Total"):
        if not writer.room(1):
            break
        amount = f"{rng.uniform(10, 9999):,.2f}"
        x = writer.x0 + writer.width - bold.getlength(amount)
        draw_text(
            canvas,
            x - bold.getlength(label) - style.body * 3,
            writer.y + style.line_h * 0.78,
            label,
            bold,
            style.ink,
        )
        writer.line(amount, bold, x=x)
    writer.fill({"paragraph": 0.5, "form": 0.3, "table": 0.2})


def receipt(canvas, rng, style, m_x, m_y) -> None:
    h, w = canvas.shape[:2]
    face = font("mono", "regular", style.body)
    writer = Writer(canvas, rng, style, m_x, w - 2 * m_x, m_y, h - m_y)
    for _ in range(int(rng.integers(2, 5))):  # centred header
        text = sentence(rng, int(rng.integers(1, 4))).upper()
        writer.line(text, face, x=(w - face.getlength(text)) / 2)
    while writer.room(3):
        roll = rng.random()
        if roll < 0.1:
            writer.line("-" * int(writer.width / face.getlength("-")), face)
        elif roll < 0.15 and writer.room(4):  # barcode
            x = writer.x0
            bar_top, bar_bottom = writer.y, writer.y + 2 * style.line_h
            while x < writer.x0 + writer.width * 0.8:
                bar = int(rng.integers(1, 4))
                cv2.rectangle(canvas, (x, bar_top), (x + bar - 1, bar_bottom), (20, 20, 20), -1)
                x += bar + int(rng.integers(1, 4))
            writer.y = bar_bottom + style.line_h
        else:
            amount = f"{rng.uniform(0.5, 99):.2f}"
            item = fill_line(rng, writer.width * rng.uniform(0.3, 0.6), face).upper()
            draw_text(canvas, writer.x0, writer.y + style.line_h * 0.78, item, face, style.ink)
            writer.line(amount, face, x=writer.x0 + writer.width - face.getlength(amount))


def form(canvas, rng, style, m_x, m_y) -> None:
    h, w = canvas.shape[:2]
    writer = Writer(canvas, rng, style, m_x, w - 2 * m_x, m_y, h - m_y)
    writer.heading(2.0)
    writer.fill({"form": 0.55, "paragraph": 0.15, "table": 0.15, "handwriting": 0.15})


def slide(canvas, rng, style, m_x, m_y) -> None:
    h, w = canvas.shape[:2]
    if rng.random() < 0.5:
        band = int(h * rng.uniform(0.1, 0.2))
        canvas[:band] = np.asarray(style.accent, np.uint8)
    writer = Writer(canvas, rng, style, m_x, w - 2 * m_x, m_y, h - m_y)
    writer.heading(float(rng.uniform(2.2, 3.2)))
    half = (w - 2 * m_x) // 2
    left = Writer(canvas, rng, style, m_x, half, writer.y, h - m_y)
    left.bullets()
    left.bullets()
    Writer(
        canvas, rng, style, m_x + half + style.body, half - style.body, writer.y, h - m_y
    ).figure()


DOCUMENTS = {
    "article": article,
    "magazine": magazine,
    "letter": letter,
    "invoice": invoice,
    "receipt": receipt,
    "form": form,
    "slide": slide,
}


def render_page(rng: np.random.Generator, long_side: int = ranges.PAGE_LONG_SIDE) -> np.ndarray:
    """A flat page (BGR uint8) of a random document type, printed on paper."""
    kind = pick(rng, ranges.DOCUMENT_TYPES)
    aspect = rng.uniform(*ranges.PAGE_ASPECT[kind])
    short = int(round(long_side / aspect))
    landscape = kind == "slide" or (kind != "receipt" and rng.random() < ranges.LANDSCAPE_SHARE)
    height, width = (short, long_side) if landscape else (long_side, short)
    canvas = np.full((height, width, 3), 255, np.uint8)
    pitch = rng.uniform(*ranges.LINE_PITCH[kind]) * long_side
    body = max(7, int(pitch * rng.uniform(0.68, 0.8)))
    ink = (20.0, 20.0, 20.0) if rng.random() < 0.5 else random_colour(rng, 0, 60)
    style = Style(
        family=pick(rng, ranges.FONT_FAMILIES),
        body=body,
        line_h=max(body + 2, int(pitch)),
        ink=ink,
        accent=random_colour(rng, 0, 220),
        justify=bool(rng.random() < 0.5),
    )
    margin_x = int(width * rng.uniform(*ranges.MARGIN))
    margin_y = int(height * rng.uniform(*ranges.MARGIN))
    DOCUMENTS[kind](canvas, rng, style, margin_x, margin_y)
    return print_on_paper(rng, canvas)
