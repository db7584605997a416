"""Numbers beside the major marks, read with Tesseract.

Text near each major mark is found as glyph-sized components (marks inpainted away, or lifted
to the paper in a search of their own, the barrel's walls and edges flattened into the
background), grouped into words; each band of words is binarised, scaled to a fixed digit
height and read by Tesseract, as it is and turned 180 degrees (for the other upright). A word
boxed wider than its digits can be (two glyphs read as one) is read again alone, larger.

Tesseract runs in-process through tesserocr (about 3 ms a call) when it can find the ``eng``
traineddata; otherwise through pytesseract, which starts the ``tesseract`` binary for every
call (about 125 ms). Same engine, same settings, same words.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from streamread.errors import DependencyError
from streamread.marks import MAJOR_STEPS, major_gap_px, major_step, print_mask
from streamread.profile import OcrConfig
from streamread.segment import true_runs
from streamread.types import Mark, Marks, OcrRead

_DEBUG_BANDS = os.environ.get("STREAMREAD_DEBUG_OCR_BANDS", "")  # a path.png: each band OCR sees is written beside it
TESSDATA_DIRS = ("/usr/share/tesseract-ocr/5/tessdata", "/usr/share/tesseract-ocr/4.00/tessdata",
                 "/usr/share/tessdata", "/usr/local/share/tessdata", "/opt/homebrew/share/tessdata")

TESSERACT_HINT = ("tesseract was not found (neither its eng traineddata nor the tesseract binary): install it "
                  "(Debian/Ubuntu: sudo apt-get install -y tesseract-ocr; macOS: brew install tesseract) or put "
                  "it on PATH / set TESSDATA_PREFIX")


Word = tuple[str, float, float, float, float, float]  # text, top, height, confidence (0-100), left, width (px)


@functools.lru_cache(maxsize=1)
def _tessdata_dir() -> str | None:
    """Where ``eng.traineddata`` lives: TESSDATA_PREFIX, the usual places, or what the binary says."""
    prefix = os.environ.get("TESSDATA_PREFIX")
    candidates = [prefix, str(Path(prefix) / "tessdata")] if prefix else []
    for c in candidates + list(TESSDATA_DIRS):
        if c and (Path(c) / "eng.traineddata").is_file():
            return c
    binary = shutil.which("tesseract")
    if binary:
        try:
            out = subprocess.run([binary, "--list-langs"], capture_output=True, text=True, timeout=10)
        except (OSError, subprocess.SubprocessError):
            return None
        m = re.search(r'"([^"]+)"', out.stdout + out.stderr)
        if m and (Path(m.group(1)) / "eng.traineddata").is_file():
            return m.group(1)
    return None


@functools.lru_cache(maxsize=4)
def _tesserocr_reader(tessdata: str, whitelist: str) -> Callable[[np.ndarray], list[Word]] | None:
    try:
        from tesserocr import PSM, RIL, PyTessBaseAPI
    except ImportError:
        return None
    try:
        api = PyTessBaseAPI(path=tessdata, lang="eng", psm=PSM.SINGLE_BLOCK)
    except RuntimeError:
        return None
    api.SetVariable("tessedit_char_whitelist", whitelist)

    def read(image: np.ndarray) -> list[Word]:
        img = np.ascontiguousarray(image, dtype=np.uint8)
        api.SetImageBytes(img.tobytes(), img.shape[1], img.shape[0], 1, img.shape[1])
        if api.Recognize() is False:
            return []
        words: list[Word] = []
        it = api.GetIterator()
        if it is None:
            return words
        while True:
            try:
                text = it.GetUTF8Text(RIL.WORD)
            except RuntimeError:  # a word with no text ("No text returned"): the next ones still count
                text = ""
            box = it.BoundingBox(RIL.WORD)
            if text and text.strip() and box is not None:
                words.append((text.strip(), float(box[1]), float(box[3] - box[1]), float(it.Confidence(RIL.WORD)),
                              float(box[0]), float(box[2] - box[0])))
            if not it.Next(RIL.WORD):
                break
        return words
    return read


def _pytesseract_reader(whitelist: str) -> Callable[[np.ndarray], list[Word]]:
    import pytesseract

    def read(image: np.ndarray) -> list[Word]:
        try:
            data = pytesseract.image_to_data(image, config=f"--psm 6 -c tessedit_char_whitelist={whitelist}",
                                             output_type=pytesseract.Output.DICT)
        except pytesseract.TesseractNotFoundError:
            raise DependencyError(TESSERACT_HINT) from None
        return [(str(t).strip(), float(top), float(h), float(c), float(left), float(w))
                for t, top, h, c, left, w in zip(data["text"], data["top"], data["height"], data["conf"], data["left"],
                                                 data["width"]) if str(t).strip()]
    return read


def word_reader(whitelist: str) -> Callable[[np.ndarray], list[Word]]:
    """Tesseract as a function of a grey image: in-process when possible (STREAMREAD_OCR=pytesseract forces the binary)."""
    if os.environ.get("STREAMREAD_OCR", "") != "pytesseract":
        tessdata = _tessdata_dir()
        if tessdata is not None:
            reader = _tesserocr_reader(tessdata, whitelist)
            if reader is not None:
                return reader
    require_tesseract()
    return _pytesseract_reader(whitelist)


def require_tesseract() -> None:
    if shutil.which("tesseract") is None:
        raise DependencyError(TESSERACT_HINT)


def parse_number(text: str) -> float | None:
    """A scale number: digits with at most one decimal point ("5", "0.5", ".5", "250")."""
    t = text.strip().replace(",", ".")
    if not re.fullmatch(r"\d+(\.\d+)?|\.\d+", t):
        return None
    value = float(t)
    return value if value < 10000 else None


MAX_MONTAGE_PX = 30000


@dataclass(frozen=True)
class Band:
    """A vertical band of the strip beside the marks, prepared for Tesseract."""

    image: np.ndarray  # dark text on white, scaled by ``scale``
    x0: int  # strip column of the band's left edge
    scale: float
    turned: bool  # rotated 180 degrees (the other upright)
    text_px: float  # the labels' height in ``image``
    x_stretch: float = 1.0  # ``image`` widened this much more than ``scale`` (``widened``)
    # the same band with the glyphs of the faint print's threshold (``FAINT_INK_CONTRAST``), for
    # counting the glyphs beside a word only (``band_words``): a thin, light "1" the usual
    # threshold lost is there (clean 13075); None where ``image`` was made at that threshold
    faint_image: np.ndarray | None = None


def _longer_than_digits_px(gap: float) -> int:
    """A length along the axis no digit reaches (digits are under 0.9 of the long-mark gap):
    what is longer is a wall, an edge or a line."""
    return int(max(7, 0.95 * gap))


# of the long marks' gap: how far from its mark a label's centre may stand above it (its own
# side) and below it, for the text height. The band is read as it is and turned, and the turned
# one measures its height the other way round: labels printed above their marks stand below them
# in a strip upside down (clean 12258, a 5 ml syringe: its digits 0.36 gap below their marks
# there; the labels the stopper half hid set the height, and the whole digits, taller, were
# dropped). A window as wide both ways took other blobs for the height (three stills of the ninth
# set lost, img_003 read 19 divisions off), and so did one mask kept for both heights
LABEL_ABOVE_GAP = 0.7
LABEL_BELOW_GAP = 0.35
THIN_GLYPH = 0.12  # narrowest width/height of a blob that sets the text height (a "1" is about 0.15-0.25)


INK_CONTRAST = 12  # grey levels under the neighbourhood's weighted mean that make a pixel ink
FAINT_INK_CONTRAST = 7  # for print too faint for that, read once more where nothing fits


def _glyph_masks(band: np.ndarray, majors: list[Mark], gap: float, unstrike: bool = False,
                 ink_contrast: float = INK_CONTRAST) -> tuple[tuple[np.ndarray, float], tuple[np.ndarray, float]]:
    """Text-sized blobs of a band (dark text on light) and the typical text height, for labels
    read in the band as it is and turned 180 degrees (the same where the heights agree).

    Adaptive threshold (uneven glass backgrounds), long horizontal lines removed (the band has
    no walls left, see ``without_walls``), then per major mark the tallest plausible blob
    nearby gives the label height (``_text_height``), which way up decides where "nearby" is.
    ``unstrike``: a line struck through the labels is taken out too (``_unstruck``).
    """
    ink = _ink(band, gap, ink_contrast)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
    widest = 5.0 if unstrike else 2.0  # a label with a line struck through it is one wide blob
    heights = (_text_height(stats, majors, gap, widest, False), _text_height(stats, majors, gap, widest, True))
    return _kept_by_height(ink, n, labels, stats, heights, unstrike)


def _kept_by_height(ink: np.ndarray, n: int, labels: np.ndarray, stats: np.ndarray, heights: tuple[float, float],
                    unstrike: bool) -> tuple[tuple[np.ndarray, float], tuple[np.ndarray, float]]:
    """``_kept_glyphs`` for the band as it is and turned (``heights``), made once where the two
    heights agree."""
    masks: dict[float, tuple[np.ndarray, float]] = {}
    for text_h in heights:
        if text_h not in masks:
            masks[text_h] = _kept_glyphs(ink, n, labels, stats, text_h, unstrike)
    return masks[heights[0]], masks[heights[1]]


def _ink(band: np.ndarray, gap: float, ink_contrast: float) -> np.ndarray:
    """The band's ink (dark on light): ``ink_contrast`` under the neighbourhood's weighted mean,
    long horizontal lines taken out."""
    block = int(max(15, 0.8 * gap)) | 1
    ink = cv2.adaptiveThreshold(band, 255, cv2.ADAPTIVE_THRESH_GAUSSIAN_C, cv2.THRESH_BINARY_INV, block,
                                ink_contrast)
    tall = _longer_than_digits_px(gap)
    horizontal = cv2.morphologyEx(ink, cv2.MORPH_OPEN, cv2.getStructuringElement(cv2.MORPH_RECT, (tall, 1)))
    return cv2.subtract(ink, cv2.dilate(horizontal, np.ones((3, 3), np.uint8)))


def _faint_glyphs(band: np.ndarray, gap: float, heights: tuple[float, float],
                  unstrike: bool) -> tuple[np.ndarray, np.ndarray]:
    """The glyphs at the faint print's threshold (``FAINT_INK_CONTRAST``) for the band as it is
    and turned, of the text heights ``heights`` that the usual threshold's glyphs set."""
    ink = _ink(band, gap, FAINT_INK_CONTRAST)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
    (upright, _), (turned, _) = _kept_by_height(ink, n, labels, stats, heights, unstrike)
    return upright, turned


def _kept_glyphs(ink: np.ndarray, n: int, labels: np.ndarray, stats: np.ndarray, text_h: float,
                 unstrike: bool) -> tuple[np.ndarray, float]:
    """The blobs of ``ink`` (``n`` components, ``labels``, ``stats``) of a glyph's size for the
    text height ``text_h``, with the decimal points beside them, and ``text_h``; no blob where
    there is no text height."""
    if text_h <= 0:
        return np.zeros_like(ink), 0.0
    if unstrike:
        ink = _unstruck(ink, text_h)
        n, labels, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
    keep = np.zeros(n, bool)
    glyph_boxes = []
    for i in range(1, n):
        x, y, w, h, area = stats[i]
        if 0.5 * text_h <= h <= 1.35 * text_h and w <= 2.5 * text_h and area >= 0.05 * text_h * text_h:
            keep[i] = True
            glyph_boxes.append((x, y, w, h))
    keep |= _decimal_points(stats, keep, glyph_boxes, text_h)
    return np.where(keep[labels], 255, 0).astype(np.uint8), text_h


def _text_height(stats: np.ndarray, majors: list[Mark], gap: float, widest: float, turned: bool) -> float:
    """The labels' height: the median over the long marks of the tallest glyph-like blob
    (``stats``: connected components) beside each, up to ``LABEL_ABOVE_GAP`` of the gap above
    it and ``LABEL_BELOW_GAP`` below (the other way round in the strip ``turned``); 0 where
    none is."""
    lo, hi = (-LABEL_BELOW_GAP, LABEL_ABOVE_GAP) if turned else (-LABEL_ABOVE_GAP, LABEL_BELOW_GAP)
    _, y, w, h, area = (stats[1:, i].astype(np.float64) for i in range(5))
    # not a thin line (a piece of wall between two erased marks): only glyphs set the height
    glyph = (h >= 5) & (h <= 0.9 * gap) & (w >= THIN_GLYPH * h) & (w <= widest * h) & (area >= 8)
    cy, h = (y + h / 2)[glyph], h[glyph]
    tallest = []
    for m in majors:
        near = (cy - m.y_up >= lo * gap) & (cy - m.y_up <= hi * gap)
        if near.any():
            tallest.append(float(h[near].max()))
    return float(np.median(tallest)) if tallest else 0.0


def _decimal_points(stats: np.ndarray, keep: np.ndarray, glyph_boxes: list[tuple[int, int, int, int]],
                    text_h: float) -> np.ndarray:
    """Which components are decimal points beside a kept digit: small, their centre in a kept
    glyph's lower half (or up to 2 px under it) and at most 0.9 of the text height across from
    the glyph's centre. All pairs at once, in blocks: a band of noise holds thousands of both,
    and pair by pair in Python that took 16 s of a noise image's 111 (``tests/test_faults.py``'s
    random images)."""
    found = np.zeros(len(stats), bool)
    if not glyph_boxes:
        return found
    x, y, w, h, area = (stats[:, i].astype(np.float64) for i in range(5))
    small = ~keep & (h <= 0.35 * text_h) & (w <= 0.35 * text_h) & (area >= 0.01 * text_h * text_h)
    small[0] = False  # the background
    g = np.asarray(glyph_boxes, np.float64)
    g_cx, g_top, g_bottom = g[:, 0] + g[:, 2] / 2, g[:, 1] + 0.5 * g[:, 3], g[:, 1] + g[:, 3] + 2
    candidates = np.flatnonzero(small)
    for block in np.array_split(candidates, len(candidates) // 1024 + 1):
        cx, cy = x[block] + w[block] / 2, y[block] + h[block] / 2
        beside = (np.abs(cx[:, None] - g_cx[None, :]) < 0.9 * text_h) & (g_top[None, :] <= cy[:, None]) \
            & (cy[:, None] <= g_bottom[None, :])
        found[block] = beside.any(axis=1)
    return found


STRIKE = 1.1  # times the text height: no digit's stroke runs this long across


def _unstruck(ink: np.ndarray, text_h: float) -> np.ndarray:
    """``ink`` without a line struck through its labels: a horizontal run longer than any
    digit's stroke (a burette's ring seen through the glass, a mark's line run through its
    number). Its rows are erased where it runs, widened by a digit to each side, and the strokes
    it cut are joined again across them (a vertical closing, there only)."""
    strike = cv2.morphologyEx(ink, cv2.MORPH_OPEN,
                              cv2.getStructuringElement(cv2.MORPH_RECT, (int(STRIKE * text_h) + 1, 1)))
    if not strike.any():
        return ink
    span = cv2.dilate(strike, cv2.getStructuringElement(cv2.MORPH_RECT, (int(text_h) | 1, 3)))
    cut = cv2.bitwise_and(ink, cv2.bitwise_not(span))
    rejoin = cv2.getStructuringElement(cv2.MORPH_RECT, (1, int(0.35 * text_h) | 1))
    joined = cv2.morphologyEx(cut, cv2.MORPH_CLOSE, rejoin)
    return np.where(span > 0, joined, cut).astype(np.uint8)


def without_walls(band: np.ndarray, gap: float) -> np.ndarray:
    """The band (dark text on light) with every dark structure longer along the axis than
    ``0.95 * gap`` flattened to the background: the barrel's walls and edges, a shadow's border.

    A vertical closing keeps what is longer than the element (walls) and fills what is shorter
    (digits, whose height is under 0.9 gap); the difference is the digits alone. A digit printed
    across the wall keeps every stroke off the wall's own columns, where masking the wall
    (dilated) used to take the "1" of "1.5" and half of a "0" with it.
    """
    tall = _longer_than_digits_px(gap)
    background = cv2.morphologyEx(band, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_RECT, (1, tall)))
    return cv2.subtract(np.full_like(band, 255), cv2.subtract(background, band))


LINE_ROW_TOL_PX = 1.0  # the line seen past a digit lies this close to the mark's own row
LINE_PAST_DIGIT_PX = 2  # columns of line alone past a digit that show the line runs on through the label
MARK_PAD_PX = 1.5  # rows beyond a mark's half thickness taken out with it (its blur)
LINE_BESIDE_ROWS = 4  # rows above and below the line's that tell a digit's stroke (ink there) from the line alone
LINE_PAPER_WINDOW_PX = 60  # columns beside the marks whose light sets the paper's level
LINE_MIN_CONTRAST = 20  # grey levels between paper and the mark's ink: below this, no line to follow


def _follow_line(print_dark: np.ndarray, mark: Mark, rows: tuple[int, int], ink: float, start: int,
                 step: int) -> tuple[int, bool]:
    """Walk from ``start`` by ``step`` along a long mark's ``rows`` while they stay dark: the
    last dark column, and whether the line was seen on its own again past a digit (ink above
    and below its rows), on its own row, for ``LINE_PAST_DIGIT_PX`` columns: it runs on
    through the label rather than ending at it."""
    y0, y1 = rows
    w = print_dark.shape[1]
    reach = start + LINE_PAPER_WINDOW_PX * step
    window = print_dark[y0 - LINE_BESIDE_ROWS:y1 + LINE_BESIDE_ROWS + 1,
                        max(0, min(start, reach)):min(w, max(start, reach) + 1)]
    paper = float(np.percentile(window, 90)) if window.size else 0.0  # the light beside the line, near the marks
    column, end, light_run = start, start, 0
    in_digit, line_only, struck = 0, 0, False
    while 0 <= column < w and light_run < 2:
        beside = np.concatenate([print_dark[y0 - LINE_BESIDE_ROWS:y0, column],
                                 print_dark[y1 + 1:y1 + 1 + LINE_BESIDE_ROWS, column]])
        dark = float(print_dark[y0:y1 + 1, column].min())
        # the paper beside the line in this column; a digit's stroke crossing the line leaves none there
        crossing = float(beside.max()) < (ink + paper) / 2 and dark < (ink + paper) / 2
        here = paper if crossing else float(beside.max())
        if here - ink < LINE_MIN_CONTRAST or dark > (ink + here) / 2:
            light_run += 1
        else:
            light_run, end = 0, column
            if float(beside.min()) < (ink + here) / 2:
                in_digit, line_only = in_digit + 1, 0
            elif in_digit >= 2:
                # the line alone again, on the mark's own row (the bar of a "5" or a "7" sits higher)
                row = y0 + int(np.argmin(print_dark[y0:y1 + 1, column]))
                line_only = line_only + 1 if abs(row - mark.y_up) <= LINE_ROW_TOL_PX else 0
                struck = struck or line_only >= LINE_PAST_DIGIT_PX
        column += step
    return end, struck


def lines_run_on_removed(print_dark: np.ndarray, erased: np.ndarray, majors: list[Mark], left_edge: int,
                         right_edge: int) -> np.ndarray:
    """``erased`` with each long mark that runs on through its number taken out there: its rows
    replaced by the interpolation between the rows just above and below, column by column.

    A burette's ring runs on through its number: the marks stage ends such a line somewhere
    inside the digits, and what is left of it strikes them through (Tesseract then reads
    nothing). The line is followed in ``print_dark`` (the strip, dark print on light) from the
    short marks' ends outward, on both sides (``_follow_line``), and taken out up to where it
    ends, past the label; the digits' vertical strokes are joined again across it. Only a line
    seen on its own again past a digit is taken out: a label apart from its mark is not reached
    (the light gap between them ends the walk), and one that merely touches its mark's end
    keeps every row.
    """
    out = erased
    h, w = print_dark.shape
    ink_cols = slice(max(0, left_edge), min(w, right_edge + 1))
    for m in majors:
        t = int(np.ceil(m.thickness_up / 2 + MARK_PAD_PX))
        yc = round(m.y_up)
        y0, y1 = yc - t, yc + t
        if y0 - LINE_BESIDE_ROWS < 0 or y1 + LINE_BESIDE_ROWS >= h:  # no rows beside it to tell digits by
            continue
        ink = float(np.median(print_dark[yc - 1:yc + 2, ink_cols].min(axis=0)))
        for step, start in ((1, right_edge + 1), (-1, left_edge - 1)):
            end, struck = _follow_line(print_dark, m, (y0, y1), ink, start, step)
            if not struck:
                continue
            a, b = (start, end + 3) if step > 0 else (end - 2, start + 1)
            a, b = max(0, a), min(w, b)
            if out is erased:
                out = erased.copy()
            above, below = out[y0 - 1, a:b].astype(np.float32), out[y1 + 1, a:b].astype(np.float32)
            frac = (np.arange(1, y1 - y0 + 2, dtype=np.float32) / (y1 - y0 + 2))[:, None]
            out[y0:y1 + 1, a:b] = np.clip(above * (1 - frac) + below * frac, 0, 255).astype(np.uint8)
    return out


def marks_erased(print_dark: np.ndarray, marks: Marks) -> np.ndarray:
    """``print_dark`` (dark print on light) with the marks' strokes taken out: within each mark's
    box, a vertical closing taller than the thickest mark, which lifts the thin line to the
    paper beside it and leaves the rest as it was.

    Inpainting the boxes from their surroundings (as before) drew the ink of a label sitting at a
    mark's end into the box: a grey smear under each digit made the label's blob taller than the
    digits, so the text height came out a third too tall and the digits too small for Tesseract
    (dev 1122). A closing never darkens, and a digit's stroke crossing the mark (taller than
    the element) stays.
    """
    mask = print_mask(print_dark.shape, marks, pad_x=2, pad_y=MARK_PAD_PX)
    thickest = max((m.thickness_up for m in marks.marks), default=1.0)
    element = cv2.getStructuringElement(cv2.MORPH_RECT, (1, int(np.ceil(thickest + 2 * MARK_PAD_PX)) + 2 | 1))
    lifted = cv2.morphologyEx(print_dark, cv2.MORPH_CLOSE, element)
    return np.where(mask > 0, lifted, print_dark).astype(np.uint8)


def _marks_inpainted(gray: np.ndarray, marks: Marks, dark_print: bool) -> np.ndarray:
    """The strip with the marks inpainted from around them, as dark print on light."""
    erased = cv2.inpaint(gray, print_mask(gray.shape, marks, pad_x=2, pad_y=MARK_PAD_PX), 3, cv2.INPAINT_TELEA)
    return erased if dark_print else 255 - erased


def bands_beside(gray: np.ndarray, marks: Marks, dark_print: bool, config: OcrConfig,
                 unstrike: bool = False, lift_marks: bool = False, over_marks: bool = False,
                 ink_contrast: float = INK_CONTRAST) -> list[Band]:
    """Left and right of the marks, upright and turned: only the digits, upscaled, on white.

    The marks are inpainted away. ``unstrike``: with a line struck through the labels taken
    out too: a long mark followed on through its number (``lines_run_on_removed``), then any
    line longer than a digit's stroke (``_unstruck``). Only in that pass: on the real
    photographs, taking the lines out in the first pass too turned two right readings into
    wrong ones. ``lift_marks``: the marks lifted to the paper (``marks_erased``) rather than
    inpainted, for labels printed at a mark's end, which inpainting smears; only in a pass of
    its own too: in the first pass it read 8 more dev stills and lost 8 others, the same
    digits read otherwise by Tesseract. ``over_marks``: each band reaches over the marks'
    columns too (they are inpainted away), for labels that begin where the short marks end: a
    band that begins after the longer of them cuts the label's first stroke (img_020's "8")."""
    majors = sorted(marks.majors, key=lambda m: m.y_up)
    if len(majors) < 2:
        return []
    gap = major_gap_px(marks)  # a long mark not seen must not double it
    minors = [m for m in marks.marks if m.tier != "major"] or list(marks.marks)
    left_edge = int(np.median([m.x0_up for m in minors]))
    right_edge = int(np.median([m.x1_up for m in minors]))
    reach = int(max(2.5 * gap, 3.0 * max(m.length_up for m in marks.marks)))
    if lift_marks:
        erased = marks_erased(gray if dark_print else 255 - gray, marks)
    else:
        erased = _marks_inpainted(gray, marks, dark_print)
    if unstrike:
        erased = lines_run_on_removed(gray if dark_print else 255 - gray, erased, majors, left_edge, right_edge)
    bands = []
    inner_left, inner_right = (right_edge, left_edge) if over_marks else (left_edge - 1, right_edge + 1)
    for x0, x1 in ((max(0, left_edge - reach), max(1, inner_left)),
                   (min(gray.shape[1] - 1, inner_right), min(gray.shape[1], right_edge + reach))):
        if x1 - x0 < 4:
            continue
        band = without_walls(np.ascontiguousarray(erased[:, x0:x1]), gap)
        masks = _glyph_masks(band, majors, gap, unstrike, ink_contrast)
        heights = (masks[0][1], masks[1][1])
        # the faint print's glyphs, for counting the glyphs beside a word (``Band.faint_image``)
        faint_masks = (_faint_glyphs(band, gap, heights, unstrike)
                       if ink_contrast > FAINT_INK_CONTRAST and max(heights) > 0 else (None, None))
        for turned, (glyphs, text_h), faint_glyphs in zip((False, True), masks, faint_masks):
            if text_h <= 0:
                continue
            scale = float(np.clip(config.text_height_px / text_h, 1.0, 6.0))
            scale = min(scale, MAX_MONTAGE_PX / max(band.shape[0], 1))  # Tesseract refuses images over 32767 px
            clean = _prepared(glyphs_on_white(band, glyphs), scale, turned)
            faint = None if faint_glyphs is None else _prepared(glyphs_on_white(band, faint_glyphs), scale, turned)
            bands.append(Band(clean, x0 if turned else x0 - int(10 / scale), scale, turned, text_h * scale,
                              faint_image=faint))
    return bands


LABEL_REACH_SPACINGS = 6.0  # how far beside the marks labels are looked for, in divisions (and 3 marks' lengths)
LABEL_TALLEST_SPACINGS = 5.0  # a label's digits are at most this many divisions tall
LABEL_SHORTEST_SPACINGS = 1.0  # and at least one division tall
LABEL_MIN_PX = 6  # and at least this many pixels
LABEL_SIZE_SPREAD = 0.3  # a label's height within this share of another's: the two are of one size
LABEL_LINE_REACH = 1.0  # times a label's height: how far from its centre its own line may run
LABEL_WIDEST = 3.0  # times its height: a blob of digits run together (a three-digit label) is no wider


def joined_into_words(blobs: list[tuple[int, int, int, int]], min_overlap: float,
                      max_gap: float) -> list[tuple[int, int, int, int]]:
    """Blobs of ink (x, y, w, h, in the order given) joined into words (x, y, w, h): a blob joins
    the first word it overlaps along the axis by ``min_overlap`` of the shorter's height and
    stands at most ``max_gap`` times the taller's height after, across."""
    words: list[list[int]] = []  # x0, y0, x1, y1
    for x, y, w, h in blobs:
        for word in words:
            overlap = min(word[3], y + h) - max(word[1], y)
            tall = max(word[3] - word[1], h)
            if overlap >= min_overlap * min(word[3] - word[1], h) and x - word[2] <= max_gap * tall:
                word[:] = [min(word[0], x), min(word[1], y), max(word[2], x + w), max(word[3], y + h)]
                break
        else:
            words.append([x, y, x + w, y + h])
    return [(x0, y0, x1 - x0, y1 - y0) for x0, y0, x1, y1 in words]


LABEL_WORD_OVERLAP = 0.6  # rows a blob shares with a word, of the shorter's height, to join it
LABEL_WORD_GAP = 0.8  # times the taller's height: at most this far after a word across, a blob joins it


@dataclass(frozen=True)
class Label:
    """A word of digit-sized blobs beside the marks: where a number is printed, not what it says."""

    y_up: float  # centre row in the strip
    height_px: float
    x0_up: float  # the word's columns in the strip
    x1_up: float
    line_y_up: float | None = None  # the row of a mark whose line runs on across the word (``_line_across``)


def label_rows(gray: np.ndarray, marks: Marks, dark_print: bool) -> tuple[list[Label], int]:
    """The words of digit-sized ink beside the marks, found without knowing which marks are long.

    ``bands_beside`` sizes its search by the long marks' gap and the blobs beside them, so where
    the long marks were not found (faint lines under the numbers that a cylinder prints on them,
    img_002) it finds no text. Here the marks' own spacing sizes it: blobs from
    ``LABEL_SHORTEST_SPACINGS`` (and ``LABEL_MIN_PX``) to ``LABEL_TALLEST_SPACINGS`` divisions
    tall, up to ``LABEL_WIDEST`` times wider (digits run together), joined into words where they
    share rows and stand close. Of those, the words on one lattice are kept
    (``_on_label_lattice``), with its step in divisions, and each with the row of its own line
    where one runs across it (``_line_across``)."""
    spacing = marks.spacing_up
    if spacing <= 0 or len(marks) < 4:
        return [], 0
    left_edge = int(np.median([m.x0_up for m in marks.marks]))
    right_edge = int(np.median([m.x1_up for m in marks.marks]))
    reach = int(max(LABEL_REACH_SPACINGS * spacing, 3.0 * float(np.median([m.length_up for m in marks.marks]))))
    erased = _marks_inpainted(gray, marks, dark_print)
    tallest = LABEL_TALLEST_SPACINGS * spacing
    words: list[list[float]] = []  # x0, y0, x1, y1 in the strip
    for x0, x1 in ((max(0, left_edge - reach), max(1, left_edge - 1)),
                   (min(gray.shape[1] - 1, right_edge + 1), min(gray.shape[1], right_edge + reach))):
        if x1 - x0 < 4:
            continue
        band = without_walls(np.ascontiguousarray(erased[:, x0:x1]), tallest / 0.95)
        block = int(max(15, 2 * tallest)) | 1
        ink = cv2.adaptiveThreshold(band, 255, cv2.ADAPTIVE_THRESH_GAUSSIAN_C, cv2.THRESH_BINARY_INV, block, 12)
        n, _, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
        shortest = max(LABEL_MIN_PX, LABEL_SHORTEST_SPACINGS * spacing)
        blobs = sorted((int(st[0]), int(st[1]), int(st[2]), int(st[3])) for st in stats[1:]
                       if shortest <= st[3] <= tallest and THIN_GLYPH * st[3] <= st[2] <= LABEL_WIDEST * st[3]
                       and st[4] >= 0.15 * st[2] * st[3])
        words += [[left + x0, top, left + x0 + w, top + h]
                  for left, top, w, h in joined_into_words(blobs, LABEL_WORD_OVERLAP, LABEL_WORD_GAP)]
    if not words:
        return [], 0
    found = [Label(y_up=(w[1] + w[3]) / 2, height_px=w[3] - w[1], x0_up=w[0], x1_up=w[2]) for w in words]
    on, step = _on_label_lattice(found, spacing)
    print_dark = gray if dark_print else 255 - gray
    marks_x = float(np.median([(m.x0_up + m.x1_up) / 2 for m in marks.marks]))
    return [replace(lab, line_y_up=_line_across(print_dark, lab, marks, marks_x)) for lab in on], step


LINE_ACROSS_SHARE = 0.85  # of a word's columns dark on a mark's row: the mark's line runs on across it
LINE_ACROSS_CONTRAST = 0.25  # of the way from the paper to the word's ink: dark enough for a (faint) line
LINE_PAST_WORD = 0.3  # times the word's height: a label's own line runs on this far past its far end


def _line_across(print_dark: np.ndarray, label: Label, marks: Marks, marks_x: float) -> float | None:
    """The row of the mark whose line runs on across a label's columns, where one does: a
    cylinder prints each number on its long line, which may be too faint to be seen whole as a
    mark (img_002) or measured no longer than its neighbours (a ring around the tube). A row
    through the digits is dark only where their strokes cross it; a line, in nearly every column,
    and on past the word's far end (``LINE_PAST_WORD``), the end away from the marks' column
    (``marks_x``, its centre)."""
    x0, x1 = int(label.x0_up), int(np.ceil(label.x1_up))
    y0, y1 = int(label.y_up - label.height_px), int(np.ceil(label.y_up + label.height_px)) + 1
    region = print_dark[max(0, y0):y1, max(0, x0):x1]
    if region.size == 0 or x1 - x0 < 3:
        return None
    paper, ink = float(np.percentile(region, 75)), float(np.percentile(region, 3))
    if paper - ink < 10:
        return None
    # the line runs on past the word's far end too (a tick drawn under a label's near digit does not)
    past = int(max(2, LINE_PAST_WORD * label.height_px))
    if (label.x0_up + label.x1_up) / 2 > marks_x:
        x1 = min(print_dark.shape[1], x1 + past)
    else:
        x0 = max(0, x0 - past)
    if x1 - x0 < 3:
        return None
    dark = print_dark[:, max(0, x0):x1] < paper - LINE_ACROSS_CONTRAST * (paper - ink)
    best: tuple[float, float] | None = None
    for m in marks.marks:
        if abs(m.y_up - label.y_up) > LABEL_LINE_REACH * label.height_px + 2:
            continue
        r = int(round(m.y_up))
        rows = dark[max(0, r - 1):r + 2]
        share = float(rows.any(axis=0).mean()) if rows.size else 0.0
        if share >= LINE_ACROSS_SHARE and (best is None or share > best[0]):
            best = (share, m.y_up)
    return None if best is None else best[1]


LABEL_LATTICE_TOL = 0.15  # of the labels' step: how far off its lattice row a label may stand (perspective)
LABEL_LATTICE_FILL = 0.75  # share of the lattice's rows from the first word to the last that hold a word


def _on_label_lattice(found: list[Label], spacing: float) -> tuple[list[Label], int]:
    """The labels that stand on one lattice, every few divisions: for each step of
    ``MAJOR_STEPS`` divisions and each word as the lattice's anchor, the words of the anchor's
    height (``LABEL_SIZE_SPREAD``) that lie within ``LABEL_LATTICE_TOL`` of a lattice row,
    filling ``LABEL_LATTICE_FILL`` of its rows between the first and the last; the largest such
    set of three or more, ties to the taller words. Debris beside a scale (a
    bubble, a stray letter) is of any size and anywhere; a scale's numbers are of one size
    and evenly spaced. Also the lattice's step in divisions (0 with no lattice)."""
    best: list[Label] = []
    best_step = 0
    for step in MAJOR_STEPS:
        period = step * spacing
        for anchor in found:
            by_row: dict[int, tuple[float, Label]] = {}  # lattice row: (how far off it, the word nearest it)
            for lab in found:
                other_size = abs(lab.height_px - anchor.height_px) > LABEL_SIZE_SPREAD * anchor.height_px
                if other_size or lab.height_px >= period:
                    continue
                k = (lab.y_up - anchor.y_up) / period
                off = abs(k - round(k))
                if off <= LABEL_LATTICE_TOL and (round(k) not in by_row or off < by_row[round(k)][0]):
                    by_row[round(k)] = (off, lab)
            if not by_row or len(by_row) < LABEL_LATTICE_FILL * (max(by_row) - min(by_row) + 1):
                continue  # rows left empty between the words: debris by chance on a lattice
            chosen = sorted((lab for _, lab in by_row.values()), key=lambda lab: lab.y_up)
            if len(chosen) > len(best) or (len(chosen) == len(best) and np.median([c.height_px for c in chosen]) >
                                           np.median([b.height_px for b in best])):
                best, best_step = chosen, step
    return (best, best_step) if len(best) >= 3 else ([], 0)


def glyphs_on_white(band: np.ndarray, glyphs: np.ndarray) -> np.ndarray:
    """The band's ``glyphs`` (a mask, slightly dilated) stretched from their darkest to the
    paper, everything else white: what Tesseract and the digit network read (and what
    ``scripts/train_digits.py`` makes of its training words)."""
    lo, hi = np.percentile(band[glyphs > 0], 5) if glyphs.any() else 0, np.percentile(band, 90)
    stretched = np.clip((band.astype(np.float32) - lo) * 255 / max(hi - lo, 1), 0, 255)
    keep = cv2.dilate(glyphs, np.ones((3, 3), np.uint8))
    return np.where(keep > 0, stretched, 255).astype(np.uint8)


def _prepared(on_white: np.ndarray, scale: float, turned: bool) -> np.ndarray:
    """A band's glyphs on white upscaled, padded 10 px each side, turned 180 degrees if ``turned``."""
    clean = cv2.resize(on_white, None, fx=scale, fy=scale, interpolation=cv2.INTER_CUBIC)
    clean = cv2.copyMakeBorder(clean, 0, 0, 10, 10, cv2.BORDER_CONSTANT, value=255)
    return cv2.rotate(clean, cv2.ROTATE_180) if turned else clean


def mirrored(bands: list[Band]) -> list[Band]:
    """The bands flipped left to right, for print seen from behind through the glass (a scale
    on the far wall). A flip keeps every row, so positions read are those of the strip; and a
    turned band flipped is the turned flipped band, so each band is flipped as it is."""
    return [replace(b, image=np.ascontiguousarray(b.image[:, ::-1]),
                    faint_image=None if b.faint_image is None else np.ascontiguousarray(b.faint_image[:, ::-1]))
            for b in bands]


WIDEN = 1.8  # a condensed font's digits are widened this much for ``widened``


def widened(bands: list[Band], factor: float = WIDEN) -> list[Band]:
    """The bands stretched across the axis, for a condensed font: Tesseract reads a thin "7"
    twice as tall as wide as a "1", and reads nothing of a column of them (img_020, a burette's
    narrow numbers), but reads them once widened. Rows are kept, so positions read are the strip's."""
    def wider(image: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(cv2.resize(image, None, fx=factor, fy=1.0, interpolation=cv2.INTER_CUBIC))
    return [replace(b, image=wider(b.image), faint_image=None if b.faint_image is None else wider(b.faint_image),
                    x_stretch=b.x_stretch * factor) for b in bands]


WORD_MIN_HEIGHT = 0.6  # times the tallest blob of ink it overlaps: a word boxed shorter is a piece of a glyph


def _word_fits_ink(band: Band, top: float, h: float, left: float, width: float) -> bool:
    """Whether a word's box is at least ``WORD_MIN_HEIGHT`` of the tallest blob of ink it
    overlaps: Tesseract also boxes a piece of a glyph (the side of a "0" read as "4") and reads
    it as a number. Ink is what is darker than half way from the paper to the darkest pixel
    around the word (faint print stays light grey). Only shorter: a glyph's strokes of uneven
    darkness fall apart at that level, so a word is often taller than its ink's blobs."""
    image, reach = band.image, band.text_px
    y0, y1 = max(0, int(top - reach)), min(image.shape[0], int(top + h + reach) + 1)
    x0, x1 = max(0, int(left - 0.5 * reach)), min(image.shape[1], int(left + width + 0.5 * reach) + 1)
    region = image[y0:y1, x0:x1]
    if region.size == 0:
        return True
    level = (int(region.min()) + 255) / 2
    _, _, stats, _ = cv2.connectedComponentsWithStats((region < level).astype(np.uint8), connectivity=8)
    x, y, w, bh = (stats[1:, i] for i in range(4))
    over = (x + x0 < left + width) & (x + x0 + w > left) & (y + y0 < top + h) & (y + y0 + bh > top)
    if not over.any():
        return True
    return h >= WORD_MIN_HEIGHT * float(bh[over].max())


JOIN_CUT = 0.4  # of a word's height: the rows cut off its bottom (or top), where a serif or a smear joins its glyphs
# of the rows left: a run of inked columns spanning this share of them is a glyph, not a piece of
# one (clean 12617: a grey "3" beside a black "1" fell into three pieces at the ink's level, its
# tongue and its lower curve each spanning half the rows)
RUN_MIN_SPAN = 0.7
RUN_MIN_WIDTH = 0.05  # of a word's height: and at least this wide (a "1" is about 0.15)


def _glyphs_beside(band: Band, top: float, h: float, left: float, width: float, split: bool = False) -> int:
    """Digit-sized blobs on a word's line, in it or within a digit's width of it: the digits
    Tesseract should have read there. Ink is what is darker than half way from the paper to the
    darkest pixel near the word: the glyphs are stretched band by band, and a label over a
    liquid or in shade stays light grey where other labels are black (clean 13187: a burette's
    "14", "15" read "4", "5", their darkest pixel 171: a fixed level of 128 saw no digit there,
    so none was missed).

    ``split``: the glyphs are also counted by their columns, the bottom rows cut off, or else the
    top ones (``JOIN_CUT``): each run of inked columns spanning ``RUN_MIN_SPAN`` of the rows left
    is one; a serif or a smear under two digits joins them into one blob (13187 too: the "1"'s
    foot touched the "4"). The larger count is returned."""
    rows, cols = band.image.shape
    digit_px = band.text_px * band.x_stretch  # a digit's reach across, in the band as widened
    x0, x1 = max(0, int(left - 0.8 * digit_px)), min(cols, int(left + width + 0.8 * digit_px) + 1)
    # whole blobs: they reach past the word, up, down and across
    y0, y1 = max(0, int(top - h)), min(rows, int(top + 2 * h) + 1)
    wx0, wx1 = max(0, int(x0 - digit_px)), min(cols, int(x1 + digit_px) + 1)
    window = band.image[y0:y1, wx0:wx1]
    if window.size == 0:
        return 0
    level = (int(window.min()) + 255) / 2
    ink = (window < level).astype(np.uint8)
    _, _, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
    x, y, w, bh = (stats[1:, i].astype(np.float64) for i in range(4))
    cx, cy = x + wx0 + w / 2, y + y0 + bh / 2
    near = (bh >= 0.5 * band.text_px) & (cy >= top) & (cy <= top + h) & (cx >= x0) & (cx <= x1)
    found = int(np.count_nonzero(near))
    if not split:
        return found
    word = band.image[max(0, int(top)):min(rows, int(top + h) + 1), x0:x1] < level
    if word.size == 0:
        return found
    cut = max(1, int(JOIN_CUT * word.shape[0]))
    for part in (word[:-cut], word[cut:]):
        runs = 0
        for first, last in true_runs(part.any(axis=0)):
            tall = np.flatnonzero(part[:, first:last + 1].any(axis=1))
            if last + 1 - first >= RUN_MIN_WIDTH * h and tall[-1] - tall[0] + 1 >= RUN_MIN_SPAN * len(part):
                runs += 1
        found = max(found, runs)
    return found


DIGIT_MAX_WIDTH = 0.65  # times the word's height: a digit boxed wider is two glyphs read as one ("40" as "4")
POINT_MAX_WIDTH = 0.35  # the same for a decimal point
CLOSER_SCALES = (2.0, 1.5, 2.5)  # a word read too wide is read once more alone at these sizes
CLOSER_AGREE = 2  # reads at those sizes that must give the same longer number


def _widest_px(text: str, h: float) -> float:
    """How wide a word of ``text`` ``h`` px tall may be boxed: ``DIGIT_MAX_WIDTH`` of its height a
    digit, ``POINT_MAX_WIDTH`` a point."""
    return h * (DIGIT_MAX_WIDTH * sum(c.isdigit() for c in text) + POINT_MAX_WIDTH * text.count("."))


def _too_wide(text: str, h: float, width: float) -> bool:
    """Whether a word's box is wider than its characters can be, by at most one digit: Tesseract
    reads two touching or close digits as one (a blurred "40" as "4", "16" over a ring as "6")
    and boxes both. A box wider still holds more than a dropped digit (a "0.8" read as "1")."""
    most = _widest_px(text, h)
    return any(c.isdigit() for c in text) and most < width <= most + DIGIT_MAX_WIDTH * h


# %: a word boxed wider than its characters and one digit more (``_far_too_wide``) read less sure
# than this is refused: Tesseract boxed a whole label and read a part of it (clean 12083, a 3 ml
# syringe: "0.5" read "5" at 0 % in a box as wide as the "1.5" beside it, its "0" and "5" joined
# into one blob, so the count of blobs did not refuse it; with "15" and "25" it made a scale of
# 5, 15, 25 ml, 241 divisions off)
UNSURE_WIDE_READ = 50.0


def _far_too_wide(text: str, h: float, width: float) -> bool:
    """Whether a word's box is wider than its characters and one digit more (``_too_wide``'s
    upper bound): it holds more than a dropped digit."""
    return width > _widest_px(text, h) + DIGIT_MAX_WIDTH * h


LOST_ZERO_WIDTH = 1.6  # digits' widths (the band's tens') a one-digit word's box spans when it lost its "0"
# sure tens a band must hold to be numbered in tens: a 10 ml cylinder's "10" alone set a digit's
# width half of its narrow "1" and "0", and its "8", "6", "3", "2", boxed as wide as the "10"
# with a stroke beside them, were made "80", "60" ... (clean 12339, 414 divisions off)
TENS_MIN = 2


def _tens_digit_width(words: list[Word]) -> float:
    """The width of a digit in a band whose sure numbers (``UNSURE_WIDE_READ`` or more) of two
    digits or more all end in "0", ``TENS_MIN`` of them or more (a scale numbered in tens), from
    those numbers' boxes; 0 where the band has fewer or some end otherwise.

    One band holds one scale's labels in one font: a single digit boxed ``LOST_ZERO_WIDTH``
    digits wide there is a ten whose "0" was lost. The fixed share of the height
    (``DIGIT_MAX_WIDTH``) misses it in a condensed font, and reading it again larger
    (``_read_closer``) does not find the "0" either (clean 12389, a 100 ml cylinder: "80" boxed
    0.9 of its height wide, "90", "40", "20" read "9", "4", "2" in boxes as wide; as read they
    made a scale of 0.1 ml with "10" for "100", 38 divisions off)."""
    sure = [(text, width) for text, _, _, conf, _, width in words
            if conf >= UNSURE_WIDE_READ and text.isdigit() and len(text) >= 2]
    if len({text for text, _ in sure}) < TENS_MIN or not all(text.endswith("0") for text, _ in sure):
        return 0.0
    return float(np.median([width / len(text) for text, width in sure]))


def _read_closer(band: Band, read_words: Callable[[np.ndarray], list[Word]], text: str, top: float, h: float,
                 left: float, width: float) -> str:
    """The word read once more on its own, larger: the number with the digits the first read
    dropped, where reads at two of ``CLOSER_SCALES`` give it alike, it has more digits, keeps
    the first read's in order and has no leading zero ("05" is a "0.5" that lost its point);
    else ``text`` as it was (the blob count then refuses it where a digit is missing)."""
    pad = int(0.5 * h) + 4
    crop = band.image[max(0, int(top) - pad):int(top + h) + pad, max(0, int(left) - pad):int(left + width) + pad]
    if crop.size == 0:
        return text
    first_digits = [c for c in text if c.isdigit()]
    votes: dict[str, int] = {}
    for scale in CLOSER_SCALES:
        larger = np.ascontiguousarray(cv2.resize(crop, None, fx=scale, fy=scale, interpolation=cv2.INTER_CUBIC))
        try:
            numbers = [w[0] for w in read_words(larger) if parse_number(w[0]) is not None]
        except DependencyError:
            raise
        except Exception:  # noqa: BLE001 - an image Tesseract cannot take: this size gives no vote
            continue
        if len(numbers) != 1:
            continue
        closer = numbers[0]
        digits = [c for c in closer if c.isdigit()]
        kept = iter(digits)
        if (len(digits) > len(first_digits) and all(c in kept for c in first_digits)
                and not re.match(r"0\d", closer)):
            votes[closer] = votes.get(closer, 0) + 1
            if votes[closer] >= CLOSER_AGREE:
                return closer
    return text


LABEL_ABOVE_MARK = 1.3  # times a number's height: how far above its mark its centre may stand
# and how far below it: a number is printed beside its mark or above it, not under it. At 0.7 a
# burette's "18", "19", "20", printed above their rings, went to the half-way marks 18 px above
# their centres (at 23 px tall; the rings were tiered as shorter): read 5 divisions off (seed
# 1550, of the second dev set 1300-1599, stop 40)
LABEL_BELOW_MARK = 0.5


def read_numbers(gray: np.ndarray, marks: Marks, dark_print: bool, config: OcrConfig,
                 bands: list[Band] | None = None, read_words: Callable[[np.ndarray], list[Word]] | None = None,
                 ) -> tuple[list[OcrRead], list[OcrRead]]:
    """Numbers beside the major marks, for the strip as it is and turned 180 degrees (one
    Tesseract call per band, and up to three more for each word boxed too wide, ``_read_closer``).

    Turned reads carry positions in the turned strip (``height - 1 - y``). ``bands``: already
    prepared (``bands_beside``, or ``mirrored`` of them), else made here. ``read_words``: what
    reads a band's words (default Tesseract; ``digits.DigitReader.words`` is the other).
    """
    if len(marks.majors) < 2:
        return [], []
    if bands is None:
        bands = bands_beside(gray, marks, dark_print, config)
    return placed(band_words(bands, config, read_words), marks, gray.shape[0])


@dataclass(frozen=True)
class BandWord:
    """A number read in a band: its text, centre and height in strip pixels (upright strip
    rows whichever way the band was read), confidence, and whether the band was turned."""

    text: str
    y_up: float
    height_up: float
    confidence: float
    turned: bool


def band_words(bands: list[Band], config: OcrConfig,
               read_words: Callable[[np.ndarray], list[Word]] | None = None) -> list[BandWord]:
    """The words of every band that pass the ink checks, in strip pixels."""
    read_words = read_words or word_reader(config.whitelist)
    # one call per band: a montage of upright and upside-down columns confuses Tesseract's line finder
    words: list[BandWord] = []
    for number, band in enumerate(bands):
        if _DEBUG_BANDS:
            cv2.imwrite(_DEBUG_BANDS.replace(".png", f"_{number}.png"), band.image)
        if not (band.image < 128).any():
            continue
        try:
            found_words = read_words(band.image)
        except DependencyError:
            raise
        except Exception:  # noqa: BLE001 - an image Tesseract cannot take: no numbers, not a crash
            continue
        if not found_words:
            continue
        tens_unit = _tens_digit_width(found_words)
        for text, top, h, conf, left, width in found_words:
            if not _word_fits_ink(band, top, h, left, width):
                continue
            boxed_px = width / band.x_stretch  # the box's width in the band as unwidened
            if _far_too_wide(text, h, boxed_px) and conf < UNSURE_WIDE_READ:
                continue  # more than one glyph boxed and not read ("0.5" read "5" at 0 %, its "0" joined to it)
            if _too_wide(text, h, boxed_px):
                text = _read_closer(band, read_words, text, top, h, left, width)
            if tens_unit and len(text) == 1 and text in "123456789" and width >= LOST_ZERO_WIDTH * tens_unit:
                text += "0"  # as wide as the band's tens: "90" read "9"
            digits = sum(c.isdigit() for c in text)
            boxed_wide = boxed_px > _widest_px(text, h)
            # a digit was left out ("4" read from "14"): a number off by ten is worse than none. Also
            # a digit only the faint print's threshold keeps (clean 13075, a 25 ml burette: the "1"s
            # of "15", "16", "19", thin and light where the labels meet the liquid, were lost at the
            # usual threshold, and "5", "6", "9" outvoted a sure "17", 100 divisions off)
            if _glyphs_beside(band, top, h, left, width, split=boxed_wide) > digits or (
                    band.faint_image is not None
                    and _glyphs_beside(replace(band, image=band.faint_image), top, h, left, width) > digits):
                continue
            y_band = (top + h / 2) / band.scale
            y = (band.image.shape[0] / band.scale - y_band) if band.turned else y_band
            words.append(BandWord(text, y, h / band.scale, conf, band.turned))
    return words


def _reach(word: BandWord) -> tuple[float, float]:
    """How far (px, down the band as read) a word's mark may lie from its centre: beside it or
    just below it (a number printed above its line)."""
    return -LABEL_ABOVE_MARK * word.height_up - 2, LABEL_BELOW_MARK * word.height_up + 2


def placed(words: list[BandWord], marks: Marks, strip_h: int) -> tuple[list[OcrRead], list[OcrRead]]:
    """Each word's number on the long mark it labels, upright and turned (the more confident
    where two words label one mark)."""
    majors = sorted(marks.majors, key=lambda m: m.y_up)
    found: dict[tuple[bool, int], OcrRead] = {}
    for word in words:
        value = parse_number(word.text)
        if value is None:
            continue
        # "below" is down the band as read, which runs up the strip for a turned band
        down = -1.0 if word.turned else 1.0
        low, high = _reach(word)
        candidates = [m for m in majors if low <= down * (word.y_up - m.y_up) <= high]
        if not candidates:
            continue
        mark = min(candidates, key=lambda m: abs(down * (word.y_up - m.y_up) + 0.3 * word.height_up))
        key = (word.turned, id(mark))
        mark_y = strip_h - 1 - mark.y_up if word.turned else mark.y_up
        read = OcrRead(y_up=mark_y, text=word.text, value=value, confidence=word.confidence)
        if key not in found or found[key].confidence < read.confidence:
            found[key] = read
    upright = [r for (turned, _), r in found.items() if not turned]
    turned = [r for (turned, _), r in found.items() if turned]
    return upright, turned


LATTICE_SNAP = 0.3  # of the long marks' period: how near a long mark's place a number with no long mark must be


def marks_for_numbers(words: list[BandWord], marks: Marks, strip_h: int) -> Marks | None:
    """The marks with a long mark for each number read where none was found: a liquid or glare
    hid the marks there, or made them look no longer than the rest, not the print (dev 1200:
    "30", "20", "10" over a yellow liquid, the long marks found only in the air above it). A
    number goes to its place on the long marks' lattice (the grid's curve carried on past the
    marks seen): the mark there becomes a long one, or, where no mark was seen there, one is
    put there; a number further than ``LATTICE_SNAP`` of a period from a place is left out.
    None where no number gains a mark."""
    majors = marks.majors
    every = major_step(marks)
    if len(marks.marks) < 6 or len(majors) < 2 or every < 2:
        return None
    ks = np.array([m.grid_index for m in marks.marks], float)
    ys = np.array([m.y_up for m in marks.marks])
    curve = np.polyfit(ks, ys, 2 if len(ks) >= 10 else 1)
    phase = int(np.bincount([m.grid_index % every for m in majors]).argmax())
    k_lo, k_hi = int(ks.min()), int(ks.max())
    span = k_hi - k_lo
    fine_k = np.arange(k_lo - 2 * span - every, k_hi + 2 * span + every + 1, 0.05)
    fine_y = np.polyval(curve, fine_k)
    steps = np.diff(fine_y)
    if not (np.all(steps > 0) or np.all(steps < 0)):
        return None  # the curve turns back within reach: no lattice to carry on
    by_index = {m.grid_index: m for m in marks.marks}
    x0 = float(np.median([m.x0_up for m in majors]))
    x1 = float(np.median([m.x1_up for m in majors]))
    thickness = float(np.median([m.thickness_up for m in majors]))
    changed: dict[int, Mark] = {}
    for word in words:
        if parse_number(word.text) is None:
            continue
        down = -1.0 if word.turned else 1.0
        low, high = _reach(word)
        if any(low <= down * (word.y_up - m.y_up) <= high for m in majors):
            continue  # it has its long mark
        mark_y = word.y_up + down * 0.3 * word.height_up  # where its mark most likely is
        if not 0 <= mark_y < strip_h:
            continue
        k_est = float(fine_k[int(np.argmin(np.abs(fine_y - mark_y)))])
        k = phase + every * round((k_est - phase) / every)
        if abs(k_est - k) > LATTICE_SNAP * every or k in changed:
            continue
        seen = by_index.get(k)
        if seen is not None:
            if seen.tier != "major" and low <= down * (word.y_up - seen.y_up) <= high:
                changed[k] = replace(seen, tier="major")
            continue
        y_k = float(np.polyval(curve, k))
        if low <= down * (word.y_up - y_k) <= high and 0 <= y_k < strip_h:
            changed[k] = Mark(y_up=y_k, x0_up=x0, x1_up=x1, thickness_up=thickness, tier="major", grid_index=k)
    if not changed:
        return None
    kept = [m for m in marks.marks if m.grid_index not in changed]
    return Marks(marks=tuple(sorted([*kept, *changed.values()], key=lambda m: m.grid_index)),
                 spacing_up=marks.spacing_up)
