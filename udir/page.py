"""Blocks of a document page set in real type: paragraphs, headings, tables, figures, forms.

A `Writer` fills one column of an ink canvas (white = no ink) with blocks; the document
layouts that use it are in `documents.py`.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .paper import photo
from .typeset import draw_text, fill_line, font, sentence


def pick(rng: np.random.Generator, weights: dict[str, float]) -> str:
    names = list(weights)
    p = np.array([weights[n] for n in names], float)
    return str(rng.choice(names, p=p / p.sum()))


def random_colour(rng: np.random.Generator, low: int = 0, high: int = 200) -> tuple[float, ...]:
    return tuple(float(c) for c in rng.uniform(low, high, 3))


@dataclass
class Style:
    family: str
    body: int  # body font size, px
    line_h: int  # line pitch, px
    ink: tuple[float, ...]
    accent: tuple[float, ...]
    justify: bool


class Writer:
    """Fills one column top to bottom with blocks; `y` is the next free row."""

    def __init__(self, canvas, rng, style: Style, x0: int, width: int, y: int, bottom: int):
        self.canvas, self.rng, self.s = canvas, rng, style
        self.x0, self.width, self.y, self.bottom = x0, width, y, bottom

    def room(self, rows: float) -> bool:
        return self.y + rows * self.s.line_h < self.bottom

    def face(self, scale: float = 1.0, style: str = "regular", family: str | None = None):
        return font(family or self.s.family, style, round(self.s.body * scale))

    def line(self, text: str, face, x: float | None = None, ink=None, justify=None) -> None:
        baseline = self.y + self.s.line_h * 0.78
        draw_text(
            self.canvas,
            self.x0 if x is None else x,
            baseline,
            text,
            face,
            ink or self.s.ink,
            justify,
        )
        self.y += self.s.line_h

    def paragraph(self) -> None:
        face = self.face(style="italic" if self.rng.random() < 0.06 else "regular")
        lines = int(self.rng.integers(2, 14))
        indent = int(self.s.body * 1.5) if self.rng.random() < 0.5 else 0
        for i in range(lines):
            if not self.room(1):
                return
            last = i == lines - 1
            width = self.width - (indent if i == 0 else 0)
            if last:
                width = int(width * self.rng.uniform(0.2, 0.95))
            text = fill_line(self.rng, width, face)
            justify = width if self.s.justify and not last else None
            self.line(text, face, x=self.x0 + (indent if i == 0 else 0), justify=justify)
        self.y += int(self.s.line_h * self.rng.uniform(0.3, 1.0))

    def heading(self, scale: float | None = None, colour=None) -> None:
        scale = scale or float(self.rng.uniform(1.2, 2.2))
        if not self.room(scale + 0.6):
            return
        face = self.face(scale, "bold" if self.rng.random() < 0.8 else "regular")
        text = sentence(self.rng, int(self.rng.integers(1, 7)))
        while face.getlength(text) > self.width and " " in text:
            text = text.rsplit(" ", 1)[0]
        self.y += int(self.s.line_h * (scale - 1) * 0.8)
        self.line(text, face, ink=colour or (self.s.accent if self.rng.random() < 0.35 else None))
        self.y += int(self.s.line_h * 0.3)

    def bullets(self) -> None:
        face = self.face()
        for _ in range(int(self.rng.integers(2, 7))):
            if not self.room(1):
                return
            draw_text(
                self.canvas, self.x0, self.y + self.s.line_h * 0.78, "\u2022", face, self.s.accent
            )
            pad = int(self.s.body * 1.2)
            self.line(
                fill_line(self.rng, (self.width - pad) * self.rng.uniform(0.4, 1), face),
                face,
                x=self.x0 + pad,
            )
        self.y += self.s.line_h // 2

    def table(self, numeric: bool = False) -> None:
        rows, cols = int(self.rng.integers(3, 12)), int(self.rng.integers(2, 6))
        row_h = int(self.s.line_h * self.rng.uniform(1.1, 1.5))
        if not self.room(rows * row_h / self.s.line_h + 1):
            return
        edges = np.sort(self.rng.uniform(0.2, 0.95, cols - 1)) * self.width
        xs = [self.x0, *(self.x0 + edges.astype(int)), self.x0 + self.width]
        top, bottom = self.y, self.y + rows * row_h
        ink = tuple(int(c) for c in self.s.ink)
        header = self.rng.random() < 0.6
        if header:
            fill = self.s.accent if self.rng.random() < 0.4 else (210, 210, 210)
            lighter = tuple(int(255 - (255 - c) * 0.35) for c in fill)
            cv2.rectangle(self.canvas, (xs[0], top), (xs[-1], top + row_h), lighter, -1)
        grid = self.rng.random() < 0.6
        for r in range(rows + 1):
            if grid or r in (0, 1, rows):
                cv2.line(self.canvas, (xs[0], top + r * row_h), (xs[-1], top + r * row_h), ink, 1)
        if grid:
            for x in xs:
                cv2.line(self.canvas, (x, top), (x, bottom), ink, 1)
        face, bold = self.face(0.9), self.face(0.9, "bold")
        for r in range(rows):
            for c in range(cols):
                cell_w = xs[c + 1] - xs[c] - 8
                if cell_w < 10 or self.rng.random() > 0.92:
                    continue
                use = bold if header and r == 0 else face
                if numeric and c > 0 and r > 0:
                    text = f"{self.rng.uniform(0, 5000):,.2f}"
                    x = xs[c + 1] - 4 - use.getlength(text)
                else:
                    text = fill_line(self.rng, cell_w * self.rng.uniform(0.3, 1), use)
                    x = xs[c] + 4
                baseline = top + r * row_h + row_h * 0.72
                draw_text(self.canvas, x, baseline, text, use, self.s.ink)
        self.y = bottom + self.s.line_h

    def figure(self) -> None:
        height = int(self.width * self.rng.uniform(0.4, 0.85))
        if not self.room(height / self.s.line_h + 2):
            return
        x0, y0, x1, y1 = self.x0, self.y, self.x0 + self.width, self.y + height
        if self.rng.random() < 0.6:
            self.canvas[y0:y1, x0:x1] = photo(self.rng, y1 - y0, x1 - x0)
        else:
            ink = tuple(int(c) for c in self.s.ink)
            cv2.line(self.canvas, (x0 + 4, y1 - 4), (x1, y1 - 4), ink, 1)
            cv2.line(self.canvas, (x0 + 4, y0), (x0 + 4, y1 - 4), ink, 1)
            n = int(self.rng.integers(4, 14))
            values = self.rng.uniform(0.1, 0.95, n)
            xs = np.linspace(x0 + 12, x1 - 8, n)
            colour = tuple(int(c) for c in self.s.accent)
            if self.rng.random() < 0.5:
                bar = max(2, int((x1 - x0) / n * 0.6))
                for x, v in zip(xs, values, strict=True):
                    top = int(y1 - 4 - v * (height - 8))
                    cv2.rectangle(
                        self.canvas,
                        (int(x) - bar // 2, top),
                        (int(x) + bar // 2, y1 - 5),
                        colour,
                        -1,
                    )
            else:
                points = np.stack([xs, y1 - 4 - values * (height - 8)], 1).astype(np.int32)
                cv2.polylines(self.canvas, [points], False, colour, 2, cv2.LINE_AA)
        self.y = y1 + self.s.line_h // 2
        if self.room(1):  # caption
            face = self.face(0.85, "italic" if self.rng.random() < 0.5 else "regular")
            self.line(fill_line(self.rng, self.width * self.rng.uniform(0.4, 1), face), face)
        self.y += self.s.line_h // 2

    def box(self) -> None:
        """A tinted side box with a few lines of text."""
        rows = int(self.rng.integers(3, 9))
        if not self.room(rows + 2):
            return
        tint = tuple(float(255 - (255 - c) * self.rng.uniform(0.15, 0.4)) for c in self.s.accent)
        top = self.y
        cv2.rectangle(
            self.canvas,
            (self.x0, top),
            (self.x0 + self.width, top + (rows + 1) * self.s.line_h),
            tint,
            -1,
        )
        inner = Writer(
            self.canvas,
            self.rng,
            self.s,
            self.x0 + self.s.body,
            self.width - 2 * self.s.body,
            top + self.s.line_h // 2,
            top + (rows + 1) * self.s.line_h,
        )
        inner.paragraph()
        self.y = top + (rows + 2) * self.s.line_h

    def form(self) -> None:
        face = self.face()
        ink = tuple(int(c) for c in self.s.ink)
        for _ in range(int(self.rng.integers(2, 8))):
            if not self.room(1.8):
                return
            label = sentence(self.rng, int(self.rng.integers(1, 4))) + ":"
            self.y += int(self.s.line_h * 0.6)
            baseline = int(self.y + self.s.line_h * 0.78)
            end = self.x0 + draw_text(self.canvas, self.x0, baseline, label, face, self.s.ink) + 8
            if self.rng.random() < 0.3:  # check boxes
                side = int(self.s.body * 0.8)
                for k in range(int(self.rng.integers(1, 5))):
                    bx = int(end + k * side * 4)
                    if bx + side > self.x0 + self.width:
                        break
                    cv2.rectangle(self.canvas, (bx, baseline - side), (bx + side, baseline), ink, 1)
            elif end < self.x0 + self.width - 10:
                cv2.line(
                    self.canvas,
                    (int(end), baseline + 2),
                    (self.x0 + self.width, baseline + 2),
                    ink,
                    1,
                )
            self.y += self.s.line_h
        self.y += self.s.line_h // 2

    def handwriting(self) -> None:
        """Pen strokes: loops along a wavy baseline (a signature or a note)."""
        pen = (
            (
                float(self.rng.uniform(90, 200)),
                float(self.rng.uniform(0, 60)),
                float(self.rng.uniform(0, 60)),
            )
            if self.rng.random() < 0.6
            else self.s.ink
        )
        for _ in range(int(self.rng.integers(1, 4))):
            if not self.room(1.6):
                return
            t = np.linspace(0, 1, 120)
            length = self.width * self.rng.uniform(0.25, 0.9)
            amp = self.s.line_h * 0.35
            freq = self.rng.uniform(10, 30)
            xs = self.x0 + t * length + amp * 0.6 * np.sin(t * freq * 2 * np.pi)
            ys = self.y + self.s.line_h * 0.8 + amp * np.cos(t * freq * 2 * np.pi + 1.0)
            points = np.stack([xs, ys], 1).astype(np.int32)
            width = 1 + int(self.s.line_h > 24)
            cv2.polylines(self.canvas, [points], False, pen, width, cv2.LINE_AA)
            self.y += int(self.s.line_h * 1.6)

    def fill(self, weights: dict[str, float]) -> None:
        stalls = 0
        while self.room(1) and stalls < 4:
            before = self.y
            getattr(self, pick(self.rng, weights))()
            stalls = stalls + 1 if self.y == before else 0
