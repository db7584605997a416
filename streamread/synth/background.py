"""Lab backgrounds and distractors: walls, benches, labels with numbers, rulers, bottles, cables.

Distractors are chosen to fool a careless reader: printed digits (OCR), rulers (graduation
look-alikes), tubes and bottles (apparatus look-alikes). A hand occluder is drawn here too.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from streamread.synth.draw import text_mask

_WORDS = ["PRODUCTO", "TERMINADO", "LOT", "REF", "EXP", "BUFFER", "NaCl", "pH 7.4", "TOTAL QTY", "DATE",
          "SAMPLE", "HCl 0.1 M", "STERILE", "KEEP COOL", "ETOH 70%", "QC PASS", "BATCH"]


def _smooth_noise(rng: np.random.Generator, h: int, w: int, scale: float) -> np.ndarray:
    small = rng.standard_normal((max(2, int(h / scale)) + 1, max(2, int(w / scale)) + 1)).astype(np.float32)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)


def _random_text(rng: np.random.Generator) -> str:
    kind = rng.integers(0, 4)
    if kind == 0:
        return str(rng.choice(_WORDS))
    if kind == 1:
        return f"{rng.integers(1, 31):02d}/{rng.integers(1, 13):02d}/{rng.integers(10, 30)}"
    if kind == 2:
        return f"{rng.choice(_WORDS)} {rng.integers(1, 999)}"
    return str(rng.integers(1, 500))


def _paste_ink(img: np.ndarray, patch: np.ndarray, left: int, top: int, color: np.ndarray) -> None:
    h, w = patch.shape
    y0, x0, y1, x1 = max(top, 0), max(left, 0), min(top + h, img.shape[0]), min(left + w, img.shape[1])
    if y1 <= y0 or x1 <= x0:
        return
    a = patch[y0 - top: y1 - top, x0 - left: x1 - left, None].astype(np.float32) / 255
    img[y0:y1, x0:x1] = img[y0:y1, x0:x1] * (1 - a) + color * a


def _label(img: np.ndarray, rng: np.random.Generator, cx: float, cy: float, scale: float) -> None:
    w, h = scale * rng.uniform(1.2, 2.5), scale * rng.uniform(0.6, 1.2)
    paper = np.array(rng.uniform(0.85, 1.0, 3), np.float32)
    box = cv2.boxPoints(((cx, cy), (w, h), rng.uniform(-8, 8))).astype(np.int32)
    cv2.fillConvexPoly(img, box, paper.tolist(), cv2.LINE_AA)
    lines = int(rng.integers(2, 5))
    ink = np.array([0.1, 0.1, 0.1], np.float32) if rng.random() < 0.7 else np.array([0.5, 0.2, 0.1], np.float32)
    for i in range(lines):
        patch = text_mask(_random_text(rng), str(rng.choice(["sans", "uni"])), int(rng.integers(400, 800)),
                          h / (lines + 1) * 0.55, 1.0)
        _paste_ink(img, patch, int(cx - w / 2 + 0.06 * w), int(cy - h / 2 + (i + 0.35) * h / (lines + 0.3)), ink)


def _ruler(img: np.ndarray, rng: np.random.Generator, cx: float, cy: float, scale: float) -> None:
    """A graduated ruler: the closest look-alike of a scale that is not an apparatus."""
    length, width = scale * rng.uniform(2.5, 5.0), scale * rng.uniform(0.25, 0.45)
    angle = rng.uniform(0, 180)
    canvas = np.full((int(width), int(length), 3), rng.uniform(0.75, 0.97), np.float32)
    canvas *= np.array(rng.uniform(0.85, 1.0, 3), np.float32)
    step = max(3.0, length / rng.uniform(40, 90))
    n = int(length / step)
    for i in range(1, n):
        tall = width * (0.45 if i % 10 == 0 else 0.3 if i % 5 == 0 else 0.18)
        x = int(i * step)
        cv2.line(canvas, (x, 0), (x, int(tall)), (0.1, 0.1, 0.1), 1, cv2.LINE_AA)
        if i % 10 == 0:
            patch = text_mask(str(i // 10), "sans", 500, width * 0.25, 1.0)
            _paste_ink(canvas, patch, x - patch.shape[1] // 2, int(width * 0.52), np.zeros(3, np.float32))
    rot = cv2.getRotationMatrix2D((length / 2, width / 2), angle, 1.0)
    rot[:, 2] += (cx - length / 2, cy - width / 2)
    mask = cv2.warpAffine(np.ones(canvas.shape[:2], np.float32), rot, (img.shape[1], img.shape[0]))
    warped = cv2.warpAffine(canvas, rot, (img.shape[1], img.shape[0]))
    img[:] = img * (1 - mask[..., None]) + warped * mask[..., None]


def _bottle(img: np.ndarray, rng: np.random.Generator, cx: float, cy: float, scale: float) -> None:
    w, h = scale * rng.uniform(0.5, 1.0), scale * rng.uniform(1.2, 2.5)
    color = np.array(rng.uniform(0.2, 0.9, 3), np.float32)
    mask = np.zeros(img.shape[:2], np.uint8)
    cv2.rectangle(mask, (int(cx - w / 2), int(cy - h / 2)), (int(cx + w / 2), int(cy + h / 2)), 255, -1, cv2.LINE_AA)
    cv2.rectangle(mask, (int(cx - w / 5), int(cy - h / 2 - h / 6)), (int(cx + w / 5), int(cy - h / 2)), 255, -1)
    a = cv2.GaussianBlur(mask, (0, 0), 1.0).astype(np.float32)[..., None] / 255
    xs = (np.arange(img.shape[1], dtype=np.float32) - cx) / max(w / 2, 1)
    shade = (0.7 + 0.3 * np.cos(np.clip(xs, -1.4, 1.4)))[None, :, None]
    opacity = rng.uniform(0.4, 0.95)
    img[:] = img * (1 - a * opacity) + (color * shade) * a * opacity


def _box(img: np.ndarray, rng: np.random.Generator, cx: float, cy: float, scale: float) -> None:
    """A cardboard or instrument box: a lit front face, a darker side, a soft contact shadow."""
    w, h = scale * rng.uniform(0.8, 2.2), scale * rng.uniform(0.6, 1.6)
    depth = w * rng.uniform(0.15, 0.35)
    color = rng.uniform(0.3, 0.85, 3).astype(np.float32)
    front = np.array([[cx - w / 2, cy - h / 2], [cx + w / 2, cy - h / 2], [cx + w / 2, cy + h / 2],
                      [cx - w / 2, cy + h / 2]])
    side = np.array([front[1], front[1] + (depth, -depth * 0.5), front[2] + (depth, -depth * 0.5), front[2]])
    top = np.array([front[0], front[0] + (depth, -depth * 0.5), side[1], front[1]])
    shadow = np.zeros(img.shape[:2], np.uint8)
    cv2.fillConvexPoly(shadow, (front + (depth * 0.6, depth * 0.3)).astype(np.int32), 255)
    a = cv2.GaussianBlur(shadow, (0, 0), depth * 0.4 + 1).astype(np.float32)[..., None] / 255
    img *= 1 - 0.35 * a
    for poly, light in ((front, 1.0), (side, 0.7), (top, 1.15)):
        mask = np.zeros(img.shape[:2], np.uint8)
        cv2.fillConvexPoly(mask, poly.astype(np.int32), 255, cv2.LINE_AA)
        m = mask.astype(np.float32)[..., None] / 255
        yy = np.linspace(1.05, 0.9, img.shape[0], dtype=np.float32)[:, None, None]
        img[:] = img * (1 - m) + np.clip(color * light * yy, 0, 1) * m


def _cable(img: np.ndarray, rng: np.random.Generator, width: int, height: int) -> None:
    """A smooth shaded cable (a cubic Bezier) with its highlight."""
    p = rng.uniform(0, 1, (4, 2)) * (width, height)
    t = np.linspace(0, 1, 80)[:, None]
    curve = ((1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1] + 3 * (1 - t) * t**2 * p[2] + t**3 * p[3])
    thick = int(rng.integers(4, 10))
    color = rng.uniform(0.05, 0.35, 3)
    pts = curve.astype(np.int32)
    cv2.polylines(img, [pts + (2, 3)], False, (float(img.mean()) * 0.6,) * 3, thick + 2, cv2.LINE_AA)
    cv2.polylines(img, [pts], False, color.tolist(), thick, cv2.LINE_AA)
    cv2.polylines(img, [pts - (0, thick // 4)], False, (color + 0.25).tolist(), max(1, thick // 4), cv2.LINE_AA)


def _pen(img: np.ndarray, rng: np.random.Generator, cx: float, cy: float, scale: float) -> None:
    length = scale * rng.uniform(1.2, 2.2)
    angle = rng.uniform(0, math.pi)
    d = np.array([math.cos(angle), math.sin(angle)]) * length / 2
    p0, p1 = np.array([cx, cy]) - d, np.array([cx, cy]) + d
    cv2.line(img, tuple(p0.astype(int)), tuple(p1.astype(int)), rng.uniform(0.05, 0.8, 3).tolist(),
             int(max(3, scale * 0.08)), cv2.LINE_AA)


def make_background(rng: np.random.Generator, width: int, height: int, dark: bool,
                    keep_clear_xyxy: tuple[float, float, float, float] | None = None,
                    n_distractors: int = 3) -> np.ndarray:
    """A lab wall and bench (or a bench seen from above), with distractors, float32 BGR in [0, 1]."""
    base = rng.uniform(0.12, 0.32) if dark else rng.uniform(0.7, 0.95)
    wall_tint = np.array(rng.uniform(0.93, 1.0, 3), np.float32)
    img = np.full((height, width, 3), base, np.float32) * wall_tint
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
    gx, gy = rng.uniform(-0.12, 0.12, 2)
    img *= (1 + gx * (xx / width - 0.5) + gy * (yy / height - 0.5))[..., None]
    img += 0.012 * _smooth_noise(rng, height, width, rng.uniform(80, 200))[..., None]
    img += 0.006 * _smooth_noise(rng, height, width, 4)[..., None]  # fine paint texture
    if rng.random() < 0.7:  # a bench edge with its own surface
        horizon = height * rng.uniform(0.55, 0.95)
        tilt = math.tan(math.radians(rng.uniform(-4, 4)))
        below = (yy > horizon + (xx - width / 2) * tilt).astype(np.float32)
        below = cv2.GaussianBlur(below, (0, 0), 1.2)[..., None]
        if rng.random() < 0.5:  # wood
            grain = 0.05 * np.sin(xx / rng.uniform(2, 5) + 0.8 * _smooth_noise(rng, height, width, 60)) \
                + 0.03 * _smooth_noise(rng, height, width, 12)
            bench = np.array([0.33, 0.48, 0.62], np.float32) * rng.uniform(0.7, 1.2) * (1 + grain[..., None])
        else:  # laminate
            bench = np.full((height, width, 3), rng.uniform(0.35, 0.9), np.float32) * wall_tint
        img = img * (1 - below) + bench * below
    if rng.random() < 0.3:  # a dark post of a frame or a shelf
        x = rng.uniform(0, width)
        cv2.rectangle(img, (int(x), 0), (int(x + rng.uniform(8, 40)), height), rng.uniform(0.1, 0.35, 3).tolist(), -1)
    for _ in range(int(rng.integers(0, 25))):  # specks on the wall
        cv2.circle(img, (int(rng.uniform(0, width)), int(rng.uniform(0, height))), int(rng.integers(1, 3)),
                   (base * 0.4,) * 3, -1, cv2.LINE_AA)
    scale = min(width, height) * 0.18
    for _ in range(n_distractors):
        for _try in range(10):
            cx, cy = rng.uniform(0, width), rng.uniform(0, height)
            if keep_clear_xyxy is None or not (keep_clear_xyxy[0] - scale < cx < keep_clear_xyxy[2] + scale
                                               and keep_clear_xyxy[1] - scale < cy < keep_clear_xyxy[3] + scale):
                break
        else:
            continue
        pick = rng.integers(0, 7)
        if pick == 0:
            _label(img, rng, cx, cy, scale)
        elif pick == 1:
            _ruler(img, rng, cx, cy, scale)
        elif pick == 2:
            _bottle(img, rng, cx, cy, scale)
        elif pick == 3:
            _box(img, rng, cx, cy, scale)
        elif pick == 4:
            _cable(img, rng, width, height)
        elif pick == 5:
            _pen(img, rng, cx, cy, scale)
        else:
            _label(img, rng, cx, cy, scale * 0.7)
    # the background is further away than the apparatus: a little out of focus
    img = cv2.GaussianBlur(img, (0, 0), float(rng.uniform(0.4, 2.0)))
    return np.clip(img, 0, 1)


def draw_hand(img: np.ndarray, center_xy: tuple[float, float], size_px: float, angle_deg: float,
              skin_bgr: tuple[float, float, float]) -> np.ndarray:
    """A hand (palm and fingers) in front of the scene; returns its coverage mask."""
    h, w = img.shape[:2]
    mask = np.zeros((h, w), np.uint8)
    cx, cy = center_xy
    rot = math.radians(angle_deg)
    ca, sa = math.cos(rot), math.sin(rot)

    def pt(dx: float, dy: float) -> tuple[int, int]:
        return int(cx + ca * dx - sa * dy), int(cy + sa * dx + ca * dy)

    cv2.ellipse(mask, pt(0, 0), (int(size_px * 0.42), int(size_px * 0.5)), angle_deg, 0, 360, 255, -1, cv2.LINE_AA)
    for i, length in enumerate((0.75, 0.85, 0.8, 0.62)):
        x = (i - 1.5) * size_px * 0.21
        cv2.line(mask, pt(x, -size_px * 0.3), pt(x * 1.1, -size_px * (0.3 + length)), 255,
                 int(size_px * 0.17), cv2.LINE_AA)
    cv2.line(mask, pt(size_px * 0.35, size_px * 0.1), pt(size_px * 0.8, -size_px * 0.25), 255,
             int(size_px * 0.19), cv2.LINE_AA)
    a = cv2.GaussianBlur(mask, (0, 0), 1.5).astype(np.float32) / 255
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    shade = 0.8 + 0.2 * np.cos(np.clip(((xx - cx) * ca + (yy - cy) * sa) / (size_px * 0.6), -1.5, 1.5))
    skin = np.asarray(skin_bgr, np.float32)[None, None, :] * shade[..., None]
    img[:] = img * (1 - a[..., None]) + skin * a[..., None]
    return a
