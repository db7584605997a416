"""Small line/scatter charts drawn with OpenCV alone, for the evaluation report.

A plotting library would be a heavy dependency for six report figures; OpenCV is already
here, so this module gives just enough: nice 1-2-5 ticks, a grid, axis labels with units,
a title, a legend that avoids the data, solid and dashed lines and marker scatters.
Colours are BGR, as everywhere in OpenCV.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import cv2
import numpy as np

Color = tuple[int, int, int]
Marker = Literal["circle", "square", "triangle", "diamond", "cross"]

BLUE: Color = (180, 119, 31)  # the usual blue/orange pair, told apart by colour-blind readers too
ORANGE: Color = (14, 127, 255)
GREEN: Color = (44, 160, 44)
RED: Color = (40, 39, 214)
GREY: Color = (127, 127, 127)
BLACK: Color = (0, 0, 0)
WHITE: Color = (255, 255, 255)
GRID: Color = (228, 228, 228)

FONT = cv2.FONT_HERSHEY_SIMPLEX
AA = cv2.LINE_AA


def nice_step(span: float, target: int = 6) -> float:
    """A 1, 2 or 5 times a power of ten step that cuts ``span`` into about ``target`` parts."""
    raw = max(span, 1e-12) / max(target, 1)
    power = 10.0 ** math.floor(math.log10(raw))
    for mult in (1.0, 2.0, 5.0, 10.0):
        if raw <= mult * power * (1 + 1e-9):
            return mult * power
    return 10.0 * power


def nice_ticks(lo: float, hi: float, target: int = 6) -> tuple[float, float, list[float]]:
    """Axis limits (``lo``..``hi``, widened only when empty) and the whole-step tick values inside them."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        lo, hi = 0.0, 1.0
    if hi < lo:
        lo, hi = hi, lo
    if hi - lo < 1e-12:
        pad = max(abs(lo) * 0.1, 0.5)
        lo, hi = lo - pad, hi + pad
    step = nice_step(hi - lo, target)
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    ticks = [i * step for i in range(first, last + 1)]
    return lo, hi, ticks


def format_tick(value: float, step: float) -> str:
    """A tick label with just the decimals the step needs (and never ``-0``)."""
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step > 0 else 0
    text = f"{value:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


@dataclass(frozen=True)
class _Series:
    label: str | None
    x: np.ndarray
    y: np.ndarray
    color: Color
    kind: Literal["line", "scatter"]
    dashed: bool = False
    thickness: int = 2
    marker: Marker = "circle"
    size: int = 4
    filled: bool = True


@dataclass(frozen=True)
class _HLine:
    label: str | None
    y: float
    color: Color
    dashed: bool
    thickness: int


def _finite(x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    xa = np.asarray(x, dtype=np.float64).ravel()
    ya = np.asarray(y, dtype=np.float64).ravel()
    if xa.shape != ya.shape:
        raise ValueError(f"x and y differ in length: {xa.size} and {ya.size}")
    keep = np.isfinite(xa) & np.isfinite(ya)
    return xa[keep], ya[keep]


class Figure:
    """One chart, built up by calls and drawn by ``render`` (limits are known only once all data is in)."""

    def __init__(self, title: str, xlabel: str, ylabel: str, size: tuple[int, int] = (800, 600),
                 equal_axes: bool = False) -> None:
        self.title, self.xlabel, self.ylabel = title, xlabel, ylabel
        self.size = size
        self.equal_axes = equal_axes  # same limits on both axes, for plots with a y = x line
        self._series: list[_Series] = []
        self._hlines: list[_HLine] = []
        self._diagonal: tuple[str | None, Color] | None = None
        self._notes: list[str] = []

    def line(self, x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray, color: Color,
             label: str | None = None, dashed: bool = False, thickness: int = 2,
             marker: Marker | None = None, size: int = 4) -> Figure:
        """A polyline through the points in the given order, optionally with markers at each."""
        xa, ya = _finite(x, y)
        self._series.append(_Series(label if marker is None else None, xa, ya, color, "line", dashed, thickness))
        if marker is not None:
            self._series.append(_Series(label, xa, ya, color, "scatter", marker=marker, size=size,
                                        thickness=thickness))
        return self

    def scatter(self, x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray, color: Color,
                label: str | None = None, marker: Marker = "circle", size: int = 4, filled: bool = True) -> Figure:
        """Unconnected markers."""
        xa, ya = _finite(x, y)
        self._series.append(_Series(label, xa, ya, color, "scatter", marker=marker, size=size, filled=filled,
                                    thickness=1 if filled else 2))
        return self

    def hline(self, y: float, color: Color, label: str | None = None, dashed: bool = False,
              thickness: int = 2) -> Figure:
        """A horizontal line across the whole plot (a bias or a limit of agreement)."""
        if math.isfinite(y):
            self._hlines.append(_HLine(label, float(y), color, dashed, thickness))
        return self

    def diagonal(self, color: Color = GREY, label: str | None = "y = x") -> Figure:
        """The ideal y = x line across the plot, drawn dashed."""
        self._diagonal = (label, color)
        return self

    def note(self, text: str) -> Figure:
        """A line of text in the middle of the plot area (e.g. why it is empty)."""
        self._notes.append(text)
        return self

    # ------------------------------------------------------------------ drawing

    def _limits(self) -> tuple[tuple[float, float, list[float]], tuple[float, float, list[float]]]:
        xs = [s.x for s in self._series if s.x.size]
        ys = [s.y for s in self._series if s.y.size] + [np.array([h.y]) for h in self._hlines]
        x_all = np.concatenate(xs) if xs else np.array([0.0, 1.0])
        y_all = np.concatenate(ys) if ys else np.array([0.0, 1.0])
        if self.equal_axes:
            both = np.concatenate([x_all, y_all])
            x_all = y_all = both
        pad_x = 0.04 * float(np.ptp(x_all))
        pad_y = 0.06 * float(np.ptp(y_all))
        x_lim = nice_ticks(float(x_all.min()) - pad_x, float(x_all.max()) + pad_x)
        y_lim = nice_ticks(float(y_all.min()) - pad_y, float(y_all.max()) + pad_y)
        if self.equal_axes:
            y_lim = x_lim
        return x_lim, y_lim

    def render(self) -> np.ndarray:
        """The chart as a BGR image of ``size`` (width, height)."""
        w, h = self.size
        img = np.full((h, w, 3), 255, np.uint8)
        (x0, x1, xticks), (y0, y1, yticks) = self._limits()
        ystep = yticks[1] - yticks[0] if len(yticks) > 1 else 1.0
        xstep = xticks[1] - xticks[0] if len(xticks) > 1 else 1.0
        ylabels = [format_tick(v, ystep) for v in yticks]
        label_w = max(cv2.getTextSize(t, FONT, 0.45, 1)[0][0] for t in ylabels)
        left = 20 + 22 + label_w + 10  # y label, tick labels, gap
        right, top, bottom = w - 25, 50, h - 60
        pw, ph = right - left, bottom - top

        def px(x: np.ndarray | float) -> np.ndarray:
            return (np.asarray(x, dtype=np.float64) - x0) / (x1 - x0) * pw

        def py(y: np.ndarray | float) -> np.ndarray:
            return (y1 - np.asarray(y, dtype=np.float64)) / (y1 - y0) * ph

        # grid and ticks
        for v, text in zip(yticks, ylabels):
            yy = top + int(round(float(py(v))))
            cv2.line(img, (left, yy), (right, yy), GRID, 1, AA)
            cv2.line(img, (left - 5, yy), (left, yy), BLACK, 1, AA)
            (tw, th), _ = cv2.getTextSize(text, FONT, 0.45, 1)
            cv2.putText(img, text, (left - 8 - tw, yy + th // 2), FONT, 0.45, BLACK, 1, AA)
        for v in xticks:
            xx = left + int(round(float(px(v))))
            cv2.line(img, (xx, top), (xx, bottom), GRID, 1, AA)
            cv2.line(img, (xx, bottom), (xx, bottom + 5), BLACK, 1, AA)
            text = format_tick(v, xstep)
            (tw, th), _ = cv2.getTextSize(text, FONT, 0.45, 1)
            cv2.putText(img, text, (xx - tw // 2, bottom + 10 + th), FONT, 0.45, BLACK, 1, AA)
        if y0 < 0 < y1:  # the zero line, a little darker than the grid
            yy = top + int(round(float(py(0.0))))
            cv2.line(img, (left, yy), (right, yy), (190, 190, 190), 1, AA)

        # data, drawn into a view of the plot area so anything outside is clipped
        area = img[top:bottom + 1, left:right + 1]
        if self._diagonal is not None:
            lo, hi = max(x0, y0), min(x1, y1)
            if hi > lo:
                pts = np.stack([px(np.array([lo, hi])), py(np.array([lo, hi]))], axis=1)
                _polyline(area, pts, self._diagonal[1], 2, dashed=True)
        for hl in self._hlines:
            yy = float(py(hl.y))
            _polyline(area, np.array([[0.0, yy], [float(pw), yy]]), hl.color, hl.thickness, hl.dashed)
        for s in self._series:
            pts = np.stack([px(s.x), py(s.y)], axis=1) if s.x.size else np.zeros((0, 2))
            if s.kind == "line":
                _polyline(area, pts, s.color, s.thickness, s.dashed)
            else:
                for p in pts:
                    draw_marker(area, (float(p[0]), float(p[1])), s.color, s.marker, s.size, s.filled)
        for i, text in enumerate(self._notes):
            (tw, th), _ = cv2.getTextSize(text, FONT, 0.6, 1)
            cv2.putText(area, text, ((pw - tw) // 2, ph // 2 + i * (th + 10)), FONT, 0.6, GREY, 1, AA)

        # frame, title, axis labels, legend
        cv2.rectangle(img, (left, top), (right, bottom), BLACK, 1, AA)
        (tw, th), _ = cv2.getTextSize(self.title, FONT, 0.65, 2)
        cv2.putText(img, self.title, (max(5, (w - tw) // 2), 18 + th), FONT, 0.65, BLACK, 2, AA)
        (tw, th), _ = cv2.getTextSize(self.xlabel, FONT, 0.55, 1)
        cv2.putText(img, self.xlabel, (left + (pw - tw) // 2, h - 14), FONT, 0.55, BLACK, 1, AA)
        _vertical_text(img, self.ylabel, 12, top + ph // 2, 0.55)
        all_pts = [np.stack([px(s.x), py(s.y)], axis=1) for s in self._series if s.x.size]
        self._legend(area, np.concatenate(all_pts) if all_pts else np.zeros((0, 2)))
        return img

    def _legend(self, area: np.ndarray, pts: np.ndarray) -> None:
        entries: list[tuple[str, Color, str, Marker, bool, bool]] = []  # label, colour, kind, marker, dashed, filled
        if self._diagonal is not None and self._diagonal[0]:
            entries.append((self._diagonal[0], self._diagonal[1], "line", "circle", True, True))
        for s in self._series:
            if s.label:
                entries.append((s.label, s.color, s.kind, s.marker, s.dashed, s.filled))
        for hl in self._hlines:
            if hl.label:
                entries.append((hl.label, hl.color, "line", "circle", hl.dashed, True))
        if not entries:
            return
        scale, row = 0.45, 20
        text_w = max(cv2.getTextSize(e[0], FONT, scale, 1)[0][0] for e in entries)
        box_w, box_h = 10 + 30 + 8 + text_w + 10, 8 + row * len(entries) + 2
        ah, aw = area.shape[:2]
        corners = [(10, 10), (aw - box_w - 10, 10), (10, ah - box_h - 10), (aw - box_w - 10, ah - box_h - 10)]

        def covered(c: tuple[int, int]) -> int:
            if pts.size == 0:
                return 0
            inside = ((pts[:, 0] >= c[0] - 5) & (pts[:, 0] <= c[0] + box_w + 5)
                      & (pts[:, 1] >= c[1] - 5) & (pts[:, 1] <= c[1] + box_h + 5))
            return int(inside.sum())

        bx, by = min(corners, key=covered)  # the corner that hides the fewest data points
        cv2.rectangle(area, (bx, by), (bx + box_w, by + box_h), WHITE, -1)
        cv2.rectangle(area, (bx, by), (bx + box_w, by + box_h), (160, 160, 160), 1, AA)
        for i, (label, color, kind, marker, dashed, filled) in enumerate(entries):
            cy = by + 8 + row * i + row // 2
            if kind == "line":
                _polyline(area, np.array([[bx + 10.0, cy], [bx + 40.0, cy]]), color, 2, dashed, dash=7, gap=4)
            else:
                draw_marker(area, (bx + 25.0, float(cy)), color, marker, 5, filled)
            (_, th), _ = cv2.getTextSize(label, FONT, scale, 1)
            cv2.putText(area, label, (bx + 48, cy + th // 2), FONT, scale, BLACK, 1, AA)


def _polyline(img: np.ndarray, pts: np.ndarray, color: Color, thickness: int, dashed: bool,
              dash: float = 10.0, gap: float = 6.0) -> None:
    """A solid or dashed polyline in float pixels (dashes carry over the corners)."""
    if len(pts) < 2:
        return
    shift = 4  # sub-pixel precision for cv2.line
    k = float(1 << shift)

    def seg(a: np.ndarray, b: np.ndarray) -> None:
        cv2.line(img, (int(round(a[0] * k)), int(round(a[1] * k))), (int(round(b[0] * k)), int(round(b[1] * k))),
                 color, thickness, AA, shift)

    if not dashed:
        for a, b in zip(pts[:-1], pts[1:]):
            seg(a, b)
        return
    on, left = True, dash
    for a, b in zip(pts[:-1], pts[1:]):
        length = float(np.hypot(*(b - a)))
        pos = 0.0
        while pos < length:
            step = min(left, length - pos)
            if on:
                seg(a + (b - a) * (pos / length), a + (b - a) * ((pos + step) / length))
            pos += step
            left -= step
            if left <= 1e-9:
                on = not on
                left = dash if on else gap


def draw_marker(img: np.ndarray, center: tuple[float, float], color: Color, marker: Marker = "circle",
                size: int = 4, filled: bool = True) -> None:
    """One scatter marker centred at ``center`` (float pixels)."""
    cx, cy = int(round(center[0])), int(round(center[1]))
    th = -1 if filled else 2
    if marker == "circle":
        cv2.circle(img, (cx, cy), size, color, th, AA)
    elif marker == "square":
        cv2.rectangle(img, (cx - size, cy - size), (cx + size, cy + size), color, th, AA)
    elif marker in ("triangle", "diamond"):
        if marker == "triangle":
            poly = np.array([[cx, cy - size - 1], [cx + size + 1, cy + size], [cx - size - 1, cy + size]], np.int32)
        else:
            poly = np.array([[cx, cy - size - 1], [cx + size + 1, cy], [cx, cy + size + 1], [cx - size - 1, cy]],
                            np.int32)
        if filled:
            cv2.fillPoly(img, [poly], color, AA)
        else:
            cv2.polylines(img, [poly], True, color, 2, AA)
    else:
        cv2.line(img, (cx - size, cy - size), (cx + size, cy + size), color, 2, AA)
        cv2.line(img, (cx - size, cy + size), (cx + size, cy - size), color, 2, AA)


def _vertical_text(img: np.ndarray, text: str, x: int, cy: int, scale: float) -> None:
    """Text turned 90 degrees counter-clockwise, centred on row ``cy`` with its top at column ``x``."""
    (tw, th), base = cv2.getTextSize(text, FONT, scale, 1)
    patch = np.full((th + base + 4, tw + 4, 3), 255, np.uint8)
    cv2.putText(patch, text, (2, th + 2), FONT, scale, BLACK, 1, AA)
    patch = cv2.rotate(patch, cv2.ROTATE_90_COUNTERCLOCKWISE)
    ph, pw = patch.shape[:2]
    y0 = max(0, cy - ph // 2)
    y1 = min(img.shape[0], y0 + ph)
    x1 = min(img.shape[1], x + pw)
    region = img[y0:y1, x:x1]
    np.minimum(region, patch[:y1 - y0, :x1 - x], out=region)  # dark text over the light background


def save_png(image: np.ndarray, path: Path) -> Path:
    """Write ``image`` as PNG (through imencode, so any path the OS accepts works); returns the path."""
    path = Path(path)
    ok, data = cv2.imencode(".png", image)
    if not ok:
        raise ValueError(f"OpenCV could not encode a PNG for {path}")
    path.write_bytes(data.tobytes())
    return path
