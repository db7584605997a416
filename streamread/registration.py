"""The per-frame check that a cached calibration still holds, and small-shift re-registration.

The calibration knows where every mark of the scale lies in the upright strip (the grid of
marks, including marks that were hidden behind the stopper then). Each frame:

- **comb**: the strip is averaged over the columns every mark covers and the thin-print
  response (1-D black-hat or top-hat, by the print's polarity) taken; at each expected mark row the peak and its
  centroid are taken. The share of expected marks that are visible is the match score (rows
  the indicator occupies are left out: a stopper hides marks as it moves); the median centroid
  offset is the shift along the axis.
- **majors**: the same response over the columns only the long marks reach must peak at the
  long-mark rows, not between them. A camera that moved by a whole number of divisions would
  fool the comb but not this.
- **across**: the column profile (walls, mark ends) is matched by normalised correlation for
  the shift across the axis.

A good match near zero confirms the calibration; a shift of half a pixel or more is corrected
by moving the strip, without OCR; a poor match means the view changed or something covers the
scale. Along the axis only shifts below 0.35 division can be told from the next mark.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import cv2
import numpy as np

from streamread.marks import kernel_for
from streamread.segment import median_small, smooth_1d
from streamread.types import Calibration, Upright


@dataclass(frozen=True)
class Signature:
    """What the print looks like in the strip, from the calibration."""

    comb_y: np.ndarray  # expected row of every grid position of the scale
    is_major: np.ndarray  # which of them are long marks
    minor_cols: tuple[int, int]  # strip columns every mark covers
    major_cols: tuple[int, int] | None  # columns only the long marks reach
    dark_print: bool
    ref_peak: float  # typical mark response at calibration
    ref_major: float  # long-mark contrast in the major-only columns at calibration
    x_profile: np.ndarray
    rows: tuple[int, int]
    columns: tuple[int, int]
    max_dx_px: int
    kernel_px: int
    spacing_px: float

    @functools.cached_property
    def peak_windows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The peak windows around every comb row (see ``_windows``), built once per calibration."""
        return _windows(self.comb_y, self.spacing_px)

    @functools.cached_property
    def x_core(self) -> np.ndarray | None:
        """The middle of the column profile, the template the across-axis shift is matched with
        (None: too short or flat to match)."""
        n, m = len(self.x_profile), self.max_dx_px
        if n <= 2 * m + 4:
            return None
        core = np.ascontiguousarray(self.x_profile[m: n - m], np.float32).reshape(1, -1)
        return core if float(core.std()) >= 1e-6 else None


@dataclass(frozen=True)
class Registration:
    """How far the print moved in the strip (px) and how well it matched."""

    dx_px: float
    dy_px: float
    score: float  # share of expected (unhidden) marks visible, 0 when the long marks do not line up
    score_x: float  # NCC of the column profile
    majors_ok: bool = True


def _high_pass(profile: np.ndarray, sigma: float) -> np.ndarray:
    p = profile.astype(np.float32).ravel()
    return p - smooth_1d(p, sigma)


def _x_profile(strip_gray: np.ndarray, rows: tuple[int, int], columns: tuple[int, int], smooth: float) -> np.ndarray:
    block = strip_gray[rows[0]:rows[1], columns[0]:columns[1]]
    return _high_pass(cv2.reduce(block, 0, cv2.REDUCE_AVG, dtype=cv2.CV_32F).ravel(), smooth)


@functools.lru_cache(maxsize=16)
def _row_element(kernel_px: int) -> np.ndarray:
    return cv2.getStructuringElement(cv2.MORPH_RECT, (kernel_px, 1))


def _hat_1d(profile: np.ndarray, kernel_px: int, dark: bool) -> np.ndarray:
    """Black-hat (``dark``) or top-hat of a 1-D profile: how much darker (lighter) than its
    closing (opening) over ``kernel_px`` samples each sample is, i.e. the thin marks.
    (OpenCV filters a one-row image far faster than a one-column one.)"""
    op = cv2.MORPH_BLACKHAT if dark else cv2.MORPH_TOPHAT
    row = np.ascontiguousarray(profile, np.float32).reshape(1, -1)
    return cv2.morphologyEx(row, op, _row_element(kernel_px), borderType=cv2.BORDER_REPLICATE).ravel()


def _columns(calibration: Calibration) -> tuple[tuple[int, int], tuple[int, int] | None]:
    marks = calibration.marks.marks
    short = [m for m in marks if m.tier != "major"] or list(marks)
    x0 = float(np.percentile([m.x0_up for m in short], 80))
    x1 = float(np.percentile([m.x1_up for m in short], 20))
    minor = (int(np.floor(x0)) + 1, int(np.ceil(x1)))
    if minor[1] - minor[0] < 2:
        c = int(round((x0 + x1) / 2))
        minor = (c - 1, c + 2)
    majors = [m for m in marks if m.tier == "major"]
    major = None
    if majors:
        right = float(np.median([m.x1_up for m in majors])) - max(m.x1_up for m in short)
        left = min(m.x0_up for m in short) - float(np.median([m.x0_up for m in majors]))
        if right >= left and right >= 3:
            major = (int(max(m.x1_up for m in short)) + 2, int(np.median([m.x1_up for m in majors])))
        elif left >= 3:
            major = (int(np.median([m.x0_up for m in majors])) + 1, int(min(m.x0_up for m in short)) - 1)
        if major is not None and major[1] - major[0] < 1:
            major = None
    return minor, major


def print_region(calibration: Calibration) -> tuple[tuple[int, int], tuple[int, int]]:
    """Strip columns (marks and walls) and rows (the graduated span) the check looks at."""
    w, h = calibration.upright.strip_wh
    marks = calibration.marks.marks
    d = calibration.marks.spacing_up
    x_lo = min(min(m.x0_up for m in marks), calibration.bore_x_up[0]) - 6
    x_hi = max(max(m.x1_up for m in marks), calibration.bore_x_up[1]) + 6
    y_lo = min(m.y_up for m in marks) - 2 * d
    y_hi = max(m.y_up for m in marks) + 2 * d
    return (int(max(0, x_lo)), int(min(w, x_hi + 1))), (int(max(0, y_lo)), int(min(h, y_hi + 1)))


def _comb(calibration: Calibration) -> tuple[np.ndarray, np.ndarray]:
    marks = calibration.marks.marks
    ks = np.array([m.grid_index for m in marks], float)
    ys = np.array([m.y_up for m in marks])
    model = np.polyfit(ks, ys, 2 if len(marks) >= 6 else 1)
    grid = np.arange(int(ks.min()), int(ks.max()) + 1)
    major_ks = sorted(m.grid_index for m in marks if m.tier == "major")
    step = int(np.median(np.diff(major_ks))) if len(major_ks) >= 2 else 0
    if step > 0:
        is_major = (grid - major_ks[0]) % step == 0
    else:
        is_major = np.isin(grid, major_ks)
    return np.polyval(model, grid), is_major


def _windows(rows: np.ndarray, spacing_px: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row indices of a window of just under a division around each expected row, the window's
    offsets, and each row's rounding error (centroids are measured from the rounded row)."""
    half = max(1, int(0.45 * spacing_px))
    offsets = np.arange(-half, half + 1)
    centre = np.round(rows).astype(int)
    return centre[:, None] + offsets[None, :], offsets.astype(np.float32), (centre - rows).astype(np.float32)


def _peaks_at(profile: np.ndarray, windows: np.ndarray, offsets: np.ndarray,
              rounding: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Peak height above the window minimum and the centroid offset at each window's row."""
    win = np.take(profile, windows, mode="clip")  # rows past the ends repeat the end row
    w = win - win.min(axis=1, keepdims=True)
    height = w.max(axis=1)
    centroid = (w @ offsets) / np.maximum(w.sum(axis=1), 1e-6) + rounding
    return height, centroid


def _responses(strip_gray: np.ndarray, sig_cols: tuple[tuple[int, int], tuple[int, int] | None],
               kernel_px: int, dark: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """The thin-print response of the mean over the columns every mark covers, and of the mean
    over the columns only the long marks reach (marks cross every column averaged, so the
    profile keeps their full depth; one 1-D hat costs far less than a 2-D one)."""
    minor, major = sig_cols

    def mean_of(cols: tuple[int, int]) -> np.ndarray:
        return cv2.reduce(strip_gray[:, cols[0]:cols[1]], 1, cv2.REDUCE_AVG, dtype=cv2.CV_32F).ravel()

    p_minor = _hat_1d(mean_of(minor), kernel_px, dark)
    p_major = None if major is None else _hat_1d(mean_of(major), kernel_px, dark)
    return p_minor, p_major


def _major_contrast(p_major: np.ndarray | None, comb_y: np.ndarray, is_major: np.ndarray) -> float:
    if p_major is None or not is_major.any() or is_major.all():
        return 0.0
    at = p_major[np.clip(np.round(comb_y).astype(int), 0, len(p_major) - 1)]
    return median_small(at[is_major]) - median_small(at[~is_major])


def make_signature(strip_gray: np.ndarray, calibration: Calibration) -> Signature:
    d = calibration.marks.spacing_up
    kernel_px = kernel_for(d)
    comb_y, is_major = _comb(calibration)
    cols = _columns(calibration)
    known = _windows(np.array([m.y_up for m in calibration.marks.marks]), d)
    best = None
    for dark in (True, False):  # the print's polarity: whichever shows the marks better
        p_minor, p_major = _responses(strip_gray, cols, kernel_px, dark)
        height, _ = _peaks_at(p_minor, *known)
        ref = float(np.median(height))
        if best is None or ref > best[0]:
            best = (ref, dark, _major_contrast(p_major, comb_y, is_major))
    assert best is not None
    columns, rows = print_region(calibration)
    return Signature(comb_y=comb_y, is_major=is_major, minor_cols=cols[0], major_cols=cols[1], dark_print=best[1],
                     ref_peak=max(best[0], 1e-3), ref_major=best[2], x_profile=_x_profile(strip_gray, rows, columns, 1.5 * d),
                     rows=rows, columns=columns, max_dx_px=max(3, int(1.0 * d)), kernel_px=kernel_px, spacing_px=d)


def _ncc_shift(core: np.ndarray, current: np.ndarray, max_shift: int) -> tuple[float, float]:
    """Sub-pixel shift of ``current`` against the template whose middle is ``core`` (the
    template trimmed by ``max_shift`` at each end, as ``Signature.x_core``), and the
    normalised correlation there."""
    cur = np.ascontiguousarray(current, np.float32).reshape(1, -1)
    if cur.shape[1] < core.shape[1]:
        return 0.0, 0.0
    ncc = cv2.matchTemplate(cur, core, cv2.TM_CCOEFF_NORMED).ravel().tolist()
    i = max(range(len(ncc)), key=ncc.__getitem__)
    shift = float(i - max_shift)
    if 0 < i < len(ncc) - 1:
        a, b, c = ncc[i - 1], ncc[i], ncc[i + 1]
        denom = a - 2 * b + c
        if denom < 0:
            shift += min(max(0.5 * (a - c) / denom, -0.5), 0.5)
    return shift, float(ncc[i])


def register(strip_gray: np.ndarray, signature: Signature,
             indicator_rows: tuple[float, float] | None = None) -> Registration:
    """Match this frame's print against the calibration; ``indicator_rows`` are left out."""
    d = signature.spacing_px
    p_minor, p_major = _responses(strip_gray, (signature.minor_cols, signature.major_cols), signature.kernel_px,
                                  signature.dark_print)
    rows = signature.comb_y
    use = (rows >= 0) & (rows < len(p_minor))
    if indicator_rows is not None:
        use &= (rows < indicator_rows[0]) | (rows > indicator_rows[1])
    x_now = _x_profile(strip_gray, signature.rows, signature.columns, 1.5 * d)
    if signature.x_core is None:
        dx, score_x = 0.0, 0.0
    else:
        dx, score_x = _ncc_shift(signature.x_core, x_now, signature.max_dx_px)
    n_use = int(np.count_nonzero(use))
    if n_use < 3:
        return Registration(dx, 0.0, 0.0, score_x, False)
    windows, offsets, rounding = signature.peak_windows
    height, centroid = _peaks_at(p_minor, windows[use], offsets, rounding[use])
    visible = height >= 0.35 * signature.ref_peak
    n_visible = int(np.count_nonzero(visible))
    score = n_visible / n_use
    dy = median_small(centroid[visible]) if n_visible >= 3 else 0.0
    majors_ok = True
    if p_major is not None and signature.ref_major > 0:
        contrast = _major_contrast(p_major, rows[use] + dy, signature.is_major[use])
        majors_ok = contrast >= 0.3 * signature.ref_major
    if not majors_ok or abs(dy) > 0.35 * d:
        score = min(score, 0.2)
    return Registration(dx_px=dx, dy_px=dy, score=score, score_x=score_x, majors_ok=majors_ok)


def shifted(upright: Upright, dx_px: float, dy_px: float) -> Upright:
    """The same rotation with the strip moved so content now at +(dx, dy) lands where it was."""
    m = upright.to_upright.copy()
    m[0, 2] -= dx_px
    m[1, 2] -= dy_px
    return replace(upright, to_upright=m)
