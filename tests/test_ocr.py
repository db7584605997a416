"""The OCR stage's band preparation, on constructed bands and on a seeded render with renderer truth."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from streamread import ocr
from streamread.ocr import (Band, _glyph_masks, _glyphs_beside, bands_beside, read_numbers, widened,
                            without_walls)
from streamread.fit import fit_scale
from streamread.marks import majors_at_labels
from streamread.profile import default_profile
from streamread.types import Mark, Marks


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
    # numbers beside long marks 60 px apart; a wall broken where the marks were erased leaves
    # 48 px pieces, taller than any digit but shorter than the gap
    marks = [Mark(y_up=float(y), x0_up=0.0, x1_up=20.0, thickness_up=2.0, tier="major") for y in range(60, 400, 60)]
    band = _labelled_band([(str(20 + k), int(m.y_up)) for k, m in enumerate(marks)])
    for m in marks:
        band[int(m.y_up) - 52: int(m.y_up) - 4, 80:82] = 60
    glyphs, text_h = _glyph_masks(band, marks, gap=60.0)[0]
    assert 12 <= text_h <= 20, f"the digits' height, not the wall's: {text_h}"
    assert glyphs[:, 30:70].any(), "the digits are kept"


def _ink_box(image: np.ndarray, level: int = 128) -> tuple[float, float, float, float]:
    """top, h, left, width of the ink darker than ``level``."""
    ys, xs = np.nonzero(image < level)
    return float(ys.min()), float(ys.max() - ys.min() + 1), float(xs.min()), float(xs.max() - xs.min() + 1)


def test_a_word_with_a_digit_left_out_is_seen() -> None:
    band_image = _labelled_band([("14", 100)])
    band = Band(band_image, 0, 1.0, False, text_px=16.0)
    top, h, left, width = _ink_box(band_image)
    right_half = band_image.copy()
    right_half[:, :int(left + width / 2)] = 220
    _, _, right_left, right_width = _ink_box(right_half)
    assert _glyphs_beside(band, top, h, right_left, right_width) == 2, \
        "a word read as '4' from '14' has two digits beside it"
    assert _glyphs_beside(band, top, h, left, width) == 2, "read whole, the count matches its two digits"


def test_a_faint_label_s_digits_are_counted_and_an_empty_band_has_none() -> None:
    # clean 13187: a burette's "14" light grey (171 at its darkest) where other labels are black,
    # read "4": a fixed level (128) saw no digit there, so none was missed
    band_image = np.full((400, 90), 255, np.uint8)
    cv2.putText(band_image, "12", (30, 108), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 175, 2)
    cv2.putText(band_image, "10", (30, 308), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 0, 2)
    band = Band(band_image, 0, 1.0, False, text_px=16.0)
    faint = band_image.copy()
    faint[200:] = 255
    top, h, left, width = _ink_box(faint, 230)
    assert _glyphs_beside(band, top, h, left + width / 2, width / 2) == 2, "the faint '1' beside the '2' is a digit"
    empty = Band(np.full((50, 40), 255, np.uint8), 0, 1.0, False, text_px=16.0)
    assert _glyphs_beside(empty, 10.0, 16.0, 10.0, 10.0) == 0


def test_digits_joined_at_their_foot_are_told_apart_by_their_columns() -> None:
    # clean 13187: a burette's "14" joined by a smear under it is one blob; read "4" in a box as
    # wide as both digits, it is two glyphs by its columns once the foot is cut off
    band_image = np.full((200, 90), 255, np.uint8)
    cv2.putText(band_image, "14", (30, 108), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 30, 2)
    top, h, left, width = _ink_box(band_image)
    band_image[int(top + 0.8 * h):int(top + h), int(left):int(left + width)] = 30  # the smear
    band = Band(band_image, 0, 1.0, False, text_px=16.0)
    assert _glyphs_beside(band, top, h, left, width) == 1, "one blob"
    assert _glyphs_beside(band, top, h, left, width, split=True) == 2, "two glyphs by their columns"
    for digit in "0123456789":
        alone = np.full((200, 90), 255, np.uint8)
        cv2.putText(alone, digit, (30, 108), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 30, 2)
        box = _ink_box(alone)
        assert _glyphs_beside(Band(alone, 0, 1.0, False, text_px=16.0), *box, split=True) == 1, digit


def test_a_light_glyph_s_pieces_are_no_glyphs_of_their_own() -> None:
    # clean 12617: a grey "3" beside a black "1" falls into pieces at the ink's level, its tongue
    # and its lower curve each spanning half the word's rows: still two glyphs, "13" kept
    band_image = np.full((200, 90), 255, np.uint8)
    cv2.putText(band_image, "1", (30, 108), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 0, 2)
    cv2.putText(band_image, "3", (44, 108), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 120, 1)  # light: in pieces at half
    band = Band(band_image, 0, 1.0, False, text_px=16.0)
    top, h, left, width = _ink_box(band_image, 250)
    assert _glyphs_beside(band, top, h, left, width, split=True) == 2


def test_a_word_boxed_on_a_piece_of_a_glyph_is_no_number() -> None:
    # seed 2207: faint "40" and "30" read as "4" and "3" from boxes a third of the digits' height
    # (the sides of the zeros): the cylinder read 27.0 ml as 2.70
    band_image = np.full((120, 80), 235, np.uint8)
    cv2.ellipse(band_image, (40, 60), (10, 18), 0, 0, 360, 170, 3)  # a faint "0", 39 px tall
    band = Band(band_image, 0, 1.0, False, text_px=36.0)
    assert not ocr._word_fits_ink(band, top=52.0, h=12.0, left=28.0, width=8.0)
    assert ocr._word_fits_ink(band, top=41.0, h=39.0, left=28.0, width=25.0)


def test_a_word_without_text_does_not_lose_the_band(monkeypatch: pytest.MonkeyPatch) -> None:
    """tesserocr raises "No text returned" for a word it found but could not read; the words
    after it in the band must still come back (the whole band used to be dropped)."""
    tesserocr = pytest.importorskip("tesserocr")

    class Iterator:
        def __init__(self) -> None:
            self.words = [None, ("12", (5, 10, 25, 30)), ("13", (5, 60, 25, 80))]
            self.at = 0

        def GetUTF8Text(self, level: object) -> str:  # noqa: N802 - tesserocr's names
            word = self.words[self.at]
            if word is None:
                raise RuntimeError("No text returned")
            return word[0]

        def BoundingBox(self, level: object) -> tuple[int, int, int, int]:  # noqa: N802
            word = self.words[self.at]
            return (0, 0, 1, 1) if word is None else word[1]

        def Confidence(self, level: object) -> float:  # noqa: N802
            return 90.0

        def Next(self, level: object) -> bool:  # noqa: N802
            self.at += 1
            return self.at < len(self.words)

    class Api:
        def __init__(self, **kwargs: object) -> None:
            pass

        def SetVariable(self, name: str, value: str) -> None:  # noqa: N802
            pass

        def SetImageBytes(self, *args: object) -> None:  # noqa: N802
            pass

        def Recognize(self) -> bool:  # noqa: N802
            return True

        def GetIterator(self) -> Iterator:  # noqa: N802
            return Iterator()

    monkeypatch.setattr(tesserocr, "PyTessBaseAPI", Api)
    ocr._tesserocr_reader.cache_clear()
    try:
        read = ocr._tesserocr_reader("/nowhere", "0123456789.")
        assert read is not None
        words = read(np.full((100, 40), 255, np.uint8))
    finally:
        ocr._tesserocr_reader.cache_clear()
    assert [w[0] for w in words] == ["12", "13"]
    assert words[0][1:3] == (10.0, 20.0)  # top, height


def _struck_scale() -> tuple[np.ndarray, Marks]:
    """A burette-like strip: a mark every 10 px, a long one every 5 (at 30, 29, 28 ... counted
    downward), and each label struck through by the long mark's ring seen through the glass,
    a line just past the label on both sides (shorter than the gap, so not taken for a wall)."""
    gray = np.full((520, 140), 215, np.uint8)
    marks = []
    for k in range(50):
        y = 20 + 10 * k
        major = k % 5 == 0
        x1 = 40 if major else 28
        gray[y - 1: y + 1, 10:x1] = 50
        marks.append(Mark(y_up=float(y), x0_up=10.0, x1_up=float(x1), thickness_up=2.0,
                          tier="major" if major else "minor", grid_index=k))
        if major:
            cv2.putText(gray, str(30 - k // 5), (50, y + 8), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 50, 2)
            gray[y: y + 2, 44:86] = 50
    return gray, Marks(marks=tuple(marks), spacing_up=10.0)


def test_labels_struck_through_by_a_line_are_read_once_it_is_taken_out() -> None:
    # a label and the line through it are one blob too wide for a digit: no text height, no band
    gray, marks = _struck_scale()
    config = default_profile("burette").ocr
    plain, _ = read_numbers(gray, marks, True, config, bands_beside(gray, marks, True, config))
    assert plain == []
    unstruck, _ = read_numbers(gray, marks, True, config, bands_beside(gray, marks, True, config, unstrike=True))
    truth = {m.y_up: 30 - m.grid_index // 5 for m in marks.marks if m.tier == "major"}
    right = [r for r in unstruck if r.value == truth.get(r.y_up)]
    assert len(right) >= 7, [(r.y_up, r.text) for r in unstruck]  # of 10 (it reads 8 here)
    assert len(right) >= 2 * (len(unstruck) - len(right))


def _ring_strip(line_to_x: int, label_x: int) -> tuple[np.ndarray, Mark]:
    """A light strip with a long mark at row 100 (3 px thick) from x 20 to ``line_to_x``, short
    marks ending at x 60, and a label of two upright strokes (an "11", 16 px tall) at ``label_x``."""
    strip = np.full((200, 160), 215, np.uint8)
    strip[99:102, 20:line_to_x] = 60
    for x in (label_x, label_x + 8):
        strip[92:108, x:x + 3] = 50
    return strip, Mark(y_up=100.0, x0_up=20.0, x1_up=float(line_to_x), thickness_up=3.0, tier="major")


def test_a_ring_run_on_through_its_label_is_taken_out_and_the_strokes_joined() -> None:
    # a burette's ring: the line goes on through the number and past it to the wall
    strip, ring = _ring_strip(line_to_x=110, label_x=70)
    out = ocr.lines_run_on_removed(strip, strip, [ring], left_edge=20, right_edge=60)
    assert out[97:104, 62:69].min() >= 190, "the line before the label is gone"
    assert out[97:104, 82:108].min() >= 190, "the line between and past the digits is gone"
    assert out[97:104, 71:72].max() <= 80 and out[97:104, 79:80].max() <= 80, "each stroke is joined across it"
    assert out[:90].min() >= 210 and out[110:].min() >= 210, "nothing above or below changes"


def test_a_label_touching_its_mark_or_apart_from_it_keeps_every_row() -> None:
    # the mark's line ends at the label (no line seen past a digit): the digits are left alone
    touching, ring = _ring_strip(line_to_x=70, label_x=70)
    assert np.array_equal(ocr.lines_run_on_removed(touching, touching, [ring], 20, 60), touching)
    apart, ring = _ring_strip(line_to_x=64, label_x=74)
    assert np.array_equal(ocr.lines_run_on_removed(apart, apart, [ring], 20, 60), apart)


def test_marks_are_lifted_to_the_paper_without_smearing_a_label_at_their_end() -> None:
    # a long mark (3 px thick) whose label starts just past its end and sits on its row, as
    # renders and real scales print them; erasing the mark must leave the label as it was
    strip = np.full((200, 160), 215, np.uint8)
    strip[99:102, 20:60] = 60
    for x in (62, 70):  # an "11", its strokes from above the mark's row down into it
        strip[88:102, x:x + 3] = 50
    mark = Mark(y_up=100.0, x0_up=20.0, x1_up=59.0, thickness_up=3.0, tier="major")
    erased = ocr.marks_erased(strip, Marks(marks=(mark,), spacing_up=10.0))
    assert erased[95:106, 18:60].min() >= 200, "the mark is lifted to the paper's level"
    label = np.zeros(strip.shape, bool)
    label[88:102, 62:65] = label[88:102, 70:73] = True
    assert erased[label].max() <= 60, "every stroke of the label is kept, its rows on the mark's too"
    assert erased[~label].min() >= 200, "nothing darker than the paper appears beside the label"


def test_a_digit_boxed_wider_than_a_digit_is_two_glyphs() -> None:
    # seed 1208: a blurred "40" read as "4" in a box as wide as it is tall (33 x 33 px); a
    # real "10" read whole is 31 x 36, and a point adds little width
    assert ocr._too_wide("4", h=33.0, width=33.0)
    assert not ocr._too_wide("10", h=36.0, width=31.0)
    assert not ocr._too_wide("7", h=36.0, width=18.0)
    assert not ocr._too_wide("0.5", h=36.0, width=40.0)
    assert not ocr._too_wide("", h=36.0, width=80.0), "no digit: nothing to read again"
    # seed 1011: a 1 ml syringe's "0.8" read as "1" in a box 1.35 times as wide as tall holds
    # more than one dropped digit; read again it gave "18"
    assert not ocr._too_wide("1", h=36.0, width=48.6)


def test_a_word_boxed_wider_than_one_digit_more_and_unsure_is_refused() -> None:
    # clean 12083, a 3 ml syringe: "0.5" read "5" at 0 % in a box 48 px wide and 35 tall, as
    # wide as the "1.5" and "2.5" read "15" and "25" beside it; its "0" and "5" joined into one
    # blob, so the count of blobs did not refuse it
    assert ocr._far_too_wide("5", h=35.0, width=48.0)
    assert not ocr._far_too_wide("25", h=35.0, width=48.0), "two digits fill that box"
    assert not ocr._far_too_wide("4", h=33.0, width=33.0), "one dropped digit: read again (_too_wide)"
    assert not ocr._far_too_wide("0.5", h=36.0, width=40.0)


def _word(text: str, width: float, conf: float = 95.0) -> tuple[str, float, float, float, float, float]:
    return (text, 0.0, 39.0, conf, 0.0, width)


def test_a_digit_as_wide_as_the_bands_tens_lost_its_zero() -> None:
    # clean 12389, a 100 ml cylinder in a condensed font: "80" boxed 36 px wide at 40 tall,
    # and "90", "40", "20" read "9", "4", "2" in boxes as wide (36-38 px)
    words = [_word("10", 49.0, 71.0), _word("9", 36.0, 37.0), _word("80", 36.0, 85.0)]
    unit = ocr._tens_digit_width(words)
    assert unit == pytest.approx((24.5 + 18.0) / 2)
    assert 36.0 >= ocr.LOST_ZERO_WIDTH * unit, "the '9' is as wide as a ten"
    assert 20.0 < ocr.LOST_ZERO_WIDTH * unit, "a digit as wide as one digit is itself"
    # only a band numbered in tens, two sure ones at least: clean 12339, a 10 ml cylinder whose
    # "8", "6", "3", "2" were boxed as wide as its "10" (47 px), a stroke beside each
    assert ocr._tens_digit_width([_word("10", 47.0), _word("8", 48.0), _word("6", 49.0)]) == 0.0
    assert ocr._tens_digit_width([_word("15", 36.0), _word("9", 36.0)]) == 0.0
    assert ocr._tens_digit_width([_word("20", 36.0), _word("25", 36.0)]) == 0.0
    assert ocr._tens_digit_width([_word("20", 36.0, 30.0), _word("9", 36.0)]) == 0.0
    assert ocr._tens_digit_width([_word("9", 36.0), _word("8", 20.0)]) == 0.0


def _fake_reader(reads_by_size: dict[int, str]):
    """A Tesseract stand-in: the word it returns for a crop, by the crop's width."""
    def read(image: np.ndarray) -> list[tuple[str, float, float, float, float, float]]:
        text = reads_by_size.get(image.shape[1], "")
        return [(text, 0.0, float(image.shape[0]), 90.0, 0.0, float(image.shape[1]))] if text else []
    return read


def _closer(reads_at: tuple[str, str, str], first: str) -> str:
    """``_read_closer`` on a 33 px word whose crop, at each of ``CLOSER_SCALES``, reads as given."""
    band = Band(np.full((200, 120), 255, np.uint8), 0, 1.0, False, text_px=33.0)
    crop_w = 33 + 2 * (int(0.5 * 33) + 4)
    widths = [round(crop_w * s) for s in ocr.CLOSER_SCALES]
    return ocr._read_closer(band, _fake_reader(dict(zip(widths, reads_at))), first, 80.0, 33.0, 40.0, 33.0)


def test_a_word_read_too_wide_is_read_again_larger_and_two_sizes_must_agree() -> None:
    assert _closer(("40", "40", ""), "4") == "40", "two sizes read the dropped digit: taken"
    assert _closer(("16", "", "16"), "6") == "16", "a leading digit dropped is taken too"
    assert _closer(("40", "", ""), "4") == "4", "one size alone is no evidence: the first read stands"
    assert _closer(("40", "49", "4"), "4") == "4", "sizes that disagree: the first read stands"


def test_a_read_again_must_keep_the_first_digits_and_have_no_leading_zero() -> None:
    assert _closer(("17", "17", "17"), "6") == "6", "a different number is no correction of the first"
    assert _closer(("05", "05", "05"), "5") == "5", "'05' is a '0.5' that lost its point, no number"
    assert _closer(("4", "4", "4"), "4") == "4", "no more digits: nothing changes"


def _labelled_scale(minor_end: int, major_end: int, font_scale: float, squeeze: float = 1.0,
                    ) -> tuple[np.ndarray, Marks, dict[float, float]]:
    """A mark every 10 px from x 30 (to ``minor_end``; every 10th, labelled 3 to 9 just above it,
    to ``major_end``), the labels starting at x 52, their digits squeezed across to ``squeeze``
    of their width; with each labelled mark's row and value."""
    gray = np.full((760, 200), 200, np.uint8)
    marks, truth = [], {}
    for k in range(61):
        y, major = 80 + 10 * k, k % 10 == 0
        x1 = major_end if major else minor_end
        gray[y:y + 2, 30:x1] = 120
        marks.append(Mark(y_up=y + 0.5, x0_up=30.0, x1_up=x1 - 1.0, thickness_up=2.0,
                          tier="major" if major else "minor", grid_index=k))
        if major:
            label = np.full((60, 80), 200, np.uint8)
            cv2.putText(label, str(3 + k // 10), (5, 50), cv2.FONT_HERSHEY_SIMPLEX, font_scale, 110, 2, cv2.LINE_AA)
            label = cv2.resize(label, None, fx=squeeze, fy=1.0, interpolation=cv2.INTER_AREA)
            x0 = 52 - round(5 * squeeze)  # the digit's first column at x 52
            under = gray[y - 55:y + 5, x0:x0 + label.shape[1]]  # the baseline 5 px above the mark
            under[:] = np.minimum(under, label)
            truth[y + 0.5] = 3 + k // 10
    return gray, Marks(marks=tuple(marks), spacing_up=10.0), truth


def test_a_condensed_font_is_read_once_widened_at_the_rows_read() -> None:
    # digits squeezed to 0.4 of their width, as img_020's burette prints them
    gray, marks, truth = _labelled_scale(minor_end=48, major_end=60, font_scale=1.6, squeeze=0.4)
    config = default_profile("burette").ocr
    bands = bands_beside(gray, marks, True, config)
    plain, _ = read_numbers(gray, marks, True, config, bands)
    wide, _ = read_numbers(gray, marks, True, config, widened(bands))
    assert all(b.x_stretch == ocr.WIDEN and b.image.shape[0] == a.image.shape[0] for a, b in zip(bands, widened(bands)))
    right_plain = [r for r in plain if r.value == truth.get(r.y_up)]
    right_wide = [r for r in wide if r.value == truth.get(r.y_up)]
    assert len(right_plain) <= 4, [(r.y_up, r.text) for r in plain]  # of 7: the "7" reads as "1" (3 right here)
    assert len(right_wide) >= 6 and len(right_wide) == len(wide), [(r.y_up, r.text) for r in wide]


def test_labels_that_begin_where_the_short_marks_end_are_read_over_the_marks() -> None:
    # labels start 5 px inside the short marks' columns (on rows of their own): a band beside the
    # marks cuts their first stroke; a band over the marks (inpainted away) does not
    gray, scale, truth = _labelled_scale(minor_end=58, major_end=90, font_scale=1.0)
    config = default_profile("burette").ocr
    beside, _ = read_numbers(gray, scale, True, config, bands_beside(gray, scale, True, config))
    over, _ = read_numbers(gray, scale, True, config, bands_beside(gray, scale, True, config, over_marks=True))
    assert sum(r.value != truth[r.y_up] for r in beside) >= 2, [(r.y_up, r.text) for r in beside]
    assert len(over) == 7 and all(r.value == truth[r.y_up] for r in over), [(r.y_up, r.text) for r in over]


def _numbers_on_faint_lines() -> tuple[np.ndarray, Marks, dict[float, float]]:
    """A cylinder's scale as img_002 shows it: a short dark tick every 8 px (x 30 to 42), and
    every 10th mark a faint line running on under its number (x 30 to 110), the number (10 to
    50, 18 px tall) standing on it. The marks stage saw each faint line only as long as a tick,
    and took two long bars of the foot, far below, for the long marks. With each labelled
    mark's row and value."""
    gray = np.full((600, 200), 215, np.uint8)
    marks, truth = [], {}
    for k in range(51):
        y = 60 + 8 * k
        labelled = k % 10 == 0
        gray[y:y + 1, 30:42] = 90
        if labelled:
            gray[y:y + 1, 42:110] = 170  # the rest of the faint line
            cv2.putText(gray, str(50 - k), (50, y - 4), cv2.FONT_HERSHEY_SIMPLEX, 0.65, 60, 2, cv2.LINE_AA)
            truth[float(y)] = float(50 - k)
        marks.append(Mark(y_up=float(y), x0_up=30.0, x1_up=41.0, thickness_up=1.0, tier="minor", grid_index=k))
    for k in (62, 63):  # the foot's rim, long bars past an empty gap
        gray[60 + 8 * k:61 + 8 * k, 20:140] = 80
        marks.append(Mark(y_up=60.0 + 8 * k, x0_up=20.0, x1_up=139.0, thickness_up=1.0, tier="major", grid_index=k))
    return gray, Marks(marks=tuple(marks), spacing_up=8.0), truth


def test_numbers_on_faint_lines_set_the_long_marks_and_read() -> None:
    gray, marks, truth = _numbers_on_faint_lines()
    config = default_profile("measuring_cylinder").ocr
    assert read_numbers(gray, marks, True, config)[0] == []  # beside the foot's bars: no number
    labels, step = ocr.label_rows(gray, marks, True)
    assert step == 10 and len(labels) >= 5, labels
    # each number's centre is over its line (half its height above it), and the line is found under it
    for lab in labels:
        line = min(truth, key=lambda y: abs(y - lab.y_up))
        assert 0 < line - lab.y_up < lab.height_px, (lab, line)
        assert lab.line_y_up == line, lab
    relabelled = majors_at_labels(marks, [(lab.y_up, lab.height_px, lab.line_y_up) for lab in labels], step)
    assert relabelled is not None
    assert sorted(m.y_up for m in relabelled.majors) == sorted(truth)
    reads, _ = read_numbers(gray, relabelled, True, config)
    right = [r for r in reads if r.value == truth.get(r.y_up)]
    assert len(right) >= 4 and len(right) == len(reads), [(r.y_up, r.text) for r in reads]
    # the long marks are no longer than the ticks, so length says nothing of a miscount; the
    # foot's bars, past an empty gap from every number read, are no marks below zero
    fit, why = fit_scale(relabelled, reads, 3, majors_by_length=False)
    assert why is None and fit is not None
    assert fit.minor_ml == pytest.approx(1.0)
    assert fit.value_at(60 + 8 * 27.5) == pytest.approx(22.5, abs=1e-6)
    assert max(fit.mark_y_up) < 60 + 8 * 62  # the foot left out


def test_a_line_that_stops_under_a_label_is_not_its_line() -> None:
    gray, marks, truth = _numbers_on_faint_lines()
    gray[:, 58:][gray[:, 58:] == 170] = 215  # each line stops under its number's first digit
    labels, step = ocr.label_rows(gray, marks, True)
    assert step == 10 and len(labels) >= 5
    assert all(lab.line_y_up is None for lab in labels), labels


def _ladder(k_range: range, majors_at: set[int], spacing: float = 6.0, top: float = 20.0) -> Marks:
    """A scale's marks, one every ``spacing`` px down the strip from ``top``; the long ones at ``majors_at``."""
    return Marks(marks=tuple(Mark(y_up=top + k * spacing, x0_up=40.0, x1_up=60.0 if k in majors_at else 50.0,
                                  thickness_up=1.5, tier="major" if k in majors_at else "minor", grid_index=k)
                             for k in k_range), spacing_up=spacing)


def test_numbers_with_no_long_mark_found_get_theirs_on_the_long_marks_lattice() -> None:
    # marks 0-25 found, only 0 and 10 tiered long (a liquid below made the others look short),
    # and none past 25 (it hid them): numbers beside 20 and 30 and 40, one between lattice places
    marks = _ladder(range(26), {0, 10})
    word = lambda text, k: ocr.BandWord(text, 20.0 + 6.0 * k - 3.0, 10.0, 90.0, False)  # centred just above
    words = [word("50", 0), word("40", 10), word("30", 20), word("20", 30), word("10", 40), word("7", 35)]
    extended = ocr.marks_for_numbers(words, marks, strip_h=300)
    assert extended is not None
    majors = {m.grid_index: m for m in extended.majors}
    assert sorted(majors) == [0, 10, 20, 30, 40]
    assert majors[20].y_up == marks.marks[20].y_up, "a mark seen there becomes a long one"
    assert abs(majors[30].y_up - (20.0 + 6.0 * 30)) < 0.5 and abs(majors[40].y_up - (20.0 + 6.0 * 40)) < 0.5
    assert len(extended.marks) == 28, "marks are added only where numbers were read"
    up, turned = ocr.placed(words, extended, 300)
    assert sorted(r.value for r in up) == [10.0, 20.0, 30.0, 40.0, 50.0] and not turned
    fit, why = fit_scale(extended, up, 3)
    assert fit is not None, why
    assert fit.minor_ml == 1.0 and abs(fit.value_at(20.0 + 6.0 * 35) - 15.0) < 1e-6


def test_no_number_without_a_long_mark_leaves_the_marks_as_found() -> None:
    marks = _ladder(range(26), {0, 10, 20})
    words = [ocr.BandWord("50", 17.0, 10.0, 90.0, False), ocr.BandWord("40", 77.0, 10.0, 90.0, False),
             ocr.BandWord("x", 200.0, 10.0, 90.0, False)]
    assert ocr.marks_for_numbers(words, marks, strip_h=300) is None
    # and a number far off its lattice place (half a period) is left out
    assert ocr.marks_for_numbers([ocr.BandWord("20", 20.0 + 6.0 * 35, 10.0, 90.0, False)], marks, 300) is None


def test_print_fainter_than_the_glyph_threshold_is_kept_at_the_faint_one() -> None:
    # a "40" 10 grey levels darker than its ground (a label over a liquid), beside a long mark
    band = np.full((200, 90), 160, np.uint8)
    cv2.putText(band, "40", (20, 104), cv2.FONT_HERSHEY_SIMPLEX, 0.5, 150, 2)
    majors = [Mark(y_up=100.0, x0_up=70, x1_up=90, thickness_up=1.5, tier="major", grid_index=0)]
    plain, plain_h = _glyph_masks(band, majors, gap=60.0)[0]
    faint, faint_h = _glyph_masks(band, majors, gap=60.0, ink_contrast=ocr.FAINT_INK_CONTRAST)[0]
    assert plain_h == 0.0 and not plain.any(), "at the usual threshold the digits are not ink"
    assert 8 <= faint_h <= 14 and faint[90:106, 18:45].sum() > 0.15 * 255 * 16 * 27


def test_a_digit_only_the_faint_threshold_keeps_makes_a_word_short_of_it() -> None:
    # clean 13075, a 25 ml burette: the "1"s of "15", "16", "19", thin and light where the label
    # meets the liquid, were lost at the glyphs' usual threshold; "5", "6", "9" outvoted a sure
    # "17", 100 divisions off. At the faint print's threshold the "1" is there: the word is short of it
    with_one = np.full((200, 120), 255, np.uint8)
    cv2.putText(with_one, "14", (30, 108), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 30, 2)
    top, h, left, width = _ink_box(with_one)
    without_one = with_one.copy()
    without_one[:, :int(left + 0.35 * width)] = 255
    _, _, four_left, four_width = _ink_box(without_one)
    word = ("4", top, h, 95.0, four_left, four_width)
    band = Band(without_one, 0, 1.0, False, text_px=16.0)
    config = default_profile("burette").ocr
    assert [w.text for w in ocr.band_words([band], config, lambda image: [word])] == ["4"]
    faint = replace(band, faint_image=with_one)
    assert ocr.band_words([faint], config, lambda image: [word]) == [], "short of the faint '1'"
    for changed in (ocr.mirrored([faint])[0], ocr.widened([faint])[0]):  # the faint image follows the band
        assert changed.faint_image is not None and changed.faint_image.shape == changed.image.shape
    assert np.array_equal(ocr.mirrored([faint])[0].faint_image, with_one[:, ::-1])
