"""The apparatus's own raster: an upright view in millimetres, drawn with anti-aliased polygons.

Each apparatus is drawn here (supersampled) and then warped into the camera image with
one homography, so ground-truth points map exactly as the pixels do.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

_SHIFT = 4  # fixed-point bits for sub-pixel polygon vertices


class Canvas:
    """Raster of the window ``x in [x_min, x_max]``, ``y in [y_min, y_max]`` (mm) at ``k`` px/mm."""

    def __init__(self, x_min: float, x_max: float, y_min: float, y_max: float, k: float) -> None:
        self.k = float(k)
        self.x0 = float(x_min)
        self.y1 = float(y_max)
        self.width = int(math.ceil((x_max - x_min) * k)) + 1
        self.height = int(math.ceil((y_max - y_min) * k)) + 1
        self.x_mm = self.x0 + np.arange(self.width, dtype=np.float32) / self.k  # column centres
        self.y_mm = self.y1 - np.arange(self.height, dtype=np.float32) / self.k  # row centres

    @property
    def shape(self) -> tuple[int, int]:
        return self.height, self.width

    def px_to_mm_matrix(self) -> np.ndarray:
        return np.array([[1 / self.k, 0, self.x0], [0, -1 / self.k, self.y1], [0, 0, 1.0]])

    def to_px(self, points_mm: np.ndarray) -> np.ndarray:
        pts = np.asarray(points_mm, dtype=np.float64).reshape(-1, 2)
        return np.column_stack([(pts[:, 0] - self.x0) * self.k, (self.y1 - pts[:, 1]) * self.k])

    def mask(self, polygons_mm: list[np.ndarray]) -> np.ndarray:
        """Float coverage in [0, 1] of the union of polygons (anti-aliased)."""
        out = np.zeros(self.shape, np.uint8)
        self.fill(out, polygons_mm)
        return out.astype(np.float32) * (1 / 255)

    def fill(self, target_u8: np.ndarray, polygons_mm: list[np.ndarray], value: int = 255) -> None:
        if not polygons_mm:
            return
        fixed = [np.round(self.to_px(p) * (1 << _SHIFT)).astype(np.int32) for p in polygons_mm]
        cv2.fillPoly(target_u8, fixed, value, lineType=cv2.LINE_AA, shift=_SHIFT)

    def rows_between(self, y_lo: float, y_hi: float) -> np.ndarray:
        """Soft (anti-aliased) indicator over rows of ``y_lo <= y <= y_hi``, shape (H, 1)."""
        half = 0.5 / self.k
        lo = np.clip((self.y_mm - (y_lo - half)) * self.k, 0, 1)
        hi = np.clip(((y_hi + half) - self.y_mm) * self.k, 0, 1)
        return (lo * hi)[:, None]

    def cols_within(self, half_width: float) -> np.ndarray:
        """Soft indicator over columns with ``|x| <= half_width``, shape (1, W)."""
        return np.clip((half_width + 0.5 / self.k - np.abs(self.x_mm)) * self.k, 0, 1)[None, :]


def rect(x0: float, x1: float, y0: float, y1: float) -> np.ndarray:
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=np.float64)


def support(coverage: np.ndarray) -> tuple[slice, slice]:
    """Row and column slices bounding the non-zero part of a 2-D coverage (all of it if empty)."""
    nz = (coverage > 0).astype(np.uint8)
    x, y, w, h = cv2.boundingRect(nz)
    if w == 0 or h == 0:
        return slice(0, 0), slice(0, 0)
    return slice(y, y + h), slice(x, x + w)


def over(color: np.ndarray, layer_color: np.ndarray | tuple[float, float, float], coverage: np.ndarray) -> None:
    """In place: ``color = color * (1 - a) + layer * a``, only where ``a`` is non-zero."""
    if coverage.ndim == 2 and coverage.shape == color.shape[:2]:
        rows, cols = support(coverage)
        a = coverage[rows, cols, None]
        region = color[rows, cols]
        layer = np.asarray(layer_color, dtype=np.float32)
        if layer.ndim == 3:
            layer = layer[rows, cols]
        region *= 1 - a
        region += layer * a
        return
    a = coverage if coverage.ndim == 3 else coverage[..., None]
    color *= 1 - a
    color += np.asarray(layer_color, dtype=np.float32) * a
