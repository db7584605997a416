"""Segmentation of print: the paper's HSV colour ranges, and an adaptive path for any ink.

The adaptive path keeps thin structures darker (black-hat) or lighter (top-hat) than their
surroundings, so black, blue, brown and white print all segment without a colour range.
Both return binary masks (uint8, 255 = print).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from streamread.profile import HsvRange


def to_gray(image: np.ndarray) -> np.ndarray:
    if image.ndim == 2:
        return image
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def segment_hsv(image_bgr: np.ndarray, ranges: tuple[HsvRange, ...]) -> np.ndarray:
    """The paper's colour segmentation: union of ``cv2.inRange`` over HSV ranges (3x3 blur first)."""
    hsv = cv2.cvtColor(cv2.GaussianBlur(image_bgr, (3, 3), 0), cv2.COLOR_BGR2HSV)
    mask = np.zeros(hsv.shape[:2], np.uint8)
    for lo, hi in ranges:
        mask |= cv2.inRange(hsv, np.array(lo, np.uint8), np.array(hi, np.uint8))
    return mask


@dataclass(frozen=True)
class ThinResponse:
    """How much darker (``dark``) or lighter (``bright``) than the surroundings each pixel is."""

    dark: np.ndarray
    bright: np.ndarray


def thin_response(gray: np.ndarray, kernel_px: int, kernel_shape: str = "ellipse") -> ThinResponse:
    """Black-hat and top-hat: structures thinner than ``kernel_px`` stand out from the background."""
    k = max(3, int(kernel_px) | 1)
    if kernel_shape == "vertical":  # marks are horizontal in the upright strip
        element = cv2.getStructuringElement(cv2.MORPH_RECT, (1, k))
    else:
        element = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    smooth = cv2.GaussianBlur(gray, (3, 3), 0)
    return ThinResponse(dark=cv2.morphologyEx(smooth, cv2.MORPH_BLACKHAT, element),
                        bright=cv2.morphologyEx(smooth, cv2.MORPH_TOPHAT, element))


def threshold_response(response: np.ndarray, floor: float = 10.0) -> np.ndarray:
    """Binary mask of a hat response: Otsu's level, but never below ``floor`` grey levels."""
    level, _ = cv2.threshold(response, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    _, mask = cv2.threshold(response, max(float(level), floor), 255, cv2.THRESH_BINARY)
    return mask


@functools.lru_cache(maxsize=64)
def _line_kernel(angle_deg: float, length_px: float, offset_px: float) -> np.ndarray:
    """Mean along a line ``length_px`` long at ``angle_deg``, moved ``offset_px`` across it
    (bilinear taps, so any angle and sub-pixel offset), as a ``filter2D`` kernel."""
    size = int(2 * max(length_px / 2, abs(offset_px)) + 3) | 1
    kernel = np.zeros((size, size), np.float32)
    c = size // 2
    a = np.radians(angle_deg)
    along, across = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
    for t in np.linspace(-length_px / 2, length_px / 2, int(2 * length_px) + 1):
        x, y = c + t * along + offset_px * across
        x0, y0 = int(np.floor(x)), int(np.floor(y))
        fx, fy = x - x0, y - y0
        kernel[y0, x0] += (1 - fx) * (1 - fy)
        kernel[y0, x0 + 1] += fx * (1 - fy)
        kernel[y0 + 1, x0] += (1 - fx) * fy
        kernel[y0 + 1, x0 + 1] += fx * fy
    return kernel / kernel.sum()


def valley_response(gray: np.ndarray, angle_deg: float, length_px: float = 5.0, offset_px: float = 2.5,
                    ) -> np.ndarray:
    """How much darker a short line at ``angle_deg`` through each pixel is than both lines
    parallel to it ``offset_px`` away (float32, 0 where it is not).

    A faint tick joined to a darker wall or spine is lost to the black-hat, whose threshold the
    wall sets; here the wall, running across the tick, is darker on neither side of it and gives
    nothing, and an edge is dark on one side only. Real glass prints such ticks (img_020).
    """
    g = gray.astype(np.float32)
    centre = cv2.filter2D(g, -1, _line_kernel(angle_deg, length_px, 0.0), borderType=cv2.BORDER_REPLICATE)
    one = cv2.filter2D(g, -1, _line_kernel(angle_deg, length_px, offset_px), borderType=cv2.BORDER_REPLICATE)
    other = cv2.filter2D(g, -1, _line_kernel(angle_deg, length_px, -offset_px), borderType=cv2.BORDER_REPLICATE)
    return np.maximum(np.minimum(one, other) - centre, 0.0)


def oriented_valleys(gray: np.ndarray, orientations: int = 12, length_px: float = 7.0,
                     offset_px: float = 2.5) -> tuple[np.ndarray, np.ndarray]:
    """The strongest ``valley_response`` over ``orientations`` directions, and the index of the
    direction (angle = index * 180 / orientations) that gave it."""
    best = np.zeros(gray.shape, np.float32)
    which = np.zeros(gray.shape, np.int32)
    for i in range(orientations):
        r = valley_response(gray, 180.0 * i / orientations, length_px, offset_px)
        stronger = r > best
        best[stronger] = r[stronger]
        which[stronger] = i
    return best, which


@functools.lru_cache(maxsize=32)
def _gaussian_taps(sigma: float) -> np.ndarray:
    radius = max(1, int(round(3 * sigma)))
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    taps = np.exp(-0.5 * (x / sigma) ** 2)
    return (taps / taps.sum()).astype(np.float32)


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) index of each run of True in a 1-D mask."""
    bounds = (np.flatnonzero(mask[1:] != mask[:-1]) + 1).tolist()
    if len(mask) and mask[0]:
        bounds.insert(0, 0)
    if len(mask) and mask[-1]:
        bounds.append(len(mask))
    return [(bounds[i], bounds[i + 1] - 1) for i in range(0, len(bounds), 2)]


def smooth_1d(profile: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing of a 1-D profile (edges reflected); for short profiles far cheaper
    than cv2.GaussianBlur on a one-column image."""
    taps = _gaussian_taps(round(float(sigma), 3))
    r = len(taps) // 2
    p = np.asarray(profile, dtype=np.float32).ravel()
    if len(p) <= r:
        return p.copy()
    padded = np.concatenate([p[r:0:-1], p, p[-2:-r - 2:-1]])
    return np.convolve(padded, taps, "valid").astype(np.float32, copy=False)


def smooth_rows(profiles: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing of each row of a (K, n) array, edges reflected as ``smooth_1d``.

    One OpenCV call for a stack of profiles (a worker's batch of frames). A separable filter
    with a one-tap column kernel never mixes rows, so a row's result is the same alone or in
    a stack (``filter2D`` may switch to a DFT for long kernels, which would not be).
    """
    taps = _gaussian_taps(round(float(sigma), 3))
    return cv2.sepFilter2D(np.ascontiguousarray(profiles, np.float32), cv2.CV_32F, taps, _ONE_TAP,
                           borderType=cv2.BORDER_REFLECT_101)


_ONE_TAP = np.ones(1, np.float32)


def row_sums(stack: np.ndarray) -> np.ndarray:
    """(K, h) sum of each row of a (K, h, n) uint8 stack, exact in integers, in one OpenCV call:
    a row's sum is the same alone or in a stack (a worker's batch of strips)."""
    k, h = stack.shape[:2]
    return cv2.reduce(stack.reshape(k * h, -1), 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S).reshape(k, h)


def median_small(values: np.ndarray) -> float:
    """Median of a short 1-D array; np.median's generality costs ~40 us a call on the per-frame path."""
    v = np.sort(np.asarray(values).ravel())
    n = len(v)
    if n == 0:
        return float("nan")
    return float(v[n // 2]) if n % 2 else (float(v[n // 2 - 1]) + float(v[n // 2])) / 2
