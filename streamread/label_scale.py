"""The scale from its printed numbers first, where its marks are too faint to be found.

The paper's order is marks first, then the number beside each long one. Under plain room light
a burette's ticks can be as faint as the paper's grain (img_007: its short marks 2-3 grey levels
deep), so that neither the marks stage nor the faint-line search finds a regular ladder, while
its numbers, "0" to "4", stand 25 px tall and plain. Here the order is turned, within the
strip of a ladder found in the image (its tube's walls, a few ticks):

1. ``label_lattice``: words of digit-sized ink in one column, of one size, evenly spaced;
2. ``read_labels``: each word read by the digit network and by Tesseract;
3. ``ring_rows``: each number's own line (a burette's ring, a cylinder's long mark), found as the
   row at one offset from every label that is darker than the paper across the label's columns:
   the offset is common to the labels, where the liquid's surface or a stray line beside one
   label is not;
4. ``divisions_per_step``: the short marks between two rings, too faint to be found one by one,
   found together as a comb: the largest count of divisions whose comb stands out of the noise
   on every division, not on every other one.

The rings with their numbers, and marks set evenly between them, go to the fit like any other
scale's. Each step refuses rather than guesses; the reader tries this last, where no other search
read a scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from streamread.digits import digit_reader
from streamread.marks import MAJOR_STEPS
from streamread.ocr import THIN_GLYPH, Label, glyphs_on_white, joined_into_words, parse_number, word_reader
from streamread.profile import OcrConfig
from streamread.types import Mark, Marks, OcrRead, Tier

LABEL_SMALLEST_PX = 10  # a number's digits are at least this tall ...
LABEL_TALLEST_PX = 80  # ... and at most this tall, in strip pixels
INK_BLOCK_PX = 41  # the adaptive threshold's window for the labels' ink
INK_CONTRAST = 10  # grey levels under the window's weighted mean that make a pixel ink
LABEL_SIZE_SPREAD = 0.25  # a label's height within this share of the others'
LATTICE_TOL = 0.15  # of the labels' period: how far off its lattice row a label may stand (perspective)
LATTICE_FILL = 0.75  # share of the lattice's rows from the first label to the last that hold one
MIN_LABELS = 3
STEP_MIN_HEIGHTS = 1.8  # the labels' period is at least this many label heights
COLUMN_REACH = 0.6  # times a label's height: how far its columns may lie from another's (one column)
LATTICE_PARTNERS = 3  # words alike below each word that, with it, set a lattice's period

READ_HEIGHT_PX = 40  # Tesseract reads a label scaled to this height ...
READ_WIDEN = 1.8  # ... and widened this much (a burette's condensed digits read as "1" or not at all)
MIN_READ_CONFIDENCE = 50.0  # % sure, either reader

RING_REACH = 1.3  # times a label's height: how far from its centre its ring is looked for
RING_BESIDE = 1.0  # times its height: the columns before the label (the marks' side) the ring spans too
RING_MIN_CONTRAST = 4.0  # grey levels the ring's row lies under the paper, on the labels' mean
RING_EDGE = 0.05  # times a label's height: an offset this near the search's end is no ring
RING_AGREE = 0.15  # times a label's height: a label's own darkest row this near the common offset is its ring
RING_MIN_FOUND = 3  # labels whose own ring is found at the common offset

COMB_MIN_Z = 3.5  # the division comb's contrast, in its standard errors, that counts as seen ...
COMB_HALF_Z = 2.0  # ... and each half of it (odd and even divisions) ...
COMB_HALF_SHARE = 0.4  # ... each at least this share as deep as the other (twice the count: half of nothing)
COMB_MIN_PITCH_PX = 3.0  # a division this short cannot be told from the print's grain
COMB_WINDOW_PX = 4  # columns of one comb window
COMB_BLUR_MIN_PX = 0.7  # the least blur of a comb window's profile (a Gaussian sigma) ...
COMB_BLUR_SHARE = 0.125  # ... and its share of a division
COMB_SMOOTH_PX = 4.0  # the profile's background (its Gaussian sigma) taken out before the comb


@dataclass(frozen=True)
class LabelRead:
    """A label and the number read in it, as the surer reader read it (confidence 0-100)."""

    label: Label
    text: str
    value: float
    confidence: float


def label_words(gray: np.ndarray) -> list[Label]:
    """Words of digit-sized ink (dark on light) anywhere in the strip."""
    ink = cv2.adaptiveThreshold(gray, 255, cv2.ADAPTIVE_THRESH_GAUSSIAN_C, cv2.THRESH_BINARY_INV, INK_BLOCK_PX,
                                INK_CONTRAST)
    _, _, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
    blobs = sorted((int(x), int(y), int(w), int(h)) for x, y, w, h, area in stats[1:]
                   if LABEL_SMALLEST_PX <= h <= LABEL_TALLEST_PX and THIN_GLYPH * h <= w <= 1.0 * h
                   and area >= 0.15 * w * h)
    return [Label(y_up=y + h / 2, height_px=float(h), x0_up=float(x), x1_up=float(x + w))
            for x, y, w, h in joined_into_words(blobs, 0.6, 0.8)]


def _right_of_marks(x0: float, x1: float, strip_width: int) -> bool:
    """Whether print spanning columns ``x0``-``x1`` stands right of the strip's middle, where
    the ladder's marks are: its near edge, on the marks' side, is then ``x0``."""
    return (x0 + x1) / 2 >= strip_width / 2


def _one_column(a: Label, b: Label) -> bool:
    reach = COLUMN_REACH * max(a.height_px, b.height_px)
    return a.x0_up - reach <= b.x1_up and b.x0_up - reach <= a.x1_up


def _alike(a: Label, b: Label) -> bool:
    """Of one size and in one column: two numbers of one scale."""
    return abs(a.height_px - b.height_px) <= LABEL_SIZE_SPREAD * max(a.height_px, b.height_px) and _one_column(a, b)


def label_lattice(words: list[Label]) -> list[Label]:
    """The largest set of words of one size, in one column, evenly spaced (``MIN_LABELS`` or
    more, filling ``LATTICE_FILL`` of the rows between the first and the last): a scale's
    numbers; debris beside it is of any size and anywhere. Each word and each of the next
    ``LATTICE_PARTNERS`` alike below it, at one to three periods, set a lattice; each anchor's
    partners are its own, so that perspective's slow change of the period is met from every
    label in turn. The work grows with the words times those alike, not their cube: a strip of
    clutter is searched here only after every other search failed."""
    words = sorted(words, key=lambda w: w.y_up)
    best: list[Label] = []
    for i, a in enumerate(words):
        alike = [w for w in words if w is a or _alike(a, w)]
        below = [w for w in words[i + 1:] if _alike(a, w)][:LATTICE_PARTNERS]
        for b in below:
            for k in range(1, 4):
                period = (b.y_up - a.y_up) / k
                if period < STEP_MIN_HEIGHTS * max(a.height_px, b.height_px):
                    break
                by_row: dict[int, tuple[float, Label]] = {}
                for w in alike:
                    t = (w.y_up - a.y_up) / period
                    off = abs(t - round(t))
                    if off <= LATTICE_TOL and (round(t) not in by_row or off < by_row[round(t)][0]):
                        by_row[round(t)] = (off, w)
                if len(by_row) < LATTICE_FILL * (max(by_row) - min(by_row) + 1):
                    continue
                chosen = sorted((w for _, w in by_row.values()), key=lambda w: w.y_up)
                if len(chosen) > len(best):
                    best = chosen
    return best if len(best) >= MIN_LABELS else []


def _label_crop(gray: np.ndarray, label: Label) -> np.ndarray:
    """The label's digits, dark on white, with a margin: what both readers read."""
    h = label.height_px
    pad_y, pad_x = int(0.2 * h), int(0.4 * h)
    y0, y1 = max(0, int(label.y_up - h / 2) - pad_y), min(gray.shape[0], int(np.ceil(label.y_up + h / 2)) + pad_y)
    x0, x1 = max(0, int(label.x0_up) - pad_x), min(gray.shape[1], int(np.ceil(label.x1_up)) + pad_x)
    crop = gray[y0:y1, x0:x1]
    ink = cv2.adaptiveThreshold(crop, 255, cv2.ADAPTIVE_THRESH_GAUSSIAN_C, cv2.THRESH_BINARY_INV,
                                INK_BLOCK_PX, INK_CONTRAST)
    glyphs = np.zeros_like(ink)
    gy0, gx0 = int(label.y_up - h / 2) - y0, int(label.x0_up) - x0
    gy1, gx1 = int(np.ceil(label.y_up + h / 2)) - y0, int(np.ceil(label.x1_up)) - x0
    glyphs[max(0, gy0):gy1, max(0, gx0):gx1] = ink[max(0, gy0):gy1, max(0, gx0):gx1]
    return glyphs_on_white(crop, glyphs)


def read_labels(gray: np.ndarray, labels: list[Label], whitelist: str = OcrConfig.whitelist) -> list[LabelRead]:
    """Each label's number, the surer of the digit network's read and Tesseract's (the fit's
    vote sorts out a misread); a label neither reads ``MIN_READ_CONFIDENCE`` sure is left out.
    Tesseract reads one glyph alone poorly at its own size: scaled and widened first, with the
    profile's ``whitelist``."""
    if not labels:
        return []
    crops = [_label_crop(gray, lab) for lab in labels]
    by_network = digit_reader().read(crops)
    tesseract = word_reader(whitelist)
    reads: list[LabelRead] = []
    for lab, crop, (net_text, net_conf) in zip(labels, crops, by_network):
        scale = READ_HEIGHT_PX / max(crop.shape[0], 1)
        big = cv2.resize(crop, None, fx=scale * READ_WIDEN, fy=scale, interpolation=cv2.INTER_CUBIC)
        big = cv2.copyMakeBorder(big, 15, 15, 15, 15, cv2.BORDER_CONSTANT, value=255)
        words = tesseract(big)
        tess_text, tess_conf = (words[0][0], words[0][3]) if len(words) == 1 else ("", 0.0)
        options = [(conf, text) for text, conf in ((net_text, net_conf), (tess_text, tess_conf))
                   if text and parse_number(text) is not None and conf >= MIN_READ_CONFIDENCE]
        if not options:
            continue
        conf, text = max(options)
        value = parse_number(text)
        assert value is not None
        reads.append(LabelRead(label=lab, text=text, value=value, confidence=conf))
    return reads


def _darkness_rows(gray: np.ndarray, label: Label, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Rows around a label and how far each lies under the paper across the label's columns and
    ``RING_BESIDE`` heights before them on the side of the strip's middle (where the marks are)."""
    h = label.height_px
    y0, y1 = max(0, int(label.y_up - reach * h)), min(gray.shape[0], int(np.ceil(label.y_up + reach * h)) + 1)
    if _right_of_marks(label.x0_up, label.x1_up, gray.shape[1]):
        x0, x1 = int(label.x0_up - RING_BESIDE * h), int(np.ceil(label.x1_up))
    else:
        x0, x1 = int(label.x0_up), int(np.ceil(label.x1_up + RING_BESIDE * h))
    region = gray[y0:y1, max(0, x0):min(gray.shape[1], x1)].astype(np.float32)
    if region.size == 0:
        return np.arange(0), np.zeros(0)
    paper = float(np.percentile(region, 75))
    return np.arange(y0, y1, dtype=np.float64), paper - region.mean(axis=1)


def ring_rows(gray: np.ndarray, labels: list[Label]) -> list[float | None]:
    """Each label's own line (None where not found): the offset from the labels' centres, in
    their heights, at which the summed darkness is greatest outside the digits' rows, then each
    label's darkest row within ``RING_AGREE`` of it. None for all where under ``RING_MIN_FOUND``
    labels show it, where it is too faint, or at the search's end (``RING_EDGE``)."""
    steps = np.linspace(-RING_REACH, RING_REACH, 105)
    total = np.zeros_like(steps)
    profiles = []
    for lab in labels:
        rows, dark = _darkness_rows(gray, lab, RING_REACH)
        profiles.append((rows, dark))
        if len(rows) < 2:
            continue
        total += np.interp(lab.y_up + steps * lab.height_px, rows, dark, left=0.0, right=0.0)
    outside = np.abs(steps) > 0.5 + 1.0 / max(np.median([lab.height_px for lab in labels]), 1.0)
    if not outside.any():
        return [None] * len(labels)
    total = np.where(outside, total, -np.inf)
    best = int(np.argmax(total))
    if total[best] / len(labels) < RING_MIN_CONTRAST or abs(steps[best]) > RING_REACH - RING_EDGE:
        # too faint, or deepest at the search's end: a line further off (the next label's, a
        # tick between) is deeper still, and none of the labels' own (second dev 1403, a
        # syringe's numbers centred on their marks: a row 1.3 heights above each was taken)
        return [None] * len(labels)
    found: list[float | None] = []
    for lab, (rows, dark) in zip(labels, profiles):
        near = np.abs(rows - (lab.y_up + steps[best] * lab.height_px)) <= RING_AGREE * lab.height_px
        if not near.any():
            found.append(None)
            continue
        i = int(np.flatnonzero(near)[np.argmax(dark[near])])
        if dark[i] < RING_MIN_CONTRAST / 2:
            found.append(None)
            continue
        lo, hi = max(0, i - 1), min(len(rows), i + 2)  # the darkness-weighted row of its three
        weights = np.clip(dark[lo:hi], 0, None)
        found.append(float(np.average(rows[lo:hi], weights=weights)) if weights.sum() > 0 else float(rows[i]))
    return found if sum(r is not None for r in found) >= RING_MIN_FOUND else [None] * len(labels)


RING_RUN_SHARE = 0.4  # of the ring's darkest: a column this dark on its row is still the ring
SHORT_MARK_SHARE = 0.15  # of a ring's length: the short marks set between the rings, at its far end


def ring_extent(gray: np.ndarray, label: Label, row: float) -> tuple[float, float] | None:
    """The columns a label's ring runs across: the run of columns dark on its row (against the
    rows three pixels above and below) that holds the label's near edge, on the marks' side."""
    r = int(round(row))
    if r < 3 or r > gray.shape[0] - 4:
        return None
    h = label.height_px
    x0, x1 = max(0, int(label.x0_up - 2 * h)), min(gray.shape[1], int(np.ceil(label.x1_up + 2 * h)))
    line = gray[r - 1:r + 2, x0:x1].astype(np.float32).min(axis=0)
    around = np.maximum(gray[r - 3, x0:x1], gray[r + 3, x0:x1]).astype(np.float32)
    dark = around - line
    if dark.max(initial=0.0) < RING_MIN_CONTRAST:
        return None
    on = dark >= RING_RUN_SHARE * dark.max()
    right = _right_of_marks(label.x0_up, label.x1_up, gray.shape[1])
    start = int(round((label.x0_up if right else label.x1_up - 1) - x0))
    start = min(max(start, 0), len(on) - 1)
    near = np.flatnonzero(on[max(0, start - 2):start + 3])
    if not len(near):
        return None
    i = j = max(0, start - 2) + int(near[0])
    while i > 0 and on[i - 1]:
        i -= 1
    while j < len(on) - 1 and on[j + 1]:
        j += 1
    return float(x0 + i), float(x0 + j + 1)


COMB_MIN_SPREAD = 0.25  # grey levels: the least spread ``_z`` assumes (a drawn strip has none)


def _z(diff: np.ndarray) -> float:
    """How many standard errors the median of ``diff`` stands above zero, the spread taken
    robustly (the median absolute deviation): the liquid's surface or a ring met by one
    division's comb is one value 30 grey levels off, which must not hide 30 marks 3 deep.
    0 for under 2 values."""
    if len(diff) < 2:
        return 0.0
    median = float(np.median(diff))
    spread = max(1.4826 * float(np.median(np.abs(diff - median))), COMB_MIN_SPREAD)
    return median / (spread / np.sqrt(len(diff)))


def divisions_per_step(gray: np.ndarray, rings: list[float], per_step: list[int], near_x: tuple[float, float],
                       reach_px: float) -> tuple[int, float] | None:
    """The count of divisions between neighbouring rings (of ``MAJOR_STEPS``), and how many
    standard errors its comb stood out; None where no count's comb is seen.

    ``rings``: sorted rows; ``per_step``: the labels' steps between neighbours (1 where every
    label was found). For each count and each window of ``COMB_WINDOW_PX`` columns within
    ``reach_px`` of ``near_x``: the darkness at the divisions' rows less that half a division on.
    Too few divisions land on every other mark or on the longer half-way one, and stand out as
    well; too many land half of the time between marks. So the count taken is the largest whose
    comb's median stands ``COMB_MIN_Z`` out in its best window and, there, each half of it (the
    odd and the even divisions) ``COMB_HALF_Z``, as deep as the other within ``COMB_HALF_SHARE``."""
    x_lo, x_hi = max(0, int(near_x[0] - reach_px)), min(gray.shape[1], int(near_x[1] + reach_px))
    y_lo, y_hi = int(max(0, rings[0] - 2)), int(min(gray.shape[0], rings[-1] + 3))
    if x_hi - x_lo < COMB_WINDOW_PX or y_hi - y_lo < 8:
        return None
    region = gray[y_lo:y_hi, x_lo:x_hi].astype(np.float32)
    rows = np.arange(y_lo, y_hi, dtype=np.float64)
    fines = []
    for c in range(0, x_hi - x_lo - COMB_WINDOW_PX + 1, 2):
        profile = -region[:, c:c + COMB_WINDOW_PX].mean(axis=1)
        background = cv2.GaussianBlur(profile.reshape(-1, 1), (1, 0), sigmaX=0, sigmaY=COMB_SMOOTH_PX).ravel()
        fines.append(profile - background)
    for n in sorted(MAJOR_STEPS, reverse=True):
        at_all: list[float] = []
        odd: list[bool] = []
        for a, b, k in zip(rings[:-1], rings[1:], per_step):
            pitch = (b - a) / (n * k)
            js = np.arange(1, n * k)
            js = js[js % n != 0]  # not the rings of labels not found
            at_all += (a + pitch * js).tolist()
            odd += (js % 2 == 1).tolist()
        pitch_px = (rings[-1] - rings[0]) / (n * sum(per_step))
        if pitch_px < COMB_MIN_PITCH_PX or len(at_all) < 4:
            continue
        at, is_odd = np.asarray(at_all), np.asarray(odd)
        # a mark a pixel thick found half a pixel off the comb's row would count half: each
        # profile blurred by an eighth of a division first
        blur = max(COMB_BLUR_MIN_PX, COMB_BLUR_SHARE * pitch_px)
        best: tuple[float, np.ndarray] | None = None  # the window where the comb stands out most
        for fine in fines:
            fine = cv2.GaussianBlur(fine.reshape(-1, 1), (1, 0), sigmaX=0, sigmaY=blur).ravel()
            diff = np.interp(at, rows, fine) - np.interp(at + pitch_px / 2, rows, fine)
            z = _z(diff)
            if best is None or z > best[0]:
                best = (z, diff)
        if best is None or best[0] < COMB_MIN_Z:
            continue
        z, diff = best
        if (~is_odd).any():  # both halves, in that window
            halves = (diff[is_odd], diff[~is_odd])
            depths = [float(np.median(half)) for half in halves]
            if min(_z(half) for half in halves) < COMB_HALF_Z or min(depths) < COMB_HALF_SHARE * max(depths):
                continue
        return n, z
    return None


MAX_TILT = 0.05  # columns per row: the labels' column leans at most this much in the strip (3 degrees)


def _straightened(gray: np.ndarray, found: list[tuple[Label, float]]) -> np.ndarray:
    """The strip sheared so that the labels' column, and the marks' beside it, runs straight
    down: the ladder that set the strip's axis (walls, a few ticks) may lean a degree from the
    print, and over 400 rows a degree moves a column of ticks 4 px wide out of a comb's window
    (img_007 leans 0.8 degree: its comb stands 4.3 standard errors out unsheared, 6.4
    sheared). The lean is the line through the labels' edges on the marks' side, sheared about
    their middle row."""
    if len(found) < 3:
        return gray
    right = _right_of_marks(float(np.median([lab.x0_up for lab, _ in found])),
                            float(np.median([lab.x1_up for lab, _ in found])), gray.shape[1])
    edges = np.array([lab.x0_up if right else lab.x1_up for lab, _ in found])
    rows = np.array([lab.y_up for lab, _ in found])
    tilt = float(np.polyfit(rows, edges, 1)[0])
    if abs(tilt) > MAX_TILT:
        return gray
    middle = float(np.median(rows))
    shear = np.array([[1.0, tilt, -tilt * middle], [0.0, 1.0, 0.0]])
    return cv2.warpAffine(gray, shear, (gray.shape[1], gray.shape[0]), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)


def marks_from_labels(gray: np.ndarray, whitelist: str = OcrConfig.whitelist) -> tuple[Marks, list[OcrRead]] | str:
    """Marks and numbers read for a strip by its labels first, or why none: the rings are the
    long marks (each with its number), the divisions between them set evenly."""
    labels = label_lattice(label_words(gray))
    if not labels:
        return "no evenly spaced numbers in the strip"
    rings = ring_rows(gray, labels)
    found = [(lab, y) for lab, y in zip(labels, rings) if y is not None]
    if not found:
        return "no line at one offset from the numbers"
    reads = {id(r.label): r for r in read_labels(gray, [lab for lab, _ in found], whitelist)}
    if len(reads) < MIN_LABELS:
        return f"{len(reads)} numbers read (need {MIN_LABELS})"
    ys = [y for _, y in found]
    period = float(np.median(np.diff(ys))) if len(ys) > 1 else 0.0
    steps = [max(1, int(round((b - a) / period))) for a, b in zip(ys[:-1], ys[1:])]
    period = float(np.median([(b - a) / k for a, b, k in zip(ys[:-1], ys[1:], steps)]))
    heights = float(np.median([lab.height_px for lab, _ in found]))
    xs = (float(np.median([lab.x0_up for lab, _ in found])), float(np.median([lab.x1_up for lab, _ in found])))
    counted = divisions_per_step(_straightened(gray, found), ys, steps, xs, 1.5 * heights)
    if counted is None:
        return "no divisions seen between the numbers' lines"
    n, _ = counted
    extents = [e for e in (ring_extent(gray, lab, y) for lab, y in found) if e is not None]
    if len(extents) < RING_MIN_FOUND:
        return "the numbers' lines are not seen across them"
    ring_x0, ring_x1 = float(np.median([e[0] for e in extents])), float(np.median([e[1] for e in extents]))
    short = SHORT_MARK_SHARE * (ring_x1 - ring_x0)
    if _right_of_marks(xs[0], xs[1], gray.shape[1]):  # the short marks start at the ring's left end
        short_x0, short_x1 = ring_x0, ring_x0 + short
    else:
        short_x0, short_x1 = ring_x1 - short, ring_x1
    marks: list[Mark] = []
    ocr_reads: list[OcrRead] = []
    index = 0
    for i, ((lab, y), next_y, k) in enumerate(zip(found, ys[1:] + [None], steps + [0])):
        marks.append(Mark(y_up=y, x0_up=ring_x0, x1_up=ring_x1, thickness_up=2.0, tier="major", grid_index=index))
        read = reads.get(id(lab))
        if read is not None:
            ocr_reads.append(OcrRead(y_up=y, text=read.text, value=read.value, confidence=read.confidence))
        if next_y is None:
            break
        pitch = (next_y - y) / (n * k)
        for j in range(1, n * k):
            tier: Tier = "major" if j % n == 0 else "minor"  # a label not found still has its ring
            x0, x1 = (ring_x0, ring_x1) if tier == "major" else (short_x0, short_x1)
            marks.append(Mark(y_up=y + j * pitch, x0_up=x0, x1_up=x1, thickness_up=1.0, tier=tier,
                              grid_index=index + j))
        index += n * k
    return Marks(marks=tuple(marks), spacing_up=period / n), ocr_reads
