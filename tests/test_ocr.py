"""The OCR stage's band preparation, on constructed bands and on a seeded render with renderer truth."""

from __future__ import annotations

import cv2
import numpy as np

from streamread.ocr import Band, _glyph_boxes, _glyph_mask, _glyphs_beside, without_walls
from streamread.types import Mark


def test_walls_are_flattened_and_a_digit_across_one_is_kept() -> None:
    # a light band with a dark wall down its whole height, and a "1" (a short dark bar) printed
    # just beside the wall and touching it, as numbers near a syringe's edge are
    band = np.full((240, 60), 215, np.uint8)
    band[:, 28:31] = 70  # the wall: far longer than a digit
    band[100:122, 31:34] = 60  # the digit: 22 px tall, under the 40 px gap between long marks
    flat = without_walls(band, gap=40.0)
    assert flat[:, 28:31].min() >= 200, "the wall is flattened into the background"
    assert flat[100:122, 31:34].max() <= 110, "the digit beside it keeps its full stroke"
    assert flat[:95].min() >= 200 and flat[127:].min() >= 200, "nothing else appears"


def _labelled_band(labels: list[tuple[str, int]], height: int = 400, width: int = 90) -> np.ndarray:
    band = np.full((height, width), 220, np.uint8)
    for text, y in labels:
        cv2.putText(band, text, (30, y + 8), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 40, 2)  # digits about 16 px tall
    return band


def test_pieces_of_wall_do_not_set_the_text_height() -> None:
    # numbers beside long marks 60 px apart; a wall broken where the marks were inpainted leaves
    # 48 px pieces, taller than any digit but shorter than the gap
    marks = [Mark(y_up=float(y), x0_up=0.0, x1_up=20.0, thickness_up=2.0, tier="major") for y in range(60, 400, 60)]
    band = _labelled_band([(str(20 + k), int(m.y_up)) for k, m in enumerate(marks)])
    for m in marks:
        band[int(m.y_up) - 52: int(m.y_up) - 4, 80:82] = 60
    glyphs, text_h = _glyph_mask(band, marks, gap=60.0)
    assert 12 <= text_h <= 20, f"the digits' height, not the wall's: {text_h}"
    assert glyphs[:, 30:70].any(), "the digits are kept"


def test_a_word_with_a_digit_left_out_is_seen() -> None:
    band_image = _labelled_band([("14", 100)])
    band = Band(band_image, 0, 1.0, False, text_px=16.0)
    boxes = _glyph_boxes(band)
    ys, xs = np.nonzero(band_image < 128)
    right_digit = xs > (xs.min() + xs.max()) / 2
    left, width = float(xs[right_digit].min()), float(xs[right_digit].max() - xs[right_digit].min() + 1)
    top, h = float(ys.min()), float(ys.max() - ys.min() + 1)
    assert _glyphs_beside(boxes, 16.0, top, h, left, width) == 2, "a word read as '4' from '14' has two digits beside it"
    whole = float(xs.min()), float(xs.max() - xs.min() + 1)
    assert _glyphs_beside(boxes, 16.0, top, h, *whole) == 2, "read whole, the count matches its two digits"
