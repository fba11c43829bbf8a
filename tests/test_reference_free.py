"""Reference-free scores for real photos: black share, kept share, text-line straightness and
coherence."""

from __future__ import annotations

import cv2
import numpy as np

from doctrpp.benchmarks.reference_free import (
    black_share,
    kept_share,
    line_coherence,
    line_straightness,
)
from doctrpp.training.validate import identity_map


def _lines_page(angle: float = 0.0) -> np.ndarray:
    page = np.full((576, 576), 235, np.uint8)
    for y in range(40, 540, 18):
        for x in range(30, 540, 40):
            cv2.line(page, (x, y), (x + 30, y), 30, 4)
    rotation = cv2.getRotationMatrix2D((288, 288), angle, 1.0)
    return cv2.warpAffine(page, rotation, (576, 576), borderValue=235)


def test_straight_lines_score_higher_than_tilted_ones():
    level, tilted = line_straightness(_lines_page(0)), line_straightness(_lines_page(8))
    print(f"straightness level {level:.2f}, tilted 8 degrees {tilted:.2f}")
    assert level > 1.5 * tilted
    assert line_straightness(np.full((100, 100), 200, np.uint8)) == 0.0  # no text: no score


def test_coherence_sees_curved_lines_that_look_straight_locally():
    """A gentle wave (lines bend by one line pitch over the width) hardly changes the band
    straightness but lowers the coherence."""
    flat = _lines_page(0)
    columns = np.arange(576, dtype=np.float32)
    map_x = np.broadcast_to(columns, (576, 576))
    map_y = np.arange(576, dtype=np.float32)[:, None] + 9 * np.sin(columns / 576 * 2 * np.pi)
    wavy = cv2.remap(flat, np.ascontiguousarray(map_x), map_y.astype(np.float32), cv2.INTER_LINEAR)
    print(
        f"flat: coherence {line_coherence(flat):.2f}, straightness {line_straightness(flat):.2f}; "
        f"wavy: {line_coherence(wavy):.2f}, {line_straightness(wavy):.2f}"
    )
    assert line_coherence(flat) > 0.9 and line_coherence(wavy) < 0.6 * line_coherence(flat)
    assert line_straightness(wavy) > 0.7 * line_straightness(flat)
    assert line_coherence(np.full((100, 100), 200, np.uint8)) == 0.0


def test_identity_keeps_everything_and_adds_no_black():
    assert black_share(identity_map()) == 0.0
    assert kept_share(identity_map()) > 0.99


def test_a_zoomed_out_map_adds_black_and_a_zoomed_in_one_drops_content():
    out, inside = identity_map() * 1.25, identity_map() * 0.5
    assert 0.3 < black_share(out) < 0.4  # 1 - 0.8 ** 2
    assert black_share(inside) == 0.0
    assert 0.2 < kept_share(inside) < 0.3


def test_ocr_check_counts_confident_words_without_tesseract():
    from doctrpp.benchmarks.ocr_check import compare, parse_tsv, summarise_words

    header = "\t".join(
        ["level", "page", "block", "par", "line", "word"] + ["x"] * 4 + ["conf", "text"]
    )
    rows = [
        "\t".join(["5"] + ["1"] * 9 + [conf, text])
        for conf, text in [("91.5", "Platinum"), ("85", "to"), ("40", "Card"), ("-1", "")]
    ]
    words = parse_tsv("\n".join([header, *rows]))
    assert words == [("Platinum", 91.5), ("to", 85.0), ("Card", 40.0)]
    summary = summarise_words(words)  # "to" is too short, "Card" not confident
    assert summary["confident_words"] == 1 and summary["confident_letters"] == 8
    table = compare([{"untouched": summarise_words([]), "rectified": summary, "aligned": summary}])
    assert table["rectified"]["more_than_untouched"] == 1
    assert table["aligned"]["fewer_than_rectified"] == 0
