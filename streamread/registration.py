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

The image work (``print_responses``) takes a stack of strips, so a batch of frames pays the
calls once; ``check`` then judges one frame with the rows its indicator hides.

A good match near zero confirms the calibration; a shift of half a pixel or more is corrected
by moving the strip, without OCR; a poor match means the view changed or something covers the
scale. Along the axis only shifts below 0.35 division can be told from the next mark.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, replace

import cv2
import numpy as np

from streamread.marks import kernel_for
from streamread.segment import median_small, row_sums, smooth_rows
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

    def in_strip(self, strip_h: int) -> np.ndarray:
        """Which grid rows lie inside a strip ``strip_h`` rows high (read only)."""
        return self._for_height("in_strip", strip_h, lambda: (self.comb_y >= 0) & (self.comb_y < strip_h))

    def windows_in(self, strip_h: int) -> np.ndarray:
        """The peak windows' rows in a strip ``strip_h`` rows high, clipped to it (read only)."""
        return self._for_height("windows", strip_h, lambda: _clipped(self.peak_windows[0], strip_h))

    def _for_height(self, what: str, strip_h: int, make: Callable[[], np.ndarray]) -> np.ndarray:
        """An array that depends on the strip's height only, made once per height (every frame asks)."""
        found = self._by_height.get((what, strip_h))
        if found is None:
            found = make()
            found.flags.writeable = False
            self._by_height[(what, strip_h)] = found
        return found

    @functools.cached_property
    def _by_height(self) -> dict[tuple[str, int], np.ndarray]:
        return {}


@dataclass(frozen=True)
class Registration:
    """How far the print moved in the strip (px) and how well it matched."""

    dx_px: float
    dy_px: float
    score: float  # share of expected (unhidden) marks visible, 0 when the long marks do not line up
    score_x: float  # NCC of the column profile
    majors_ok: bool = True


def _high_pass(profiles: np.ndarray, sigma: float) -> np.ndarray:
    return profiles - smooth_rows(profiles, sigma)


def _row_means(strips: np.ndarray, cols: tuple[int, int]) -> np.ndarray:
    """(K, h) mean of each row over ``cols`` of each strip of a (K, h, w) uint8 stack, summed
    exactly in integers (a frame's result is the same alone or in a batch)."""
    block = strips[:, :, cols[0]:cols[1]]
    return row_sums(block).astype(np.float32) / np.float32(max(block.shape[2], 1))


def _x_profiles(strips: np.ndarray, rows: tuple[int, int], columns: tuple[int, int], smooth: float) -> np.ndarray:
    """(K, n) high-passed column profiles of the print region of each strip."""
    n = max(rows[1] - rows[0], 1)
    sums = np.concatenate([cv2.reduce(strip[rows[0]:rows[1], columns[0]:columns[1]], 0, cv2.REDUCE_SUM,
                                      dtype=cv2.CV_32S) for strip in strips])
    return _high_pass(sums.astype(np.float32) / np.float32(n), smooth)


@functools.lru_cache(maxsize=16)
def _row_element(kernel_px: int) -> np.ndarray:
    return cv2.getStructuringElement(cv2.MORPH_RECT, (kernel_px, 1))


def _hat_rows(profiles: np.ndarray, kernel_px: int, dark: bool) -> np.ndarray:
    """Black-hat (``dark``) or top-hat of each row of a (K, n) profile array: how much darker
    (lighter) than its closing (opening) over ``kernel_px`` samples each sample is, i.e. the
    thin marks. The element is one row high, so rows (frames) do not mix."""
    op = cv2.MORPH_BLACKHAT if dark else cv2.MORPH_TOPHAT
    return cv2.morphologyEx(np.ascontiguousarray(profiles, np.float32), op, _row_element(kernel_px),
                            borderType=cv2.BORDER_REPLICATE)


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


def _peaks_at(profiles: np.ndarray, windows: np.ndarray, offsets: np.ndarray,
              rounding: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Peak height above the window minimum and the centroid offset at each window's row, for
    each row of a (K, n) profile array: two (K, rows) arrays. ``windows`` must lie in the
    profile (see ``_clipped``)."""
    win = profiles[:, windows]
    w = win - win.min(axis=2, keepdims=True)
    height = w.max(axis=2)
    centroid = (w @ offsets) / np.maximum(w.sum(axis=2), 1e-6) + rounding
    return height, centroid


def _clipped(windows: np.ndarray, length: int) -> np.ndarray:
    """Window rows past the ends of a profile ``length`` long moved onto its end rows (the end row repeats)."""
    return np.clip(windows, 0, length - 1)


def _responses(strips: np.ndarray, sig_cols: tuple[tuple[int, int], tuple[int, int] | None],
               kernel_px: int, dark: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """The thin-print response of the mean over the columns every mark covers, and of the mean
    over the columns only the long marks reach, for each strip of a (K, h, w) stack (marks
    cross every column averaged, so the profile keeps their full depth; one 1-D hat costs far
    less than a 2-D one)."""
    minor, major = sig_cols
    p_minor = _hat_rows(_row_means(strips, minor), kernel_px, dark)
    p_major = None if major is None else _hat_rows(_row_means(strips, major), kernel_px, dark)
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
    strips = strip_gray[None]
    best = None
    for dark in (True, False):  # the print's polarity: whichever shows the marks better
        p_minor, p_major = _responses(strips, cols, kernel_px, dark)
        height, _ = _peaks_at(p_minor, _clipped(known[0], p_minor.shape[1]), *known[1:])
        ref = float(np.median(height[0]))
        if best is None or ref > best[0]:
            best = (ref, dark, _major_contrast(None if p_major is None else p_major[0], comb_y, is_major))
    assert best is not None
    columns, rows = print_region(calibration)
    return Signature(comb_y=comb_y, is_major=is_major, minor_cols=cols[0], major_cols=cols[1], dark_print=best[1],
                     ref_peak=max(best[0], 1e-3), ref_major=best[2],
                     x_profile=_x_profiles(strips, rows, columns, 1.5 * d)[0],
                     rows=rows, columns=columns, max_dx_px=max(3, int(1.0 * d)), kernel_px=kernel_px, spacing_px=d)


def _ncc_shifts(core: np.ndarray, current: np.ndarray, max_shift: int) -> tuple[np.ndarray, np.ndarray]:
    """Sub-pixel shift of each row of ``current`` (K, n) against the template whose middle is
    ``core`` (the template trimmed by ``max_shift`` at each end, as ``Signature.x_core``), and
    the normalised correlation there. The template is one row high, so one OpenCV call
    correlates every row with it."""
    k, n = current.shape
    if n < core.shape[1]:
        return np.zeros(k), np.zeros(k)
    ncc = cv2.matchTemplate(np.ascontiguousarray(current, np.float32), core, cv2.TM_CCOEFF_NORMED)
    shifts, scores = np.zeros(k), np.zeros(k)
    for j, row in enumerate(ncc.tolist()):  # a few dozen values a row: plain Python is cheapest
        i = max(range(len(row)), key=row.__getitem__)
        shift = float(i - max_shift)
        if 0 < i < len(row) - 1:
            a, b, c = row[i - 1], row[i], row[i + 1]
            denom = a - 2 * b + c
            if denom < 0:
                shift += min(max(0.5 * (a - c) / denom, -0.5), 0.5)
        shifts[j], scores[j] = shift, row[i]
    return shifts, scores


@dataclass(frozen=True)
class PrintResponse:
    """The image work of the check on one strip, before the indicator's rows are known:
    what :func:`check` needs. :func:`print_responses` makes them for a stack of strips at once."""

    height: np.ndarray  # peak height at every grid row of the signature
    centroid: np.ndarray  # centroid offset (px) at every grid row
    p_major: np.ndarray | None  # the long-mark response along the strip
    strip_h: int
    dx_px: float
    score_x: float


def print_responses(strips: np.ndarray, signature: Signature) -> list[PrintResponse]:
    """The check's image work for a (K, h, w) stack of grey strips cut with one calibration.

    A worker measuring a video checks many frames at once: the same numpy and OpenCV calls
    serve the whole stack, where one frame at a time spends most of its time in the calls
    themselves. Each strip's result is what it would be alone.
    """
    if strips.ndim != 3:
        raise ValueError(f"print_responses: expected a (K, h, w) stack of grey strips, got shape {strips.shape}")
    d = signature.spacing_px
    p_minor, p_major = _responses(strips, (signature.minor_cols, signature.major_cols), signature.kernel_px,
                                  signature.dark_print)
    k = len(strips)
    if signature.x_core is None:
        dx, score_x = np.zeros(k), np.zeros(k)
    else:
        x_now = _x_profiles(strips, signature.rows, signature.columns, 1.5 * d)
        dx, score_x = _ncc_shifts(signature.x_core, x_now, signature.max_dx_px)
    h = strips.shape[1]
    _, offsets, rounding = signature.peak_windows
    height, centroid = _peaks_at(p_minor, signature.windows_in(h), offsets, rounding)
    return [PrintResponse(height[j], centroid[j], None if p_major is None else p_major[j], h,
                          float(dx[j]), float(score_x[j])) for j in range(k)]


def check(response: PrintResponse, signature: Signature,
          indicator_rows: tuple[float, float] | None = None) -> Registration:
    """The match of one strip's print against the calibration; ``indicator_rows`` are left out."""
    d = signature.spacing_px
    rows = signature.comb_y
    use = signature.in_strip(response.strip_h)
    if indicator_rows is not None:
        use = use & ((rows < indicator_rows[0]) | (rows > indicator_rows[1]))
    dx, score_x = response.dx_px, response.score_x
    n_use = int(np.count_nonzero(use))
    if n_use < 3:
        return Registration(dx, 0.0, 0.0, score_x, False)
    visible = use & (response.height >= 0.35 * signature.ref_peak)
    n_visible = int(np.count_nonzero(visible))
    score = n_visible / n_use
    dy = median_small(response.centroid[visible]) if n_visible >= 3 else 0.0
    majors_ok = True
    if response.p_major is not None and signature.ref_major > 0:
        contrast = _major_contrast(response.p_major, rows[use] + dy, signature.is_major[use])
        majors_ok = contrast >= 0.3 * signature.ref_major
    if not majors_ok or abs(dy) > 0.35 * d:
        score = min(score, 0.2)
    return Registration(dx_px=dx, dy_px=dy, score=score, score_x=score_x, majors_ok=majors_ok)


def register(strip_gray: np.ndarray, signature: Signature,
             indicator_rows: tuple[float, float] | None = None) -> Registration:
    """Match this frame's print against the calibration; ``indicator_rows`` are left out."""
    return check(print_responses(strip_gray[None], signature)[0], signature, indicator_rows)


def shifted(upright: Upright, dx_px: float, dy_px: float) -> Upright:
    """The same rotation with the strip moved so content now at +(dx, dy) lands where it was."""
    m = upright.to_upright.copy()
    m[0, 2] -= dx_px
    m[1, 2] -= dy_px
    return replace(upright, to_upright=m)
