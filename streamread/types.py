"""Small frozen types passed between the reader's stages.

Coordinates carry their frame in the name: ``_px`` are pixels of the input image (OpenCV
convention, pixel centres at integers); ``_up`` are pixels of the upright scale strip, where
the scale axis is vertical and the numbers read upright (y down, as in images).
"""

from __future__ import annotations

import bisect
import functools
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from streamread.errors import expected

ApparatusKind = Literal["syringe", "measuring_cylinder", "burette"]
Tier = Literal["major", "medium", "minor"]


def _finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise ValueError(expected("value", name, "a finite number", value))


@dataclass(frozen=True)
class Upright:
    """The rotation that makes the scale upright, and the strip cut from the rotated image.

    ``to_upright`` is the 2x3 affine from input pixels to strip pixels.
    """

    angle_deg: float
    to_upright: np.ndarray
    strip_wh: tuple[int, int]

    def __post_init__(self) -> None:
        if self.to_upright.shape != (2, 3):
            raise ValueError(expected("upright", "to_upright", "a 2x3 affine matrix", self.to_upright.shape))

    @functools.cached_property
    def _inverse(self) -> np.ndarray:
        return cv2_invert_affine(self.to_upright)

    def to_input(self, points_up: np.ndarray) -> np.ndarray:
        """Map (N, 2) strip points back to input pixels."""
        inverse = self._inverse
        pts = np.asarray(points_up, dtype=np.float64).reshape(-1, 2)
        return pts @ inverse[:, :2].T + inverse[:, 2]

    def point_to_input(self, x_up: float, y_up: float) -> tuple[float, float]:
        """One strip point in input pixels (the per-frame path: no arrays for a single point)."""
        (a, b, c), (d, e, f) = self._inverse.tolist()
        return a * x_up + b * y_up + c, d * x_up + e * y_up + f

    def from_input(self, points_px: np.ndarray) -> np.ndarray:
        pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
        return pts @ self.to_upright[:, :2].T + self.to_upright[:, 2]


def cv2_invert_affine(m: np.ndarray) -> np.ndarray:
    a = np.vstack([m, [0.0, 0.0, 1.0]])
    return np.linalg.inv(a)[:2]


@dataclass(frozen=True)
class Mark:
    """One graduation mark in the upright strip: a horizontal bar."""

    y_up: float
    x0_up: float
    x1_up: float
    thickness_up: float
    tier: Tier = "minor"
    grid_index: int = 0

    @property
    def length_up(self) -> float:
        return self.x1_up - self.x0_up

    @property
    def center_up(self) -> tuple[float, float]:
        return (self.x0_up + self.x1_up) / 2, self.y_up


@dataclass(frozen=True)
class Marks:
    """The scale's marks on a regular grid: mark ``k`` sits near ``y(k)``; spacing in strip pixels."""

    marks: tuple[Mark, ...]
    spacing_up: float

    def __post_init__(self) -> None:
        if self.spacing_up <= 0:
            raise ValueError(expected("marks", "spacing_up", "> 0", self.spacing_up))

    @property
    def majors(self) -> tuple[Mark, ...]:
        return tuple(m for m in self.marks if m.tier == "major")

    def __len__(self) -> int:
        return len(self.marks)


@dataclass(frozen=True)
class OcrRead:
    """A number read beside a major mark."""

    y_up: float
    text: str
    value: float | None
    confidence: float = 0.0


NEAR_LINE_MARKS = 16  # marks in the line that reads a position past the nearest run of 8
PROJECTIVE_READ_MARKS = 10  # marks from which a position past them is read on the projective map
PROJECTIVE_GAIN = 0.7  # of the line's residual over the marks: the map's, where it reads past them
PROJECTIVE_BEND = 0.5  # the map's denominator may change this much (of itself) between the marks and a position


def _nearest_run(ys: list[float], y: float, k: int) -> tuple[int, int]:
    """start, stop of the ``k`` sorted positions nearest ``y`` (they are a run of neighbours)."""
    n = len(ys)
    right = bisect.bisect_left(ys, y)
    left = right - 1
    for _ in range(min(k, n)):
        if right >= n or (left >= 0 and y - ys[left] <= ys[right] - y):
            left -= 1
        else:
            right += 1
    return left + 1, right


@dataclass(frozen=True)
class ScaleFit:
    """value = slope * y_up + offset, fitted over all marks once their values are known."""

    slope: float
    offset: float
    residual_px: float
    minor_ml: float
    mark_y_up: tuple[float, ...] = ()
    mark_values: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        _finite("slope", self.slope)
        _finite("offset", self.offset)
        if self.slope == 0:
            raise ValueError(expected("fit", "slope", "non-zero", self.slope))
        if self.minor_ml <= 0:
            raise ValueError(expected("fit", "minor_ml", "> 0", self.minor_ml))

    @functools.cached_property
    def _local_quadratics(self) -> tuple[list[float], np.ndarray, list[tuple[float, float, float, float]]]:
        """Sorted mark rows (a list: the per-frame lookup is plain Python) and their values, and
        for every run of 8 neighbouring marks its quadratic (centre, c0, c1, c2)."""
        order = np.argsort(self.mark_y_up)
        ys = np.asarray(self.mark_y_up, dtype=np.float64)[order]
        vals = np.asarray(self.mark_values, dtype=np.float64)[order]
        fits = []
        for i in range(max(len(ys) - 7, 0)):
            local, v = ys[i:i + 8], vals[i:i + 8]
            centre = float(local.mean())
            c2, c1, c0 = np.polyfit(local - centre, v, 2)
            fits.append((centre, float(c0), float(c1), float(c2)))
        return ys.tolist(), vals, fits

    def value_at(self, y_up: float) -> float:
        """Value at a strip position: local quadratic over the 8 nearest marks; past them, the
        line through the 16 nearest.

        The fits are made once per calibration (per run of marks); a call only picks the run.
        """
        if len(self.mark_y_up) >= 6:
            ys, vals, fits = self._local_quadratics
            start, stop = _nearest_run(ys, y_up, 8)
            if ys[start] - 1 <= y_up <= ys[stop - 1] + 1:
                if len(ys) >= 8:
                    centre, c0, c1, c2 = fits[start]
                    x = y_up - centre
                    return c0 + x * (c1 + x * c2)
                c2, c1, c0 = np.polyfit(np.asarray(ys) - y_up, vals, 2)  # 6 or 7 marks
                return float(c0)
            # past the run (a stopper beyond the last mark seen, or over the marks it hides): not
            # the whole scale's line, which perspective bends away from its ends
            projective = self._projective_value(y_up)
            if projective is not None:
                return projective
            # no map (too few marks, or no bend in them): the line through 16 marks, not 8, to
            # average out the marks' own misplacement
            start, stop = _nearest_run(ys, y_up, NEAR_LINE_MARKS)
            line = self._run_lines.get(start)
            if line is None:
                slope, offset = np.polyfit(np.asarray(ys[start:stop]), vals[start:stop], 1)
                line = self._run_lines[start] = (float(slope), float(offset))
            return line[0] * y_up + line[1]
        return self.slope * y_up + self.offset

    @functools.cached_property
    def _projective_map(self) -> tuple[float, float, float, float, float, float, float] | None:
        """(centre, scale, a, b, c, x_first, x_last) of value = (a x + b) / (c x + 1), x = (y -
        centre) / scale, fitted over every mark (x_first, x_last: the marks' ends); None under
        ``PROJECTIVE_READ_MARKS`` marks, or where it fits them no better than ``PROJECTIVE_GAIN``
        of a straight line's residual.

        A camera maps a straight scale onto the image by this map exactly (the quadratic and the
        local line are its Taylor steps), so it carries the marks' spacing on past them as the
        perspective does. On the 154 syringes of seeds 9600-11399 read a division or more past
        their marks, it read 14 more than 0.3 division off where the line through the 16 nearest
        marks read 31 (median 0.05 against 0.14 division). Where the marks show no bend its
        curvature is their noise, carried on: on ``syringe5ml_staircase``, seen square on, it
        read the nearly empty syringe 0.02 ml lower than the line. Fitted linearly: value =
        a x + b - c x value."""
        if len(self.mark_y_up) < PROJECTIVE_READ_MARKS:
            return None
        ys = np.asarray(self.mark_y_up, dtype=np.float64)
        vals = np.asarray(self.mark_values, dtype=np.float64)
        centre, scale = float(ys.mean()), float(ys.std()) or 1.0
        x = (ys - centre) / scale
        (a, b, c), *_ = np.linalg.lstsq(np.stack([x, np.ones_like(x), -x * vals], 1), vals, rcond=None)
        mapped = (a * x + b) / (c * x + 1.0)
        line = np.polyval(np.polyfit(x, vals, 1), x)
        if np.sqrt(np.mean((mapped - vals) ** 2)) >= PROJECTIVE_GAIN * np.sqrt(np.mean((line - vals) ** 2)):
            return None  # the marks show no bend: what the map would carry on is their noise
        return centre, scale, float(a), float(b), float(c), float(x.min()), float(x.max())

    def _projective_value(self, y_up: float) -> float | None:
        """The projective map's value at ``y_up``, or None where there is no map or its
        denominator bends by ``PROJECTIVE_BEND`` or more between the marks and ``y_up`` (the
        map's pole near: its curvature there is the marks' noise, not perspective)."""
        found = self._projective_map
        if found is None:
            return None
        centre, scale, a, b, c, x_first, x_last = found
        x = (y_up - centre) / scale
        denominators = [c * v + 1.0 for v in (x, x_first, x_last)]
        if min(denominators) < 1.0 - PROJECTIVE_BEND or max(denominators) > 1.0 + PROJECTIVE_BEND:
            return None
        return (a * x + b) / (c * x + 1.0)

    @functools.cached_property
    def _run_lines(self) -> dict[int, tuple[float, float]]:
        """(slope, offset) of the line through the run of marks starting at each index, as used."""
        return {}

    @property
    def division_px(self) -> float:
        return abs(self.minor_ml / self.slope)

    @functools.cached_property
    def value_range(self) -> tuple[float, float]:
        if not self.mark_values:
            return (-math.inf, math.inf)
        return min(self.mark_values), max(self.mark_values)


@dataclass(frozen=True)
class Indicator:
    """The level indicator found in the strip: where the level is read and how sure we are."""

    kind: Literal["stopper", "meniscus"]
    y_up: float
    x_up: float
    sigma_px: float
    strength: float = 0.0
    coloured_liquid: bool = False  # a meniscus over a liquid whose colour hides the marks under it
    by_network: bool = False  # found by a bore network (meniscus or stopper), where no rule found one

    def __post_init__(self) -> None:
        _finite("y_up", self.y_up)
        if self.sigma_px < 0:
            raise ValueError(expected("indicator", "sigma_px", ">= 0", self.sigma_px))


@dataclass(frozen=True)
class Calibration:
    """Everything read once per apparatus view: orientation, strip, marks, numbers and fit."""

    apparatus: ApparatusKind
    upright: Upright
    marks: Marks
    reads: tuple[OcrRead, ...]
    fit: ScaleFit
    bore_x_up: tuple[float, float]
    box_xyxy: tuple[float, float, float, float] | None = None


@dataclass(frozen=True)
class Reading:
    """The result for one image or frame. ``level`` is None when there is no trustworthy reading."""

    level: float | None
    sigma: float | None
    apparatus: str
    error: str | None = None
    calibration: Calibration | None = None
    indicator: Indicator | None = None
    indicator_px: tuple[float, float] | None = None
    timings_s: dict[str, float] = field(default_factory=dict)
    unit: str = "ml"

    def __post_init__(self) -> None:
        if self.level is not None:
            _finite("level", self.level)
            if self.error is not None:
                raise ValueError("reading: expected no error with a level, got " + self.error)
        elif self.error is None:
            raise ValueError("reading: expected an error that says why there is no level")

    def to_json(self, image: str) -> dict[str, object]:
        fit = None
        if self.calibration is not None:
            f = self.calibration.fit
            fit = {"slope": f.slope, "offset": f.offset, "residual_px": f.residual_px}
        return {
            "image": image, "level": self.level, "unit": self.unit, "sigma": self.sigma,
            "apparatus": self.apparatus, "marks": 0 if self.calibration is None else len(self.calibration.marks),
            "fit": fit, "error": self.error,
        }
