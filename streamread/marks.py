"""Marks in the upright strip: horizontal linear contours on a regular grid, grouped by length.

Bars are segmented (HSV or adaptive; where neither shows a scale, adaptive in each colour
plane alone, for print as light as a coloured liquid behind it), kept when linear (the paper's
aspect ratio on the axis-aligned box, now that the strip is upright) and not much thicker than
the typical mark, then placed on a grid: mark ``k`` at ``y(k) = a + b k + c k^2`` (the quadratic term absorbs
perspective). Bars off the grid (digits, meniscus, stopper ribs, clutter) are dropped.
Major/minor grouping follows the paper: sorted by length, a jump of over 15 % starts a group.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from streamread.profile import GroupingConfig, MarksConfig
from streamread.segment import segment_hsv, threshold_response, thin_response, to_gray, valley_response
from streamread.types import Mark, Marks


@dataclass(frozen=True)
class Bar:
    y: float
    x0: float
    x1: float
    thickness: float
    strength: float
    # per column from x0: the bar's response-weighted row there (NaN where it has no pixel).
    # A ring round a burette's tube is an arc: its centroid lies off the ticks' rows, its row
    # over the ticks' columns on them (``rings_placed``)
    column_ys: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def length(self) -> float:
        return self.x1 - self.x0

    def y_over(self, x0: float, x1: float) -> float | None:
        """The bar's mean row over columns ``x0``-``x1``, or None where it has no pixel there."""
        if self.column_ys is None:
            return None
        a, b = int(round(x0 - self.x0)), int(round(x1 - self.x0)) + 1
        part = self.column_ys[max(0, a):max(0, b)]
        part = part[np.isfinite(part)]
        return float(part.mean()) if len(part) else None


def bars_from_mask(mask: np.ndarray, weight: np.ndarray, config: MarksConfig) -> list[Bar]:
    """Horizontal linear contours of a mask, with sub-pixel y from the response-weighted centroid."""
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    bars = []
    w_float = weight.astype(np.float32)
    for i in range(1, n):
        x, y, w, h, area = stats[i]
        if w < config.min_length_px or w / max(h, 1) < config.aspect_min:
            continue
        region = (labels[y: y + h, x: x + w] == i) * w_float[y: y + h, x: x + w]
        total = float(region.sum())
        if total <= 0:
            continue
        rows = np.arange(y, y + h, dtype=np.float32)
        cy = float((region.sum(axis=1) * rows).sum() / total)
        thickness = float(area) / max(w, 1)
        column_ys = None
        if config.rings and h > 1:  # a bar one row tall lies on its row everywhere
            per_column = region.sum(axis=0)
            with np.errstate(invalid="ignore", divide="ignore"):
                column_ys = np.where(per_column > 0, (region * rows[:, None]).sum(axis=0) / per_column, np.nan)
        bars.append(Bar(y=cy, x0=float(x), x1=float(x + w - 1), thickness=thickness, strength=total / max(area, 1),
                        column_ys=column_ys))
    return bars


FAINT_FLOOR = 5.0  # grey levels: the faint-line path's least threshold

CHANNEL_NAMES = ("blue", "green", "red")  # the colour planes of a BGR strip, in order
PLANE_PATH_PREFIX = "dark-"  # ``best_marks``'s path for a colour plane's marks: "dark-<plane>"


def _plane(strip_bgr: np.ndarray, channel: int) -> np.ndarray:
    """One colour plane of a BGR strip, contiguous (as OpenCV's morphology wants it)."""
    return np.ascontiguousarray(strip_bgr[:, :, channel])


def print_plane(strip_bgr: np.ndarray, path: str, luminance: np.ndarray | None = None) -> np.ndarray:
    """The grey image the print of ``path`` (a ``segment_bars`` key) was found in: one colour
    plane for a ``dark-<plane>`` path, else the luminance (``luminance``, when already made)."""
    if is_plane_path(path) and strip_bgr.ndim == 3:
        return _plane(strip_bgr, CHANNEL_NAMES.index(path[len(PLANE_PATH_PREFIX):]))
    return to_gray(strip_bgr) if luminance is None else luminance


PLANE_GAIN = 1.5  # times the luminance's contrast that a colour plane must give the weakest marks


def clearest_plane(strip_bgr: np.ndarray, marks: Marks) -> np.ndarray | None:
    """The colour plane in which the faintest marks stand out most, where it beats the
    luminance by ``PLANE_GAIN``; else None. A mark's contrast is its ink against the rows
    half a division beside it, in its own columns; the faintest quarter of the marks (those
    over a coloured liquid, where the numbers were not read) decides."""
    if strip_bgr.ndim != 3 or len(marks.marks) < 4:
        return None
    planes = [to_gray(strip_bgr)] + [_plane(strip_bgr, c) for c in range(len(CHANNEL_NAMES))]
    h = strip_bgr.shape[0]
    beside = max(2, round(0.5 * marks.spacing_up))
    weakest = []
    for plane in planes:
        contrasts = []
        for m in marks.marks:
            y, x0, x1 = round(m.y_up), int(m.x0_up), int(m.x1_up) + 1
            if y - beside < 0 or y + beside >= h or x1 - x0 < 2:
                continue
            ink = float(np.median(plane[y, x0:x1]))
            paper = float(np.median(np.concatenate([plane[y - beside, x0:x1], plane[y + beside, x0:x1]])))
            contrasts.append(abs(paper - ink))
        if len(contrasts) < 4:
            return None
        weakest.append(float(np.percentile(contrasts, 25)))
    best = int(np.argmax(weakest[1:])) + 1
    return planes[best] if weakest[best] >= PLANE_GAIN * max(weakest[0], 1.0) else None


def segment_bars(strip_bgr: np.ndarray, config: MarksConfig, kernel_px: int,
                 faint: bool = False) -> dict[str, list[Bar]]:
    """Candidate bars per segmentation path: adaptive dark, adaptive bright, and HSV; with
    ``faint``, also faint dark lines (``valley_response``)."""
    gray = to_gray(strip_bgr)
    out: dict[str, list[Bar]] = {}
    if config.segmentation in ("adaptive", "auto"):
        resp = thin_response(gray, kernel_px, "vertical")
        out["dark"] = bars_from_mask(threshold_response(resp.dark), resp.dark, config)
        out["bright"] = bars_from_mask(threshold_response(resp.bright), resp.bright, config)
    if config.segmentation in ("hsv", "auto") and strip_bgr.ndim == 3:
        mask = segment_hsv(strip_bgr, config.hsv_ranges)
        # the paper's mask is solid print: keep only thin horizontal parts (a mark, not a stopper)
        opened = cv2.morphologyEx(mask, cv2.MORPH_OPEN, cv2.getStructuringElement(cv2.MORPH_RECT, (1, kernel_px)))
        thin = cv2.subtract(mask, opened)
        weight = 255 - gray
        out["hsv"] = bars_from_mask(thin, weight, config)
    if faint and config.segmentation in ("adaptive", "auto"):
        # marks fainter than the numbers and the liquid's edge, which set the black-hat's level
        valley = np.clip(valley_response(gray, 0.0, 5.0, float(np.clip(kernel_px / 4, 1.5, 3.0))), 0, 255)
        valley = valley.astype(np.uint8)
        out["valley"] = bars_from_mask(threshold_response(valley, FAINT_FLOOR), valley, config)
    return out


ON_GRID = 0.18  # of a division: how far from its grid line a bar may lie and be a mark
ON_GRID_MIN_PX = 0.6  # and at least this, where divisions are a few pixels


def _comb(ys: np.ndarray, guess: float) -> tuple[float, float]:
    """Spacing and phase of the comb that best matches the bar positions (robust to gaps and strays)."""
    best, best_score, best_phase = guess, -1.0, 0.0
    for d in np.linspace(0.75 * guess, 1.3 * guess, 221):
        total = np.exp(2j * np.pi * ys / d).sum()
        if abs(total) > best_score:
            best, best_score, best_phase = float(d), float(abs(total)), float(np.angle(total))
    return best, best_phase / (2 * np.pi) * best


def _grid_by_comb(bars: list[Bar], d: float, phase: float, config: MarksConfig) -> Marks | None:
    """Grid indices from the comb.

    The comb gives spacing and phase; each bar snaps to its nearest grid line; a quadratic
    y(k) (perspective) is refitted and bars re-snapped, twice; off-grid bars are dropped.
    """
    ys = np.array([b.y for b in bars])
    ks = np.round((ys - phase) / d)
    model = np.array([d, phase])  # y = d * k + phase, refined to a quadratic below
    keep = np.abs(ys - np.polyval(model, ks)) <= 0.2 * d
    for _ in range(3):
        steps = len(np.unique(ks[keep]))  # bars on one grid line (a mark in pieces) count once
        if keep.sum() < config.min_marks or steps < 2:
            return None
        deg = 2 if steps >= 10 else 1
        model = np.polyfit(ks[keep], ys[keep], deg)
        # re-snap every bar to the nearest grid line of the refined model
        grid_k = np.arange(ks[keep].min() - 200, ks[keep].max() + 201)
        grid_y = np.polyval(model, grid_k)
        nearest = np.abs(ys[:, None] - grid_y[None, :]).argmin(axis=1)
        ks = grid_k[nearest].astype(float)
        local = np.abs(np.polyval(np.polyder(model), ks))
        keep = np.abs(ys - grid_y[nearest]) <= np.maximum(ON_GRID * local, ON_GRID_MIN_PX)
    chosen: dict[int, int] = {}  # one bar per grid line: the longest
    for i in np.nonzero(keep)[0]:
        k = int(ks[i])
        if k not in chosen or bars[i].length > bars[chosen[k]].length:
            chosen[k] = int(i)
    if len(chosen) < config.min_marks:
        return None
    k0 = min(chosen)
    marks = tuple(Mark(y_up=bars[i].y, x0_up=bars[i].x0, x1_up=bars[i].x1, thickness_up=bars[i].thickness,
                       grid_index=k - k0) for k, i in sorted(chosen.items()))
    spacing = abs(float(np.polyval(np.polyder(model), float(np.median(list(chosen))))))
    return Marks(marks=marks, spacing_up=max(spacing, 1e-3))


def _grid_by_walk(bars: list[Bar], d: float, config: MarksConfig) -> Marks | None:
    """Grid indices by walking outward from the middle bar, following slowly changing spacing."""
    assigned = _walk(bars, d)
    if len(assigned) < config.min_marks:
        return None
    ks = np.array([k for k, _ in assigned], dtype=np.float64)
    yv = np.array([b.y for _, b in assigned])
    keep = np.ones(len(ks), bool)
    coef = np.zeros(3)
    for _ in range(3):
        deg = 2 if keep.sum() >= 8 else 1
        coef = np.polyfit(ks[keep], yv[keep], deg)
        resid = np.abs(np.polyval(coef, ks) - yv)
        keep = resid <= max(ON_GRID * d, ON_GRID_MIN_PX)
    if keep.sum() < config.min_marks:
        return None
    k0 = int(ks[keep].min())
    marks = tuple(Mark(y_up=b.y, x0_up=b.x0, x1_up=b.x1, thickness_up=b.thickness, grid_index=int(k) - k0)
                  for (k, b), ok in zip(assigned, keep) if ok)
    spacing = abs(float(np.polyval(np.polyder(coef), float(np.median(ks)))))
    return Marks(marks=marks, spacing_up=max(spacing, 1e-3))


WALK_START_BARS = 6  # bars each side of the middle whose gaps give the walk's first spacing
# grid steps the walk crosses in one stride: a 1 ml syringe's stopper hides 8 of its 0.01 ml
# divisions, and at six the walk stopped there and lost every mark past it (clean 11908, on a
# strip whose spacing changes from 7.6 to 6.6 px: the comb's one spacing placed the marks past
# the stopper off their lines; 11455 read 0.08 ml a division). A stride over more than
# ``WALK_PLAIN_STEPS`` lands only on a run spaced as the walk is there, within
# ``WALK_RUN_SPACING`` (at a slant a spacing changes by 0.3 % a division at most on the dev
# stills), else the stride's count of steps is not to be trusted: on clean 11807 the marks past
# the stopper stood 6.3 px apart, those before it (under a dyed liquid) 5.7 px apart; placed a
# step off, they fitted numbers misread there, and the stopper was then not found
WALK_MAX_STEPS = 12
WALK_PLAIN_STEPS = 6
WALK_RUN_SPACING = 0.05
WALK_RUN_GAPS = 3  # single-step gaps of a run past a long stride that give its spacing, at least


def _spacing_near(bars: list[Bar], mid: int, d: float) -> float:
    """The spacing about the middle bar: the median of the gaps there within a third of ``d``
    (the whole ladder's), else ``d``. Seen at a slant, a long scale's spacing changes by a third
    from end to end (dev 1264: 5.7 to 7.5 px, the comb's 7.2): started from ``d``, the walk
    takes six divisions for five where they are shortest."""
    near = np.array([b.y for b in bars[max(0, mid - WALK_START_BARS):mid + WALK_START_BARS + 1]])
    gaps = np.diff(near)
    gaps = gaps[(gaps > 0.67 * d) & (gaps < 1.33 * d)]
    return float(np.median(gaps)) if len(gaps) >= 3 else d


WALK_STARTS = 2  # bars each side of the middle the walk may start from too


def _walk(bars: list[Bar], d: float) -> list[tuple[int, Bar]]:
    """Assign grid indices outward from the middle, following slowly changing spacing: the walk
    from the middle bar or one of its ``WALK_STARTS`` neighbours each side that places the most.
    A walk that starts on a stray (a digit's stroke beside the marks, a fragment of the stopper's
    edge) finds every mark off its step and places that bar alone (clean 11908)."""
    mid = len(bars) // 2
    starts = range(max(0, mid - WALK_STARTS), min(len(bars), mid + WALK_STARTS + 1))
    return max((_walk_from(bars, d, start) for start in starts), key=len)


def _walk_from(bars: list[Bar], d: float, mid: int) -> list[tuple[int, Bar]]:
    """Assign grid indices outward from ``bars[mid]``, following slowly changing spacing."""
    result: dict[int, Bar] = {0: bars[mid]}
    start = _spacing_near(bars, mid, d)
    for direction in (1, -1):
        k, y_last, local, last = 0, bars[mid].y, start, mid
        idx = range(mid + 1, len(bars)) if direction > 0 else range(mid - 1, -1, -1)
        for i in idx:
            gap = (bars[i].y - y_last) * direction
            n = int(round(gap / local))
            if n <= 0:
                # two bars on one grid line: keep the longer (a mark, not a fragment)
                if abs(gap) < 0.3 * local and bars[i].length > result[k].length:
                    result[k] = bars[i]
                    y_last, last = bars[i].y, i
                continue
            if abs(gap - n * local) > 0.22 * local or n > WALK_MAX_STEPS:
                continue
            if n > WALK_PLAIN_STEPS and not _spaced_alike(bars, last, i, direction, local):
                continue
            k += n * direction
            result[k] = bars[i]
            if n <= 2:
                local = 0.8 * local + 0.2 * gap / n
            y_last, last = bars[i].y, i
    return sorted(result.items())


def _run_spacing(bars: list[Bar], start: int, direction: int, local: float) -> float | None:
    """The spacing of the run of bars from ``bars[start]`` on, in ``direction``: the median of
    its first single-step gaps (about ``local``); None where it has under ``WALK_RUN_GAPS``."""
    reach = 2 * WALK_START_BARS + 1  # bars looked at
    if direction > 0:
        idx = range(start, min(len(bars), start + reach))
    else:
        idx = range(start, max(-1, start - reach), -1)
    gaps = np.abs(np.diff([bars[i].y for i in idx]))
    gaps = gaps[(gaps > 0.67 * local) & (gaps < 1.33 * local)][:2 * WALK_RUN_GAPS]
    return float(np.median(gaps)) if len(gaps) >= WALK_RUN_GAPS else None


def _spaced_alike(bars: list[Bar], last: int, landing: int, direction: int, local: float) -> bool:
    """Whether the run a long stride lands on (from ``bars[landing]`` on) is spaced as the run
    it leaves (up to ``bars[last]``), within ``WALK_RUN_SPACING``."""
    before = _run_spacing(bars, last, -direction, local)
    after = _run_spacing(bars, landing, direction, local)
    return before is not None and after is not None and abs(after - before) <= WALK_RUN_SPACING * before


def fit_grid(bars: list[Bar], config: MarksConfig) -> Marks | None:
    """Place bars on a regular grid; None when no ladder of ``min_marks`` bars exists.

    Bars much thicker than the typical mark are dropped; the comb gives spacing and phase.
    Two placements follow: the comb (robust to gaps and strays) and a walk outward from the
    middle (follows strong perspective); the one that places more marks wins.
    """
    if len(bars) < config.min_marks:
        return None
    t_med = float(np.median([b.thickness for b in bars]))
    bars = sorted((b for b in bars if b.thickness <= config.max_thickness_ratio * t_med + 0.5), key=lambda b: b.y)
    ys = np.array([b.y for b in bars])
    gaps = np.diff(ys)
    gaps = gaps[gaps > 1.0]
    if len(ys) < config.min_marks or len(gaps) == 0:
        return None
    d, phase = _comb(ys, float(np.median(gaps[gaps > 0.5 * np.median(gaps)])))
    results = [m for m in (_grid_by_comb(bars, d, phase, config), _grid_by_walk(bars, d, config)) if m is not None]
    if not results:
        return None
    best = max(results, key=len)
    return rings_placed(best, bars) if config.rings else best


RING_LONG = 1.5  # times the marks' median length a dropped bar must reach to be looked at as a ring
# and times the longest mark on the grid: a ring is the longest mark there is (img_020: a bar of
# three ticks' length, 0.78 of its rings', placed off their phase, changed the long marks and
# lost its reading). Also how long a burette's unnumbered long mark must be, of the numbered
# rings beside it, to be a ring (``reader._unnumbered_ring_ml``)
RING_AS_LONGEST = 0.9


def rings_placed(marks: Marks, bars: list[Bar]) -> Marks:
    """The marks with long bars the grid dropped put back by their row over the usual marks'
    columns: a ring round a burette's tube is an arc, seen curved at any tilt, and its centroid
    lies off the ticks' rows by a third of a division (clean 9189, 9587: the rings dropped, the
    numbers beside them went to the half-ml ticks five divisions off). Only where the profile
    says the long marks are rings (``MarksConfig.rings``: burettes): on syringes and cylinders a
    long bar off the grid is a label's rule or a stopper's rib (stop 52's trial, every long bar
    placed so on every kind, read dev 1011 and 1142, 1 ml syringes, and img_029 wrong)."""
    if len(marks.marks) < 4:
        return marks
    on = {(m.y_up, m.x0_up, m.x1_up) for m in marks.marks}
    lengths = np.array([m.length_up for m in marks.marks])
    usual, longest = float(np.median(lengths)), float(lengths.max())
    x0, x1 = float(np.median([m.x0_up for m in marks.marks])), float(np.median([m.x1_up for m in marks.marks]))
    ks = np.array([m.grid_index for m in marks.marks], float)
    ys = np.array([m.y_up for m in marks.marks])
    model = np.polyfit(ks, ys, 2 if len(ks) >= 10 else 1)
    grid_k = np.arange(ks.min() - 2, ks.max() + 3)
    grid_y = np.polyval(model, grid_k)
    by_index = {m.grid_index: m for m in marks.marks}
    changed: dict[int, Mark] = {}
    for b in bars:
        if (b.y, b.x0, b.x1) in on or b.length < max(RING_LONG * usual, RING_AS_LONGEST * longest) \
                or b.x0 > x0 + 1 or b.x1 < x1 - 1:
            continue
        y = b.y_over(x0, x1)
        if y is None:
            continue
        i = int(np.argmin(np.abs(grid_y - y)))
        local = abs(float(np.polyval(np.polyder(model), grid_k[i])))
        if abs(grid_y[i] - y) > max(ON_GRID * local, ON_GRID_MIN_PX):
            continue
        k = int(grid_k[i])
        holder = changed.get(k, by_index.get(k))  # the mark the line holds now, if any: the longer stays
        if holder is not None and holder.length_up >= b.length:
            continue
        changed[k] = Mark(y_up=y, x0_up=b.x0, x1_up=b.x1, thickness_up=b.thickness, grid_index=k)
    if not changed:
        return marks
    kept = [m for m in marks.marks if m.grid_index not in changed]
    placed = sorted([*kept, *changed.values()], key=lambda m: m.grid_index)
    k0 = placed[0].grid_index
    return Marks(marks=tuple(replace(m, grid_index=m.grid_index - k0) for m in placed), spacing_up=marks.spacing_up)


STRAY_GAP = 8  # grid steps with no mark that part a stray from the scale


def _runs(marks: list[Mark], gap: int) -> list[list[Mark]]:
    """``marks`` (sorted by grid index) cut where ``gap`` or more grid steps are empty."""
    runs: list[list[Mark]] = [[marks[0]]]
    for prev, cur in zip(marks, marks[1:]):
        if cur.grid_index - prev.grid_index > gap:
            runs.append([cur])
        else:
            runs[-1].append(cur)
    return runs


def strays(marks: Marks) -> list[Mark]:
    """Lone bars far off the scale: one or two marks ``STRAY_GAP`` or more empty steps away from
    the rest (a cylinder's foot or rim, a label's rule, that fell on a grid line). Only the
    fit can tell them from marks seen past a stopper, which come in ones and twos too."""
    runs = _runs(sorted(marks.marks, key=lambda m: m.grid_index), STRAY_GAP)
    biggest = max(len(r) for r in runs)
    return [m for r in runs if len(r) <= 2 and len(r) < biggest for m in r]


def apart_from(marks: Marks, grid_indices: set[int]) -> set[int]:
    """The marks (by identity) in runs ``STRAY_GAP`` empty grid steps apart from those at
    ``grid_indices`` (where numbers were read): a cylinder's foot below its scale, a rim above it."""
    runs = _runs(sorted(marks.marks, key=lambda m: m.grid_index), STRAY_GAP)
    return {id(m) for run in runs if not any(m.grid_index in grid_indices for m in run) for m in run}


def group_by_length(marks: Marks, config: GroupingConfig) -> Marks:
    """The paper's relative grouping: longest first; a jump over ``jump`` starts a new group.

    The first group with at least two regularly spaced marks is major; a second group, if a
    third exists, is medium; the rest are minor.
    """
    ordered = sorted(marks.marks, key=lambda m: -m.length_up)
    groups: list[list[Mark]] = [[ordered[0]]]
    for prev, cur in zip(ordered, ordered[1:]):
        if prev.length_up - cur.length_up > config.jump * max(cur.length_up, 1e-6):
            groups.append([cur])
        else:
            groups[-1].append(cur)
    first = 0
    while first < len(groups) - 1 and len(groups[first]) < 2:
        first += 1  # a lone long bar is clutter (a meniscus edge, a label underline), not a major series
    majors, last = groups[first], first
    if len(majors) >= 3 and not _regular_series(majors):  # a scatter, or long marks every 3 or 15 steps
        # on real glass a digit printed at a mark's end joins it, and that mark measures longer
        # than its fellows: the long group is then a scatter of labelled marks (two long marks
        # are no scatter: they may be the majors of a scale with mediums). The next groups
        # down are added while the long marks stay under half of all; the longest regular series
        # so found is major (a short series by chance, three marks every 15, loses to it).
        best: list[Mark] = []
        for j in range(first + 1, len(groups) - 1):
            union = [m for g in groups[first: j + 1] for m in g]
            if 2 * len(union) > len(marks.marks):
                break
            on = _regular_series(union)
            if len(on) > len(best):
                best, last = on, j
        if best:
            majors = best
        else:
            lattice = _lattice_tiers(list(marks.marks))
            if lattice is not None:
                return _with_tiers(marks, *lattice)
    return _with_tiers(marks, majors, groups[last + 1] if len(groups) > last + 2 else [])


MAJOR_STEPS = (2, 4, 5, 10, 20)  # divisions between long marks on 1-2-5 scales (0.2 ml ticks, 1 ml labels: 5)


def _with_tiers(marks: Marks, majors: list[Mark], mediums: list[Mark]) -> Marks:
    """``marks`` with ``majors`` and ``mediums`` (by identity) tiered so, the rest minor."""
    major_ids, medium_ids = {id(m) for m in majors}, {id(m) for m in mediums}
    return Marks(marks=tuple(replace(m, tier="major" if id(m) in major_ids else "medium" if id(m) in medium_ids
                                     else "minor") for m in marks.marks), spacing_up=marks.spacing_up)


LONGER = 1.1  # a long mark is this much longer than the typical short one


def _lattice_tiers(marks: list[Mark]) -> tuple[list[Mark], list[Mark]] | None:
    """Majors as the lattice of grid positions whose marks are longer, when grouping by length
    jumps fails: lengths that creep (22, 25, 27, 28 px where a ring mark is drawn darker in
    places) make one group of them all, and the three longest fall every 15 steps by chance.

    For each step of ``MAJOR_STEPS``, largest first, and each phase: at least three marks on
    the lattice filling 80 % of its positions, 80 % of them longer than the others' median by
    ``LONGER``, at most 20 % of the others that long outside the half-step lattice (mediums),
    and longer than those mediums. None when no lattice qualifies.
    """
    # the lattice's positions are counted over the scale's own run: a stray far off it (a
    # label's rule under the foot) would add empty positions the lattice cannot fill
    run = max(_runs(sorted(marks, key=lambda m: m.grid_index), STRAY_GAP), key=len)
    lo, hi = run[0].grid_index, run[-1].grid_index
    for step in sorted(MAJOR_STEPS, reverse=True):
        best: tuple[float, list[Mark], list[Mark]] | None = None
        for phase in range(step):
            on = [m for m in marks if (m.grid_index - phase) % step == 0]
            off = [m for m in marks if (m.grid_index - phase) % step != 0]
            positions = len(range(lo + (phase - lo) % step, hi + 1, step))
            if len(on) < 3 or len(on) < 0.8 * positions or len(off) < len(on):
                continue
            half = step // 2 if step % 2 == 0 else 0
            mediums = [m for m in off if half and (m.grid_index - phase) % half == 0]
            short = [m for m in off if not (half and (m.grid_index - phase) % half == 0)]
            if not short:
                continue
            threshold = LONGER * float(np.median([m.length_up for m in short]))
            on_long = np.mean([m.length_up > threshold for m in on])
            stray = np.mean([m.length_up > threshold for m in short])
            if on_long < 0.8 or stray > 0.2:
                continue
            long_mediums = [m for m in mediums if m.length_up > threshold]
            if long_mediums and np.median([m.length_up for m in on]) < LONGER * np.median(
                    [m.length_up for m in long_mediums]):
                continue  # the long marks at the half steps are as long: the lattice is the half step
            score = float(on_long - stray)
            if best is None or score > best[0]:
                best = (score, on, long_mediums if len(long_mediums) >= 0.8 * len(mediums) else [])
        if best is not None:
            return best[1], best[2]
    return None


def _regular_series(marks: list[Mark]) -> list[Mark]:
    """The longest run of ``marks`` that lie every ``step`` grid positions (step one of
    ``MAJOR_STEPS``, gaps of one missing mark allowed), when it has at least three, is 80 % of
    the marks within its range and fills 80 % of that range; else none. A stray long bar off
    the run is dropped. Long marks every 3 or 15 divisions are no scale's majors: ring marks
    drawn darker in places by the light, read longer than their fellows at random."""
    ks = sorted(m.grid_index for m in marks)
    diffs = [b - a for a, b in zip(ks, ks[1:]) if b > a]
    if len(ks) < 3 or not diffs:
        return []
    values, counts = np.unique(diffs, return_counts=True)
    step = int(values[np.argmax(counts)])
    if step not in MAJOR_STEPS:
        return []
    residues, n_res = np.unique(np.array(ks) % step, return_counts=True)
    residue = int(residues[np.argmax(n_res)])
    on = sorted((m for m in marks if m.grid_index % step == residue), key=lambda m: m.grid_index)
    runs: list[list[Mark]] = []
    for m in on:
        if runs and m.grid_index - runs[-1][-1].grid_index <= 2 * step:
            runs[-1].append(m)
        else:
            runs.append([m])
    run = max(runs, key=len)
    lo, hi = run[0].grid_index, run[-1].grid_index
    within = sum(1 for k in ks if lo <= k <= hi)
    if len(run) < 3 or len(run) < 0.8 * within or len(run) < 0.8 * ((hi - lo) // step + 1):
        return []
    return run


LABEL_REACH = 0.8  # times a label's height: its mark lies this far from the label's centre at most
LONGEST_ELSEWHERE = 1.5  # times the label's mark on the phase: a mark this long beside it is its own
LABEL_OFFSET_SPREAD = 0.35  # times a label's height: how far its mark may lie from where the others' lie


def majors_at_labels(marks: Marks, labels_up: list[tuple[float, float, float | None]], step: int) -> Marks | None:
    """``marks`` with the long marks set where the numbers are printed, every ``step`` grid
    steps (the labels' own spacing). Each label (centre row, height, the row of a line running
    on across it or None) votes for the lattice's phase: with its line's mark, where it has
    one and three or more labels' lines lie alike (a cylinder prints each number on its long
    line; twice the weight), else with the longest mark within ``LABEL_REACH`` heights of it
    (beside a number, or under it; of marks as long, the nearest). Then each label's mark is its
    mark on that phase nearest it, unless a mark ``LONGEST_ELSEWHERE`` as long lies beside it off
    the phase, and where it lies where the other labels' marks lie (``LABEL_OFFSET_SPREAD``).
    None where fewer than three labels have one, or where they are the long marks already.
    Grouping by length fails where a long line is too faint to be seen whole (img_002: the
    lines under a cylinder's numbers, lighter than its short ticks)."""
    if step < 2:
        return None
    by_row = {round(m.y_up, 3): m for m in marks.marks}
    lines = [(line_y - y, h) for y, h, line_y in labels_up if line_y is not None]
    usual_line = float(np.median([o for o, _ in lines])) if lines else 0.0
    # lines across the labels count where three or more lie alike (a tick under a label's digit
    # is one line, at any row; a cylinder's lines under its numbers are all at one place)
    lines_alike = len(lines) >= 3 and all(abs(o - usual_line) <= max(LABEL_OFFSET_SPREAD * h, marks.spacing_up)
                                          for o, h in lines)
    votes = np.zeros(step)
    near_each = []
    for y, h, line_y in labels_up:
        near = [m for m in marks.marks if abs(m.y_up - y) <= LABEL_REACH * h + 2]
        line = by_row.get(round(line_y, 3)) if line_y is not None and lines_alike else None
        if line is not None:
            votes[line.grid_index % step] += 2
            near = [line] + near
        elif near:
            votes[max(near, key=lambda m: (m.length_up, -abs(m.y_up - y))).grid_index % step] += 1
        near_each.append((y, near))
    if not votes.any():
        return None
    phase = int(votes.argmax())
    chosen: list[tuple[float, float, Mark]] = []  # label row, height, its mark
    for (y, near), (_, h, _) in zip(near_each, labels_up):
        on = [m for m in near if m.grid_index % step == phase]
        if not on:
            continue
        mark = on[0] if near[0] is on[0] else min(on, key=lambda m: abs(m.y_up - y))
        if max(m.length_up for m in near) >= LONGEST_ELSEWHERE * mark.length_up and near[0] is not mark:
            continue  # a plainly longer mark beside it, off the phase: the grid miscounted there (a step lost)
        chosen.append((y, h, mark))
    if not chosen:
        return None
    # a scale prints every number at one place beside its mark: a label whose mark lies
    # elsewhere (labels drifting along marks miscounted, dev 1053) is not one of them
    usual = float(np.median([m.y_up - y for y, _, m in chosen]))
    majors = {id(m): m for y, h, m in chosen
              if abs(m.y_up - y - usual) <= max(LABEL_OFFSET_SPREAD * h, marks.spacing_up)}
    if len(majors) < 3 or set(majors) == {id(m) for m in marks.majors}:
        return None
    return _with_tiers(marks, list(majors.values()), [])


def _most_common_step(ks: list[int]) -> int:
    """The most common difference of sorted grid indices; 0 for fewer than two."""
    diffs = [b - a for a, b in zip(ks, ks[1:]) if b > a]
    if not diffs:
        return 0
    values, counts = np.unique(diffs, return_counts=True)
    return int(values[np.argmax(counts)])


def _major_steps(marks: Marks) -> tuple[int, int]:
    """The grid steps between the long marks as seen (their most common difference) and as
    ``major_step`` takes them; (0, 0) for fewer than two long marks."""
    ks = sorted(m.grid_index for m in marks.majors)
    seen = _most_common_step(ks)
    if seen == 0:
        return 0, 0
    mediums = [m.grid_index for m in marks.marks if m.tier == "medium"]
    if mediums:
        half = min(abs(k - major) for major in ks for k in mediums)
        # every medium mark half way between long marks at that step: a lattice, not a miscount
        if half > 0 and seen % (2 * half) == 0 and 2 * half < seen \
                and all((k - ks[0]) % (2 * half) == half for k in mediums):
            return seen, 2 * half
    return seen, seen


def major_step(marks: Marks) -> int:
    """Grid steps between consecutive major marks: their most common difference, or, where
    that skips a long mark not seen (an object or glare across it) and the medium marks halve
    a shorter step, twice the steps from a long mark to its nearest medium mark."""
    return _major_steps(marks)[1]


def major_gap_px(marks: Marks) -> float:
    """The long marks' spacing along the axis (px) at ``major_step``: their median gap, less
    where a long mark not seen doubled it. The gap bounds a label's height."""
    gap = float(np.median(np.diff(sorted(m.y_up for m in marks.majors))))
    seen, step = _major_steps(marks)
    return gap * step / seen if seen else gap


RUN_GAP = 3  # empty grid steps that part two runs of marks (a stopper, a label, glare hides them)
MAX_RUN_SHIFT = 2  # grid steps a run past a gap may be off: the grid's curve extrapolated over the gap
LONG_IN_RUN = 0.9  # of the main run's shorter long marks: a mark in a run past a gap this long is a long one
LONG_IN_RUN_OFFSET = 0.3  # of that length: how far its ends may lie from where one of the main run's long marks ends


def _long_in_run(run: list[Mark], main: list[Mark]) -> list[Mark]:
    """The long marks of a run past a gap: its major tier, or where it has none, its marks as
    long as the main run's long marks and standing where one of them stands. Grouping came
    before the anchoring, and a long mark the grid numbered off the lattice was tiered with the
    short ones (dev 1004: a 1 ml syringe's "0.1" and "0" marks past its stopper, 34 px beside
    the 17 px ticks, as "minor"); a bar beside the scale is as long as a mark, not where it
    stands (dev 1285: a 30 px bar a scale's width to the side)."""
    majors = [m for m in run if m.tier == "major"]
    main_majors = [m for m in main if m.tier == "major"]
    if majors or not main_majors:
        return majors
    long_px = LONG_IN_RUN * float(np.percentile([m.length_up for m in main_majors], 25))
    near = LONG_IN_RUN_OFFSET * long_px
    return [m for m in run if m.length_up >= long_px
            and any(abs(m.x0_up - o.x0_up) + abs(m.x1_up - o.x1_up) <= near for o in main_majors)]


PROJECTIVE_MIN_MARKS = 6  # marks placed before the projective curve numbers a run past a gap (twice its parameters)
PROJECTIVE_FITS = 0.2  # of a step: the worst miss of the curve through a run placed right
PROJECTIVE_MARGIN = 2.5  # how many times worse every other placement's worst miss must be


def _projective(ks: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """The 1-D projective map y = (a k + b) / (c k + 1) through the marks (least squares on
    y (c k + 1) = a k + b, in centred, scaled units): a straight scale seen through a lens is
    that map, exactly, where a quadratic is a Taylor step of it."""
    k0, ks_scale = float(ks.mean()), float(max(np.ptp(ks), 1.0))
    y0, ys_scale = float(ys.mean()), float(max(np.ptp(ys), 1.0))
    k, y = (ks - k0) / ks_scale, (ys - y0) / ys_scale
    a = np.column_stack([k, np.ones_like(k), -k * y])
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    return np.array([coef[0], coef[1], coef[2], k0, ks_scale, y0, ys_scale])


def _projective_at(model: np.ndarray, ks: np.ndarray) -> np.ndarray:
    a, b, c, k0, ks_scale, y0, ys_scale = model
    k = (ks - k0) / ks_scale
    return (a * k + b) / (c * k + 1) * ys_scale + y0


def _projective_shift(run: list[Mark], placed_ks: list[int], placed_ys: list[float]) -> int | None:
    """The shift of a run past a gap with no long mark (or long marks that do not settle it),
    by the projective curve through the marks placed and the run itself: the shift (within
    ``MAX_RUN_SHIFT``) under which every mark lies within ``PROJECTIVE_FITS`` of a step of that
    curve, where each other shift misses by ``PROJECTIVE_MARGIN`` times more. None where none
    is that plain.

    The grid's curve is a quadratic fitted mostly on one side of the gap; seen at a slant,
    the spacing changes faster past a stopper than it bends (clean 9676: a 10 ml syringe's
    marks 5.65 px apart before the stopper and 5.05 after, the runs past it one and two
    steps off; 10212: 19 steps past a 1 ml syringe's stopper counted 20)."""
    if len(placed_ks) < PROJECTIVE_MIN_MARKS:
        return None
    worst = _projective_misses(run, placed_ks, placed_ys)
    if not worst:
        return None
    best = min(worst, key=worst.__getitem__)
    others = [v for k, v in worst.items() if k != best]
    if worst[best] > PROJECTIVE_FITS or (others and min(others) < PROJECTIVE_MARGIN * worst[best]):
        return None
    return best


def _projective_misses(run: list[Mark], placed_ks: list[int], placed_ys: list[float]) -> dict[int, float]:
    """For each shift of ``run`` within ``MAX_RUN_SHIFT``, the worst miss, in steps, of the
    projective curve through the marks placed and the run so shifted."""
    run_ks = np.array([m.grid_index for m in run], float)
    run_ys = np.array([m.y_up for m in run])
    ks_all, ys_all = np.array(placed_ks, float), np.array(placed_ys)
    worst: dict[int, float] = {}
    for shift in range(-MAX_RUN_SHIFT, MAX_RUN_SHIFT + 1):
        ks = np.concatenate([ks_all, run_ks + shift])
        ys = np.concatenate([ys_all, run_ys])
        model = _projective(ks, ys)
        fitted = _projective_at(model, ks)
        step = np.abs(_projective_at(model, ks + 0.5) - _projective_at(model, ks - 0.5))
        if not np.all(np.isfinite(fitted)) or np.any(step <= 0):
            continue
        worst[shift] = float(np.max(np.abs(ys - fitted) / step))
    return worst


def _mediums_halfway(main: list[Mark], every: int, phase: int) -> bool:
    """Whether the main run's medium marks stand half-way between its long ones, all of them
    (a 1 ml syringe's 0.05 marks between its 0.1 ones): then a run past a gap with only a
    medium mark is anchored by it (clean 10473: 8 marks past a 1 ml syringe's stopper, the
    0.25 mark among them, numbered a step off by the grid's curve, read 0.64 division off)."""
    if every % 2:
        return False
    mediums = [m.grid_index % every for m in main if m.tier == "medium"]
    return len(mediums) >= 2 and all(r == (phase + every // 2) % every for r in mediums)


def anchored_runs(marks: Marks) -> Marks:
    """Grid indices across gaps counted by the long marks, as a person counts past a stopper.

    The grid's curve, fitted mostly on one side, can be a step or two off across a gap of
    unseen marks (perspective grows the spacing there), and a scale misnumbered by a step past
    a stopper reads a step off there. A run past a gap whose long marks fall off the main
    run's long-mark lattice is shifted onto it (by at most ``MAX_RUN_SHIFT`` steps; long marks
    every 4 or more steps, so the shift is not ambiguous). A run with no long mark is anchored
    by a half-way one (``_mediums_halfway``), else numbered by the projective curve through
    the marks placed (``_projective_shift``); the grid's curve is then refitted through the
    anchored runs and a run still loose is placed by it, or dropped when its marks do not fall
    on whole steps of that curve.
    """
    every = major_step(marks)
    ordered = sorted(marks.marks, key=lambda m: m.grid_index)
    if every < 4 or len(ordered) < 2:
        return marks
    runs = _runs(ordered, RUN_GAP)
    if len(runs) < 2:
        return marks
    main = max(runs, key=len)
    residues = [m.grid_index % every for m in main if m.tier == "major"]
    if not residues:
        return marks
    phase = max(set(residues), key=residues.count)
    halfway = _mediums_halfway(main, every, phase)
    shift_of: dict[int, int] = {id(m): 0 for m in main}
    loose: list[list[Mark]] = []
    for run in runs:
        if run is main:
            continue
        run_residues = [m.grid_index % every for m in _long_in_run(run, main)]
        if not run_residues and halfway:
            # no long mark past the gap, but a half-way one: it counts as well, half a step on
            run_residues = [(m.grid_index - every // 2) % every for m in run if m.tier == "medium"]
        if not run_residues:
            loose.append(run)
            continue
        residue = max(set(run_residues), key=run_residues.count)
        if 2 * run_residues.count(residue) <= len(run_residues):
            loose.append(run)  # its long marks disagree among themselves: placed by the curve, if at all
            continue
        shift = (phase - residue) % every
        shift = shift - every if shift > every // 2 else shift
        if abs(shift) > MAX_RUN_SHIFT:
            loose.append(run)
            continue
        shift_of.update({id(m): shift for m in run})
    for run in sorted(loose, key=lambda r: min(abs(r[0].grid_index - main[-1].grid_index),
                                               abs(r[-1].grid_index - main[0].grid_index))):
        placed = [m for m in ordered if id(m) in shift_of]
        shift = _projective_shift(run, [m.grid_index + shift_of[id(m)] for m in placed], [m.y_up for m in placed])
        if shift is not None:
            shift_of.update({id(m): shift for m in run})
    loose = [run for run in loose if id(run[0]) not in shift_of]
    if not any(shift_of.values()):
        return marks  # every long mark on the lattice: the grid's numbering stands
    anchored = [m for m in ordered if id(m) in shift_of]
    ks = np.array([m.grid_index + shift_of[id(m)] for m in anchored], float)
    ys = np.array([m.y_up for m in anchored])
    curve = np.polyfit(ks, ys, 2 if len(ks) >= 10 else 1)
    placed = {id(m): int(k) for m, k in zip(anchored, ks)}
    for run in loose:
        lo, hi = run[0].grid_index - 2 * RUN_GAP - 20, run[-1].grid_index + 2 * RUN_GAP + 20
        grid_k = np.arange(lo, hi + 1)
        grid_y = np.polyval(curve, grid_k)
        local = np.abs(np.polyval(np.polyder(curve), grid_k))
        run_y = np.array([m.y_up for m in run])
        nearest = np.abs(run_y[:, None] - grid_y[None, :]).argmin(axis=1)
        misses = np.abs(run_y - grid_y[nearest]) / local[nearest]
        if np.all(misses <= 0.25) and len(set(nearest.tolist())) == len(run):
            placed.update({id(m): int(grid_k[i]) for m, i in zip(run, nearest)})
    kept = [m for m in ordered if id(m) in placed]
    if len({placed[id(m)] for m in kept}) < len(kept):
        return marks  # two marks on one step: the anchoring is not to be trusted
    k0 = min(placed[id(m)] for m in kept)
    return Marks(marks=tuple(replace(m, grid_index=placed[id(m)] - k0) for m in kept), spacing_up=marks.spacing_up)


def in_column(marks: Marks) -> Marks:
    """The marks that reach within a mark's length of the marks' usual columns. The faint-line
    path also finds short faint lines on the grid's rows well beside the scale (img_020: a
    scratch, an edge of the glass); as marks they would widen the search for the walls."""
    x0 = float(np.median([m.x0_up for m in marks.marks]))
    x1 = float(np.median([m.x1_up for m in marks.marks]))
    reach = float(np.median([m.length_up for m in marks.marks]))
    kept = tuple(m for m in marks.marks if m.x1_up >= x0 - reach and m.x0_up <= x1 + reach)
    return replace(marks, marks=kept) if len(kept) >= 2 else marks


LATTICE_SHARE_ENOUGH = 0.5  # of a long-mark lattice's rows holding a long mark: a series in full


def ladder_quality(marks: Marks | None) -> float:
    """Marks on a complete grid with a regular major series score high; anything else zero.

    The light gaps between dark marks also form a ladder, but all its bars share one length:
    without a longer major series every few steps it is not a scale. A series that holds
    under half of its lattice's rows within the ladder counts for that share, doubled: two gaps
    a little longer than the rest, ten steps apart on a ladder of 44 with room for five, are not
    the long marks of a scale; they outscored the dark marks themselves, with a long mark every
    five steps, on a 10 ml cylinder (dev 1201: the numbers were read beside the gaps). Counted
    for the share itself, a ladder whose long marks were partly unseen (5 of 7) lost to one of
    fewer marks, and a meniscus was found 0.7 division off (seed 1459).
    """
    if marks is None or len(marks) == 0:
        return 0.0
    step = major_step(marks)
    majors = marks.majors
    if step < 2 or len(majors) < 2:
        return 0.0
    major_len = float(np.median([m.length_up for m in majors]))
    other_len = float(np.median([m.length_up for m in marks.marks if m.tier != "major"] or [major_len]))
    if major_len < 1.15 * other_len:
        return 0.0
    ks = [m.grid_index for m in marks.marks]
    span = max(ks) - min(ks) + 1
    on_step = sum(1 for m in majors if (m.grid_index - majors[0].grid_index) % step == 0)
    lattice_rows = sum(1 for k in range(min(ks), max(ks) + 1) if (k - majors[0].grid_index) % step == 0)
    lattice_held = min(1.0, on_step / (LATTICE_SHARE_ENOUGH * lattice_rows))
    return len(marks) * (len(marks) / span) * (on_step / len(majors)) * lattice_held


def best_marks(strip_bgr: np.ndarray, config: MarksConfig, grouping: GroupingConfig, kernel_px: int,
               faint: bool = False, planes: bool = False) -> tuple[Marks | None, str]:
    """The best grouped ladder over the segmentation paths, and which path gave it; ``faint``:
    the faint-line path too (``segment_bars``). The colour planes (``_plane_bars``) are looked
    in where the luminance paths find no ladder, or with ``planes`` ranked with them."""
    best: tuple[Marks | None, str] = (None, "")
    best_q = 0.0
    for paths in (functools.partial(segment_bars, faint=faint), _plane_bars):
        for path, bars in paths(strip_bgr, config, kernel_px).items():
            marks = fit_grid(bars, config)
            if marks is None:
                continue
            marks = anchored_runs(group_by_length(marks, grouping))
            q = ladder_quality(marks)
            if q > best_q:
                best, best_q = (marks, path), q
        if best[0] is not None and not planes:
            break
    return best


def is_plane_path(path: str) -> bool:
    """Whether ``best_marks``'s ``path`` is a colour plane's (``_plane_bars``)."""
    return path.startswith(PLANE_PATH_PREFIX)


def _plane_bars(strip_bgr: np.ndarray, config: MarksConfig, kernel_px: int) -> dict[str, list[Bar]]:
    """Dark bars in each colour plane alone, where the luminance showed no scale: print over a
    coloured liquid (brown over orange, blue over red) is about as light as the liquid, and
    far darker in one plane (the red plane, behind blue or brown print on orange)."""
    if config.segmentation not in ("adaptive", "auto") or strip_bgr.ndim != 3:
        return {}
    out = {}
    for channel, name in enumerate(CHANNEL_NAMES):
        dark = thin_response(_plane(strip_bgr, channel), kernel_px, "vertical").dark
        out[f"{PLANE_PATH_PREFIX}{name}"] = bars_from_mask(threshold_response(dark), dark, config)
    return out


_PRINT_MASKS: dict[tuple[tuple[int, int], int, int, float], tuple[Marks, np.ndarray]] = {}


def print_mask(shape: tuple[int, int], marks: Marks, pad_x: int, pad_y: float) -> np.ndarray:
    """Mask (255) of the marks' strokes in the strip, padded: print, not a level or a number.

    Cached by the identity of ``marks`` (the per-frame path asks for the same calibration's
    mask every frame, and hashing every mark each time would cost more than the search): read only.
    """
    key = (tuple(shape), id(marks), pad_x, pad_y)
    found = _PRINT_MASKS.get(key)
    if found is not None and found[0] is marks:
        return found[1]
    mask = np.zeros(shape, np.uint8)
    for m in marks.marks:
        t = int(np.ceil(m.thickness_up / 2 + pad_y))
        y = int(m.y_up)
        cv2.rectangle(mask, (int(m.x0_up) - pad_x, y - t), (int(m.x1_up) + pad_x, y + t), 255, -1)
    mask.flags.writeable = False
    if len(_PRINT_MASKS) >= 16:
        _PRINT_MASKS.clear()
    _PRINT_MASKS[key] = (marks, mask)
    return mask


def kernel_for(spacing_px: float, least_px: int = 5) -> int:
    """Structuring element taller than a mark but shorter than a division; ``least_px``: the
    shortest (3 only for a retry: 5 px is a whole division where marks are 5 px apart)."""
    return int(np.clip(round(0.8 * spacing_px), least_px, 41)) | 1
