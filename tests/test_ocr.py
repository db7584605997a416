"""The OCR stage's band preparation, on constructed bands and on a seeded render with renderer truth."""

from __future__ import annotations

import numpy as np

from streamread.ocr import without_walls


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
