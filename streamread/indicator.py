"""The level indicator in the upright strip, where the level is read.

- Syringe: the stopper is the darkest bounded run of rows across the bore; the reading line
  is its leading sealing edge, the end towards lower values. Rows are sampled near the walls
  (0.75-0.95 of the half bore), outside any conical nose. A run that carries a hue is dyed
  liquid between stopper and nozzle, not rubber: the edge is where the hue ends
  (``stopper_behind_liquid``).
- Cylinder and burette: the meniscus is a dark band across the bore (darker than the rows
  above and below, unlike a plain liquid/air step); its lowest point is the largest strip y
  of its lower edge near the tube axis (upright strip: physically down is down). Over a
  coloured liquid the lowest point is where the liquid's hue starts (a dark liquid is as dark
  as the band above it). Among several bands, the meniscus is the one the colour changes
  across, that does not repeat every major step (printed numbers do), and that has the liquid
  right under it. Where that ranking, made on the rows near the axis, finds none, the band is
  followed as a curve from wall to wall (``_arc_band``): a deeply curved meniscus crosses only
  the middle of the bore near its bottom row. Before that rescue, a coloured liquid is found by
  where its hue starts (``_hue_surface``): its meniscus may be drawn thin, or lie on a long
  mark, and a faint arc may be a background edge. The rescues look only at rows the camera's
  frame covers.

Marks are masked out before the rows are summarised.
"""

from __future__ import annotations

import functools
import math
import statistics
from dataclasses import dataclass, replace

import cv2
import numpy as np

from streamread.marks import major_step, print_mask
from streamread.segment import row_sums, smooth_1d, smooth_rows, true_runs
from streamread.types import Indicator, Mark, Marks, ScaleFit


STRAY_SHARE = 0.1  # marks reaching past an edge, at most, for it to be a wall inside the marks' full extent
WALL_OVER_BACKGROUND = 4.0  # times the edge found outside every mark that such a wall must be
STRAY_PUSH = 1.0  # marks' usual lengths between a wall found and where most marks end, for it to be looked for again


def find_bore(gray: np.ndarray, marks: Marks) -> tuple[float, float]:
    """Left and right inner walls in the strip, from the two strongest long vertical edges.

    Each wall is first looked for outside every mark. A bar the marks stage kept far beside
    the scale (a background line, a meniscus's edge) pushes that search past the wall, onto a
    faint background edge or the strip's end (dev 1218: a bar from column 12, the wall at 68,
    the wall found at 9; the meniscus network's row, right, was then refused as a band going on
    outside the walls). So where a wall was found over ``STRAY_PUSH`` marks' lengths from where
    most marks end, an edge within the marks' full extent is the wall instead where at most
    ``STRAY_SHARE`` of the marks reach past it and it is ``WALL_OVER_BACKGROUND`` times as
    strong (not a label's or a ring's end: many marks reach past those). Only so far out: two
    pixels' move of a wall found beside the marks changed which band the ranking took
    (``burette25ml_leave``, a background edge read as a meniscus)."""
    x_lo = min(m.x0_up for m in marks.marks)
    x_hi = max(m.x1_up for m in marks.marks)
    ys = [m.y_up for m in marks.marks]
    r0, r1 = int(max(0, min(ys))), int(min(gray.shape[0], max(ys) + 1))
    band = gray[r0:r1].astype(np.float32)
    if band.shape[0] < 3:
        return x_lo, x_hi
    edges = np.abs(cv2.Sobel(cv2.GaussianBlur(band, (0, 0), 1.0), cv2.CV_32F, 1, 0, ksize=3))
    profile = np.median(edges, axis=0)  # long edges survive the median over rows; marks do not
    span = x_hi - x_lo
    max_reach = 2.5 * span + 10
    w = gray.shape[1]
    left_zone = np.arange(int(max(0, x_lo - max_reach)), int(max(1, x_lo - 1)))
    right_zone = np.arange(int(min(w - 1, x_hi + 1)), int(min(w, x_hi + max_reach)))
    left = float(left_zone[np.argmax(profile[left_zone])]) if len(left_zone) else x_lo
    right = float(right_zone[np.argmax(profile[right_zone])]) if len(right_zone) else x_hi
    starts, ends = np.array([m.x0_up for m in marks.marks]), np.array([m.x1_up for m in marks.marks])

    def within(zone: np.ndarray, found: float, searched: bool, past: np.ndarray) -> float:
        """The strongest edge of ``zone`` where it is the wall, else ``found`` (an edge where
        ``searched``, else the marks' end); ``past``: for each column of ``zone``, the share of
        marks reaching past it."""
        if not len(zone):
            return found
        i = int(np.argmax(profile[zone]))
        beside = float(profile[int(found)]) if searched else 0.0
        return float(zone[i]) if profile[zone[i]] >= WALL_OVER_BACKGROUND * beside and past[i] <= STRAY_SHARE \
            else found
    start, end = float(np.median(starts)), float(np.median(ends))
    far = STRAY_PUSH * float(np.median(ends - starts))  # a wall this far from where most marks end was pushed out
    if start - left > far:
        inner = np.arange(int(max(0, x_lo)), int(max(1, start - 1)))
        left = within(inner, left, len(left_zone) > 0, np.array([np.mean(starts < c) for c in inner]))
    if right - end > far:
        inner = np.arange(int(min(w - 1, end + 1)), int(min(w, x_hi + 1)))
        right = within(inner, right, len(right_zone) > 0, np.array([np.mean(ends > c) for c in inner]))
    return left, right


@dataclass(frozen=True)
class _Sampling:
    """How to summarise rows over a set of columns with print masked (the same every frame of a calibration)."""

    masked_ref: np.ndarray  # kept so the cache key (its id) cannot be reused by another array
    cols: np.ndarray
    hidden: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    fill: np.ndarray
    keep: np.ndarray  # (rows, cols) uint8: 1 on unmasked pixels, for the masked mean
    count: np.ndarray  # (rows,) float32: unmasked pixels per row (at least 1)
    fill_from: tuple[np.ndarray, np.ndarray, np.ndarray]  # per fully masked row: rows it is interpolated from, weight


_SAMPLINGS: dict[tuple[int, bytes], _Sampling] = {}


def _sampling(columns: np.ndarray, masked: np.ndarray, width: int) -> _Sampling:
    key = (id(masked), columns.tobytes())
    found = _SAMPLINGS.get(key)
    if found is not None and found.masked_ref is masked:
        return found
    cols = columns[(columns >= 0) & (columns < width)]
    hidden = masked[:, cols] > 0
    count = len(cols) - hidden.sum(axis=1)
    top = max(len(cols) - 1, 0)
    fill = count == 0
    made = _Sampling(masked, cols, hidden, np.clip((count - 1) // 2, 0, top), np.clip(count // 2, 0, top),
                     fill, (~hidden).astype(np.uint8), np.maximum(count, 1).astype(np.float32),
                     _interpolation(fill))
    if len(_SAMPLINGS) > 32:
        _SAMPLINGS.clear()
    _SAMPLINGS[key] = made
    return made


def _fill_masked_rows(prof: np.ndarray, fill: np.ndarray) -> np.ndarray:
    """Rows with every pixel masked take the value interpolated from their neighbours."""
    if fill.any() and not fill.all():
        prof[fill] = np.interp(np.nonzero(fill)[0], np.nonzero(~fill)[0], prof[~fill])
    return prof


def _row_profile(gray: np.ndarray, columns: np.ndarray, masked: np.ndarray,
                 rows: tuple[int, int] | None = None) -> np.ndarray:
    """Median of each row over ``columns``, ignoring masked (print) pixels; ``rows``: only those.

    Masked pixels are set to 255 and sort last; each row's median is then read at its own
    count of unmasked pixels (a real 255 sorts among them, equal, so nothing changes). Much
    faster than a NaN-aware median, and the sampling is cached per calibration.
    """
    s = _sampling(columns, masked, gray.shape[1])
    r0, r1 = (0, gray.shape[0]) if rows is None else (max(0, rows[0]), min(gray.shape[0], rows[1]))
    fill = s.fill[r0:r1]
    if len(s.cols) == 0 or fill.all():
        return np.zeros(max(r1 - r0, 0), np.float32)
    values = gray[r0:r1, s.cols]
    values[s.hidden[r0:r1]] = 255
    values.sort(axis=1)
    index = np.arange(len(values))
    prof = (values[index, s.lo[r0:r1]].astype(np.float32) + values[index, s.hi[r0:r1]]) / 2
    return _fill_masked_rows(prof, fill)


def _interpolation(fill: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each ``fill`` row, the nearest rows before and after that are not, and the weight of
    the one after (linear interpolation; past the ends, the end row)."""
    rows = np.flatnonzero(fill)
    known = np.flatnonzero(~fill)
    if len(rows) == 0 or len(known) == 0:
        return np.zeros(0, int), np.zeros(0, int), np.zeros(0, np.float32)
    after = np.clip(np.searchsorted(known, rows), 1, max(len(known) - 1, 1))
    lo, hi = known[after - 1], known[np.minimum(after, len(known) - 1)]
    span = np.maximum(hi - lo, 1)
    weight = np.clip((rows - lo) / span, 0.0, 1.0).astype(np.float32)
    return lo, hi, weight


def _row_means(strips: np.ndarray, columns: np.ndarray, masked: np.ndarray) -> np.ndarray:
    """(K, h) mean of each row over ``columns`` of each strip of a (K, h, w) stack, ignoring
    masked (print) pixels: the cheap summary for finding where the stopper is (its edge is then
    located with the median). Summed exactly in integers, so a strip's result is the same
    alone or in a stack; rows with every pixel masked are interpolated from their neighbours."""
    k, h, w = strips.shape
    s = _sampling(columns, masked, w)
    if len(s.cols) == 0 or s.fill.all():
        return np.zeros((k, h), np.float32)
    prof = row_sums(strips[:, :, s.cols] * s.keep).astype(np.float32) / s.count  # masked pixels count 0
    lo, hi, weight = s.fill_from
    if len(weight):
        prof[:, s.fill] = prof[:, lo] + (prof[:, hi] - prof[:, lo]) * weight
    return prof


def stopper_profiles(strips: np.ndarray, marks: Marks, bore: tuple[float, float]) -> np.ndarray:
    """The row profile ``find_stopper`` finds the rubber in, for each strip of a (K, h, w) stack:
    the mean of mid-bore columns with print masked, lightly smoothed. A worker makes it for a
    batch of frames at once and hands each frame's row to ``find_stopper``."""
    left, right = bore
    axis, half = (left + right) / 2, (right - left) / 2
    masked = print_mask(strips.shape[1:], marks, pad_x=3, pad_y=2.5)
    return smooth_rows(_row_means(strips, _columns(axis, half, 0.3, 0.6), masked), 0.8)


def _smoothed_profile(gray: np.ndarray, columns: np.ndarray, masked: np.ndarray, sigma: float) -> np.ndarray:
    """Row profile of ``columns`` (print masked), lightly smoothed along the axis."""
    return smooth_1d(_row_profile(gray, columns, masked), sigma)


def _crossing(profile: np.ndarray, start: int, stop: int, level: float) -> float | None:
    """Sub-pixel position between ``start`` and ``stop`` (either order) where ``profile`` crosses ``level``."""
    step = 1 if stop >= start else -1
    for i in range(start, stop, step):
        a, b = profile[i], profile[i + step]
        if (a - level) * (b - level) <= 0 and a != b:
            return i + step * (level - a) / (b - a)
    return None


@functools.lru_cache(maxsize=64)
def _columns(axis: float, half: float, lo: float, hi: float) -> np.ndarray:
    offsets = np.arange(lo * half, hi * half + 0.5)
    return np.unique(np.round(np.concatenate([axis - offsets, axis + offsets])).astype(int))


def walls_found(bore: tuple[float, float], width: int) -> bool:
    """Whether ``find_bore`` found both walls, not only the end of its search (the strip's
    first or last column): else there is no bore to follow, nor to cut a network's input to."""
    return bore[0] > 0 and bore[1] < width - 1


def _side_columns(axis: float, half: float, lo: float, hi: float, width: int) -> np.ndarray:
    """The strip columns from ``lo`` to ``hi`` half bore widths from the axis (one side), within the strip."""
    cols = np.arange(int(axis + lo * half), int(axis + hi * half) + 1)
    return cols[(cols >= 0) & (cols < width)]


EDGE_COLUMNS = ((0.72, 0.82), (0.6, 0.68))  # where the sealing edge is traced, in outer half widths, in turn


def find_stopper(gray: np.ndarray, marks: Marks, fit: ScaleFit, bore: tuple[float, float],
                 min_contrast: float, body_profile: np.ndarray | None = None,
                 rows_seen: tuple[int, int] | None = None, grey: np.ndarray | None = None) -> Indicator | None:
    """The stopper's leading sealing edge.

    The stopper is found as the darkest bounded run of rows in mid-bore columns; its leading
    edge is then located in columns just inside the wall (0.72-0.82 of the half width between
    the outer walls), where the sealing rib touches the barrel and no conical nose reaches.
    ``body_profile``: this strip's row of ``stopper_profiles``, when a batch of frames made it.
    ``rows_seen``: the strip rows the camera's frame covers across the bore; the run must end
    inside them (past the frame the strip repeats the edge's pixels: a dark edge runs on).
    ``grey``: the rows whose middle carries no hue (``grey_rows``), when a dyed liquid as dark
    as the rubber joins it in one run: the rubber is looked for in them only, and its edge must
    lie in them, not past the dye's first row (a light gap under a cone, then the dye: the
    dye's far edge is no sealing edge).
    """
    left, right = bore
    axis, half = (left + right) / 2, (right - left) / 2
    if half < 4:
        return None
    masked = print_mask(gray.shape, marks, pad_x=3, pad_y=2.5)
    prof = stopper_profiles(gray[None], marks, bore)[0] if body_profile is None else body_profile
    d = fit.division_px
    k_dark, k_ref = int(0.02 * (len(prof) - 1)), int(0.75 * (len(prof) - 1))
    ordered = np.partition(prof, (k_dark, k_ref))
    reference, darkest = float(ordered[k_ref]), float(ordered[k_dark])
    if reference - darkest < min_contrast:
        return None
    bore_px = right - left
    first, last = (0, len(prof) - 1) if rows_seen is None else (max(0, rows_seen[0]), min(len(prof) - 1, rows_seen[1]))
    candidates: list[tuple[int, int]] = []
    for frac in (0.5, 0.35, 0.22, 0.12):  # dark liquid next to the rubber: separate them by going darker
        dark = prof < darkest + frac * (reference - darkest)
        candidates = [(a, b) for a, b in true_runs(dark if grey is None else dark & grey)
                      if 0.25 * bore_px <= b - a + 1 <= 2.0 * bore_px and b - a + 1 >= 1.2 * d
                      and a > first and b < last]  # bounded: the stopper ends inside the strip and the frame
        if candidates:
            break
    if not candidates:
        return None
    if len(candidates) > 1:
        a, b = min(candidates, key=lambda r: float(prof[r[0]: r[1] + 1].sum()) / (r[1] - r[0] + 1))
    else:
        a, b = candidates[0]
    # a short column of liquid in front of the rubber can join it in one run: keep the dark core
    run = prof[a: b + 1]
    core = np.flatnonzero(run < (float(run.min()) + float(run.max())) / 2)
    a, b = a + int(core[0]), a + int(core[-1])
    forward = fit.slope < 0  # the leading edge faces lower values; values fall with y when slope < 0
    lead = b if forward else a
    window = int(1.5 * d) + 3
    # the edge profile is needed only around the lead (a margin beyond the smoothing's reach):
    # ``edge`` holds strip rows r0..r1-1, and every row read below lies in them
    r0, r1 = max(0, lead - window - 6), min(len(prof), lead + window + 7)
    # columns just inside the wall: 0.72-0.82 of the outer half width on thin-walled barrels;
    # on a 1 ml syringe the wall is 0.3 of it, those columns are glass, and the rib is met at
    # 0.6-0.68 (still outside the nose, whose base is 0.8 of the bore)
    for lo_f, hi_f in EDGE_COLUMNS:
        edge = smooth_1d(_row_profile(gray, _columns(axis, half, lo_f, hi_f), masked, (r0, r1)), 0.8).tolist()
        if forward:
            inside = min(edge[max(a, lead - int(d) - 1) - r0: lead + int(0.5 * d) + 1 - r0])
            outside_rows = edge[lead + int(0.5 * d) + 1 - r0: lead + window + 1 - r0]
        else:
            inside = min(edge[max(0, lead - int(0.5 * d)) - r0: min(b, lead + int(d) + 1) + 1 - r0])
            outside_rows = edge[max(0, lead - window) - r0: max(0, lead - int(0.5 * d)) - r0]
        if len(outside_rows) < 2:
            return None
        # the sealing rib right at the edge is the darkest rubber; the rows behind it are ribbed and
        # lighter, so the half-way level is taken between the rib and the barrel in front
        outside = statistics.median(outside_rows)
        if outside - inside >= min_contrast:
            break
    else:
        return None
    # the sealing edge is where the profile rises from rubber to barrel going outward, and the
    # steepest such rise: a lighter stretch of rubber between two ribs rises less, and a change of
    # background behind the barrel (a table edge) is milder, or falls
    lo_row, hi_row = max(1, lead - window), min(len(prof) - 2, lead + window)
    y = _sealing_edge(edge[lo_row - r0: hi_row + 1 - r0], (inside + outside) / 2, outward=1 if forward else -1)
    if y is None:
        return None
    y += lo_row
    if grey is not None:  # the edge's row and the rubber's row beside it carry no hue
        r = int(np.floor(y)) - 1 if forward else int(np.ceil(y))
        if not grey[max(0, r):r + 2].all():
            return None
    return Indicator(kind="stopper", y_up=float(y), x_up=float(axis), sigma_px=0.3, strength=outside - inside)


STOPPER_PAST_TOP = 0.3  # share of the scale's range past its top value where the network may find the stopper


def stopper_rows(fit: ScaleFit, n_rows: int, rows_seen: tuple[int, int] | None = None) -> tuple[int, int]:
    """The strip rows the stopper network may choose: from two divisions before the scale's
    zero (the nozzle's end) to ``STOPPER_PAST_TOP`` of its range past its top value (a
    plunger drawn past the last mark; ``reader.reading_from`` judges how far is readable), a
    division inside the camera's frame (past it the strip repeats the frame's edge)."""
    lo, hi = fit.value_range
    start = -2 * fit.minor_ml
    end = hi + STOPPER_PAST_TOP * (hi - lo) + 2 * fit.minor_ml
    ys = sorted((v - fit.offset) / fit.slope for v in (start, end))
    first, last = max(0, int(np.ceil(ys[0]))), min(n_rows - 1, int(np.floor(ys[1])))
    if rows_seen is not None:
        reach = int(np.ceil(fit.division_px))
        first, last = max(first, rows_seen[0] + reach), min(last, rows_seen[1] - reach)
    return first, last


def stopper_view(shape: tuple[int, ...], marks: Marks, fit: ScaleFit, bore: tuple[float, float],
                 rows_seen: tuple[int, int] | None) -> tuple[np.ndarray, tuple[int, int], bool] | None:
    """The bore as the stopper network sees it: the print mask, the rows it may choose
    (``stopper_rows``) and whether its input is turned (``bore_net.nozzle_up``); None with no
    bore to cut the input to. For ``stopper_by_network`` and ``scripts/train_bore_net.py``,
    which must cut its samples alike (as ``meniscus_view`` for the meniscus)."""
    from streamread.bore_net import nozzle_up

    if bore[1] - bore[0] < 8 or not walls_found(bore, shape[1]):
        return None
    masked = print_mask(shape[:2], marks, pad_x=3, pad_y=2.5)
    return masked, stopper_rows(fit, shape[0], rows_seen), nozzle_up(fit.slope)


def stopper_by_network(strip_bgr: np.ndarray, marks: Marks, fit: ScaleFit, bore: tuple[float, float],
                       rows_seen: tuple[int, int] | None, min_confidence: float) -> tuple[float, float] | None:
    """The stopper's sealing edge as the bundled stopper network (``bore_net.stopper_net``) sees
    it: (strip row, confidence) or None. ``strip_bgr``: the strip, or at least its bore and
    ``bore_net.MARGIN`` beside it, in colour (grey works, less surely: a dye is told by its hue)."""
    from streamread.bore_net import stopper_net  # onnxruntime only once the network is asked

    view = stopper_view(strip_bgr.shape, marks, fit, bore, rows_seen)
    if view is None:
        return None
    masked, allowed, turned = view
    return stopper_net().locate(strip_bgr, masked, bore, fit.division_px, allowed, min_confidence=min_confidence,
                                turned=turned)


DARK_PAST_REACH_DIV = 3.0  # rows either side of a stopper edge where an edge outside the walls is looked for
DARK_PAST_MIN = 20.0  # grey levels the bore must change by across the edge for the background to be judged


def dark_past_walls(gray: np.ndarray, fit: ScaleFit, bore: tuple[float, float], y: float) -> bool:
    """Whether the background outside the walls changes near a stopper edge at row ``y`` as
    much as the bore does across it (half as much or more, within ``DARK_PAST_REACH_DIV``
    divisions, on each side the strip shows): a dark object crossing behind the syringe (at a
    slant, so not at the same row), not rubber, which ends at the walls (tuning 8254: a bar
    past the flange, taken by the stopper network where the walls found were the background's
    edge). Columns off the strip, or left black by a per-frame cut, say nothing."""
    left, right = bore
    axis, half, d = (left + right) / 2, (right - left) / 2, fit.division_px
    n, w = gray.shape
    near, far = max(1, int(round(0.3 * d))), max(2, int(round(1.5 * d)))
    reach = max(far, int(round(DARK_PAST_REACH_DIV * d)))
    y0, y1 = max(0, int(y) - reach), min(n, int(y) + reach + 1)
    before, past = gray[max(0, int(y) - far):max(0, int(y) - near)], gray[int(y) + near:int(y) + far]
    if len(before) == 0 or len(past) == 0 or y1 - y0 < 3:
        return False
    middle = _side_columns(axis, half, -0.5, 0.5, w)
    if len(middle) < 2:
        return False
    across = abs(float(np.median(before[:, middle])) - float(np.median(past[:, middle])))
    changes = []
    for lo, hi in BACKGROUND_COLUMNS:
        cols = _side_columns(axis, half, lo, hi, w)
        block = gray[y0:y1, cols] if len(cols) >= 2 else None
        if block is None or not block.any():
            continue
        rows = smooth_1d(np.median(block, axis=1).astype(np.float32), 0.7)
        changes.append(float(rows.max() - rows.min()))
    # a bore hardly changing across the edge (dye as dark as the rubber past it) says nothing
    return across >= DARK_PAST_MIN and bool(changes) and all(c >= 0.5 * across for c in changes)


LIQUID_CHROMA = 14.0  # Lab a*b* distance from grey (8-bit units) above which the rows behind an edge are liquid
LIQUID_GONE = 0.3  # share of the liquid's chroma the rows past its end stay below (a faint tint is not gone: 1215)


def stopper_behind_liquid(color: np.ndarray, marks: Marks, fit: ScaleFit, bore: tuple[float, float],
                          found: Indicator) -> Indicator | None:
    """The stopper's edge when the dark run ``find_stopper`` took is coloured liquid, not rubber.

    On a dark background a dark stopper is hardly darker than the barrel, and a dark dye
    drawn into the syringe (blue, red, brown) is the darkest run: its end at the nozzle was
    read as the stopper's edge, near zero, dozens of divisions off. Rubber is grey; the rows
    behind an edge that carry a hue are liquid, and the liquid ends at the stopper's face: the
    reading line is where that hue ends, going away from the nozzle, in the columns where the
    sealing rib meets the wall (outside a conical nose, which the liquid surrounds).

    ``found`` itself when the rows behind it are grey (it was the stopper). None when they carry
    a hue but its end is not found: ``found`` is then the liquid's end at the nozzle, not the
    stopper, and no reading is better than that one (seed 1140 read 12 divisions off).
    """
    left, right = bore
    axis, half = (left + right) / 2, (right - left) / 2
    d = fit.division_px
    n = color.shape[0]
    lead = int(round(found.y_up))
    back = -1 if fit.slope < 0 else 1  # away from the nozzle: towards higher values
    near = sorted((lead + back * int(0.5 * d), lead + back * int(3 * d)))
    if near[0] < 0 or near[1] > n:
        return found  # nothing behind it to tell by
    masked = print_mask(color.shape[:2], marks, pad_x=3, pad_y=2.5)
    lab = cv2.cvtColor(np.ascontiguousarray(color[near[0]:near[1]]), cv2.COLOR_BGR2LAB)
    # the body of a stopper is grey across the middle of the bore (its walls may carry a tint)
    centre = _bore_rows(lab[:, :, 1:], masked[near[0]:near[1]], _columns(axis, half, 0.0, 0.5), 0, len(lab))
    if centre is None or float(np.median(np.hypot(centre[:, 0] - 128, centre[:, 1] - 128))) < LIQUID_CHROMA:
        return found
    lab = cv2.cvtColor(np.ascontiguousarray(color), cv2.COLOR_BGR2LAB)
    for lo_f, hi_f in EDGE_COLUMNS:
        ab = _bore_rows(lab[:, :, 1:], masked, _columns(axis, half, lo_f, hi_f), 0, n)
        if ab is None:
            continue
        chroma = smooth_1d(np.hypot(ab[:, 0] - 128, ab[:, 1] - 128), 0.8)
        liquid = float(np.median(chroma[near[0]:near[1]]))
        if liquid < 0.5 * LIQUID_CHROMA:
            continue
        rows = np.arange(lead, -1, -1) if back < 0 else np.arange(lead, n)
        # the liquid's end at the nozzle may still be paling at ``lead``: its far end is looked
        # for only once inside it (seed 1010 "ended" a row past the nozzle)
        inside = np.flatnonzero(chroma[rows] >= 0.5 * liquid)
        if len(inside) == 0:
            return None
        below = np.flatnonzero(chroma[rows] < 0.5 * liquid)
        below = below[below > int(inside[0])]
        if len(below) == 0:
            return None
        i = int(below[0])
        y1, y0 = int(rows[i]), int(rows[i - 1])  # first grey row, last liquid row
        c0, c1 = float(chroma[y0]), float(chroma[y1])
        y = y0 + (y1 - y0) * (c0 - 0.5 * liquid) / max(c0 - c1, 1e-6)
        beyond = sorted((y1 + back * int(0.5 * d), y1 + back * int(2 * d)))
        if beyond[0] < 0 or beyond[1] > n or float(np.median(chroma[beyond[0]:beyond[1]])) >= LIQUID_GONE * liquid:
            return None  # a bubble or a mark, not the end of the liquid
        return Indicator(kind="stopper", y_up=float(y), x_up=float(axis), sigma_px=0.5, strength=liquid)
    return None


DYE_ONSET = 0.25  # share of the way from the rubber's chroma to the dye's where the dye starts
DYE_MOVE_DIV = 0.5  # how far inside a dark dye (divisions) the rules' edge must lie to be moved back


def dye_front(color: np.ndarray, marks: Marks, fit: ScaleFit, bore: tuple[float, float],
              found: Indicator) -> Indicator:
    """The stopper's edge moved back to where a dark dye in front of it starts.

    A dye as dark as the rubber joins it in one dark run near the walls, and the rules' edge
    lands where the dye pales, past its darkest rows (clean 10203: dark red in front of a 1 ml
    syringe's stopper, the edge 1.4 divisions into the dye). Across the middle of the bore the
    dye's hue starts at the rubber's face: where the rows behind ``found`` (1.5-3 divisions,
    rubber) are grey and the rows in front of it (0.5-2 divisions) carry a liquid's hue, the
    edge is the row where the chroma first climbs ``DYE_ONSET`` of the way from the one to the
    other, going out from the rubber, when that lies ``DYE_MOVE_DIV`` or more behind ``found``.
    A conical nose reaches into the middle of the bore past the sealing edge, so the hue there
    starts past the edge, never before it: the edge is only ever moved back. Else ``found``."""
    d = fit.division_px
    out = 1 if fit.slope < 0 else -1  # from the rubber towards the nozzle
    lead = found.y_up
    rubber = sorted((int(round(lead - out * 3 * d)), int(round(lead - out * 1.5 * d))))
    dye = sorted((int(round(lead + out * 0.5 * d)), int(round(lead + out * 2 * d))))
    lo, hi = min(rubber[0], dye[0]), max(rubber[1], dye[1]) + 1
    if lo < 0 or hi > color.shape[0]:
        return found
    chroma = _middle_chroma(color, marks, bore, lo, hi)
    if chroma is None:
        return found
    grey = float(np.median(chroma[rubber[0] - lo:rubber[1] - lo + 1]))
    liquid = float(np.median(chroma[dye[0] - lo:dye[1] - lo + 1]))
    if grey >= LIQUID_CHROMA or liquid < LIQUID_CHROMA:
        return found
    level = grey + DYE_ONSET * (liquid - grey)
    start = rubber[1] if out > 0 else rubber[0]
    stop = int(round(lead)) + out * int(d)
    rows = list(range(start, stop + out, out))
    for prev, row in zip(rows, rows[1:]):
        c0, c1 = float(chroma[prev - lo]), float(chroma[row - lo])
        if c0 < level <= c1:
            y = prev + out * (level - c0) / (c1 - c0)
            if out * (lead - y) >= DYE_MOVE_DIV * d:
                return Indicator(kind="stopper", y_up=float(y), x_up=found.x_up, sigma_px=0.5, strength=found.strength)
            return found
    return found


def grey_rows(color: np.ndarray, marks: Marks, bore: tuple[float, float]) -> np.ndarray | None:
    """Rows whose middle of the bore carries no hue (rubber, glass, clear liquid; Lab a*b*
    within ``LIQUID_CHROMA`` of grey, print left out), for ``find_stopper``'s ``grey``. None
    when too little of the bore is clear of print to tell."""
    chroma = _middle_chroma(color, marks, bore, 0, color.shape[0])
    return None if chroma is None else chroma < LIQUID_CHROMA


def _middle_chroma(color: np.ndarray, marks: Marks, bore: tuple[float, float], r0: int, r1: int) -> np.ndarray | None:
    """Rows ``r0:r1``' Lab a*b* distance from grey across the middle half of the bore, print
    left out, smoothed; None when too little of it is clear of print to tell. Only those rows
    and columns go to Lab: ``grey_rows`` runs once a frame where no stopper shows."""
    left, right = bore
    axis, half = (left + right) / 2, (right - left) / 2
    cols = _columns(axis, half, 0.0, 0.5)
    cols = cols[(cols >= 0) & (cols < color.shape[1])]
    if len(cols) < 2:
        return None
    c0, c1 = int(cols.min()), int(cols.max()) + 1
    masked = print_mask(color.shape[:2], marks, pad_x=3, pad_y=2.5)[r0:r1, c0:c1]
    lab = cv2.cvtColor(np.ascontiguousarray(color[r0:r1, c0:c1]), cv2.COLOR_BGR2LAB)
    ab = _bore_rows(lab[:, :, 1:], masked, cols - c0, 0, len(lab))
    if ab is None:
        return None
    return smooth_1d(np.hypot(ab[:, 0] - 128, ab[:, 1] - 128), 0.8)


def _sealing_edge(seg: list[float], level: float, outward: int) -> float | None:
    """Sub-pixel position in ``seg`` (a profile's rows, from 0) where it crosses ``level`` rising
    in the ``outward`` direction (+1: towards larger rows), the steepest such crossing.
    A few dozen values: plain Python is cheaper than numpy here."""
    n = len(seg)
    if outward < 0:
        seg = seg[::-1]

    def steep(j: int) -> float:  # |gradient|: central differences, one-sided at the ends (as np.gradient)
        if j == 0:
            return abs(seg[1] - seg[0])
        if j == n - 1:
            return abs(seg[-1] - seg[-2])
        return abs(seg[j + 1] - seg[j - 1]) / 2

    best, best_steep = -1, -1.0
    for j in range(n - 1):
        if seg[j] < level <= seg[j + 1]:
            s = max(steep(j), steep(j + 1))
            if s > best_steep:
                best, best_steep = j, s
    if best < 0:
        return None
    t = best + (level - seg[best]) / (seg[best + 1] - seg[best])
    return float(t) if outward > 0 else float(n - 1 - t)


def _bore_mean(color: np.ndarray, columns: np.ndarray, masked: np.ndarray, r0: int, r1: int,
               min_clear: int = 4) -> np.ndarray | None:
    """Mean colour of the rows ``r0:r1`` over ``columns``, print left out; None if fewer than
    ``min_clear`` pixels are left."""
    cols = columns[(columns >= 0) & (columns < color.shape[1])]
    r0, r1 = max(0, r0), min(color.shape[0], r1)
    if r1 - r0 < 2:
        return None
    block = color[r0:r1][:, cols].reshape(-1, 3).astype(np.float32)
    keep = masked[r0:r1][:, cols].reshape(-1) == 0
    return block[keep].mean(axis=0) if keep.sum() >= min_clear else None


def _liquid_step(color: np.ndarray, columns: np.ndarray, masked: np.ndarray, y: int, d: float) -> float:
    """Colour difference between the bore above and below a row: liquid on one side, air on the other."""
    lo = int(max(2.0, 1.5 * d))
    hi = int(max(6.0, 6 * d))  # wide: a cable or a line of print behind the glass averages out
    above, below = _bore_mean(color, columns, masked, y - hi, y - lo), _bore_mean(color, columns, masked, y + lo, y + hi)
    return 0.0 if above is None or below is None else float(np.linalg.norm(above - below))


def _band_and_step(q: np.ndarray, h: int) -> tuple[np.ndarray, np.ndarray]:
    """Along axis 0 of ``q`` (dark features low): how much darker each row is than both rows
    ``h`` away (a band), and how much lighter the row ``h`` above is than the row ``h`` below
    (a step down into dark liquid). Rows past the ends repeat the end row."""
    n = len(q)
    idx = np.arange(n)
    above, below = q[np.clip(idx - h, 0, n - 1)], q[np.clip(idx + h, 0, n - 1)]
    return np.minimum(above, below) - q, above - below


BACKGROUND_COLUMNS = ((-2.2, -1.5), (1.5, 2.2))  # where _background_crosses looks, in half bore widths from the axis


BESIDE_DIVISIONS = 1.5  # an edge outside one wall only, this near the band's row, made it; further off, both walls


def _outside_responses(gray: np.ndarray, axis: float, half: float, rows: np.ndarray, h: int,
                       dark_band: bool) -> list[np.ndarray]:
    """For each side of ``BACKGROUND_COLUMNS`` that the strip shows in ``rows`` (columns off the
    strip, or left black by a per-frame cut, say nothing): each row's band response in the
    columns outside that wall, or half its step, whichever is larger."""
    responses = []
    for lo, hi in BACKGROUND_COLUMNS:
        cols = _side_columns(axis, half, lo, hi, gray.shape[1])
        if len(cols) < 2:
            continue
        block = gray[:, cols]
        if not block[rows].any():
            continue
        q = smooth_1d(cv2.reduce(block, 1, cv2.REDUCE_AVG, dtype=cv2.CV_32F).ravel(), 0.7)
        band, step = _band_and_step(q if dark_band else 255 - q, h)
        responses.append(np.maximum(band, 0.5 * np.abs(step)))
    return responses


def _background_crosses(gray: np.ndarray, axis: float, half: float, y: int, h: int, d: float, dark_band: bool,
                        inside: float) -> bool:
    """Whether the band at row ``y`` goes on outside the walls: the edge of a table or a shadow
    seen through the glass, not a meniscus (which ends at the walls).

    Columns just outside either wall are summarised like the bore; an edge there half as strong
    as the band inside, outside both walls within three divisions of it, or outside one wall
    within ``BESIDE_DIVISIONS`` (or one wall only is seen, within three), means the background
    made the band. Outside one wall only and further off, it is an object's edge that ends
    behind the glass (tuning seeds 3255, 3544: clear menisci refused 2.5-3 divisions from one).
    An edge oblique to the scale (a tilted apparatus before a level table) is seen outside
    further off, on opposite sides of the band left and right: edges on both sides in line with
    the band (their mean row within a division of it) made it too (seed 1182, read 41 divisions
    off on a table's edge). Columns a per-frame strip left black (not cut) say nothing.
    """
    n = gray.shape[0]
    reach = max(2, int(round(3 * d)))  # the edge outside is seen shifted by refraction and tilt
    beside = max(2, round(BESIDE_DIVISIONS * d))  # on one side alone (an object's edge ending behind the bore)
    far = max(reach, round(BACKGROUND_COLUMNS[1][1] * half))  # an edge at up to 45 degrees to the rows
    rows = np.arange(max(0, y - far), min(n, y + far + 1))
    strong_rows = []
    for response in _outside_responses(gray, axis, half, rows, h, dark_band):
        strong = rows[response[rows] >= 0.5 * inside]
        if np.any(np.abs(strong - y) <= beside):
            return True
        strong_rows.append(strong)
    near = [bool(np.any(np.abs(strong - y) <= reach)) for strong in strong_rows]
    if near and all(near):
        return True  # on both sides within the reach, or on the one side seen
    if len(strong_rows) == 2 and len(strong_rows[0]) and len(strong_rows[1]):
        # rows in line with the band: left and right offsets (nearly) cancel
        offsets = (strong_rows[0][:, None] - y) + (strong_rows[1][None, :] - y)
        return bool(np.any(np.abs(offsets) <= 2 * max(d, 1.0)))
    return False


MIN_BAND_COVERAGE = 0.55  # share of the bore's columns a meniscus band must cross


def _band_coverage(gray: np.ndarray, masked: np.ndarray, axis: float, half: float, d: float, h: int,
                   dark_band: bool, min_contrast: float) -> np.ndarray:
    """For each row, the share of the bore's columns (print left out) with a band near it.

    A column shows a band at a row when the row is darker (lighter, on a dark background) than
    both rows ``h`` away by ``0.4 * min_contrast``; near means within 0.8 division, since the
    meniscus climbs towards the walls. (A step, dark liquid under air, is not counted: steps
    cross the bore everywhere a background edge does, and counting them let every wrong band
    through.)
    """
    c0, c1 = max(0, int(axis - 0.8 * half)), min(gray.shape[1], int(axis + 0.8 * half) + 1)
    if c1 - c0 < 2 or gray.shape[0] <= 2 * h:
        return np.zeros(gray.shape[0], np.float32)
    g = cv2.GaussianBlur(gray[:, c0:c1].astype(np.float32), (1, 3), 0)
    band, _ = _band_and_step(g if dark_band else 255 - g, h)
    clear = (masked[:, c0:c1] == 0).astype(np.uint8)
    hit = ((band >= 0.4 * min_contrast) & (clear > 0)).astype(np.uint8)
    reach = np.ones((2 * max(1, int(round(0.8 * d))) + 1, 1), np.uint8)
    near = cv2.dilate(hit, reach).sum(axis=1)
    seen = cv2.dilate(clear, reach).sum(axis=1)
    return (near / np.maximum(seen, 1)).astype(np.float32)


CHROMA_STEP = 12.0  # Lab a*b* distance: a hue change, not noise
CHROMA_COVERAGE = 0.75  # share of the bore's columns a coloured liquid's surface must cross


def _chroma_coverage_near(color: np.ndarray, masked: np.ndarray, axis: float, half: float, d: float, h: int,
                          y: float, reach_rows: int) -> float:
    """The largest share, within ``reach_rows`` of row ``y``, of the bore's columns (print left
    out) where the hue changes between ``h`` rows above and below and stays changed ``3 h``
    below: a coloured liquid starts there. A coloured cable changes the hue too, but only for
    its own width. Only the rows that share can depend on are converted to Lab."""
    n = color.shape[0]
    c0, c1 = max(0, int(axis - 0.8 * half)), min(color.shape[1], int(axis + 0.8 * half) + 1)
    if c1 - c0 < 2 or n <= 2 * h:
        return 0.0
    near_px = max(1, int(round(0.8 * d)))
    y0, y1 = max(0, int(round(y)) - reach_rows), min(n, int(round(y)) + reach_rows)  # as _near_max
    if y1 <= y0:
        return 0.0
    margin = near_px + 3 * h + 2  # the dilation, the farthest row compared, the blur
    w0, w1 = max(0, y0 - margin), min(n, y1 + margin)
    lab = cv2.cvtColor(np.ascontiguousarray(color[w0:w1, c0:c1]), cv2.COLOR_BGR2LAB).astype(np.float32)
    # rows near the window's edges are wrong (its border is not the strip's) but never read:
    # the margin keeps every row the share depends on inside, or at the strip's own end
    ab = cv2.GaussianBlur(lab[:, :, 1:], (1, 3), 0)
    idx = np.arange(w1 - w0)
    up, down, deeper = (ab[np.clip(idx + k, 0, w1 - w0 - 1)] for k in (-h, h, 3 * h))
    clear = (masked[w0:w1, c0:c1] == 0).astype(np.uint8)
    change = np.linalg.norm(up - down, axis=2)
    # stays changed: nearer the liquid just under the row than half the step (shading and print
    # vary a liquid's hue by more than noise; a cable's width further down it is the air's again)
    stays = np.linalg.norm(deeper - down, axis=2) < np.maximum(0.5 * CHROMA_STEP, 0.5 * change)
    hit = ((change >= CHROMA_STEP) & stays & (clear > 0)).astype(np.uint8)
    reach = np.ones((2 * near_px + 1, 1), np.uint8)
    near = cv2.dilate(hit, reach).sum(axis=1)
    seen = cv2.dilate(clear, reach).sum(axis=1)
    share = (near / np.maximum(seen, 1)).astype(np.float32)[y0 - w0: y1 - w0]
    return float(share.max())


def _bore_rows(image: np.ndarray, masked: np.ndarray, cols: np.ndarray, r0: int, r1: int) -> np.ndarray | None:
    """Mean of each row ``r0:r1`` over ``cols`` with print left out (per channel), rows with
    fewer than two clear pixels interpolated (``_fill_masked_rows``); None when too little is
    left to see."""
    n = image.shape[0]
    r0, r1 = max(0, r0), min(n, r1)
    cols = cols[(cols >= 0) & (cols < image.shape[1])]
    if r1 - r0 < 6 or len(cols) < 2:
        return None
    block = image[r0:r1][:, cols].astype(np.float32)
    keep = (masked[r0:r1][:, cols] == 0).astype(np.float32)[:, :, None]
    count = keep.sum(axis=1)
    ok = count[:, 0] >= 2
    if ok.sum() < 6:
        return None
    means = ((block * keep).sum(axis=1) / np.maximum(count, 1)).astype(np.float64)
    for channel in means.T:  # views: filled in place
        _fill_masked_rows(channel, ~ok)
    return means


def _half_crossing(prof: np.ndarray, r0: int, above: tuple[float, float], below: tuple[float, float],
                   start: float, min_change: float, share: float = 0.5) -> float | None:
    """The first row from ``start`` down where ``prof`` (rows from ``r0``) has gone half way
    (``share`` of the way) from its mean over the rows ``above`` to its mean over the rows
    ``below``; None when those two differ by less than ``min_change``."""
    rows = np.arange(r0, r0 + len(prof))

    def mean(span: tuple[float, float]) -> np.ndarray | None:
        sel = (rows >= span[0]) & (rows < span[1])
        return prof[sel].mean(axis=0) if sel.sum() >= 2 else None
    top, bottom = mean(above), mean(below)
    if top is None or bottom is None:
        return None
    delta = bottom - top
    size = float(np.linalg.norm(delta))
    if size < min_change:
        return None
    t = (prof - top) @ (delta / size) / size
    for i in range(max(0, int(np.searchsorted(rows, start))), len(t) - 1):
        if t[i] < share <= t[i + 1]:
            return float(rows[i] + (share - t[i]) / (t[i + 1] - t[i]))
    return None


def _chroma_bottom(color: np.ndarray, masked: np.ndarray, axis: float, half: float, d: float,
                   y_band: int) -> float | None:
    """Where a coloured liquid's hue starts below the band, near the axis (the meniscus's
    lowest point); None for a colourless liquid. The grey edge fails there: a dark liquid is
    as dark as the band above it."""
    r0, r1 = max(0, int(y_band - 3 * d)), min(color.shape[0], int(y_band + 4 * d) + 1)
    if r1 - r0 < 6:
        return None
    ab = cv2.cvtColor(np.ascontiguousarray(color[r0:r1]), cv2.COLOR_BGR2LAB)[:, :, 1:]
    prof = _bore_rows(ab, masked[r0:r1], np.arange(int(axis - 0.3 * half), int(axis + 0.3 * half) + 1), 0, r1 - r0)
    if prof is None:
        return None
    return _half_crossing(prof, r0, (y_band - 3 * d, y_band - 1.5 * d), (y_band + 1.5 * d, y_band + 3.5 * d),
                          y_band - d, 2 * CHROMA_STEP)


def _liquid_below(color: np.ndarray, masked: np.ndarray, central: np.ndarray, d: float, y_band: int) -> float | None:
    """Where the colour turns from that above a band to that well below it (3-5 divisions
    down), or None where it does not change (by 30 levels)."""
    prof = _bore_rows(color, masked, central, int(y_band - 3 * d), int(y_band + 5 * d) + 1)
    if prof is None:
        return None
    return _half_crossing(prof, max(0, int(y_band - 3 * d)), (y_band - 3 * d, y_band - 1.5 * d),
                          (y_band + 3 * d, y_band + 5 * d), y_band - d, 30.0)


BACKGROUND_LIKE = 0.25  # share of the colour's change by which the bore under it may differ from the background beside
BACKGROUND_CHANGE = 0.5  # share of the bore's colour change the background beside must make within two divisions


def _background_below(view: _BoreView, y_band: int, start: float) -> bool:
    """Whether the colour change that ``_liquid_below`` saw start at row ``start`` is the
    background's: beside either wall, one to three divisions under ``start``, the background
    has the colour the bore has there, and it changed to it at an edge between the band's rows
    and those (half the bore's change within two divisions): a table's edge behind the glass,
    seen through the bore a little lower than beside it (dev 1260), where a coloured liquid has
    a colour of its own. Either side: an edge slanting behind the bore reaches one side rows
    before the other. A background that changes only by a glow's gradient makes no edge: a
    clear liquid that shows the wall behind it darker than the air does (refraction) under a
    band is the liquid's change, and that band stays refused (the sample recording
    ``cylinder50ml_ramp``: bands so refused, the meniscus's upper edge, read 0.3 division low
    where taken, when the arc under them read right)."""
    color, d, n = view.color, view.d, view.gray.shape[0]
    if color is None:
        return False
    a0, a1 = max(0, int(y_band - 3 * d)), max(0, int(y_band - 1.5 * d) + 1)
    b0, b1 = int(start + d), min(n, int(start + 3 * d) + 1)
    above = _bore_rows(color, view.masked, view.central, a0, a1)  # None under 6 rows: both spans have more
    below = _bore_rows(color, view.masked, view.central, b0, b1)
    if above is None or below is None:
        return False
    bore_below = below.mean(axis=0)
    change = float(np.linalg.norm(bore_below - above.mean(axis=0)))
    k = max(2, int(round(2 * d)))  # an edge: the change made within two divisions, not a glow's gradient over many
    for lo_f, hi_f in BACKGROUND_COLUMNS:
        cols = _side_columns(view.axis, view.half, lo_f, hi_f, color.shape[1])
        if len(cols) < 2:
            continue
        beside = color[a0:b1][:, cols].astype(np.float64).mean(axis=1)  # a row's mean colour, rows a0..b1
        if float(np.linalg.norm(bore_below - beside[b0 - a0:].mean(axis=0))) >= BACKGROUND_LIKE * change:
            continue
        if len(beside) > k and \
                float(np.linalg.norm(beside[k:] - beside[:-k], axis=1).max()) >= BACKGROUND_CHANGE * change:
            return True
    return False


def _periodic_part(response: np.ndarray, marks: Marks, d: float) -> np.ndarray:
    """What of ``response`` repeats one or two major steps away on both sides: numbers and
    words printed beside every major mark make bands at the same place in each step, while a
    meniscus is one of a kind. (The numbers at the two ends of the scale have a twin on one
    side only and stay: counting one side there lost more stills than it won.)"""
    every = major_step(marks)
    n = len(response)
    if every < 2:
        return np.zeros(n, np.float32)
    reach = max(2, int(round(0.3 * d)))  # perspective stretches the steps a little
    widest = cv2.dilate(response.astype(np.float32).reshape(-1, 1), np.ones((2 * reach + 1, 1), np.uint8)).ravel()
    idx = np.arange(n)
    part = np.zeros(n, np.float32)
    for j in (1, 2):  # labels may sit at every second major (a 250 ml cylinder)
        shift = int(round(j * every * d))
        up = np.where(idx >= shift, widest[np.clip(idx - shift, 0, n - 1)], np.nan)
        down = np.where(idx + shift < n, widest[np.clip(idx + shift, 0, n - 1)], np.nan)
        part = np.fmax(part, np.nan_to_num(np.fmin(up, down), nan=0.0))
    return part


def _borrowed_steps(color: np.ndarray, masked: np.ndarray, central: np.ndarray, d: float, y_band: int,
                    others: list[int]) -> set[int]:
    """Of two bands within four divisions, the one the colour does not change across.

    The colour step of a band measures six divisions each way, so a band just above the
    surface borrows the liquid's step. Between the two bands the colour is that of the side
    the true surface does not border: air under the upper one, liquid over the lower one.
    """
    gap = max(2.0, 0.6 * d)

    def mean(r0: float, r1: float) -> np.ndarray | None:
        return _bore_mean(color, central, masked, int(round(r0)), int(round(r1)))
    dropped = set()
    for other in others:
        if abs(other - y_band) > 4 * d:
            continue
        upper, lower = min(other, y_band), max(other, y_band)
        above, between = mean(upper - 3 * d, upper - gap), mean(upper + gap, lower - gap)
        below = mean(lower + gap, lower + 3 * d)
        if above is None or between is None or below is None:
            continue
        step_upper, step_lower = float(np.linalg.norm(above - between)), float(np.linalg.norm(between - below))
        if step_upper < 0.5 * step_lower:
            dropped.add(upper)
        elif step_lower < 0.5 * step_upper:
            dropped.add(lower)
    return dropped


def _near_max(profile: np.ndarray, y: float, reach: int) -> float:
    """The largest value of ``profile`` within ``reach`` rows of ``y`` (0 outside it)."""
    part = profile[max(0, int(round(y)) - reach): int(round(y)) + reach]
    return float(part.max()) if len(part) else 0.0


@dataclass(frozen=True)
class _BoreView:
    """What every meniscus search shares: the strip, its print mask, the bore's geometry."""

    gray: np.ndarray
    color: np.ndarray | None
    marks: Marks
    fit: ScaleFit
    masked: np.ndarray
    axis: float
    half: float
    d: float  # pixels per division
    h: int  # a band is darker than the rows h above and below
    dark_band: bool  # dark against a light background, silvery against a dark one
    central: np.ndarray  # columns near the axis
    min_contrast: float
    rows_seen: tuple[int, int] | None = None  # the strip rows inside the camera's frame, if known

    @property
    def allowed_rows(self) -> tuple[int, int]:
        """The graduated range, or just past it (a cylinder filled over its top mark); never the
        rim or the foot, which are dark bands too, nor where the frame's edge crosses the bore. The
        range's top is the marks' run's (``top_of_run``): the rim's edge or a word over the scale,
        taken for a mark, stands apart above it."""
        ys = np.asarray(self.fit.mark_y_up)
        first, last = 0, self.gray.shape[0] - 1
        if self.rows_seen is not None:
            first, last = max(first, self.rows_seen[0] + self.h), min(last, self.rows_seen[1] - self.h)
        return (max(first, int(np.ceil(top_of_run(ys, self.d) - 2 * self.d))),
                min(last, int(np.floor(ys.max() + 2 * self.d))))


# a mark or two standing this many divisions or more above the rest of the marks, of at least
# RUN_LEAST_MARKS, are not the scale's: the rim's edge or a word printed over the top mark ("mL"),
# which the fit put on the lattice, and whose band the meniscus search then took for the surface
# (seeds 13958, 14339 of the twelfth set: a cylinder's rim read, 22 and 20 divisions off). Only
# above: below the surface the marks seen through a liquid may be few and far apart, one of them
# alone several divisions under the rest (13790, 14165 of the eleventh and twelfth sets: 25 and
# 5 divisions; a meniscus read right on a cylinder's 8.8 mark 3.9 divisions above the rest, 13659)
RUN_GAP_DIV = 4.0
RUN_STRAYS_MAX = 2
RUN_LEAST_MARKS = 10


def top_of_run(mark_y_up: np.ndarray, d: float) -> float:
    """The top row of the marks' run: the first mark, or the first under up to
    ``RUN_STRAYS_MAX`` marks each ``RUN_GAP_DIV`` divisions or more above the next one down."""
    ys = np.sort(np.asarray(mark_y_up, dtype=float))
    top = 0
    for _ in range(RUN_STRAYS_MAX):
        if len(ys) - top > RUN_LEAST_MARKS and ys[top + 1] - ys[top] >= RUN_GAP_DIV * d:
            top += 1
    return float(ys[top])


FRAME_EDGE_DIV = 2.0  # divisions from where the camera's frame crosses the bore: a band there may be its edge


NETWORK_FRAME_EDGE_DIV = 3.0  # the same for the meniscus network's row (``_by_network``)


def _near_frame_edge(view: _BoreView, y: float, reach_div: float = FRAME_EDGE_DIV) -> bool:
    """Whether strip row ``y`` lies within ``reach_div`` divisions of where the camera's frame
    crosses the bore (only where it does, inside the strip)."""
    if view.rows_seen is None:
        return False
    first, last = view.rows_seen
    reach = reach_div * view.d
    return (first > 0 and y - first < reach) or (last < view.gray.shape[0] - 1 and last - y < reach)


def _near_strip_end(view: _BoreView, y: float) -> bool:
    """Whether strip row ``y`` lies within ``FRAME_EDGE_DIV`` of the strip's own first or last
    row. The network sees no bore past them: a band there is half a band, and it has no liquid
    or air beyond it to tell a surface by (fresh 8037: a cylinder's strip cut at its top mark,
    the network 0.98 sure of a surface 1.3 divisions from that end, 32 divisions off)."""
    reach = FRAME_EDGE_DIV * view.d
    return y < reach or view.gray.shape[0] - 1 - y < reach


_COMPLETED: dict[tuple[int, int, int], tuple[Marks, Marks, Marks]] = {}
COMPLETE_RING = 0.8  # share of the bore's width a phase's usual mark spans to be a ring (completed)
COMPLETE_SHORT = 0.1  # share of its phase-mates' usual extent a mark must leave out to be a piece of one
COMPLETE_MATES = 6  # the nearest phase-mates that give a mark's usual extent (3 at least)


def _phase_mates(marks: Marks, period: int) -> dict[int, list[Mark]]:
    """The marks by their place in a period of ``period`` grid steps (``grid_index % period``)."""
    phases: dict[int, list[Mark]] = {}
    for m in marks.marks:
        phases.setdefault(m.grid_index % period, []).append(m)
    return phases


def _phase_extents(marks: Marks) -> dict[int, tuple[float, float]]:
    """For each mark's grid index: the usual extent (x0, x1) of the other marks at the same
    place in the long marks' period, over its nearest ``COMPLETE_MATES`` of them (nearest:
    perspective and a residual tilt move the ends along the scale), counted over two periods
    where rings and medium marks alternate, else over one."""
    step = major_step(marks)
    if step < 2:
        return {}
    by_phase = {period: _phase_mates(marks, period) for period in (2 * step, step)}
    extents = {}
    for k in {m.grid_index for m in marks.marks}:
        for period in (2 * step, step):
            mates = [o for o in by_phase[period][k % period] if o.grid_index != k]
            if len(mates) >= 3:
                near = sorted(mates, key=lambda o: abs(o.grid_index - k))[:COMPLETE_MATES]
                # pieces are what goes wrong, so the ends two of them reach, not the median ends (one
                # may be a mark lengthened by a meniscus lying on it)
                extents[k] = (sorted(o.x0_up for o in near)[1], sorted(o.x1_up for o in near)[-2])
                break
    return extents


def _completed(marks: Marks, bore_px: float, found: Marks | None = None) -> Marks:
    """``marks`` completed where the marks ``found`` (default: ``marks`` themselves) show rings:
    phases whose usual mark spans ``COMPLETE_RING`` of the bore. The marks stage may keep one
    piece of a ring (broken where the wall's shading crosses it) or miss it (beside a meniscus
    that confused it); what is left out of the print mask is a straight band across the bore
    as plain as a meniscus, and the arc search took it for one, or the two refused each other
    (seed 2014). A ring's piece is extended to its phase-mates' usual extent. (A missing
    ring is not put back: its mask changed which bands the ranking saw, for one right reading
    more and one wrong one more in 300 stills.) Only extended, never cut, and from the
    calibration alone, so a meniscus on a mark's row in this frame does not move it. Cached by
    the identities of both."""
    found = marks if found is None else found
    key = (id(marks), id(found), round(bore_px))
    cached = _COMPLETED.get(key)
    if cached is not None and cached[0] is marks and cached[1] is found:
        return cached[2]
    extents = {k: e for k, e in _phase_extents(found).items() if e[1] - e[0] >= COMPLETE_RING * bore_px}
    out = list(marks.marks)
    for i, m in enumerate(out):
        if m.grid_index not in extents:
            continue
        x0, x1 = extents[m.grid_index]
        left_out = max(0.0, m.x0_up - x0) + max(0.0, x1 - m.x1_up)
        if left_out > COMPLETE_SHORT * (x1 - x0):
            out[i] = replace(m, x0_up=min(m.x0_up, x0), x1_up=max(m.x1_up, x1))
    completed = Marks(marks=tuple(out), spacing_up=marks.spacing_up) if out != list(marks.marks) else marks
    if len(_COMPLETED) >= 16:
        _COMPLETED.clear()
    _COMPLETED[key] = (marks, found, completed)
    return completed


_AS_PRINTED: dict[int, tuple[Marks, Marks]] = {}
LENGTHENED = 1.6  # a mark this many times its usual length took in something that crosses it


def _as_printed(marks: Marks) -> Marks:
    """The marks cut to the extent usual for their tier where they are ``LENGTHENED`` times
    longer than it: such a mark took in a meniscus lying on it, and the band beyond the print
    must stay visible. Cached by the identity of ``marks`` (one calibration, every frame)."""
    found = _AS_PRINTED.get(id(marks))
    if found is not None and found[0] is marks:
        return found[1]
    tiers = {tier: [m for m in marks.marks if m.tier == tier] for tier in sorted({m.tier for m in marks.marks})}
    usual = {tier: (float(np.median([m.x0_up for m in same])), float(np.median([m.x1_up for m in same])))
             for tier, same in tiers.items()}
    # a tier of one or two marks has no usual length of its own (a meniscus merged into a mark
    # can make one): the widest tier of three or more stands for it
    widest = max((usual[tier] for tier, same in tiers.items() if len(same) >= 3), key=lambda e: e[1] - e[0],
                 default=None)
    cut = []
    for tier, same in tiers.items():
        x0, x1 = widest if len(same) < 3 and widest is not None else usual[tier]
        slack = 0.25 * (x1 - x0) + 2
        cut += [replace(m, x0_up=max(m.x0_up, x0 - slack), x1_up=min(m.x1_up, x1 + slack))
                if m.length_up > LENGTHENED * (x1 - x0) else m for m in same]
    printed = Marks(marks=tuple(sorted(cut, key=lambda m: m.y_up)), spacing_up=marks.spacing_up)
    if len(_AS_PRINTED) >= 16:
        _AS_PRINTED.clear()
    _AS_PRINTED[id(marks)] = (marks, printed)
    return printed


def _bore_views(gray: np.ndarray, marks: Marks, fit: ScaleFit, bore: tuple[float, float], min_contrast: float,
                color: np.ndarray | None, rows_seen: tuple[int, int] | None
                ) -> tuple[_BoreView, _BoreView, np.ndarray] | None:
    """The bore as the ranking sees it (print masked as found), as the arc, the hue and the
    network see it (``printed``: marks lengthened by a meniscus cut back, rings completed), and
    the ranking's row profile; None for a bore under 6 px wide."""
    left, right = bore
    axis, half = (left + right) / 2, (right - left) / 2
    if half < 3:
        return None
    d = fit.division_px
    central = np.arange(int(axis - 0.5 * half), int(axis + 0.5 * half) + 1)
    masked = print_mask(gray.shape, marks, pad_x=3, pad_y=2.5)
    prof = _smoothed_profile(gray, central, masked, 0.7)
    view = _BoreView(gray=gray, color=color, marks=marks, fit=fit, masked=masked, axis=axis, half=half, d=d,
                     h=max(2, int(round(0.9 * d))), dark_band=float(np.median(prof)) > LIGHT_BEHIND, central=central,
                     min_contrast=min_contrast, rows_seen=rows_seen)
    # the hue and the arc see the band beyond a mark it lay on and lengthened, and not the
    # pieces of rings the marks stage left out (the ranking keeps the marks as found: their full
    # length hides print it would take for bands; a completed ring hid a meniscus that had
    # swallowed part of it, and the ranking took another band, 12 divisions off: seed 1172)
    printed_marks = _completed(_as_printed(marks), right - left, marks)
    printed = replace(view, masked=print_mask(gray.shape, printed_marks, pad_x=3, pad_y=2.5))
    return view, printed, prof


def meniscus_view(gray: np.ndarray, marks: Marks, fit: ScaleFit, bore: tuple[float, float], min_contrast: float,
                  color: np.ndarray | None = None, rows_seen: tuple[int, int] | None = None) -> _BoreView | None:
    """The bore as ``find_meniscus``'s network sees it: its print mask and the rows it may choose
    (``allowed_rows``); for ``scripts/train_bore_net.py``, which must cut its samples alike."""
    views = _bore_views(gray, marks, fit, bore, min_contrast, color, rows_seen)
    return None if views is None else views[1]


BEHIND_REACH_DIV = 3.0  # divisions either side of a band over which the background behind it is judged
LIGHT_BEHIND = 90.0  # grey level of the bore over which a band is dark (under it, silvery)
FLIP_APART_DIV = 0.5  # divisions the other polarity's band must lie from the first one's to replace it


def _behind_reach(d: float) -> int:
    """Rows either side of a band over which ``_dark_behind`` judges the background."""
    return max(2, int(round(BEHIND_REACH_DIV * d)))


def _dark_behind(prof: np.ndarray, y: float, d: float) -> bool:
    """Whether a band at row ``y`` is a dark one: the bore about it (``prof``, the central
    columns' row profile, print masked) is light."""
    reach = _behind_reach(d)
    near = prof[max(0, int(y) - reach): int(y) + reach + 1]
    return float(np.median(near)) > LIGHT_BEHIND if len(near) else True


def _dark_behind_anywhere(prof: np.ndarray, d: float, dark: bool) -> bool:
    """Whether ``_dark_behind`` could be ``dark`` at some row of the profile: a window where at
    least half the rows are of that kind (the median needs as many). Cheap, and it never says
    no where ``_dark_behind`` would say yes: the other polarity's search is skipped where it
    could not be taken (a burette's frames with no meniscus found, 142 of 182 in
    ``burette25ml_leave``, each paid a second search of the rules, 7 ms)."""
    reach = _behind_reach(d)
    of_kind = (prof > LIGHT_BEHIND) if dark else (prof <= LIGHT_BEHIND)
    counts = np.concatenate([[0], np.cumsum(of_kind)])
    rows = np.arange(len(prof))
    lo, hi = np.maximum(0, rows - reach), np.minimum(len(prof), rows + reach + 1)
    return bool(np.any(counts[hi] - counts[lo] >= (hi - lo) // 2))


def _other_polarity(view: _BoreView, printed: _BoreView, prof: np.ndarray, bore: tuple[float, float],
                    found: Indicator | None) -> Indicator | None:
    """The band as the other polarity sees it, where the background about the first one's (or
    about any, where it found none) is of the other kind: a meniscus is dark over a light
    background and silvery over a dark one, as the background right behind it is, not the bore's
    as a whole (half the bore over a dark table, half over a light wall). Second dev set 1540:
    the dark gap under a silvery surface over a dark table, in a bore mostly over a light wall,
    was read 0.95 division low. Taken where its own background agrees with it, and only where it
    lies over ``FLIP_APART_DIV`` from the first one's (within that, both saw the same surface and
    the first one's edge stands: dev 1271's other edge lay 0.16 division further from the truth)."""
    if found is not None and _dark_behind(prof, found.y_up, view.d) == view.dark_band:
        return found
    other = not view.dark_band
    if not _dark_behind_anywhere(prof, view.d, other):
        return found
    flipped = _by_rules(replace(view, dark_band=other), replace(printed, dark_band=other), prof, bore)
    if flipped is None or _dark_behind(prof, flipped.y_up, view.d) != other:
        return found
    if found is not None and abs(flipped.y_up - found.y_up) <= FLIP_APART_DIV * view.d:
        return found
    return flipped


def network_sigma_px(division_px: float) -> float:
    """The localisation sigma of a bore network's row (meniscus or stopper): 0.15 of a division,
    0.3 px at least; its input has 8 rows a division."""
    return max(0.3, 0.15 * division_px)


CHECK_CONFIDENCE = 0.95  # how sure the network must be of a row near the rules' meniscus to read its row instead
CHECK_APART_DIV = 2.0  # divisions between the rules' meniscus and the network's that make them disagree
# how sure the network must be of another row to overrule the rules' meniscus. 0.95 until stop
# 59: on the cylinders and burettes of seeds 12000-13199, of the rules' menisci the network put
# elsewhere, all 34 it was 0.95 sure of or more were wrong and its row right; at 0.92 and 0.95,
# 12855 and 12996, no reading then, the same
OVERRULE_CONFIDENCE = 0.90
# and to make it no reading. Between 0.70 and 0.85 on those seeds it doubted six wrong menisci
# (12133, 12804, 12832, 12890, 12891, 12940, 3-47 divisions off) and one right (13096, 0.71), but
# also img_029's, right (0.77): at 0.70 the real photograph went unread
MENISCUS_DOUBT_CONFIDENCE = 0.85


def find_meniscus(gray: np.ndarray, marks: Marks, fit: ScaleFit, bore: tuple[float, float],
                  min_contrast: float, color: np.ndarray | None = None,
                  rows_seen: tuple[int, int] | None = None, network: bool = True,
                  check: bool = False) -> Indicator | None:
    """The meniscus in the strip, or None. ``rows_seen``: the strip rows the camera's frame
    covers across the bore (``orientation.rows_in_frame``); no band is looked for outside them:
    past the frame the strip repeats the edge's pixels, and the frame's edge across the bore is
    as plain a band as a meniscus. ``network``: where every rule finds none, the bundled
    meniscus network (``bore_net.meniscus_net``) looks once more. ``check``: the network also looks
    where the rules found one, and a meniscus it is ``OVERRULE_CONFIDENCE`` sure lies over
    ``CHECK_APART_DIV`` divisions away replaces theirs (a label's band, a ring's edge, a cable
    taken for the surface: on the stills the rules read, it disagreed so with none of the dev
    stills read right), as the network's own finding, with its vetoes (``_by_network``): where
    they refuse it, no reading. One it is as sure of nearer theirs is the same surface, and its
    row is read: it lies closer than the rules' band edge."""
    views = _bore_views(gray, marks, fit, bore, min_contrast, color, rows_seen)
    if views is None:
        return None
    view, printed, prof = views
    found = _by_rules(view, printed, prof, bore)
    if found is not None:
        found = _other_polarity(view, printed, prof, bore, found)
    walls = walls_found(bore, gray.shape[1])
    if found is None:
        # where the rules find none, the network's band before the other polarity's (dev 1182:
        # the network's meniscus 0.00 division off, the other polarity's 0.21); with both walls
        # found, as the hue and the arc need them
        if network and walls:
            found = _by_network(printed, bore)
        if found is None and walls:
            found = _other_polarity(view, printed, prof, bore, None)
    elif check and walls:
        other = _network_row(printed, bore, MENISCUS_DOUBT_CONFIDENCE)
        if other is None:
            return found
        row, confidence = other
        if abs(row - found.y_up) > CHECK_APART_DIV * printed.d:
            # another row: the network's own meniscus where it is sure (dev 1075, 1095: the rules
            # took another band, the network's row right); no reading where it is less sure but
            # still doubts theirs (held-out 2113, fresh 8544: the rules' band 5 divisions off,
            # the network's row right, 0.93 and 0.89 sure; the rules' right band was doubted at
            # 0.80 at most on the dev, second dev, held-out and fresh stills; img_029's at 0.77)
            if confidence >= OVERRULE_CONFIDENCE or (found.coloured_liquid and row < found.y_up
                                                  and _spans_bore(view, int(round(row)))):
                # also, less sure, a surface above a coloured liquid's (up the strip, where the
                # numbers stand upright) that runs across the whole bore: a clear liquid over the
                # coloured one, whose top surface is the level, as a person reads it (img_007,
                # clear over blue: the blue's surface was read 35 divisions off; the labels of
                # img_014, 022, 026, oil over water, give the oil's surface too). No synthetic
                # still of the dev or fresh sets moved: the renderer draws one liquid
                return _by_network(printed, bore, other)
            return None
        if confidence >= CHECK_CONFIDENCE:
            # both see the surface there: the network's row, which lies closer (on the fresh
            # seeds 8000-8599, 11 of their 336 cylinders and burettes read 0.5-2 divisions off
            # by the rules are read within half a division so, none the other way; the median
            # error 0.087 -> 0.054 division), as the stopper network's row is taken
            return replace(found, y_up=row, sigma_px=network_sigma_px(printed.d))
    return found


def _spans_bore(view: _BoreView, y: int) -> bool:
    """Whether a dark band at row ``y`` (within a band's reach) crosses the whole bore: the
    columns near the axis and those near each wall all show it ``min_contrast`` deep, print
    masked. A label printed in the bore covers a part of it only."""
    near = slice(max(0, y - view.h), y + view.h + 1)
    for lo_f, hi_f in ((-0.3, 0.3), (-0.8, -0.35), (0.35, 0.8)):
        columns = np.arange(int(view.axis + lo_f * view.half), int(view.axis + hi_f * view.half) + 1)
        prof = _smoothed_profile(view.gray, columns, view.masked, 0.7)
        band, _ = _band_and_step(prof if view.dark_band else 255 - prof, view.h)
        if band[near].max(initial=0.0) < view.min_contrast:
            return False
    return True


def _network_row(view: _BoreView, bore: tuple[float, float], min_confidence: float) -> tuple[float, float] | None:
    """``BoreNet.locate`` on the bore as ``view`` shows it: (row, confidence) or None."""
    from streamread.bore_net import meniscus_net  # onnxruntime only once the network is asked

    colour = view.color if view.color is not None else view.gray
    return meniscus_net().locate(colour, view.masked, bore, view.d, view.allowed_rows, min_confidence=min_confidence)


def _by_network(view: _BoreView, bore: tuple[float, float],
                located: tuple[float, float] | None = None) -> Indicator | None:
    """The network's meniscus (``bore_net.meniscus_net``), where it is sure of one in the allowed
    rows. ``located``: its (row, confidence) where the caller asked it already, as sure or surer."""
    from streamread.bore_net import MIN_CONFIDENCE

    located = located if located is not None else _network_row(view, bore, MIN_CONFIDENCE)
    if located is None:
        return None
    row, confidence = located
    if _near_strip_end(view, row) or _near_frame_edge(view, row, NETWORK_FRAME_EDGE_DIV):
        # past the frame's edge the strip repeats the edge's pixels, a plain run the network's
        # context of 8 divisions reaches into as it would into a liquid (clean 9063: a burette's
        # frame edge, the network 0.94 sure of a surface 2.5 divisions inside it, 64 divisions
        # off; of the 1,232 cylinders and burettes of seeds 1000-1599, 2000-2299, 8000-8599 and
        # 9000-9599, no other reading lay within 11 divisions of a frame's edge but one of the
        # rules', 6.7 divisions in)
        return None
    # vetoes as the rules': a band that goes on outside the walls (a table's edge behind the
    # glass; here within a division, ``_band_outside_walls``), or one with the same liquid above
    # and below it, is not the surface
    y = int(round(row))
    prof = _smoothed_profile(view.gray, view.central, view.masked, 0.7)
    band, step = _band_and_step(prof if view.dark_band else 255 - prof, view.h)
    near = slice(max(0, y - view.h), y + view.h + 1)
    inside = float(max(band[near].max(initial=0.0), 0.5 * np.abs(step[near]).max(initial=0.0)))
    if _band_outside_walls(view, y, inside):
        return None
    if view.color is not None and _within_one_liquid(view, y):
        return None
    return Indicator(kind="meniscus", y_up=row, x_up=float(view.axis), sigma_px=network_sigma_px(view.d),
                     strength=100 * confidence, by_network=True)


OUTSIDE_EDGE_OVER_USUAL = 3.0  # times a side's median response down the strip that an edge there must reach
OUTSIDE_EDGE_MIN = 4.0  # grey levels an edge outside the walls must reach, or the whole band's depth if less


def _band_outside_walls(view: _BoreView, y: int, inside: float) -> bool:
    """Whether a band half as strong as ``inside`` crosses the columns outside the walls within
    a division of row ``y``, on both sides (or on the one side the strip shows): a straight edge
    behind the glass (a table's), not a surface. Stricter than ``_background_crosses`` (three
    divisions, or one side of two), which refused 13 of the network's 18 right readings among
    the dev stills the rules found no meniscus in: where the network sees the surface the band
    is faint or hidden by print, and half of it is matched by any texture outside. So too, an
    edge outside must stand ``OUTSIDE_EDGE_OVER_USUAL`` times over that side's usual response,
    and ``OUTSIDE_EDGE_MIN`` grey levels, or the band's whole depth where it is fainter: where
    the surface is two or three levels deep, half of it and three times a plain wall's median
    were still matched by the wall's noise on one side (fresh 8211, 8490: 1.8 levels against
    a band of 2.5-2.6, the network's row right and over 99.9 % sure, refused while a cable
    crossed the other side, or nothing did). Where the grey shows no band at all (a hue's edge
    alone, hand-made strips), any edge outside matches it: refused."""
    reach = max(2, int(round(view.d)))
    rows = np.arange(max(0, y - reach), min(view.gray.shape[0], y + reach + 1))
    responses = _outside_responses(view.gray, view.axis, view.half, rows, view.h, view.dark_band)
    # an edge, not the side's own texture: half a faint surface's band (a grey level or two) is
    # matched by the noise of a plain wall (dev 1056, 1106, 1226: right readings refused)
    return bool(responses) and all(
        r[rows].max(initial=0.0) >= max(0.5 * inside, OUTSIDE_EDGE_OVER_USUAL * float(np.median(r)),
                                            min(OUTSIDE_EDGE_MIN, inside))
        for r in responses)


def _by_rules(view: _BoreView, printed: _BoreView, prof: np.ndarray, bore: tuple[float, float]) -> Indicator | None:
    """The rules' meniscus: the ranked band, a coloured liquid's hue step, the arc, a surface the
    marks stage took for a mark, in turn."""
    d = view.d
    walls = walls_found(bore, view.gray.shape[1])  # as found: the axis and half width give them back only to rounding
    ranked = _ranked_band(view, prof)
    if ranked is not None:
        y_band, strength, cover = ranked
        if _near_frame_edge(view, y_band):
            # the rows just inside the camera's frame make a band of their own where its edge
            # crosses the bore (held-out 2116, dev 1159: read 34 and 85 divisions off); the band
            # ranked first there may be that edge, and the one ranked next has lost its rival
            return None
        found = _meniscus_at(view, y_band, strength, cover)
        if found is not None:
            if not found.coloured_liquid and walls:
                # a colourless band over a coloured liquid's surface found well under it (a
                # label's band in the air above it): the liquid's own surface is the level
                under = _hue_surface(printed)
                if under is not None and under.y_up > found.y_up + 2 * d:
                    return under
            return found
    if not walls:
        return None
    # a coloured liquid's own hue step, which many checks must pass, before the arc: a faint
    # arc may be a background edge across the bore
    found = _hue_surface(printed)
    if found is not None:
        return found
    arc = _arc_band(printed)
    found = None if arc is None else _meniscus_at(printed, arc.y0, arc.strength, None, arc)
    return found if found is not None else _surface_taken_for_mark(view)


_USUAL_LENGTHS: dict[int, tuple[Marks, dict[int, float]]] = {}


def _usual_lengths(marks: Marks) -> dict[int, float]:
    """Each mark's usual length, by its identity: the 90th percentile of its phase-mates' (the
    marks at the same place in the long marks' period), for a meniscus on a short mark can
    lengthen it into a longer tier, where it looks usual. Not their median: a period counted
    on the medium marks makes a ring's phase-mates half rings, half mediums. Without three
    phase-mates, its tier's median. Cached by the identity of ``marks``, as ``_as_printed``
    is: it costs 2-4 ms, and a stream with no meniscus in view asks for it every frame."""
    found = _USUAL_LENGTHS.get(id(marks))
    if found is not None and found[0] is marks:
        return found[1]
    tiers: dict[str, list[float]] = {}
    for m in marks.marks:
        tiers.setdefault(m.tier, []).append(m.length_up)
    step = major_step(marks)
    phases = _phase_mates(marks, step) if step >= 2 else {}
    usual = {}
    for m in marks.marks:
        mates = [o.length_up for o in phases.get(m.grid_index % step, []) if o is not m] if step >= 2 else []
        usual[id(m)] = float(np.percentile(mates, 90)) if len(mates) >= 3 else float(np.median(tiers[m.tier]))
    if len(_USUAL_LENGTHS) >= 16:
        _USUAL_LENGTHS.clear()
    _USUAL_LENGTHS[id(marks)] = (marks, usual)
    return usual


ACROSS_BORE = 0.6  # a mark this share of the bore's width long may be a band across it (ends climb the walls)


def _surface_taken_for_mark(view: _BoreView) -> Indicator | None:
    """A level surface seen edge-on is a thin line from wall to wall; on a mark, or in the
    ladder's rhythm (a cylinder filled one division past its top mark), the mark search took it
    for a mark, whose print mask hides it from every search above (the arc's too, where the mark
    reaches the walls). Such a "mark" is ``LENGTHENED`` times its usual length and spans most of
    the bore: unmasked, the band under it must pass the same checks as any other. Two such
    bands apart are no reading, as two alike bands are for the ranking."""
    marks = view.marks.marks
    usual = _usual_lengths(view.marks)
    y_lo, y_hi = view.allowed_rows
    surfaces: list[Indicator] = []
    for m in marks:
        if not (m.length_up > LENGTHENED * usual[id(m)] and m.length_up >= ACROSS_BORE * 2 * view.half
                and y_lo <= m.y_up <= y_hi):
            continue
        if sum(o is not m and o.tier != "major" and o.length_up >= 0.8 * m.length_up for o in marks) >= 2:
            continue  # short marks as long are print the ladder took for short (a burette's rings), not one surface
        others = Marks(marks=tuple(o for o in marks if o is not m), spacing_up=view.marks.spacing_up)
        masked = print_mask(view.gray.shape, others, pad_x=3, pad_y=2.5)
        prof = _smoothed_profile(view.gray, view.central, masked, 0.7)
        band, _ = _band_and_step(prof if view.dark_band else 255 - prof, view.h)
        y = int(round(m.y_up))
        strength = float(band[max(0, y - 2): y + 3].max())
        if strength < view.min_contrast:
            continue
        found = _meniscus_at(replace(view, masked=masked), y, strength, None)
        if found is not None:
            surfaces.append(found)
    if not surfaces or any(abs(f.y_up - surfaces[0].y_up) > 2 * view.d for f in surfaces):
        return None
    return surfaces[0]


def _ranked_band(view: _BoreView, prof: np.ndarray) -> tuple[int, float, np.ndarray | None] | None:
    """The band across the bore that the row profile near the axis ranks first: (its row, its
    response, the band coverage if it was needed to choose), or None (no band, or two alike)."""
    gray, masked, axis, half, d, h = view.gray, view.masked, view.axis, view.half, view.d, view.h
    color, central, min_contrast, dark_band = view.color, view.central, view.min_contrast, view.dark_band
    n = len(prof)

    def response_of(p: np.ndarray) -> np.ndarray:
        """A dark band, or (dark liquid as dark as the band) a drop from air to liquid."""
        band, step = _band_and_step(p if dark_band else 255 - p, h)
        band[:h] = 0
        band[-h:] = 0
        return np.maximum(band, 0.5 * step)

    response = response_of(prof)
    # the meniscus spans the bore: at least one side (numbers may cover the other) must show it too
    sides = []
    for lo_f, hi_f in ((-0.8, -0.35), (0.35, 0.8)):
        side = np.arange(int(axis + lo_f * half), int(axis + hi_f * half) + 1)
        side_prof = _smoothed_profile(gray, side, masked, 0.7)
        # the meniscus climbs towards the walls: accept the side band a little higher than the centre
        reach = max(1, int(round(0.8 * d)))
        side_resp = response_of(side_prof).astype(np.float32)
        sides.append(cv2.dilate(side_resp.reshape(-1, 1), np.ones((2 * reach + 1, 1), np.uint8)).ravel())
    response = np.minimum(response, np.maximum(sides[0], sides[1]))
    y_lo, y_hi = view.allowed_rows
    rows = np.arange(n)
    response = np.where((rows >= y_lo) & (rows <= y_hi), response, 0)
    # several dark bands may cross the bore (a cable behind the glass): the meniscus also
    # separates liquid from air, so the colour changes across it
    # numbers printed in the bore are bands too, one per major step: candidates are ranked on
    # what does not repeat (the bands themselves are still judged on their full response)
    ranking = response - _periodic_part(response, view.marks, d)
    peaks = [int(i) for i in np.argsort(ranking)[::-1][:40] if ranking[i] >= min_contrast * 0.4]
    candidates: list[int] = []
    for p in peaks:
        if all(abs(p - c) > 2 * d for c in candidates):
            candidates.append(p)
        if len(candidates) == 5:
            break
    if not candidates:
        return None
    cover: np.ndarray | None = None
    if color is not None and len(candidates) > 1:
        scores = sorted(((_liquid_step(color, central, masked, c, d) + 0.3 * response[c], c) for c in candidates),
                        reverse=True)
        top_score, y_band = scores[0]
        # the colour changes across the whole meniscus, from where it climbs the wall down to its
        # dark bottom: a step with a faint band of its own just above a plain band is its top
        below = [(s, c) for s, c in scores[1:] if 0 < c - y_band <= 3 * d
                 and response[c] >= max(min_contrast, 3 * response[y_band])]
        if below:
            scores = [(s, c) for s, c in scores if c != y_band]
            top_score, y_band = below[0]
        borrowed = _borrowed_steps(color, masked, central, d, y_band, [c for _, c in scores if c != y_band])
        if borrowed:
            scores = [(s, c) for s, c in scores if c not in borrowed]
            top_score, y_band = scores[0]
        alike = [c for score, c in scores if c != y_band and score > 0.75 * top_score]
        if alike:
            # two bands alike (a cable, a label line): refuse rather than guess, unless exactly
            # one of them crosses the whole bore and the others plainly do not
            cover = _band_coverage(gray, masked, axis, half, d, h, dark_band, min_contrast)
            covered = {c: _near_max(cover, c, 4) for c in [y_band] + alike}
            crossing = [c for c, share in covered.items() if share >= 0.8]
            if len(crossing) != 1 or any(share >= 0.4 for c, share in covered.items() if c != crossing[0]):
                return None
            y_band = crossing[0]
    else:
        y_band = candidates[0]
    if response[y_band] < min_contrast:
        # weaker bands are kept above only so that two alike can refuse each other; the band read
        # must reach the profile's contrast (every such reading in 300 test stills was wrong)
        return None
    return y_band, float(response[y_band]), cover


ARC_REACH = 0.85  # the arc is followed out to this share of the half bore (the walls blur the band)
ARC_CONTRAST = 1.3  # times the profile's contrast: a rescue must see the band plainly
ARC_MAX_RIVAL = 0.6  # the best arc that never comes within a division of it scores at most this share


def _arc_columns(axis: float, half: float) -> np.ndarray:
    return np.arange(int(np.ceil(axis - ARC_REACH * half)), int(axis + ARC_REACH * half) + 1)


@dataclass(frozen=True)
class _Arc:
    """A curved band across the bore: row ``y0`` at the axis, climbing ``sag_px`` at the walls."""

    y0: int
    sag_px: float
    power: int
    axis: float
    half: float
    strength: float  # mean band response along it, on its weaker side
    reach_px: int  # how far the band may stray from the arc in a column

    @property
    def columns(self) -> np.ndarray:
        return _arc_columns(self.axis, self.half)

    def rows_at(self, xs: np.ndarray) -> np.ndarray:
        """The arc's row in each of the columns ``xs``, to the whole pixel."""
        climb = self.sag_px * np.minimum(1.0, np.abs(xs - self.axis) / self.half) ** self.power
        return np.rint(self.y0 - climb).astype(int)


def _arc_band(view: _BoreView) -> _Arc | None:
    """The meniscus as a curved dark band from wall to wall, or None.

    The profile ranking above judges rows near the axis, then asks the sides to agree; a band
    that sags (a concave meniscus: lowest at the axis, climbing the walls) is seen better by
    following it: each arc ``y(x) = y0 - sag * |x/half|^p`` (p = 2, a narrow tube; 4, a wide
    one, flat in the middle) scores the mean band response along it, print left out, on the
    weaker side of the axis, so a number beside the marks (one side) does not count. The best
    arc must reach ``ARC_CONTRAST`` times the profile's contrast and stand out
    (``ARC_MAX_RIVAL``): several arcs alike (labels, a cable) are no reading. A straight arc is
    allowed (a meniscus seen edge-on); one that goes on past the walls is refused later, as a
    ranked band is.
    """
    gray, axis, half, h = view.gray, view.axis, view.half, view.h
    n, w = gray.shape
    cols = _arc_columns(axis, half)
    cols = cols[(cols >= 0) & (cols < w)]
    cols = cols[:: max(1, int(round(len(cols) / 40)))]  # 40 columns follow a band well enough, and cost less
    y_lo, y_hi = view.allowed_rows
    y_lo, y_hi = max(y_lo, h), min(y_hi, n - 1 - h)
    if len(cols) < 6 or y_hi <= y_lo:
        return None
    block = cv2.GaussianBlur(gray[:, cols].astype(np.float32), (1, 3), 0)
    band, _ = _band_and_step(block if view.dark_band else 255 - block, h)
    band = cv2.dilate(band, np.ones((3, 1), np.uint8))  # the band's shape is not exactly the arc's
    left = cols < axis
    if left.sum() < 3 or (~left).sum() < 3:
        return None
    # every arc at once: for each (power, climb at the walls) and each row y0 at the axis, the
    # mean response along the arc over the pixels print leaves clear, side by side of the axis
    sags = np.unique(np.round(np.geomspace(1.0, max(1.0, 0.45 * half), 12)))
    arcs = [(2, 0.0)] + [(power, sag) for power in (2, 4) for sag in sags]  # straight once
    y0s = np.arange(y_lo, y_hi + 1)
    clear = view.masked[:, cols] == 0
    value, count = np.where(clear, band, 0.0).astype(np.float32), clear.astype(np.float32)
    xn = np.abs(cols - axis) / half
    climbs = np.array([np.round(sag * xn**power) for power, sag in arcs], int)  # (arcs, columns)
    score = np.full((len(arcs), len(y0s)), np.inf, np.float32)
    for part in (left, ~left):
        rows = np.clip(y0s[None, :, None] - climbs[:, None, part], 0, n - 1)
        where = (rows, np.flatnonzero(part)[None, None, :])
        total, seen = value[where].sum(axis=2), count[where].sum(axis=2)
        # a side all hidden by print says nothing: the other decides (both hidden: no score)
        score = np.minimum(score, np.where(seen > 0, total / np.maximum(seen, 1), np.inf))
    score[np.isinf(score)] = -np.inf
    pick = np.argmax(score, axis=0)  # the first best arc for each row, as a strict running best would keep
    best_score = score[pick, np.arange(len(y0s))].astype(np.float64)
    top = int(np.argmax(best_score))
    if best_score[top] < ARC_CONTRAST * view.min_contrast:
        return None
    # a rival is an arc that never comes within a division of this one: the arcs around it that
    # cross it (a deeper one from below meets it at the walls) are the same band seen in part
    offset = climbs - climbs[pick[top]]  # where each arc shape lies against the top one, y0 for y0
    near_lo = y0s[top] + offset.min(axis=1) - view.d  # per arc shape: the y0s that come within a division
    near_hi = y0s[top] + offset.max(axis=1) + view.d
    apart = (y0s[None, :] < near_lo[:, None]) | (y0s[None, :] > near_hi[:, None])
    rivals = score[apart]
    if len(rivals) and float(rivals.max()) > ARC_MAX_RIVAL * best_score[top]:
        return None
    power, sag = arcs[pick[top]]
    return _Arc(y0=int(y0s[top]), sag_px=float(sag), power=int(power), axis=axis, half=half,
                strength=float(best_score[top]), reach_px=max(2, int(round(0.4 * view.d))))


def _arc_edges(view: _BoreView, arc: _Arc, span: int) -> list[tuple[float, float]]:
    """(signed distance from the axis, row) of the band's lower edge in each of the arc's columns, as
    ``_meniscus_at`` finds it near the axis, but looking for the darkest row only within
    ``reach_px`` of the arc: where the band's darkest row is, then where the column comes half
    way back up to the rows 0.8-1.6 divisions under it. A column whose darkest rows print hides,
    or whose band is fainter than half the contrast, gives none. All columns at once."""
    gray, d = view.gray, view.d
    n, w = gray.shape
    cols = arc.columns
    cols = cols[(cols >= 0) & (cols < w)]
    if len(cols) == 0:
        return []
    reach = arc.reach_px
    start = arc.rows_at(cols) - reach  # each column's window: from reach_px above the arc to 2 span below
    rows = start[:, None] + np.arange(reach + 2 * span + 1)[None, :]
    inside = (rows >= 0) & (rows < n)
    rows = np.clip(rows, 0, n - 1)
    seg = gray[rows, cols[:, None]].astype(np.float32)
    if not view.dark_band:
        seg = 255 - seg
    seg[(view.masked[rows, cols[:, None]] > 0) | ~inside] = np.nan
    darkest = 2 * reach + 1
    ok = (np.isnan(seg).mean(axis=1) <= 0.3) & ~np.isnan(seg[:, :darkest]).any(axis=1)
    if not ok.any():
        return []
    seg, cols, start = seg[ok], cols[ok], start[ok]
    seg = np.where(np.isnan(seg), np.nanmedian(seg, axis=1, keepdims=True), seg)
    y_min = np.argmin(seg[:, :darkest], axis=1)
    below = y_min[:, None] + np.arange(max(2, int(0.8 * d)), max(4, int(1.6 * d)))[None, :]
    tail = np.median(np.take_along_axis(seg, np.minimum(below, seg.shape[1] - 1), axis=1), axis=1)
    low = seg[np.arange(len(seg)), y_min]
    level = (low + tail) / 2
    # the first step at or past the darkest row across the half-way level (as ``_crossing``)
    a, b = seg[:, :-1], seg[:, 1:]
    steps = np.arange(seg.shape[1] - 1)[None, :]
    crosses = ((a - level[:, None]) * (b - level[:, None]) <= 0) & (a != b) & (steps >= y_min[:, None])
    found = crosses.any(axis=1) & (tail - low >= 0.5 * view.min_contrast)
    i = np.argmax(crosses, axis=1)
    k = np.arange(len(seg))
    sub = i + (level - a[k, i]) / np.where(b[k, i] != a[k, i], b[k, i] - a[k, i], 1.0)
    return [(float(c - arc.axis), float(r0 + y)) for c, r0, y, f in zip(cols, start, sub, found) if f]


TILT_REACH = 0.3  # of the bore's half width: edges this far out on both sides let a tilt be fitted
TILT_MIN_EDGES = 3  # edges so far out on each side


def _arc_bottom(edges: list[tuple[float, float]], arc: _Arc, d: float) -> tuple[float, float] | None:
    """The lower edge's row at the axis, and its standard error, from the lower edges found in
    the arc's columns: ``y = bottom - climb * |x/half|^power`` (power 2 or 4, whichever fits
    better; ``+ tilt * x/half`` where edges reach out on both sides: a band seen tilted, dev
    1062), fitted by least squares with the edges more than 1.5 px past three median deviations
    left out; None where the two powers fit alike (neither residual half the other's) and
    disagree by over 0.4 division (``d`` pixels).
    The band's lower edge climbs less than its middle (the band thickens towards the
    walls), so the arc's own climb is not used; where print hides the axis, the edges further
    out still give the bottom."""
    if len(edges) < 5:
        return None
    x, y = np.array(edges, float).T
    dx = np.abs(x)
    # a band seen tilted across the strip (the meniscus's plane not square to the axis as the
    # marks' centres set it: perspective) climbs on one side and sinks on the other; where edges
    # reach well out on both sides, a tilt is fitted too and the row read at the axis
    far = TILT_REACH * arc.half
    tilted = min(int((x <= -far).sum()), int((x >= far).sum())) >= TILT_MIN_EDGES
    fits: list[tuple[float, float, float]] = []  # (residual, bottom, its standard error)
    for power in (2, 4):  # the arc's own power was chosen on the band's middle, quantised
        terms = [np.ones_like(dx), -np.minimum(1.0, dx / arc.half) ** power]
        if tilted:
            terms.append(np.clip(x / arc.half, -1.0, 1.0))
        design = np.stack(terms, axis=1)
        keep = np.ones(len(y), bool)
        for _ in range(3):
            coef, *_ = np.linalg.lstsq(design[keep], y[keep], rcond=None)
            resid = y - design @ coef
            mad = float(np.median(np.abs(resid[keep])))
            keep = np.abs(resid) <= 3 * mad + 1.5
            if keep.sum() < 5:
                break
        else:
            coef, *_ = np.linalg.lstsq(design[keep], y[keep], rcond=None)
            resid = y[keep] - design[keep] @ coef
            rms = float(np.sqrt(resid @ resid / max(1, int(keep.sum()) - 2)))
            se = rms * float(np.sqrt(max(np.linalg.pinv(design[keep].T @ design[keep])[0, 0], 0.0)))
            fits.append((rms, float(coef[0]), se))
    if len(fits) < 2:
        return None
    (rms, bottom, se), (rms_other, bottom_other, _) = sorted(fits)
    if rms > 0.5 * rms_other and abs(bottom - bottom_other) > max(1.0, 0.4 * d):
        return None  # edges far from the axis only, fitted alike by both: the guess would decide
    return bottom, se


HUE_STEP = 1.0  # times CHROMA_STEP: the liquid's hue differs this much from the air's above it
HUE_RIVAL = 0.5  # another hue step anywhere in the bore this share of the surface's makes it no reading
HUE_TINT = 0.75  # share of the surface's hue step by which the liquid differs from the background beside it
HUE_AIR = 0.35  # share of the surface's hue step that the air over it may vary by
HUE_STEADY = 0.8  # share of the rows under the surface, to the scale's end, that keep the liquid's hue
HUE_SIDE_NEAR = 0.8  # share of a half's strongest hue step that it reaches within a division of the surface's row


def _hue_surface(view: _BoreView) -> Indicator | None:
    """A coloured liquid's surface found by its hue alone, where no dark band was seen: the
    meniscus drawn thin, or lying on a long mark that hides it, with the liquid's colour
    starting under it. None unless the hue changes once only in the bore (``HUE_RIVAL``), at
    one row on both halves of it (a surface is level), stays changed down to the end of the
    scale (the liquid fills the tube under its surface, ``HUE_STEADY``), does not change
    outside the walls too (a card's edge behind the glass), and leaves the liquid a hue of its
    own (``HUE_TINT``: clear liquid over a tinted card has the card's). Print is left out of
    every mean, so marks across the bore (a burette) do not hide the liquid."""
    color, masked, axis, half, d = view.color, view.masked, view.axis, view.half, view.d
    if color is None:
        return None
    n, w = color.shape[:2]
    y_lo, y_hi = view.allowed_rows
    lo, hi = max(2, int(round(1.5 * d))), max(6, int(round(4 * d)))
    r0, r1 = max(0, y_lo - hi), min(n, y_hi + hi + 1)
    # only the bore's columns are converted to Lab (the background beside it later, only for a
    # step that passed every check inside): the common frame with no coloured liquid stops early
    x0, x1 = max(0, int(axis - 0.85 * half)), min(w, int(axis + 0.85 * half) + 1)
    if r1 - r0 < 2 or x1 - x0 < 2:  # no rows to search (a scale of a few marks near the strip's end)
        return None
    ab = cv2.cvtColor(np.ascontiguousarray(color[r0:r1, x0:x1]), cv2.COLOR_BGR2LAB)[:, :, 1:]
    masked = masked[r0:r1, x0:x1]
    axis -= x0

    def columns(lo_f: float, hi_f: float) -> np.ndarray:
        return np.arange(int(axis + lo_f * half), int(axis + hi_f * half) + 1)
    prof = _bore_rows(ab, masked, columns(-0.6, 0.6), 0, r1 - r0)
    if prof is None or len(prof) <= 2 * hi:
        return None
    rows = np.arange(hi, len(prof) - hi)
    inside = (rows + r0 >= y_lo) & (rows + r0 <= y_hi)

    def steps(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per row of ``rows``: the hue's change from the rows lo-hi above it to those below
        (0 outside the scale), and the mean hue below."""
        sums = np.concatenate([np.zeros((1, 2)), np.cumsum(p, axis=0)])
        above = (sums[rows - lo + 1] - sums[rows - hi]) / (hi - lo + 1)
        below = (sums[rows + hi] - sums[rows + lo - 1]) / (hi - lo + 1)
        return np.where(inside, np.linalg.norm(below - above, axis=1), 0.0), below
    step, below = steps(prof)
    top = int(np.argmax(step))
    size = float(step[top])
    if size < HUE_STEP * CHROMA_STEP:
        return None
    if np.any((np.abs(rows - rows[top]) > hi) & (step > HUE_RIVAL * size)):
        return None
    # a surface is level: each half of the bore sees its hue change at the same row, where a
    # cable slanting across the bore changes it rows apart. The step's peak is a plateau (its
    # means span 1.5-4 divisions), which a highlight paling the liquid in one half moves: a half
    # whose peak is away from the surface's row still agrees where its step is near as strong
    # at that row, and both halves' hues depart from the air's where the whole bore's does
    reach = max(2.0, d)
    y_step = int(rows[top]) + r0
    air, liquid_rows = (y_step - 3 * d, y_step - 1.5 * d), (y_step + 1.5 * d, y_step + 3.5 * d)

    def departs(p: np.ndarray, first_row: int = r0) -> float | None:
        """Where the hue of ``p`` (strip rows from ``first_row``) is a quarter of the way from air to liquid."""
        return _half_crossing(p, first_row, air, liquid_rows, y_step - 2 * d, HUE_STEP * CHROMA_STEP, share=0.25)
    halves = []  # (its hue profile, whether its strongest step is away from the surface's row)
    for side in (columns(-0.85, -0.15), columns(0.15, 0.85)):
        seen = _bore_rows(ab, masked, side, 0, r1 - r0)
        if seen is None:
            continue
        side_step, _ = steps(seen)
        strongest = float(side_step.max())
        if strongest < HUE_RIVAL * size:
            continue
        away = abs(int(np.argmax(side_step)) - top) > reach
        if away and float(side_step[max(0, top - int(reach)): top + int(reach) + 1].max()) < HUE_SIDE_NEAR * strongest:
            return None
        halves.append((seen, away))
    if any(away for _, away in halves):
        onsets = [departs(seen) for seen, _ in halves] + [departs(prof)]
        if None in onsets or max(onsets) - min(onsets) > reach:  # type: ignore[type-var, operator]
            return None
    y = int(rows[top])
    liquid = prof[y + lo:]
    if float(np.mean(np.linalg.norm(liquid - below[top], axis=1) < 0.5 * size)) < HUE_STEADY:
        return None
    y_surface = y_step
    # outside the walls, at the same rows: the background. Its own hue step there means the
    # background made the step (a card's edge); a "liquid" the hue of the background beside
    # it is colourless liquid over a tinted card, or air, whatever changed above it
    for lo_f, hi_f in BACKGROUND_COLUMNS:
        c0, c1 = max(0, int(axis + x0 + lo_f * half)), min(w, int(axis + x0 + hi_f * half) + 1)
        if c1 - c0 < 2:
            continue
        # rows hi above the surface down to hi below it, and on down to a bore's width under it
        block = cv2.cvtColor(np.ascontiguousarray(color[r0 + y - hi: r0 + y + max(hi, int(2 * half)) + 1, c0:c1]),
                             cv2.COLOR_BGR2LAB)[:, :, 1:].astype(np.float32)
        beside, under = block[: 2 * hi + 1], block[2 * hi: hi + int(2 * half) + 1]
        out_above = beside[: hi - lo + 1].reshape(-1, 2).mean(axis=0)
        out_below = beside[-(hi - lo + 1):].reshape(-1, 2).mean(axis=0)
        if float(np.linalg.norm(out_below - out_above)) >= 0.5 * size:
            return None
        if float(np.linalg.norm(below[top] - out_below)) < HUE_TINT * size:
            return None
        # further down too: a thing of the liquid's hue wider than the bore (the plastic foot
        # a cylinder stands in, its collar's top taken for the surface)
        if len(under) and float(np.linalg.norm(under.mean(axis=1) - below[top], axis=1).min()) < HUE_TINT * size:
            return None
    # near the axis: where the hue first departs from the air's (a quarter of the way to the
    # liquid's), then half way to the hue just under that: the liquid's hue may deepen further
    # down (the background seen through it changes), which would pull a plain half-way point low
    c0, c1 = int(y_surface - 4 * d), int(y_surface + 4 * d) + 1
    near_axis = _bore_rows(ab, masked, columns(-0.3, 0.3), c0 - r0, c1 - r0)
    if near_axis is None:
        return None
    row0 = max(0, c0 - r0) + r0
    onset = departs(near_axis, row0)
    if onset is None:
        return None
    # the air over the surface keeps one hue: a coloured cable just above it would be taken for its start
    rows_near = np.arange(row0, row0 + len(near_axis))
    over = near_axis[(rows_near >= air[0]) & (rows_near < onset - 1)]
    if len(over) == 0 or float(np.linalg.norm(over - np.median(over, axis=0), axis=1).max()) > HUE_AIR * size:
        return None
    under = (onset + 2, onset + 2 + max(2.0, d))
    bottom = _half_crossing(near_axis, row0, air, under, onset - d, 0.5 * HUE_STEP * CHROMA_STEP)
    if bottom is None or abs(bottom - y_surface) > 2 * d:
        return None
    return Indicator(kind="meniscus", y_up=bottom, x_up=float(axis + x0), sigma_px=0.5, strength=size,
                     coloured_liquid=True)


ONE_LIQUID_ROWS = (1.5, 5.0)  # divisions above and below a band where _within_one_liquid compares the bore
ONE_LIQUID_HUE_DEG = 20.0  # hue angles (a*b* around the background's) this close are one liquid's


def _within_one_liquid(view: _BoreView, y_band: int) -> bool:
    """Whether the band lies inside a coloured liquid: the bore has one hue above and below it,
    a hue of its own (not the background's beside the walls, nor beside either wall alone: a
    clear liquid shows the background from beside the other wall, mirrored). A surface has the
    liquid on one side and air, which shows the background, on the other; a band with liquid on
    both sides is print, a ring's far side or a shadow behind the liquid (a burette filled past
    the view read 21.9 ml by a ring while its level stood at 0.6 ml, out of view: recording
    burette25ml_leave).
    Hue is compared by its angle around the background's a*b*: the light behind the liquid
    changes its depth (a blue two thirds as deep before a dark wall as before a light one), not
    its angle."""
    color, masked, axis, half, d = view.color, view.masked, view.axis, view.half, view.d
    assert color is not None
    n, w = color.shape[:2]
    near, far = (round(k * d) for k in ONE_LIQUID_ROWS)
    r0, r1 = max(0, y_band - far), min(n, y_band + far + 1)
    if y_band - near - r0 < 2 or r1 - (y_band + near) < 2:
        return False
    # only the columns read are converted: this runs on every frame's candidate bands
    x0 = max(0, int(axis + BACKGROUND_COLUMNS[0][0] * half))
    x1 = min(w, int(axis + BACKGROUND_COLUMNS[1][1] * half) + 1)
    window = np.ascontiguousarray(color[r0:r1, x0:x1])
    lab = cv2.cvtColor(window, cv2.COLOR_BGR2LAB)
    bore = np.arange(int(axis - 0.6 * half), int(axis + 0.6 * half) + 1) - x0
    sides = [np.arange(int(axis + lo * half), int(axis + hi * half) + 1) - x0 for lo, hi in BACKGROUND_COLUMNS]
    outside = np.concatenate(sides)
    mid = y_band - r0
    above = _bore_mean(lab, bore, masked[r0:r1, x0:x1], 0, mid - near, min_clear=8)
    below = _bore_mean(lab, bore, masked[r0:r1, x0:x1], mid + near + 1, r1 - r0, min_clear=8)
    unseen = (window.max(axis=2) == 0).astype(np.uint8)  # columns a per-frame strip left black say nothing
    background = _bore_mean(lab, outside, unseen, 0, r1 - r0, min_clear=8)
    if above is None or below is None or background is None:
        return False
    up, down = above[1:] - background[1:], below[1:] - background[1:]  # a*b*
    if min(np.linalg.norm(up), np.linalg.norm(down)) < CHROMA_STEP:
        return False  # one side (or both) has the background's hue: air, or a pale liquid
    for columns in sides:
        # a clear liquid shows the background from beside the other wall, mirrored: one side's
        # background there is no hue of the liquid's own (clean 10883, water before wood on one
        # side and white on the other: the network's surface, 0.998 sure and right, vetoed)
        side = _bore_mean(lab, columns, unseen, 0, r1 - r0, min_clear=8)
        if side is not None and min(np.linalg.norm(above[1:] - side[1:]),
                                    np.linalg.norm(below[1:] - side[1:])) < CHROMA_STEP:
            return False
    # one hue: the light behind changes how deep it looks, not which hue it is
    turn = abs(math.degrees(math.atan2(up[1], up[0]) - math.atan2(down[1], down[0]))) % 360
    return min(turn, 360 - turn) <= ONE_LIQUID_HUE_DEG


EDGE_CLUSTER_PX = 1.0  # the band's lower edges within this of one another are one edge
EDGE_CLUSTER_LEAD = 1.5  # times the edges of the next row apart from it: the densest row is the surface's


def _densest(edges_y: np.ndarray, width_px: float) -> np.ndarray:
    """The band's lower edges that lie together, where the columns disagree: a number printed
    across the bore just under the meniscus gives its strokes' edges instead in the columns it
    crosses, scattered below the surface's one row (dev 1155: "110" under a thin band, half the
    columns 3-14 px low, the median 3.8 px low). The densest row is also where a curved
    meniscus is flattest, its lowest point. Edges with no row shared by a third of them, or
    whose densest row another row apart rivals (two halves of a band seen tilted, one of them
    over print: second dev set 1525, 14 edges against 13), are kept as they are."""
    if len(edges_y) < 3:
        return edges_y
    together = np.abs(edges_y[:, None] - edges_y[None, :]) <= width_px
    counts = together.sum(axis=1)
    best = int(np.argmax(counts))
    members = together[best]
    # the next row's edges, among those not with the best row's
    others = (together & ~members[None, :])[~members].sum(axis=1)
    second = int(others.max()) if len(others) else 0
    if 3 * counts[best] < len(edges_y) or counts[best] < EDGE_CLUSTER_LEAD * second:
        return edges_y
    return edges_y[members]


def _meniscus_at(view: _BoreView, y_band: int, strength: float, cover: np.ndarray | None,
                 arc: _Arc | None = None) -> Indicator | None:
    """The meniscus's lowest point under the band at ``y_band``, or None where the band is not
    the liquid's surface. Without ``arc``, a band that crosses only part of the bore is refused
    (the arc search has checked both sides already, and says where the band is in each column)."""
    gray, masked, axis, half, d, h = view.gray, view.masked, view.axis, view.half, view.d, view.h
    color, central, min_contrast, dark_band = view.color, view.central, view.min_contrast, view.dark_band
    n = gray.shape[0]
    background_seen_below = False
    if color is not None:
        # a band a few divisions above a coloured liquid, which starts further down, is not its surface
        start = _liquid_below(color, masked, central, d, y_band)
        if start is not None and start > y_band + 2 * d:
            if not _background_below(view, y_band, start):
                return None
            # the background's edge, seen through the bore under the band: the edge outside
            # the walls near the band is that one, not the band going on (dev 1260)
            background_seen_below = True
    if not background_seen_below and _background_crosses(gray, axis, half, y_band, h, d, dark_band, strength):
        return None
    if color is not None and _within_one_liquid(view, y_band):
        return None
    # lower edge of the band, column by column near the axis; the lowest one is the meniscus bottom
    span = int(max(2, 1.5 * d))
    if arc is not None:  # where print hides the axis, the columns further out give the bottom through the curve
        edges = _arc_edges(view, arc, span)
    else:
        edges = []
        for c in central:
            if c < 0 or c >= gray.shape[1]:
                continue
            col = gray[:, c].astype(np.float32)
            if not dark_band:
                col = 255 - col
            col = np.where(masked[:, c] > 0, np.nan, col)
            lo, hi = max(0, y_band - span), min(n - 1, y_band + 2 * span)
            seg = col[lo: hi + 1]
            if np.isnan(seg).mean() > 0.3:
                continue
            seg = np.where(np.isnan(seg), np.nanmedian(seg), seg)
            y_min = int(np.argmin(seg[: min(len(seg), 2 * span)]))
            tail = seg[y_min + max(2, int(0.8 * d)): y_min + max(4, int(1.6 * d))]
            if len(tail) == 0:
                continue
            level = (seg[y_min] + float(np.median(tail))) / 2
            y = _crossing(seg, y_min, len(seg) - 1, level)
            if y is not None and float(np.median(tail)) - seg[y_min] >= min_contrast * 0.5:
                edges.append((abs(c - axis), lo + y))
    # a coloured liquid's hue starts at the meniscus's lowest point, where a dark liquid hides
    # the band's lower edge
    hue_start = None if color is None else _chroma_bottom(color, masked, axis, half, d, y_band)
    if hue_start is not None and not y_band - span <= hue_start <= y_band + 2 * span:
        hue_start = None
    if hue_start is not None:
        bottom, spread = hue_start, 0.5
    elif len(edges) >= 3:
        # the bottom of the meniscus is at the axis; near it the curve is flat, so take the median there
        if arc is None:
            near_axis = np.array([y for dx, y in edges if dx <= 0.3 * half]) \
                if any(dx <= 0.3 * half for dx, _ in edges) else np.array([y for _, y in edges])
            near_axis = _densest(near_axis, EDGE_CLUSTER_PX)
            bottom = float(np.median(near_axis))
            spread = float(np.std(near_axis)) / max(1.0, np.sqrt(len(near_axis)))
        else:
            fitted = _arc_bottom(edges, arc, d)
            if fitted is None:
                return None
            bottom, spread = fitted
    else:
        return None
    # the meniscus is a line from wall to wall; a printed word, the end of a mark or a shadow's
    # edge crosses only part of the bore (13 of the 15 wrong readings in 300 test stills). This
    # only refuses: letting it choose among the bands would silence the "two alike" refusal above
    if arc is None:
        if cover is None:
            cover = _band_coverage(gray, masked, axis, half, d, h, dark_band, min_contrast)
        if _near_max(cover, bottom, 4) < MIN_BAND_COVERAGE:
            # a dark liquid makes no band below the meniscus, only a change of hue across the bore
            if hue_start is None or color is None:
                return None
            if _chroma_coverage_near(color, masked, axis, half, d, h, bottom, 4) < CHROMA_COVERAGE:
                return None
    return Indicator(kind="meniscus", y_up=bottom, x_up=float(axis), sigma_px=max(0.3, spread),
                     strength=strength, coloured_liquid=hue_start is not None)
