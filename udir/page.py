"""Flat document pages with varied content, drawn with OpenCV only (fast, no font files)."""

from __future__ import annotations

import cv2
import numpy as np

FONTS = (
    cv2.FONT_HERSHEY_SIMPLEX,
    cv2.FONT_HERSHEY_DUPLEX,
    cv2.FONT_HERSHEY_COMPLEX,
    cv2.FONT_HERSHEY_TRIPLEX,
    cv2.FONT_HERSHEY_COMPLEX_SMALL,
    cv2.FONT_HERSHEY_PLAIN,
)
SCRIPT_FONTS = (cv2.FONT_HERSHEY_SCRIPT_SIMPLEX, cv2.FONT_HERSHEY_SCRIPT_COMPLEX)
SYLLABLES = (
    "ka",
    "ro",
    "mi",
    "te",
    "sa",
    "lu",
    "ne",
    "po",
    "ri",
    "da",
    "ve",
    "lo",
    "an",
    "en",
    "in",
    "or",
    "us",
    "ex",
    "pre",
    "con",
    "ter",
    "al",
    "ment",
    "tion",
    "ble",
    "ing",
    "ous",
    "st",
    "tr",
    "pl",
    "gr",
    "ch",
    "th",
    "qu",
)
BLOCK_KINDS = ("paragraph", "heading", "table", "figure", "form", "handwriting")
BLOCK_WEIGHTS = (0.42, 0.12, 0.12, 0.12, 0.12, 0.10)


def _word(rng: np.random.Generator) -> str:
    word = "".join(rng.choice(SYLLABLES, size=int(rng.integers(1, 4))))
    roll = rng.random()
    if roll < 0.12:
        word = word.capitalize()
    elif roll < 0.16:
        word = str(int(rng.integers(1, 9999)))
    elif roll < 0.19:
        word = word.upper()
    return word + ("," if rng.random() < 0.06 else ".") if rng.random() < 0.1 else word


def _text_line(rng: np.random.Generator, width: int, font: int, scale: float) -> str:
    words: list[str] = []
    while True:
        candidate = " ".join([*words, _word(rng)])
        if cv2.getTextSize(candidate, font, scale, 1)[0][0] > width:
            return " ".join(words) if words else candidate[:4]
        words = candidate.split(" ")


class PageWriter:
    """Fills one column top to bottom with blocks; `y` is the next free row."""

    def __init__(self, page, rng, ink, x0: int, width: int, y: int, bottom: int, line_h: int):
        self.page, self.rng, self.ink = page, rng, ink
        self.x0, self.width, self.y, self.bottom, self.line_h = x0, width, y, bottom, line_h
        self.font = int(rng.choice(FONTS))
        self.scale = self._scale_for(self.font, line_h * 0.62)

    @staticmethod
    def _scale_for(font: int, cap_height: float) -> float:
        return max(0.2, cap_height / cv2.getTextSize("H", font, 1.0, 1)[0][1])

    def room(self, rows: float) -> bool:
        return self.y + rows * self.line_h < self.bottom

    def paragraph(self) -> None:
        lines = int(self.rng.integers(2, 9))
        thickness = 1 if self.line_h < 22 else 2
        for i in range(lines):
            if not self.room(1):
                return
            indent = int(self.line_h * 1.5) if i == 0 and self.rng.random() < 0.5 else 0
            width = self.width - indent
            if i == lines - 1:
                width = int(width * self.rng.uniform(0.3, 0.9))
            text = _text_line(self.rng, width, self.font, self.scale)
            baseline = self.y + int(self.line_h * 0.8)
            cv2.putText(
                self.page,
                text,
                (self.x0 + indent, baseline),
                self.font,
                self.scale,
                self.ink,
                thickness,
                cv2.LINE_AA,
            )
            self.y += self.line_h
        self.y += self.line_h // 2

    def heading(self) -> None:
        size = self.rng.uniform(1.4, 2.4)
        if not self.room(size + 0.5):
            return
        font = int(self.rng.choice(FONTS[:4]))
        scale = self._scale_for(font, self.line_h * 0.62 * size)
        text = " ".join(_word(self.rng) for _ in range(int(self.rng.integers(1, 5)))).title()
        while cv2.getTextSize(text, font, scale, 2)[0][0] > self.width and " " in text:
            text = text.rsplit(" ", 1)[0]
        colour = (
            self.ink
            if self.rng.random() < 0.7
            else tuple(int(c) for c in self.rng.integers(0, 160, 3))
        )
        baseline = self.y + int(self.line_h * size * 0.85)
        cv2.putText(
            self.page,
            text,
            (self.x0, baseline),
            font,
            scale,
            colour,
            max(2, int(size * self.line_h / 14)),
            cv2.LINE_AA,
        )
        self.y += int(self.line_h * (size + 0.6))

    def table(self) -> None:
        rows, cols = int(self.rng.integers(3, 9)), int(self.rng.integers(2, 6))
        row_h = int(self.line_h * 1.3)
        if not self.room(rows * 1.3 + 1):
            return
        edges = np.sort(self.rng.uniform(0.15, 0.95, cols - 1)) * self.width
        xs = [self.x0, *(self.x0 + edges.astype(int)), self.x0 + self.width]
        top, bottom = self.y, self.y + rows * row_h
        if self.rng.random() < 0.4:  # shaded header row
            cv2.rectangle(self.page, (xs[0], top), (xs[-1], top + row_h), (215, 215, 215), -1)
        grid = self.rng.random() < 0.7
        for r in range(rows + 1):
            if grid or r in (0, 1, rows):
                cv2.line(
                    self.page, (xs[0], top + r * row_h), (xs[-1], top + r * row_h), self.ink, 1
                )
        if grid:
            for x in xs:
                cv2.line(self.page, (x, top), (x, bottom), self.ink, 1)
        small = self.scale * 0.85
        for r in range(rows):
            for c in range(cols):
                cell_w = xs[c + 1] - xs[c] - 6
                if cell_w > 8 and self.rng.random() < 0.9:
                    text = _text_line(
                        self.rng, int(cell_w * self.rng.uniform(0.4, 1)), self.font, small
                    )
                    cv2.putText(
                        self.page,
                        text,
                        (xs[c] + 3, top + r * row_h + int(row_h * 0.75)),
                        self.font,
                        small,
                        self.ink,
                        1,
                        cv2.LINE_AA,
                    )
        self.y = bottom + self.line_h

    def figure(self) -> None:
        height = int(self.width * self.rng.uniform(0.35, 0.8))
        if not self.room(height / self.line_h + 2):
            return
        x0, y0, x1, y1 = self.x0, self.y, self.x0 + self.width, self.y + height
        kind = self.rng.integers(0, 3)
        if kind == 0:  # photo-like: smooth colour field with blobs
            field = self.rng.integers(0, 255, (4, 4, 3)).astype(np.uint8)
            patch = cv2.resize(field, (x1 - x0, y1 - y0), interpolation=cv2.INTER_CUBIC)
            for _ in range(int(self.rng.integers(2, 6))):
                centre = (int(self.rng.integers(0, x1 - x0)), int(self.rng.integers(0, y1 - y0)))
                colour = tuple(int(c) for c in self.rng.integers(0, 255, 3))
                cv2.circle(
                    patch,
                    centre,
                    int(self.rng.integers(5, height // 2 + 6)),
                    colour,
                    -1,
                    cv2.LINE_AA,
                )
            self.page[y0:y1, x0:x1] = cv2.GaussianBlur(patch, (0, 0), 1.5)
        else:  # a chart: axes and a curve or bars
            cv2.rectangle(self.page, (x0, y0), (x1, y1), self.ink, 1)
            colour = tuple(int(c) for c in self.rng.integers(0, 200, 3))
            n = int(self.rng.integers(4, 12))
            values = self.rng.uniform(0.1, 0.95, n)
            xs = np.linspace(x0 + 8, x1 - 8, n)
            if kind == 1:
                bar_w = max(2, int((x1 - x0) / n * 0.6))
                for x, v in zip(xs, values, strict=True):
                    cv2.rectangle(
                        self.page,
                        (int(x) - bar_w // 2, int(y1 - v * height)),
                        (int(x) + bar_w // 2, y1 - 1),
                        colour,
                        -1,
                    )
            else:
                points = np.stack([xs, y1 - values * height], axis=1).astype(np.int32)
                cv2.polylines(self.page, [points], False, colour, 2, cv2.LINE_AA)
        self.y = y1 + self.line_h // 2
        if self.room(1):  # caption
            text = _text_line(self.rng, int(self.width * 0.7), self.font, self.scale * 0.8)
            cv2.putText(
                self.page,
                text,
                (self.x0, self.y + int(self.line_h * 0.7)),
                self.font,
                self.scale * 0.8,
                self.ink,
                1,
                cv2.LINE_AA,
            )
            self.y += int(self.line_h * 1.5)

    def form(self) -> None:
        fields = int(self.rng.integers(2, 6))
        for _ in range(fields):
            if not self.room(1.6):
                return
            label = " ".join(_word(self.rng) for _ in range(int(self.rng.integers(1, 3)))) + ":"
            baseline = self.y + int(self.line_h * 1.1)
            cv2.putText(
                self.page,
                label,
                (self.x0, baseline),
                self.font,
                self.scale,
                self.ink,
                1,
                cv2.LINE_AA,
            )
            start = self.x0 + cv2.getTextSize(label, self.font, self.scale, 1)[0][0] + 6
            if self.rng.random() < 0.3:  # check boxes
                for k in range(int(self.rng.integers(1, 4))):
                    bx = start + k * self.line_h * 3
                    if bx + self.line_h > self.x0 + self.width:
                        break
                    side = int(self.line_h * 0.6)
                    cv2.rectangle(
                        self.page, (bx, baseline - side), (bx + side, baseline), self.ink, 1
                    )
            elif start < self.x0 + self.width - 10:
                cv2.line(
                    self.page,
                    (start, baseline + 2),
                    (self.x0 + self.width, baseline + 2),
                    self.ink,
                    1,
                )
            self.y += int(self.line_h * 1.6)
        self.y += self.line_h // 2

    def handwriting(self) -> None:
        lines = int(self.rng.integers(1, 4))
        pen = tuple(
            int(c)
            for c in (
                self.rng.integers(90, 200),
                self.rng.integers(0, 60),
                self.rng.integers(0, 60),
            )
        )  # blue-ish ink (BGR)
        for _ in range(lines):
            if not self.room(1.5):
                return
            if self.rng.random() < 0.5:  # script font
                font = int(self.rng.choice(SCRIPT_FONTS))
                text = _text_line(
                    self.rng, int(self.width * self.rng.uniform(0.4, 1)), font, self.scale * 1.2
                )
                cv2.putText(
                    self.page,
                    text,
                    (self.x0, self.y + int(self.line_h * 1.1)),
                    font,
                    self.scale * 1.2,
                    pen,
                    1 + (self.line_h > 20),
                    cv2.LINE_AA,
                )
            else:  # scribble: a wavy stroke with loops
                n = 60
                t = np.linspace(0, 1, n)
                length = self.width * self.rng.uniform(0.3, 1.0)
                amp = self.line_h * 0.35
                freq = self.rng.uniform(8, 25)
                xs = self.x0 + t * length + amp * 0.6 * np.sin(t * freq * 2 * np.pi)
                ys = self.y + self.line_h * 0.8 + amp * np.cos(t * freq * 2 * np.pi + 1.0)
                points = np.stack([xs, ys], 1).astype(np.int32)
                cv2.polylines(self.page, [points], False, pen, 1 + (self.line_h > 20), cv2.LINE_AA)
            self.y += int(self.line_h * 1.5)


def paper_colour(rng: np.random.Generator) -> np.ndarray:
    if rng.random() < 0.7:
        return np.array([rng.uniform(228, 252)] * 3) + rng.uniform(-4, 4, 3)
    tint = np.array([rng.uniform(200, 250), rng.uniform(205, 250), rng.uniform(210, 252)])
    return rng.permutation(tint)


def render_page(rng: np.random.Generator, long_side: int = 768) -> np.ndarray:
    """A flat page (BGR uint8), portrait or landscape, with blocks of varied content."""
    aspect = rng.uniform(1.25, 1.5)
    short = int(round(long_side / aspect))
    height, width = (long_side, short) if rng.random() < 0.75 else (short, long_side)
    page = np.empty((height, width, 3), np.uint8)
    page[:] = np.clip(paper_colour(rng), 0, 255).astype(np.uint8)
    grain = rng.normal(0, rng.uniform(0.5, 3.0), (height // 4 + 1, width // 4 + 1, 1))
    page[:] = np.clip(page + cv2.resize(grain, (width, height))[:, :, None], 0, 255)
    ink = tuple(int(c) for c in rng.integers(0, 50, 3)) if rng.random() < 0.8 else (0, 0, 0)
    margin_x = int(width * rng.uniform(0.05, 0.12))
    margin_y = int(height * rng.uniform(0.04, 0.1))
    line_h = int(np.clip(rng.normal(18, 5), 10, 34) * long_side / 768)
    columns = int(
        rng.choice([1, 2, 3], p=[0.5, 0.38, 0.12] if width < height else [0.3, 0.45, 0.25])
    )
    gutter = int(width * 0.04)
    col_w = (width - 2 * margin_x - (columns - 1) * gutter) // columns
    y_start = margin_y
    if rng.random() < 0.6:  # a page-wide title
        writer = PageWriter(
            page, rng, ink, margin_x, width - 2 * margin_x, y_start, height - margin_y, line_h
        )
        writer.heading()
        y_start = writer.y
    for c in range(columns):
        x0 = margin_x + c * (col_w + gutter)
        writer = PageWriter(page, rng, ink, x0, col_w, y_start, height - margin_y, line_h)
        stalls = 0
        while writer.room(1) and stalls < 4:
            before = writer.y
            getattr(writer, str(rng.choice(BLOCK_KINDS, p=BLOCK_WEIGHTS)))()
            stalls = stalls + 1 if writer.y == before else 0
    if rng.random() < 0.5:  # page number / footer
        cv2.putText(
            page,
            str(int(rng.integers(1, 400))),
            (width // 2, height - margin_y // 2),
            FONTS[0],
            max(0.3, line_h / 40),
            ink,
            1,
            cv2.LINE_AA,
        )
    return page
