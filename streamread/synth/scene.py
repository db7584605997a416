"""Random scenes and their rendering: apparatus, look, camera, background, light, sensor.

Every random choice is drawn from ``RANGES`` with one ``numpy.random.Generator`` seeded by
the caller, so a seed names an image exactly. ``render`` is a pure function of the
parameters (plus a level, pose and occluder for video frames).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from streamread.apparatus import CATALOGUE, KINDS, ApparatusSpec, format_value, get_spec
from streamread.errors import InputError, expected
from streamread.synth import camera
from streamread.synth.background import draw_hand, make_background
from streamread.synth.camera import CameraPose
from streamread.synth.canvas import Canvas
from streamread.synth.draw import Look, draw_apparatus, extent_mm
from streamread.synth.photo import Photometry, expose, illuminate
from streamread.synth.truth import MarkTruth, SceneTruth

# Documented randomisation ranges (uniform unless a list of choices).
RANGES: dict[str, object] = {
    "roll_deg": (0.0, 360.0),  # in-plane rotation of the apparatus, full circle
    "size_fraction": (0.25, 0.95),  # apparatus length / longest segment of the frame along its axis
    "min_px_per_division": 5.0,  # below this the camera zooms in on the level (partial view, as burettes need)
    "pitch_deg": (-15.0, 15.0),  # perspective tilt of the apparatus plane, top towards/away from the camera
    "yaw_deg": (-15.0, 15.0),  # perspective tilt about the apparatus axis
    "focal_over_width": (0.8, 1.8),  # focal length / frame width (wide webcam to short tele)
    "scale_turn_deg": (-35.0, 35.0),  # scale turned away from the camera about the tube axis: foreshortened marks
    "elevation_deg": (-1.5, 1.5),  # camera slightly above/below the level: rings curve
    "ink": ["black", "blue", "brown", "white"],  # white print comes with a dark background
    "fonts": ["sans", "uni"],  # OpenCV 5's built-in TrueType sans faces
    "font_weight": (350, 750),
    "text_squeeze": (0.8, 1.1),
    "mark_thickness_mm": (0.18, 0.35),
    "gain": (0.75, 1.15),  # overall exposure
    "gradient": (-0.35, 0.35),  # illumination slope across the frame, per axis
    "vignette": (0.0, 0.35),
    "white_balance": (0.94, 1.06),  # per-channel gain
    "glare_count": (0, 2),
    "glare_strength": (0.05, 0.45),
    "blur_sigma_px": (0.0, 1.2),
    "read_noise": (0.002, 0.015),  # additive sensor noise std (0..1 scale)
    "shot_noise": (0.0, 0.002),  # signal-dependent variance
    "jpeg_quality": (45, 95),
    "distractors": (0, 6),
    "shadow_strength": (0.0, 0.35),  # soft shadow of the apparatus on the wall
    "frame_sizes": [(640, 480), (800, 600), (1024, 768), (1280, 720)],
}

INKS: dict[str, tuple[float, float, float]] = {
    "black": (0.08, 0.08, 0.08),
    "blue": (0.58, 0.24, 0.08),
    "brown": (0.1, 0.24, 0.46),
    "white": (0.95, 0.95, 0.95),
}
LIQUIDS: list[tuple[float, float, float]] = [
    (0.9, 0.55, 0.2),  # blue
    (0.35, 0.85, 0.95),  # yellow
    (0.3, 0.32, 0.9),  # red
    (0.45, 0.85, 0.4),  # green
    (0.25, 0.55, 0.85),  # amber
]

MIN_DIGIT_PX = 12.0  # printed digits are at least this tall in the image
KIND_WEIGHTS = (0.4, 0.35, 0.25)  # syringe, measuring_cylinder, burette
BASES: list[tuple[float, float, float]] = [(0.55, 0.25, 0.08), (0.5, 0.3, 0.1), (0.9, 0.9, 0.9), (0.1, 0.45, 0.9)]


@dataclass(frozen=True)
class SceneParams:
    """Everything that decides one scene except the level and per-frame events."""

    apparatus: str
    level_ml: float
    look: Look
    pose: CameraPose
    photometry: Photometry
    frame_wh: tuple[int, int]
    background_seed: int
    n_distractors: int
    dark_background: bool
    noise_seed: int
    shadow: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        spec = get_spec(self.apparatus)
        lo, hi = level_range(spec)
        if not lo - 1e-9 <= self.level_ml <= hi + 1e-9:
            raise ValueError(expected("scene", "level_ml", f"within [{lo}, {hi}]", self.level_ml))
        if self.frame_wh[0] < 16 or self.frame_wh[1] < 16:
            raise ValueError(expected("scene", "frame_wh", "at least 16x16", self.frame_wh))

    @property
    def spec(self) -> ApparatusSpec:
        return get_spec(self.apparatus)


def level_range(spec: ApparatusSpec) -> tuple[float, float]:
    """Levels a scene may show: syringes from 0, cylinders from their first mark, burettes 0..capacity."""
    if spec.kind == "measuring_cylinder":
        return spec.graduation.first_ml, spec.capacity_ml
    return 0.0, spec.capacity_ml


def _u(rng: np.random.Generator, key: str) -> float:
    lo, hi = RANGES[key]  # type: ignore[misc]
    return float(rng.uniform(lo, hi))


def _resolve_apparatus(rng: np.random.Generator, apparatus: str | None) -> ApparatusSpec:
    if apparatus is None:
        kind = KINDS[int(rng.choice(len(KINDS), p=KIND_WEIGHTS))]
        names = [n for n, s in CATALOGUE.items() if s.kind == kind]
        return CATALOGUE[names[int(rng.integers(0, len(names)))]]
    if apparatus in KINDS:
        names = [n for n, s in CATALOGUE.items() if s.kind == apparatus]
        return CATALOGUE[names[int(rng.integers(0, len(names)))]]
    if apparatus == "cylinder":
        return _resolve_apparatus(rng, "measuring_cylinder")
    if apparatus in CATALOGUE:
        return CATALOGUE[apparatus]
    raise InputError(expected("apparatus", repr(apparatus), "a kind (" + ", ".join(KINDS) + ") or one of "
                              + ", ".join(CATALOGUE), "an unknown name"))


def max_text_height_mm(spec: ApparatusSpec) -> float:
    """Tallest number that still fits on the face of the tube (its width within about 40 degrees)."""
    chars = max(len(spec.graduation.label(t) or "") for t in spec.graduation.ticks)
    return spec.outer_radius_mm * math.radians(40) / (0.62 * max(chars, 1))


def _label_vertical(rng: np.random.Generator, spec: ApparatusSpec) -> str:
    """Where a number sits against its long mark: centred beside it, or above it.

    A burette's long marks are full rings around the tube, so a number centred on one would be
    struck through by the ring: burettes carry their numbers above the ring (as the real ones
    in ``real-dev`` do). The choice is still drawn for them, so that every later random choice
    of a seed, and so the rest of its scene, stays what it was.
    """
    if spec.kind == "syringe":
        return str(rng.choice(["center", "center", "center", "above"]))
    drawn = str(rng.choice(["center", "above"]))
    return "above" if spec.kind == "burette" else drawn


def sample_look(rng: np.random.Generator, spec: ApparatusSpec, px_per_mm: float, ink: str) -> Look:
    ro = spec.outer_radius_mm
    label_spacing_mm = spec.graduation.label_every * spec.division_mm
    if spec.kind == "syringe":
        text_h = rng.uniform(0.17, 0.26) * 2 * ro
        aligned = str(rng.choice(["left", "right"]))
    elif spec.kind == "measuring_cylinder":
        text_h = rng.uniform(0.12, 0.2) * 2 * ro
        aligned = str(rng.choice(["left", "right", "center"]))
    else:
        text_h = rng.uniform(2.2, 3.5)
        aligned = "center"
    text_h = min(text_h, 0.55 * label_spacing_mm, max_text_height_mm(spec))
    text_h = max(text_h, MIN_DIGIT_PX / px_per_mm)  # print a human can read at this distance
    if aligned == "center":
        label_side = "right"
    else:
        label_side = str(rng.choice(["left", "right"]))
    minor_span = rng.uniform(14, 24) if spec.kind != "burette" else rng.uniform(40, 60)
    spans = (minor_span, minor_span * rng.uniform(1.4, 1.7), minor_span * rng.uniform(1.9, 2.6))
    turn = _u(rng, "scale_turn_deg")
    # keep the numbers within +-40 degrees of the line of sight: a user turns the scale to face the camera
    label_width_deg = math.degrees(0.6 * text_h * len(format_value(spec.capacity_ml)) / ro)
    major_half = spans[2] / 2 if spec.kind != "burette" else spans[1] / 2
    if label_side == "right":
        centre = major_half + 6 + label_width_deg / 2
    else:
        centre = -(major_half + 6 + label_width_deg / 2)
    if aligned == "right" and label_side == "right":
        centre = major_half + 6 + label_width_deg / 2
    turn = float(np.clip(turn, -40 - centre, 40 - centre))
    thickness = max(_u(rng, "mark_thickness_mm"), 0.9 / px_per_mm)
    thickness = min(thickness, 0.3 * spec.division_mm)
    if spec.kind == "syringe":
        options: list[tuple[str, ...]] = [("ml",), ("mL",), ("ml", "LUER"), ()]
    else:
        options = [("mL",), ("ml", "20 C"), ("mL", "CLASS B"), ("TC", "mL"), ()]
    extra = options[int(rng.integers(0, len(options)))]
    coloured = rng.random() < 0.5
    liquid = LIQUIDS[int(rng.integers(0, len(LIQUIDS)))] if coloured else tuple(rng.uniform(0.95, 0.99, 3))
    side = 1.0 if rng.random() < 0.5 else -1.0
    ri = spec.inner_radius_mm
    return Look(
        ink_bgr=INKS[ink],
        ink_alpha=float(rng.uniform(0.8, 1.0)),
        font=str(rng.choice(RANGES["fonts"])),  # type: ignore[arg-type]
        font_weight=int(rng.integers(*RANGES["font_weight"])),  # type: ignore[misc]
        text_height_mm=float(text_h),
        text_squeeze=_u(rng, "text_squeeze"),
        marks_aligned=aligned,
        label_side=label_side,
        label_vertical=_label_vertical(rng, spec),
        mark_thickness_mm=float(thickness),
        mark_span_deg=tuple(float(s) for s in spans),  # type: ignore[arg-type]
        scale_turn_deg=turn,
        elevation_deg=_u(rng, "elevation_deg"),
        extra_text=tuple(str(t) for t in extra),
        glass_haze=float(rng.uniform(0.04, 0.14) if spec.kind == "syringe" else rng.uniform(0.0, 0.04)),
        glass_tint_bgr=(0.98, 0.98, 0.98) if spec.kind == "syringe" else (0.96, 0.99, 0.96),
        wall_transmission=float(rng.uniform(0.55, 0.85)),
        specular_pos=side * float(rng.uniform(0.4, 0.75)),
        specular_width=float(rng.uniform(0.04, 0.12)),
        specular_strength=float(rng.uniform(0.1, 0.5)),
        liquid_bgr=tuple(float(c) for c in liquid),  # type: ignore[arg-type]
        liquid_density=float(rng.uniform(0.25, 0.8) if coloured else rng.uniform(0.02, 0.1)),
        liquid_in_syringe=bool(rng.random() < 0.7),
        refraction_gain=float(rng.uniform(0.3, 0.7)),
        meniscus_depth_mm=float(min(0.3 * ri, rng.uniform(0.4, 1.2))),
        meniscus_band_mm=float(max(rng.uniform(0.4, 1.0), 1.5 / px_per_mm)),
        meniscus_darkness=float(rng.uniform(0.5, 0.9)),
        stopper_bgr=tuple(float(c) for c in rng.uniform(0.08, 0.2) * rng.uniform(0.9, 1.1, 3)),  # type: ignore[arg-type]
        stopper_length_ratio=float(rng.uniform(0.55, 0.85)),
        stopper_cone_ratio=float(0.0 if rng.random() < 0.3 else rng.uniform(0.1, 0.35)),
        rod_bgr=tuple(float(c) for c in rng.uniform(0.85, 0.97) * np.ones(3)),  # type: ignore[arg-type]
        rod_alpha=float(rng.uniform(0.4, 0.75)),
        base_bgr=tuple(float(c) * float(rng.uniform(0.8, 1.1)) for c in BASES[int(rng.integers(0, len(BASES)))]),  # type: ignore[arg-type]
        base_is_glass=bool(rng.random() < 0.35),
        spout_side=1 if rng.random() < 0.5 else -1,
        ink_texture_seed=int(rng.integers(0, 2**31)),
    )


def _fit_length(width: int, height: int, roll_deg: float) -> float:
    """Longest segment through the frame centre along the apparatus axis at this roll."""
    c, s = abs(math.cos(math.radians(roll_deg))), abs(math.sin(math.radians(roll_deg)))
    return min(height / max(c, 1e-6), width / max(s, 1e-6))


def sample_scene(seed: int | np.random.Generator, apparatus: str | None = None, level_ml: float | None = None,
                 frame_wh: tuple[int, int] | None = None, min_px_per_division: float | None = None,
                 roll_deg: float | None = None, photometric: bool = True, size_fraction: float | None = None,
                 tilt_scale: float = 1.0, centered: bool = False) -> SceneParams:
    """A random scene. ``apparatus``: a catalogue name, a kind, or None for any.

    The keyword options pin what a recording or a test needs fixed: the roll, the size,
    less perspective (``tilt_scale`` multiplies the tilt ranges), the apparatus centred.
    """
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    spec = _resolve_apparatus(rng, apparatus)
    if frame_wh is None:
        sizes = RANGES["frame_sizes"]
        frame_wh = tuple(sizes[int(rng.integers(0, len(sizes)))])  # type: ignore[arg-type, index]
    width, height = frame_wh
    lo, hi = level_range(spec)
    if level_ml is None:
        level_ml = float(rng.uniform(lo, hi))
    min_ppd = float(RANGES["min_px_per_division"] if min_px_per_division is None else min_px_per_division)  # type: ignore[arg-type]

    roll = _u(rng, "roll_deg") if roll_deg is None else float(roll_deg)
    x0, x1, y0, y1 = extent_mm(spec, spec.capacity_ml if spec.kind == "syringe" else level_ml)
    length_mm = y1 - y0
    size = _u(rng, "size_fraction") if size_fraction is None else float(size_fraction)
    px_per_mm = size * _fit_length(width, height, roll) / length_mm
    # close enough that a division spans min_ppd pixels and the numbers are MIN_DIGIT_PX tall
    needed = max(min_ppd / spec.division_mm, MIN_DIGIT_PX / max_text_height_mm(spec))
    partial = px_per_mm < needed
    if partial:
        px_per_mm = needed * float(rng.uniform(1.0, 1.35))
    y_level = spec.y_mm(level_ml)
    if partial:
        view_mm = _fit_length(width, height, roll) / px_per_mm
        anchor_mm = (0.0, y_level + float(rng.uniform(-0.2, 0.2)) * view_mm)
        anchor_px = (width / 2 + float(rng.uniform(-0.1, 0.1)) * width, height / 2 + float(rng.uniform(-0.1, 0.1)) * height)
    else:
        anchor_mm = (0.0, (y0 + y1) / 2)
        c, s = abs(math.cos(math.radians(roll))), abs(math.sin(math.radians(roll)))
        half_len, half_w = length_mm * px_per_mm / 2, (x1 - x0) * px_per_mm / 2
        bx, by = s * half_len + c * half_w, c * half_len + s * half_w
        ax = float(rng.uniform(bx, width - bx)) if bx < width / 2 and not centered else width / 2
        ay = float(rng.uniform(by, height - by)) if by < height / 2 and not centered else height / 2
        anchor_px = (ax, ay)
    pose = CameraPose(px_per_mm=px_per_mm, roll_deg=roll, pitch_deg=tilt_scale * _u(rng, "pitch_deg"),
                      yaw_deg=tilt_scale * _u(rng, "yaw_deg"),
                      focal_px=width * _u(rng, "focal_over_width"), anchor_mm=anchor_mm, anchor_px=anchor_px)

    ink = str(rng.choice(RANGES["ink"], p=[0.45, 0.25, 0.2, 0.1]))  # type: ignore[arg-type]
    look = sample_look(rng, spec, px_per_mm, ink)
    glare = tuple((float(rng.uniform(0, 1)), float(rng.uniform(0, 1)), float(rng.uniform(0.03, 0.15)),
                   _u(rng, "glare_strength")) for _ in range(int(rng.integers(0, 3))))
    photometry = Photometry(
        gain=_u(rng, "gain"), gradient_xy=(_u(rng, "gradient"), _u(rng, "gradient")), vignette=_u(rng, "vignette"),
        white_balance_bgr=tuple(float(g) for g in rng.uniform(*RANGES["white_balance"], 3)),  # type: ignore[arg-type]
        glare=glare, blur_sigma_px=_u(rng, "blur_sigma_px"), read_noise=_u(rng, "read_noise"),
        shot_noise=_u(rng, "shot_noise"), jpeg_quality=int(rng.integers(45, 96)),
    )
    if not photometric:
        photometry = Photometry()
    return SceneParams(apparatus=spec.name, level_ml=float(level_ml), look=look, pose=pose, photometry=photometry,
                       frame_wh=(int(width), int(height)), background_seed=int(rng.integers(0, 2**31)),
                       n_distractors=int(rng.integers(0, 7)), dark_background=ink == "white",
                       noise_seed=int(rng.integers(0, 2**31)),
                       shadow=(float(rng.uniform(-0.04, 0.04)), float(rng.uniform(0.0, 0.04)),
                               float(rng.uniform(0.01, 0.03)), float(rng.uniform(0.0, 0.35))))


@functools.lru_cache(maxsize=4)
def _background(seed: int, width: int, height: int, dark: bool, n_distractors: int,
                keep_clear: tuple[float, float, float, float] | None) -> np.ndarray:
    bg = make_background(np.random.default_rng(seed), width, height, dark, keep_clear, n_distractors)
    bg.setflags(write=False)
    return bg


def background_of(params: SceneParams) -> np.ndarray:
    """The scene's background (cached: video frames share it)."""
    h = camera.homography_mm_to_px(params.pose)
    x0, x1, y0, y1 = extent_mm(params.spec, params.level_ml)
    corners = camera.apply(h, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
    keep = (float(corners[:, 0].min()), float(corners[:, 1].min()), float(corners[:, 0].max()), float(corners[:, 1].max()))
    return _background(params.background_seed, params.frame_wh[0], params.frame_wh[1], params.dark_background,
                       params.n_distractors, keep)


@dataclass(frozen=True)
class Hand:
    """A hand in front of the camera: centre in pixels, size (palm to fingertip) and angle."""

    center_px: tuple[float, float]
    size_px: float
    angle_deg: float = 0.0
    skin_bgr: tuple[float, float, float] = (0.55, 0.66, 0.86)


def _visible_window(h_mm: np.ndarray, width: int, height: int, ext: tuple[float, float, float, float],
                    ) -> tuple[float, float] | None:
    """Axial range (mm) of the apparatus that can appear in the frame."""
    margin = 0.15 * max(width, height)
    frame = np.array([[-margin, -margin], [width + margin, -margin], [width + margin, height + margin],
                      [-margin, height + margin]])
    inv = np.linalg.inv(h_mm)
    hom = np.column_stack([frame, np.ones(4)]) @ inv.T
    if np.any(hom[:, 2] <= 0):  # the plane's horizon is in view: take everything
        return ext[2], ext[3]
    pts = hom[:, :2] / hom[:, 2:3]
    lo, hi = max(ext[2], pts[:, 1].min()), min(ext[3], pts[:, 1].max())
    if lo >= hi:
        return None
    # an apparatus that lies across the frame is seen whole: x must also overlap
    if pts[:, 0].max() < ext[0] or pts[:, 0].min() > ext[1]:
        return None
    return float(lo), float(hi)


_MAX_CANVAS_PX = 4_000_000


def _shadow(coverage: np.ndarray, shadow: tuple[float, float, float, float]) -> np.ndarray:
    """Soft shadow of the apparatus on the wall behind it: (dx_frac, dy_frac, blur_frac, strength)."""
    dx, dy, blur, strength = shadow
    if strength <= 0:
        return np.zeros_like(coverage)
    h, w = coverage.shape
    size = max(h, w)
    moved = cv2.warpAffine(coverage, np.float32([[1, 0, dx * size], [0, 1, dy * size]]), (w, h))
    small = cv2.resize(moved, (w // 4 + 1, h // 4 + 1), interpolation=cv2.INTER_AREA)
    small = cv2.GaussianBlur(small, (0, 0), max(blur * size / 4, 0.5))
    return strength * cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)


def render(params: SceneParams, level_ml: float | None = None, pose: CameraPose | None = None,
           hand: Hand | None = None, noise_seed: int | None = None) -> tuple[np.ndarray, SceneTruth]:
    """Render the scene (optionally at another level, pose, with a hand): uint8 BGR image and its truth."""
    spec = params.spec
    level = params.level_ml if level_ml is None else float(level_ml)
    lo, hi = level_range(spec)
    if not lo - 1e-9 <= level <= hi + 1e-9:
        raise ValueError(expected("render", "level_ml", f"within [{lo}, {hi}]", level))
    pose = params.pose if pose is None else pose
    width, height = params.frame_wh
    bg = background_of(params)
    h_mm = camera.homography_mm_to_px(pose)
    ext = extent_mm(spec, level)
    window = _visible_window(h_mm, width, height, ext)
    scene = bg.copy()
    coverage = np.zeros((height, width), np.float32)
    marks: list[MarkTruth] = []
    if window is not None:
        ppm = max(camera.local_scale(h_mm, (0.0, y)) for y in window)
        k = 2.0 * ppm
        span_x, span_y = ext[1] - ext[0], window[1] - window[0]
        k = min(k, math.sqrt(_MAX_CANVAS_PX / max(span_x * span_y, 1e-6)))
        canvas = Canvas(ext[0], ext[1], window[0], window[1], k)
        h_canvas = h_mm @ canvas.px_to_mm_matrix()
        bg_canvas = cv2.warpPerspective(bg, np.linalg.inv(h_canvas), (canvas.width, canvas.height),
                                        flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        drawing = draw_apparatus(spec, params.look, level, canvas, bg_canvas)
        premult = np.dstack([drawing.color * drawing.alpha[..., None], drawing.alpha])
        sigma = 0.45 * k / ppm
        if sigma > 0.3:
            premult = cv2.GaussianBlur(premult, (0, 0), sigma)
        warped = cv2.warpPerspective(premult, h_canvas, (width, height), flags=cv2.INTER_LINEAR,
                                     borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        coverage = warped[..., 3]
        shadow = _shadow(coverage, params.shadow)
        scene = scene * (1 - shadow[..., None]) * (1 - coverage[..., None]) + warped[..., :3]
        for m in drawing.marks:
            pts = camera.apply(h_mm, np.array([m.center_mm, m.ends_mm[0], m.ends_mm[1]]))
            cx, cy = pts[0]
            marks.append(MarkTruth(value_ml=m.value_ml, tier=m.tier, label=m.label, center_px=(float(cx), float(cy)),
                                   ends_px=((float(pts[1, 0]), float(pts[1, 1])), (float(pts[2, 0]), float(pts[2, 1]))),
                                   in_frame=bool(0 <= cx <= width - 1 and 0 <= cy <= height - 1)))
        indicator_mm, line_mm = drawing.indicator_mm, drawing.indicator_line_mm
    else:
        indicator_mm, line_mm = (0.0, spec.y_mm(level)), ((-1.0, spec.y_mm(level)), (1.0, spec.y_mm(level)))

    occluded = False
    ind = camera.apply(h_mm, np.array([indicator_mm]))[0]
    if hand is not None:
        hand_cov = draw_hand(scene, hand.center_px, hand.size_px, hand.angle_deg, hand.skin_bgr)
        ix, iy = int(round(ind[0])), int(round(ind[1]))
        if 0 <= ix < width and 0 <= iy < height:
            occluded = bool(hand_cov[iy, ix] > 0.3)
    rng = np.random.default_rng(params.noise_seed if noise_seed is None else noise_seed)
    image = expose(illuminate(scene, params.photometry), params.photometry, rng)

    box = None
    solid = (coverage > 0.5).astype(np.uint8)
    if solid.any():
        bx, by, bw, bh = cv2.boundingRect(solid)
        box = (float(bx), float(by), float(bx + bw - 1), float(by + bh - 1))
    g = spec.graduation
    axis = camera.apply(h_mm, np.array([[0.0, spec.y_mm(g.first_ml)], [0.0, spec.y_mm(g.last_ml)]]))
    step = camera.apply(h_mm, np.array([[0.0, spec.y_mm(level)], [0.0, spec.y_mm(level + g.minor_ml)]]))
    line = camera.apply(h_mm, np.array(line_mm))
    truth = SceneTruth(
        apparatus=spec.name, kind=spec.kind, minor_ml=g.minor_ml, level_ml=level,
        indicator_px=(float(ind[0]), float(ind[1])),
        indicator_line_px=((float(line[0, 0]), float(line[0, 1])), (float(line[1, 0]), float(line[1, 1]))),
        indicator_in_frame=bool(window is not None and 0 <= ind[0] <= width - 1 and 0 <= ind[1] <= height - 1),
        box_xyxy=box,
        axis_px=((float(axis[0, 0]), float(axis[0, 1])), (float(axis[1, 0]), float(axis[1, 1]))),
        axis_values_ml=(g.first_ml, g.last_ml), marks=tuple(marks),
        px_per_division=float(np.hypot(*(step[1] - step[0]))), occluded=occluded,
    )
    return image, truth


def render_still(seed: int, apparatus: str | None = None, **kwargs: object) -> tuple[np.ndarray, SceneTruth]:
    """One random still: ``render(sample_scene(seed, apparatus, ...))``."""
    return render(sample_scene(seed, apparatus, **kwargs))  # type: ignore[arg-type]

