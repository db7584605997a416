"""Orientation: which way the scale runs, by PCA on its mark contours, and the upright strip.

Marks are many short parallel bars in a row. We keep linear contours (the paper's aspect
test on the rotated rectangle, so any rotation passes), take the dominant bar direction,
keep the bars that line up in one ladder, and run PCA on their centres: the first principal
axis is the scale axis. Two uprights remain (numbers upright or upside down); the OCR stage
decides between them. Where that finds no scale, ``faint_segments`` gives the bars of faint
lines instead, each direction apart, for the same ladders.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from streamread.segment import oriented_valleys
from streamread.types import Upright


@dataclass(frozen=True)
class Segment:
    """A linear contour: centre, length, thickness and direction of its long side (degrees, mod 180)."""

    cx: float
    cy: float
    length: float
    thickness: float
    angle_deg: float


def linear_contours(mask: np.ndarray, aspect_min: float, min_length_px: float) -> list[Segment]:
    """Contours whose rotated rectangle is at least ``aspect_min`` times longer than thick."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    out = []
    for c in contours:
        if len(c) < 2:
            continue
        (cx, cy), (w, h), angle = cv2.minAreaRect(c)
        length, thick = (w, h) if w >= h else (h, w)
        thick = max(thick, 1.0)
        if length < min_length_px or length / thick < aspect_min:
            continue
        direction = angle if w >= h else angle + 90.0
        out.append(Segment(float(cx), float(cy), float(length), float(thick), float(direction % 180.0)))
    return out


FAINT_ORIENTATIONS = 12  # directions of the faint-line search: 15 degrees apart


def faint_segments(gray: np.ndarray, aspect_min: float, min_length_px: float,
                   floor: float = 6.0) -> list[Segment]:
    """Linear contours of faint thin lines, each in its own direction (``oriented_valleys``).

    The pixels of one direction, with its two neighbours (a line between two directions is
    kept whole), are cut apart from those of the others: a tick and the wall it stands on
    cross, and only apart is the tick a short bar of its own. A line found in two windows of
    directions is kept once. Otsu's level on the strongest response, never under ``floor``."""
    response, which = oriented_valleys(gray, FAINT_ORIENTATIONS)
    scaled = np.clip(response, 0, 255).astype(np.uint8)
    level, _ = cv2.threshold(scaled, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    strong = response > max(float(level), floor)
    segments: list[Segment] = []
    seen: set[tuple[int, int, int]] = set()
    n = FAINT_ORIENTATIONS
    for i in range(n):
        near = (which == i) | (which == (i + 1) % n) | (which == (i - 1) % n)
        mask = (strong & near).astype(np.uint8) * 255
        for seg in linear_contours(mask, aspect_min, min_length_px):
            key = (round(seg.cx), round(seg.cy), round(seg.length))
            if key not in seen:
                seen.add(key)
                segments.append(seg)
    return segments


def angle_distance(a: float, b: float) -> float:
    """Degrees between two undirected line angles (mod 180)."""
    d = abs(a - b) % 180.0
    return min(d, 180.0 - d)


@dataclass(frozen=True)
class Ladder:
    """Parallel bars in one row: the scale's marks as seen in the input image."""

    segments: tuple[Segment, ...]
    axis_angle_deg: float  # direction of the scale axis (PCA), mod 360 only after the upright choice
    center_px: tuple[float, float]
    extent_px: float  # length of the ladder along the axis
    bar_length_px: float  # longest bar


LADDER_ANGLE_TOL_DEG = 7.0  # bars this close to a ladder's direction are its bars


def find_ladders(segments: list[Segment], max_ladders: int = 3,
                 angle_tol_deg: float = LADDER_ANGLE_TOL_DEG) -> list[Ladder]:
    """Candidate ladders, best first: bars of a common direction whose centres line up."""
    if len(segments) < 4:
        return []
    angles = np.array([s.angle_deg for s in segments])
    hist = np.zeros(180)
    for a in angles:
        hist[int(a) % 180] += 1
    hist = np.convolve(np.concatenate([hist[-5:], hist, hist[:5]]), np.ones(5), "same")[5:-5]
    ladders: list[Ladder] = []
    used_angles: list[float] = []
    for peak in np.argsort(hist)[::-1]:
        # every strong direction is looked at before the best ladders are kept: the walls of a
        # tube make several rows of long parallel lines, which must not crowd out the marks
        if len(used_angles) >= 2 * max_ladders or hist[peak] < 4:
            break
        if any(angle_distance(peak, u) < 15 for u in used_angles):
            continue
        used_angles.append(float(peak))
        members = [s for s in segments if angle_distance(s.angle_deg, peak) <= angle_tol_deg]
        ladders.extend(_rows_of_bars(members))
    ladders.sort(key=lambda lad: -len(lad.segments))
    return ladders[:max_ladders]


def _rows_of_bars(members: list[Segment]) -> list[Ladder]:
    """Split parallel bars into rows (by position along the bar direction) and keep long rows."""
    if len(members) < 4:
        return []
    mean_angle = math.radians(float(np.median([s.angle_deg for s in members])))
    u = np.array([math.cos(mean_angle), math.sin(mean_angle)])  # along the bars
    centers = np.array([[s.cx, s.cy] for s in members])
    along = centers @ u
    lengths = np.array([s.length for s in members])
    order = np.argsort(along)
    groups: list[list[int]] = []
    tol = float(np.median(lengths))
    for i in order:
        if groups and along[i] - along[groups[-1][-1]] <= tol:
            groups[-1].append(int(i))
        else:
            groups.append([int(i)])
    out = []
    for g in groups:
        if len(g) < 4:
            continue
        pts = centers[g]
        center = pts.mean(axis=0)
        _, vectors = np.linalg.eigh(np.cov((pts - center).T))
        axis = vectors[:, -1]  # first principal component of the mark centres
        proj = (pts - center) @ axis
        out.append(Ladder(segments=tuple(members[i] for i in g),
                          axis_angle_deg=math.degrees(math.atan2(axis[1], axis[0])) % 180.0,
                          center_px=(float(center[0]), float(center[1])),
                          extent_px=float(proj.max() - proj.min()),
                          bar_length_px=float(np.max(lengths[g]))))
    return out


def upright_for(ladder: Ladder, flip: bool, pad_along: float, half_width: float) -> Upright:
    """The rotation that puts the ladder's axis vertical (down the strip), and the strip size."""
    angle = ladder.axis_angle_deg + (180.0 if flip else 0.0)
    a = math.radians(angle)
    v = np.array([math.cos(a), math.sin(a)])  # strip's +y
    u = np.array([math.sin(a), -math.cos(a)])  # strip's +x; [u; v] is a proper rotation
    width = int(round(2 * half_width))
    height = int(round(ladder.extent_px + 2 * pad_along))
    c = np.array(ladder.center_px)
    # turned, the strip must equal the unturned one rotated by 180 degrees as an array
    # (pixel y -> h - 1 - y), which is how marks and reads are turned: one pixel less
    shift = 1.0 if flip else 0.0
    m = np.array([[u[0], u[1], -c @ u + width / 2 - shift], [v[0], v[1], -c @ v + height / 2 - shift]])
    return Upright(angle_deg=angle, to_upright=m, strip_wh=(width, height))


def cut_strip(image: np.ndarray, upright: Upright, columns: tuple[int, int] | None = None,
              gray: bool = False, luma_lut: np.ndarray | None = None) -> np.ndarray:
    """The upright strip; with ``columns`` only that range of strip columns is resampled (the
    per-frame path needs the bore and the print, not the margins), the rest left black.

    With ``gray`` the strip is grey: only the source pixels the strip covers are converted,
    then resampled (one channel is a third of the work; the per-frame path of a syringe needs
    no colour). ``luma_lut`` maps a luma plane's resampled pixels to grey (see ``Frame``):
    only the columns resampled, a fifth of the strip's pixels in a syringe's per-frame path.
    """
    w, h = upright.strip_wh
    x0, x1 = (0, w) if columns is None else (max(0, int(columns[0])), min(w, int(columns[1])))
    x1 = max(x1, x0 + 1)
    m = upright.to_upright.copy()
    m[0, 2] -= x0
    src, (sx, sy) = _source_window(image, m, x1 - x0, h)
    if gray and src.ndim == 3:
        src = cv2.cvtColor(src, cv2.COLOR_BGR2GRAY)
    m[0, 2] += m[0, 0] * sx + m[0, 1] * sy
    m[1, 2] += m[1, 0] * sx + m[1, 1] * sy
    part = cv2.warpAffine(src, m, (x1 - x0, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    if luma_lut is not None:
        part = cv2.LUT(part, luma_lut)
    if x0 == 0 and x1 == w:
        return part
    out = np.zeros((h, w) + part.shape[2:], image.dtype)
    out[:, x0:x1] = part
    return out


def rows_in_frame(upright: Upright, columns_up: tuple[float, ...], frame_hw: tuple[int, int]) -> tuple[int, int]:
    """The first and last strip rows whose points at every one of ``columns_up`` lie in the
    input frame; (0, -1) where none does. Past the frame the strip repeats the edge pixels, and
    the frame's edge crossing the bore looks like a band."""
    h = upright.strip_wh[1]
    ys = np.arange(h, dtype=np.float64)
    inside = np.ones(h, bool)
    frame_h, frame_w = frame_hw
    for x in columns_up:
        pts = upright.to_input(np.stack([np.full(h, float(x)), ys], axis=1))
        inside &= (pts[:, 0] >= 0) & (pts[:, 0] <= frame_w - 1) & (pts[:, 1] >= 0) & (pts[:, 1] <= frame_h - 1)
    rows = np.flatnonzero(inside)
    return (int(rows[0]), int(rows[-1])) if len(rows) else (0, -1)


def _source_window(image: np.ndarray, to_part: np.ndarray, w: int, h: int) -> tuple[np.ndarray, tuple[int, int]]:
    """The part of ``image`` an output of ``w`` x ``h`` under ``to_part`` reads, and its corner.

    Resampling only this window gives the same pixels as resampling the whole image: it keeps
    a margin for the interpolation, and where it is clipped it is clipped at the image border,
    which the replicated border continues in both cases.
    """
    (a, b, c), (d, e, f) = to_part.tolist()
    ih, iw = image.shape[:2]
    bounds = _window_bounds(a, b, c, d, e, f, w, h, ih, iw)
    if bounds is None:
        return image, (0, 0)
    sx0, sy0, sx1, sy1 = bounds
    return image[sy0:sy1, sx0:sx1], (sx0, sy0)


@functools.lru_cache(maxsize=64)  # the per-frame path asks the same question every frame
def _window_bounds(a: float, b: float, c: float, d: float, e: float, f: float, w: int, h: int,
                   ih: int, iw: int) -> tuple[int, int, int, int] | None:
    det = a * e - b * d
    if abs(det) < 1e-12:
        return None
    xs, ys = [], []
    for u, v in ((0.0, 0.0), (w - 1.0, 0.0), (0.0, h - 1.0), (w - 1.0, h - 1.0)):
        p, q = u - c, v - f
        xs.append((e * p - b * q) / det)
        ys.append((a * q - d * p) / det)
    sx0 = min(max(int(math.floor(min(xs))) - 2, 0), iw - 1)
    sy0 = min(max(int(math.floor(min(ys))) - 2, 0), ih - 1)
    sx1 = max(min(int(math.ceil(max(xs))) + 3, iw), sx0 + 1)
    sy1 = max(min(int(math.ceil(max(ys))) + 3, ih), sy0 + 1)
    return sx0, sy0, sx1, sy1
