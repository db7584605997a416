"""From numbers to a scale: the paper's auto-correction, then a fit over every mark.

1. Auto-correction (the paper): slopes of all pairs of OCR reads; the most common slope (a
   cluster within 8 %, since pixel slopes are not exact) is right; reads that disagree are
   misreads and dropped. Where some numbers disagree, the same is done counting marks instead
   of pixels (``_grid_correction``): a steep perspective spreads the pixel slopes, not the
   number of marks between two numbers; the one that explains more numbers is kept.
2. Every mark gets its value: the agreeing reads fix the value per grid step (snapped to a
   1-2-5 series) and the value of grid step zero, so marks OCR never read are valued too.
3. value = slope * y + offset is fitted over all marks (dozens of points, hence sub-pixel),
   and ``ScaleFit.value_at`` reads locally from the nearest marks, which absorbs perspective.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from streamread.marks import apart_from, major_step, strays
from streamread.types import Mark, Marks, OcrRead, ScaleFit

NICE = (1.0, 2.0, 2.5, 5.0)


def snap_nice(value: float, tolerance: float = 0.06) -> float | None:
    """The 1-2-2.5-5 series number closest to ``value`` if within ``tolerance`` (relative)."""
    if value <= 0 or not math.isfinite(value):
        return None
    exponent = math.floor(math.log10(value))
    best = min((n * 10.0**e for n in NICE for e in (exponent - 1, exponent, exponent + 1)),
               key=lambda c: abs(math.log(value / c)))
    return best if abs(value / best - 1) <= tolerance else None


@dataclass(frozen=True)
class Correction:
    slope: float
    offset: float
    inliers: tuple[OcrRead, ...]


def mode_of_slopes(reads: list[OcrRead], min_dy: float, weights: list[float] | None = None,
                   slope_tolerance: float = 0.08, value_tolerance: float | None = None) -> Correction | None:
    """The paper's auto-correction: the most common pairwise slope and the reads that agree.

    ``weights`` (one per read) make some reads count less towards the mode (a guessed reading
    of a number, such as one with its decimal point restored); a mark keeps one read. Slopes
    within ``slope_tolerance`` (relative) of the mode agree; a read is an inlier within
    ``value_tolerance`` of the line (default: a fifth of the value over ``min_dy``).
    """
    kept = [(r, w) for r, w in zip(reads, weights or [1.0] * len(reads)) if r.value is not None]
    pts = [(r.y_up, r.value) for r, _ in kept]
    pairs = []
    for i in range(len(pts)):
        for j in range(i + 1, len(pts)):
            dy = pts[j][0] - pts[i][0]
            if abs(dy) >= min_dy:
                pairs.append(((pts[j][1] - pts[i][1]) / dy, i, j))
    pairs = [p for p in pairs if p[0] != 0]
    if not pairs:
        return None
    slopes = np.array([p[0] for p in pairs])
    pair_weight = np.array([kept[i][1] * kept[j][1] for _, i, j in pairs])
    support = [float(pair_weight[(np.sign(slopes) == np.sign(s)) & (np.abs(slopes / s - 1) <= slope_tolerance)].sum())
               for s in slopes]
    best = int(np.argmax(support))
    mode = slopes[best]
    agree = [p for p in pairs if np.sign(p[0]) == np.sign(mode) and abs(p[0] / mode - 1) <= slope_tolerance]
    members = sorted({i for _, i, _ in agree} | {j for _, _, j in agree})
    slope = float(np.median([p[0] for p in agree]))
    offset = float(np.median([pts[i][1] - slope * pts[i][0] for i in members]))
    tol = 0.2 * abs(slope) * min_dy if value_tolerance is None else value_tolerance * abs(slope)
    best_at: dict[float, OcrRead] = {}
    for r, _ in kept:
        miss = abs(r.value - (slope * r.y_up + offset))  # type: ignore[operator]
        if miss <= tol:
            old = best_at.get(r.y_up)
            if old is None or miss < abs(old.value - (slope * old.y_up + offset)):  # type: ignore[operator]
                best_at[r.y_up] = r
    return Correction(slope=slope, offset=offset, inliers=tuple(best_at.values()))


def with_lost_points(reads: list[OcrRead]) -> tuple[list[OcrRead], list[float]]:
    """Reads plus their guesses with a lost decimal point, and a weight for each.

    A decimal point is a few pixels and often lost: "2.5" comes back as "25", "0.5" as "05".
    A number with a leading zero stands only for that, since scales print no leading zeros.
    One of two or more digits ending in 5 also stands for itself divided by ten (weighted
    less, so a scale of 5, 15, 25 stays itself): a label with one decimal is a half (1.5, 2.5)
    on the scales that print decimals at all. Other numbers are never divided: "90" whose "0"
    was lost reads "9", and dividing "250", "210" as well would agree with it. So a single
    digit also stands for itself times ten (weighted as a lost point): where more labels lost their
    "0" than kept it ("9", "7", "6" beside "100", "80"), the ones that kept it still decide.
    Only where some number read does end in "0" after two digits or more: without one, "15"
    and "25" beside "2" would take "20" for a scale of 15, 20, 25 rather than 1.5, 2, 2.5.
    Where some number read has a leading zero, the scale prints decimals, and a number ending in
    "0" stands for itself divided by ten as well (weighted as a lost point): "30", "25", "2",
    "15", "05" on a 3 ml syringe are 3, 2.5, 2, 1.5, 0.5 ("30" read from "3" and a stroke
    beside it), not 30, 25, 20, 15 with "05" left out (fresh 8258, read 81 divisions off).
    """
    out: list[OcrRead] = []
    weights: list[float] = []
    texts = [r.text.strip() for r in reads if r.value is not None]
    tens = any(text.isdigit() and len(text) >= 2 and text.endswith("0") and not text.startswith("0") for text in texts)
    decimals = any(len(text) >= 2 and text.startswith("0") for text in texts)  # "05", "0.5"
    for r in reads:
        if r.value is None:
            continue
        text = r.text.strip()
        digits_only = text.isdigit() and len(text) >= 2
        leading_zero = digits_only and text.startswith("0")
        if not leading_zero:
            out.append(r)
            weights.append(1.0)
        if leading_zero or (digits_only and (text.endswith("5") or (decimals and text.endswith("0")))):
            out.append(OcrRead(y_up=r.y_up, text=text[:-1] + "." + text[-1], value=r.value / 10,
                               confidence=r.confidence))
            weights.append(LOST_POINT_WEIGHT)
        if tens and text.isdigit() and len(text) == 1 and text != "0":
            out.append(OcrRead(y_up=r.y_up, text=text + "0", value=r.value * 10, confidence=r.confidence))
            weights.append(LOST_ZERO_WEIGHT)
    return out, weights


LOST_POINT_WEIGHT = 0.7  # a guessed decimal point counts this much towards the mode of slopes
LOST_ZERO_WEIGHT = 0.7  # a guessed trailing zero, as much


def _grid_correction(marks: Marks, by_y: dict[float, Mark], reads: list[OcrRead],
                     weights: list[float]) -> Correction | None:
    """The auto-correction in grid steps rather than pixels: perspective shrinks the spacing
    toward the far end of a tilted scale (a 58 px label gap at one end, 43 px at the other),
    which spreads pixel slopes past any tolerance; the count of marks between two numbers
    does not change. Values per grid step then agree exactly, so the tolerances are tight; the
    slope and offset returned are per grid step (only the inliers are used). ``by_y``: the
    marks by their position rounded to 0.001 px, as reads carry it."""
    on_grid, grid_weights, original = [], [], {}
    for r, w in zip(reads, weights):
        mark = by_y.get(round(r.y_up, 3))
        if mark is None:
            continue
        g = replace(r, y_up=float(mark.grid_index))
        on_grid.append(g)
        grid_weights.append(w)
        original[id(g)] = r
    every = max(1, major_step(marks))
    correction = mode_of_slopes(on_grid, min_dy=0.8 * every, weights=grid_weights,
                                slope_tolerance=GRID_SLOPE_TOLERANCE, value_tolerance=GRID_VALUE_TOLERANCE)
    if correction is None:
        return None
    return replace(correction, inliers=tuple(original[id(g)] for g in correction.inliers))


GRID_SLOPE_TOLERANCE = 0.02  # value per grid step of two reads (relative): exact but for misreads
GRID_VALUE_TOLERANCE = 0.3  # grid steps between a read and the line through the agreeing reads


DISPLACED_ON_MARK = 0.25  # grid steps from a mark at most, for the value of a displaced number


def _on_grid(by_y: dict[float, Mark], reads: tuple[OcrRead, ...]) -> tuple[list[tuple[int, float]], float]:
    """(grid index, value) of each read on a mark, and the median value per grid step over
    their pairs on distinct marks (0 when there is no such pair)."""
    grid = [(by_y[round(r.y_up, 3)].grid_index, r.value) for r in reads if round(r.y_up, 3) in by_y]
    steps = [(v2 - v1) / (k2 - k1) for (k1, v1) in grid for (k2, v2) in grid if k2 != k1]  # type: ignore[operator]
    return grid, float(np.median(steps)) if steps else 0.0  # type: ignore[return-value]


def _displaced(marks: Marks, by_y: dict[float, Mark], reads: list[OcrRead], inliers: tuple[OcrRead, ...],
               grid: list[tuple[int, float]], step: float) -> list[OcrRead]:
    """Reads that disagree only in where they were put: their value is a mark's, on the line
    through the agreeing reads, within one long-mark step of the mark they were given. A label
    whose own long mark the marks stage missed (hidden by a liquid's edge, tiered as shorter)
    goes to the long mark beside it (seed 1102: "70", "210" one step off), and counted as a
    misread it outvoted the numbers that agree. Only beside three agreeing reads (two make a
    line with anything: seed 1208, read upside down), and never a value the agreeing reads have
    already (seed 1051: "4" beside two long marks). They count for the majority, never in the fit.
    ``grid``, ``step``: the inliers on the grid and their value per grid step (``_on_grid``)."""
    if len(grid) < 3 or step == 0:
        return []  # two numbers make a line with anything: a third must say it is the scale's
    anchor = float(np.median([v - k * step for k, v in grid]))  # type: ignore[operator]
    every = max(1, major_step(marks))
    kept = {id(r) for r in inliers}
    agreed = [r.value for r in inliers]
    out = []
    for r in reads:
        mark = by_y.get(round(r.y_up, 3))
        if r.value is None or id(r) in kept or mark is None:
            continue
        if any(abs(r.value - v) <= 0.25 * abs(step) for v in agreed):  # type: ignore[operator]
            continue  # a number read twice: one of the two is a misread, and it may be this one
        k_value = (r.value - anchor) / step
        if abs(k_value - round(k_value)) <= DISPLACED_ON_MARK and 0 < abs(round(k_value) - mark.grid_index) <= every:
            out.append(r)
    return out


LONG_MARK_SHARE = 0.85  # of the long marks' median length: a mark this long is one of them
MISCOUNT_MIN = 3  # long marks off the lattice, and more than on it, show a miscount


def long_marks_off_lattice(marks: Marks, every: int) -> tuple[int, int]:
    """Marks as long as the long marks (off, on) their lattice: every ``every``-th mark from the
    long marks' usual grid phase.

    A scale's long marks come every few marks; where the grid skipped or doubled marks (a gap
    it bridged by its curve, strong perspective), the long marks past the gap fall between the
    lattice's places, shorter tiers take them for strays, and the fit numbers the marks there
    divisions off (dev 1125: long marks 8, 8 and 17 marks apart where the lattice has one every
    5, read 30 divisions off; 4 off the lattice, 3 on it). Counted on length alone, not tiers,
    since the tiers follow the lattice. A few off it are no miscount: a meniscus, an interface
    between two liquids or a label joined to a mark lengthens it (img_026: 3 off, 6 on)."""
    majors = marks.majors
    if every < 2 or not majors:
        return 0, 0
    long_px = LONG_MARK_SHARE * float(np.median([m.length_up for m in majors]))
    phase = int(np.bincount([m.grid_index % every for m in majors]).argmax())
    longs = [m for m in marks.marks if m.length_up >= long_px]
    off = sum(1 for m in longs if (m.grid_index - phase) % every)
    return off, len(longs) - off


LENGTHS_TELL = 1.3  # the long marks' median length over the others': length tells them apart


def _lengths_tell(marks: Marks) -> bool:
    """Whether the long marks are plainly longer than the others (``LENGTHS_TELL``)."""
    others = [m.length_up for m in marks.marks if m.tier != "major"]
    return bool(marks.majors and others and
                np.median([m.length_up for m in marks.majors]) >= LENGTHS_TELL * np.median(others))


STUB_SHARE = 0.6  # of the short marks' usual length: a bar shorter is a stroke of print, not a mark


def _stubs(marks: Marks) -> set[int]:
    """Bars (by identity) far shorter than the shortest tier's marks: a letter's stroke on a
    grid line, or a mark cut short (by a liquid's edge, a stopper): the caller tells which."""
    minors = [m.length_up for m in marks.marks if m.tier == "minor"]
    if not minors:
        return set()
    shortest = STUB_SHARE * float(np.median(minors))
    return {id(m) for m in marks.marks if m.length_up < shortest}


def _not_marks(marks: Marks, read_at: set[int], stubs: bool) -> set[int]:
    """The bars (by identity) that are no graduation mark, wherever they lie: strays, runs apart
    from every number read (grid indices ``read_at``) and, with ``stubs``, bars far shorter than
    the short marks (``_stubs``)."""
    out = {id(m) for m in strays(marks)} | apart_from(marks, read_at)
    return out | _stubs(marks) if stubs else out


def fit_scale(marks: Marks, reads: list[OcrRead], min_reads: int,
              majors_by_length: bool = True) -> tuple[ScaleFit | None, str | None]:
    """Values for every mark and the fit, or (None, why). ``majors_by_length``: the long marks
    were told by their length, so marks as long off their lattice show a miscount; where they
    were told by the numbers beside them (``marks.majors_at_labels``), only if they are also
    plainly longer than the rest (``_lengths_tell``): where they are not (img_002, faint long
    lines), every mark is as long as they are."""
    majors = sorted(marks.majors, key=lambda m: m.y_up)
    if len(majors) < 2:
        return None, "fewer than two major marks"
    major_gap = float(np.median(np.abs(np.diff([m.y_up for m in majors]))))
    by_y = {round(m.y_up, 3): m for m in marks.marks}
    candidates, weights = with_lost_points(reads)
    fit, why, correction = _fit_on(marks, by_y, major_gap, reads, candidates, weights, min_reads, majors_by_length)
    if fit is not None or correction is None:
        return fit, why
    # the numbers that agreed made no scale (a check of ``_fit_by`` refused it: marks below
    # zero, no 1-2-5 step, too few, no majority): where some of them, as read, stand for
    # another number too (a lost decimal point: "15" beside "2" is 1.5 as well as 15), the
    # number as read counted more; once more with those marks' other reading and every other
    # number as read (dev 1152: "2", "15" on a 3 ml syringe). Not the other way round: a guess
    # that failed leaves a number as read that was mostly a misread (dev 1185: "9" beside "90"
    # once the guessed "90" made no scale)
    as_read = {id(r) for r in reads}
    guessed_at = {round(c.y_up, 3) for c in candidates if id(c) not in as_read}
    retold = {round(c.y_up, 3) for c in correction.inliers if id(c) in as_read and round(c.y_up, 3) in guessed_at}
    if not retold:
        return fit, why
    kept = [(c, w) for c, w in zip(candidates, weights)
            if (id(c) in as_read) != (round(c.y_up, 3) in retold)]
    again, _, _ = _fit_on(marks, by_y, major_gap, reads, [c for c, _ in kept], [w for _, w in kept], min_reads,
                          majors_by_length)
    return (again, None) if again is not None else (fit, why)


def _fit_on(marks: Marks, by_y: dict[float, Mark], major_gap: float, reads: list[OcrRead], candidates: list[OcrRead],
            weights: list[float], min_reads: int,
            majors_by_length: bool) -> tuple[ScaleFit | None, str | None, Correction | None]:
    """``fit_scale`` on the reads ``candidates`` (the reads and their guesses, ``weights``),
    with the auto-correction it stood on (None where none was found). ``by_y``: the marks by
    their position rounded to 0.001 px; ``major_gap``: the long marks' usual spacing."""
    correction = mode_of_slopes(candidates, min_dy=0.8 * major_gap, weights=weights)
    numeric = sum(1 for r in reads if r.value is not None)
    if correction is None or len(correction.inliers) < numeric:  # some numbers disagree: perspective?
        on_grid = _grid_correction(marks, by_y, candidates, weights)
        if on_grid is not None and (correction is None or len(on_grid.inliers) > len(correction.inliers)):
            correction = on_grid
    if correction is None:
        return None, f"0 consistent scale numbers read (need {min_reads})", None
    return (*_fit_by(marks, by_y, reads, correction, min_reads, majors_by_length), correction)


def _fit_by(marks: Marks, by_y: dict[float, Mark], reads: list[OcrRead], correction: Correction, min_reads: int,
            majors_by_length: bool) -> tuple[ScaleFit | None, str | None]:
    """``fit_scale`` on the reads that ``correction`` kept."""
    majors = marks.majors
    if len(correction.inliers) < min_reads:
        return None, f"{len(correction.inliers)} consistent scale numbers read (need {min_reads})"
    if len(majors) >= 6 and len(correction.inliers) < max(min_reads, 3):  # two agreeing misreads happen
        return None, f"{len(correction.inliers)} consistent scale numbers read (need 3 with {len(majors)} long marks)"
    # the numbers that agree must be the majority; and two against one is none: two agreeing
    # misreads ("0.7", "0.6" read "7", "6" beside "08") are as likely as one misread. Counted by
    # marks, not reads: two readers' texts for one mark are one vote, and at most one is right
    # (seed 1013: Tesseract's "2" and the network's "29" beside a burette's "20")
    grid, raw_step = _on_grid(by_y, correction.inliers)
    agreeing_reads = [*correction.inliers, *_displaced(marks, by_y, reads, correction.inliers, grid, raw_step)]
    agreeing = len({round(r.y_up, 3) for r in agreeing_reads})
    voting = len({round(r.y_up, 3) for r in reads if r.value is not None})
    if 2 * agreeing < voting or (agreeing == 2 and voting >= 3):
        return None, f"only {agreeing} of {voting} numbers read agree with each other"
    if len({k for k, _ in grid}) < min_reads:
        return None, "the numbers read do not sit on distinct marks"
    step = snap_nice(abs(raw_step))
    if step is None:
        return None, f"value per division {abs(raw_step):.4g} is not a 1-2-5 scale step"
    step = math.copysign(step, raw_step)
    anchors = [v - k * step for k, v in grid]  # type: ignore[operator]
    zero = float(np.median(anchors))
    zero = round(zero / step) * step
    if sum(1 for a in anchors if abs(a - zero) <= 0.25 * abs(step)) < min_reads:
        return None, "the numbers read disagree with the marks' spacing"
    below_zero = {id(m) for m in marks.marks if zero + m.grid_index * step < -0.5 * abs(step)}
    if below_zero and below_zero <= _not_marks(marks, {k for k, _ in grid}, len(below_zero) <= 2):
        # a lone bar a dozen steps past the scale's zero is the foot or the rim, not a mark; so
        # are bars past an empty gap from every number read (img_002: a cylinder's foot), and
        # one or two stubs shorter than any mark (dev 1051: a stroke of a burette's "TC" above 0)
        marks = Marks(marks=tuple(m for m in marks.marks if id(m) not in below_zero), spacing_up=marks.spacing_up)
    ys = np.array([m.y_up for m in marks.marks])
    values = np.array([zero + m.grid_index * step for m in marks.marks])
    if values.min() < -0.5 * abs(step):  # volume scales start at zero: marks below it are a misreading
        return None, f"the numbers read put marks at {values.min():.3g}, below zero"
    # a scale's long marks sit on round values: 1, 2, 3 ml or 10, 20, 30 ml, never 13.5; long
    # marks 20 ml apart on tens too (``round_unit``)
    every = major_step(marks)
    if every >= 2:
        major_value = snap_nice(abs(every * step), 0.001)
        if major_value is None:
            return None, f"{abs(every * step):.4g} between long marks is not a 1-2-5 step"
        unit = round_unit(major_value) if majors_by_length else major_value
        off_round = [abs(v / unit - round(v / unit)) for m, v in zip(marks.marks, values) if m.tier == "major"]
        if np.median(off_round) > 0.05:
            return None, "the long marks do not fall on round values"
        off, on = long_marks_off_lattice(marks, every) if majors_by_length or _lengths_tell(marks) else (0, 0)
        if off >= MISCOUNT_MIN and off > on:
            return None, f"{off} marks as long as the long marks lie off their every-{every} lattice: marks miscounted"
    return _fitted(ys, values, abs(step)), None


def round_unit(major_value: float) -> float:
    """The round values long marks ``major_value`` apart sit on: multiples of it, or of ten where
    it is 20 (a 250 ml cylinder's long marks every 20 ml at 30, 50 ... 250, the 10 ml marks
    between them found no longer than the rest: seed 1322). Not below 20: long marks at 13.5
    ml, or every 2 ml at odd values, are a miscount or a misreading (seed 1541: every other
    mark of a burette found, its long marks valued 1, 3, 5, 9). Only for long marks found by
    their length: long marks set where the labels are printed (``majors_at_labels``) half a
    period off their lattice fall on those odd tens too (seed 1185, read 4.5 divisions off
    when they did)."""
    return 10.0 if abs(major_value - 20.0) < 1e-6 else major_value


def _fitted(ys: np.ndarray, values: np.ndarray, minor_ml: float) -> ScaleFit:
    """value = slope * y + offset over the marks at rows ``ys`` valued ``values``, with the residual."""
    slope, offset = np.polyfit(ys, values, 1)
    # residual against a quadratic: perspective bends the linear map, misplaced marks do not fit either
    curve = np.polyfit(ys, values, 2) if len(ys) >= 6 else np.array([0.0, slope, offset])
    residual_px = float(np.sqrt(np.mean(((np.polyval(curve, ys) - values) / slope) ** 2)))
    order = np.argsort(ys)
    return ScaleFit(slope=float(slope), offset=float(offset), residual_px=residual_px, minor_ml=minor_ml,
                    mark_y_up=tuple(float(y) for y in ys[order]),
                    mark_values=tuple(float(round(v, 6)) for v in values[order]))


def fit_on_marks_seen(fit: ScaleFit, marks: Marks) -> ScaleFit:
    """``fit`` kept to the marks seen (``marks``): a fit made with long marks placed past them
    (``ocr.marks_for_numbers``, where only the numbers were seen) reads positions by the marks in
    the image, not by places the grid's curve was carried to."""
    seen = {round(m.y_up, 3) for m in marks.marks}
    kept = [(y, v) for y, v in zip(fit.mark_y_up, fit.mark_values) if round(y, 3) in seen]
    return _fitted(np.array([y for y, _ in kept]), np.array([v for _, v in kept]), fit.minor_ml)
