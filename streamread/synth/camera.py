"""Pinhole camera looking at the apparatus plane: the homography from millimetres to pixels.

The apparatus is drawn upright in its own plane (x across, y along the axis, up). A camera
at distance ``focal_px / px_per_mm`` looks at the anchor point; the plane is tilted by
``pitch`` (top towards the camera) and ``yaw``, then rolled in the image by ``roll``.
Pixel coordinates follow OpenCV: pixel centres at integers, y down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CameraPose:
    px_per_mm: float
    roll_deg: float
    pitch_deg: float
    yaw_deg: float
    focal_px: float
    anchor_mm: tuple[float, float]
    anchor_px: tuple[float, float]

    def __post_init__(self) -> None:
        if self.px_per_mm <= 0 or self.focal_px <= 0:
            raise ValueError(f"camera: expected px_per_mm and focal_px > 0, got {self.px_per_mm}, {self.focal_px}")

    def moved(self, dx_px: float = 0.0, dy_px: float = 0.0, droll_deg: float = 0.0) -> CameraPose:
        """The same camera after the apparatus shifted and rolled in the image (bump, leave)."""
        return CameraPose(self.px_per_mm, self.roll_deg + droll_deg, self.pitch_deg, self.yaw_deg, self.focal_px,
                          self.anchor_mm, (self.anchor_px[0] + dx_px, self.anchor_px[1] + dy_px))


def _rot(axis: str, deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def homography_mm_to_px(pose: CameraPose) -> np.ndarray:
    """3x3 H with [u, v, w] = H @ [x_mm, y_mm, 1]."""
    ax, ay = pose.anchor_mm
    to_plane = np.array([[1.0, 0.0, -ax], [0.0, -1.0, ay], [0.0, 0.0, 1.0]])
    # negative roll: a positive roll_deg turns the apparatus counter-clockwise on screen
    rotation = _rot("z", -pose.roll_deg) @ _rot("x", pose.pitch_deg) @ _rot("y", pose.yaw_deg)
    distance = pose.focal_px / pose.px_per_mm
    extrinsic = np.column_stack([rotation[:, 0], rotation[:, 1], [0.0, 0.0, distance]])
    f = pose.focal_px
    intrinsic = np.array([[f, 0, pose.anchor_px[0]], [0, f, pose.anchor_px[1]], [0, 0, 1.0]])
    h = intrinsic @ extrinsic @ to_plane
    return h / h[2, 2]


def apply(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map (N, 2) points through a homography."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    hom = np.column_stack([pts, np.ones(len(pts))]) @ h.T
    return hom[:, :2] / hom[:, 2:3]


def local_scale(h: np.ndarray, point_mm: tuple[float, float], direction: tuple[float, float] = (0.0, 1.0)) -> float:
    """Pixels per millimetre along ``direction`` at a point (the foreshortened magnification)."""
    eps = 0.5
    p0 = np.array(point_mm, dtype=np.float64)
    d = np.array(direction, dtype=np.float64) / np.hypot(*direction)
    a, b = apply(h, np.stack([p0 - eps * d, p0 + eps * d]))
    return float(np.hypot(*(b - a)) / (2 * eps))
