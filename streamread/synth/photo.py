"""Camera and light: uneven illumination, white balance, glare, blur, sensor noise, JPEG.

Applied to the composed scene in display-referred float BGR; ranges live in ``scene.RANGES``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Photometry:
    gain: float = 1.0
    gradient_xy: tuple[float, float] = (0.0, 0.0)
    vignette: float = 0.0
    white_balance_bgr: tuple[float, float, float] = (1.0, 1.0, 1.0)
    glare: tuple[tuple[float, float, float, float], ...] = ()  # (x_frac, y_frac, sigma_frac, strength)
    blur_sigma_px: float = 0.0
    read_noise: float = 0.0  # std of additive noise, in [0, 1] units
    shot_noise: float = 0.0  # variance per unit of intensity
    jpeg_quality: int = 0  # 0: no JPEG round trip


def illuminate(img: np.ndarray, p: Photometry) -> np.ndarray:
    h, w = img.shape[:2]
    ys = (np.arange(h, dtype=np.float32) / h - 0.5)[:, None]
    xs = (np.arange(w, dtype=np.float32) / w - 0.5)[None, :]
    field = p.gain * (1 + p.gradient_xy[0] * xs + p.gradient_xy[1] * ys) * (1 - p.vignette * (xs**2 + ys**2) * 2)
    out = img * field[..., None] * np.asarray(p.white_balance_bgr, np.float32)
    for fx, fy, fs, strength in p.glare:
        sigma = fs * max(h, w)
        blob = np.exp(-(((xs + 0.5) * w - fx * w) ** 2 + ((ys + 0.5) * h - fy * h) ** 2) / (2 * sigma**2))
        out += (strength * blob)[..., None]
    return out


def expose(img: np.ndarray, p: Photometry, rng: np.random.Generator) -> np.ndarray:
    """Optics and sensor: blur, noise, quantisation and JPEG; returns uint8 BGR."""
    out = img
    if p.blur_sigma_px > 0.05:
        out = cv2.GaussianBlur(out, (0, 0), p.blur_sigma_px)
    if p.read_noise > 0 or p.shot_noise > 0:
        var = p.read_noise**2 + p.shot_noise * np.clip(out, 0, 1)
        out = out + rng.standard_normal(out.shape, dtype=np.float32) * np.sqrt(var)
    u8 = np.clip(out * 255 + 0.5, 0, 255).astype(np.uint8)
    if p.jpeg_quality:
        ok, buf = cv2.imencode(".jpg", u8, [cv2.IMWRITE_JPEG_QUALITY, int(p.jpeg_quality)])
        if ok:
            u8 = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return u8
