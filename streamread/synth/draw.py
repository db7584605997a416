"""Drawing one apparatus upright on its canvas: tube optics, liquid, indicator, printed scale.

Optics are simple but physical in kind: the background is seen through the tube
(refracted: mirrored and squeezed behind liquid), walls darken at grazing angles, specular
stripes run along the glass, liquid absorbs more along longer paths, the meniscus is a dark
band whose lowest point is the level, and the print sits on the outer surface of a
cylinder, so a scale turned away from the camera is foreshortened and rings curve when the
camera is slightly above or below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from streamread.apparatus import ApparatusSpec, Tier
from streamread.synth.canvas import Canvas, over, rect, support

BGR = tuple[float, float, float]


@dataclass(frozen=True)
class Look:
    """How one apparatus looks: print, glass, liquid, indicator. Sampled by ``scene.sample_look``."""

    ink_bgr: BGR = (0.08, 0.08, 0.08)
    ink_alpha: float = 0.95
    font: str = "sans"
    font_weight: int = 500
    text_height_mm: float = 2.2
    text_squeeze: float = 1.0
    marks_aligned: str = "left"  # left | right | center
    label_side: str = "right"  # left | right of the marks
    label_vertical: str = "center"  # center | above
    mark_thickness_mm: float = 0.3
    mark_span_deg: tuple[float, float, float] = (22.0, 32.0, 44.0)  # minor, medium, major
    scale_turn_deg: float = 0.0
    elevation_deg: float = 0.0
    extra_text: tuple[str, ...] = ()
    glass_haze: float = 0.03
    glass_tint_bgr: BGR = (0.97, 0.99, 0.97)
    wall_transmission: float = 0.7
    specular_pos: float = 0.6  # fraction of the inner radius, signed: the light's side
    specular_width: float = 0.06
    specular_strength: float = 0.3
    liquid_bgr: BGR = (0.97, 0.97, 0.95)
    liquid_density: float = 0.1
    liquid_in_syringe: bool = True
    refraction_gain: float = 0.55
    meniscus_depth_mm: float = 0.8
    meniscus_band_mm: float = 0.7
    meniscus_darkness: float = 0.75
    stopper_bgr: BGR = (0.12, 0.12, 0.13)
    stopper_length_ratio: float = 0.7
    stopper_cone_ratio: float = 0.2
    rod_bgr: BGR = (0.93, 0.93, 0.93)
    rod_alpha: float = 0.55
    base_bgr: BGR = (0.55, 0.25, 0.08)
    base_is_glass: bool = False
    spout_side: int = 1
    ink_texture_seed: int = 0


@dataclass
class MarkGeometry:
    tick: int
    value_ml: float
    tier: Tier
    label: str | None
    center_mm: tuple[float, float]
    ends_mm: tuple[tuple[float, float], tuple[float, float]]


@dataclass
class Drawing:
    color: np.ndarray  # (H, W, 3) float32, not premultiplied
    alpha: np.ndarray  # (H, W) float32
    marks: list[MarkGeometry] = field(default_factory=list)
    indicator_mm: tuple[float, float] = (0.0, 0.0)
    indicator_line_mm: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0), (0.0, 0.0))
    outline_mm: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))


# ----------------------------------------------------------------------------- geometry

def _top_of_tube(spec: ApparatusSpec) -> float:
    g = spec.graduation
    length = abs(spec.y_mm(g.last_ml) - spec.y_mm(g.first_ml))
    if spec.kind == "syringe":
        return spec.y_mm(spec.capacity_ml) + 0.14 * length + 3.0
    if spec.kind == "measuring_cylinder":
        return spec.y_mm(spec.capacity_ml) + 0.16 * length + 6.0
    return 45.0


def _bottom_of_tube(spec: ApparatusSpec) -> float:
    if spec.kind == "syringe":
        return -1.5
    if spec.kind == "measuring_cylinder":
        return -4.0
    return spec.y_mm(spec.capacity_ml) - 30.0


def extent_mm(spec: ApparatusSpec, level_ml: float) -> tuple[float, float, float, float]:
    """(x_min, x_max, y_min, y_max) of everything drawn, for the canvas window and the box."""
    ro = spec.outer_radius_mm
    if spec.kind == "syringe":
        top = _top_of_tube(spec)
        rod_top = spec.y_mm(level_ml) + top + 12.0
        half = 2.3 * ro + 1.0
        return -half, half, -13.0, rod_top + 2.5
    if spec.kind == "measuring_cylinder":
        half = max(1.6 * ro + 4.0, ro + 5.0)
        return -half, half, -4.0 - 14.0, _top_of_tube(spec) + 2.0
    half = ro + 1.0
    return -half, half, _bottom_of_tube(spec) - 25.0, _top_of_tube(spec) + 1.0


# ----------------------------------------------------------------------------- text

_FONTS: dict[str, cv2.FontFace] = {}


def _font(name: str) -> cv2.FontFace:
    if name not in _FONTS:
        _FONTS[name] = cv2.FontFace(name)
    return _FONTS[name]


def text_mask(text: str, font: str, weight: int, height_px: float, squeeze: float) -> np.ndarray:
    """Ink coverage (uint8) of ``text`` whose digits are ``height_px`` tall, cropped to the ink."""
    size = max(4, int(round(height_px / 0.76)))
    pad = size
    buf = np.zeros((size * 3, size * (len(text) + 2)), np.uint8)
    cv2.putText(buf, text, (pad // 2, size * 2), 255, _font(font), size, weight)
    ys, xs = np.nonzero(buf)
    if len(xs) == 0:
        return np.zeros((1, 1), np.uint8)
    crop = buf[ys.min(): ys.max() + 1, xs.min(): xs.max() + 1]
    width = max(1, int(round(crop.shape[1] * squeeze)))
    return cv2.resize(crop, (width, crop.shape[0]), interpolation=cv2.INTER_AREA)


def _paste_max(target: np.ndarray, patch: np.ndarray, left: int, top: int) -> None:
    h, w = patch.shape
    y0, x0 = max(top, 0), max(left, 0)
    y1, x1 = min(top + h, target.shape[0]), min(left + w, target.shape[1])
    if y1 <= y0 or x1 <= x0:
        return
    region = target[y0:y1, x0:x1]
    np.maximum(region, patch[y0 - top: y1 - top, x0 - left: x1 - left], out=region)


# ----------------------------------------------------------------------------- print

def _surface_point(radius: float, angle_deg: float, y: float, elevation_deg: float) -> tuple[float, float]:
    """Where a point printed on the tube's outer surface appears (front-referenced projection)."""
    a = math.radians(angle_deg)
    return radius * math.sin(a), y + radius * (1 - math.cos(a)) * math.sin(math.radians(elevation_deg))


def _mark_span(look: Look, tier: Tier) -> tuple[float, float]:
    minor, medium, major = look.mark_span_deg
    span = {"minor": minor, "medium": medium, "major": major}[tier]
    if look.marks_aligned == "left":
        start = -major / 2
        return start, start + span
    if look.marks_aligned == "right":
        end = major / 2
        return end - span, end
    return -span / 2, span / 2


def draw_print(spec: ApparatusSpec, look: Look, canvas: Canvas, ink_u8: np.ndarray, full_ring_major: bool,
               ) -> list[MarkGeometry]:
    """Marks and numbers on the outer surface; returns the visible marks' geometry."""
    ro = spec.outer_radius_mm
    g = spec.graduation
    phi = look.scale_turn_deg
    half_t = look.mark_thickness_mm / 2
    y_lo_win, y_hi_win = float(canvas.y_mm[-1]) - 5, float(canvas.y_mm[0]) + 5
    polygons: list[np.ndarray] = []
    back_polygons: list[np.ndarray] = []
    marks: list[MarkGeometry] = []
    label_jobs: list[tuple[str, float, float, float]] = []  # text, y, angle of the inner edge, direction
    for tick in g.ticks:
        value = g.value_ml(tick)
        y = spec.y_mm(value)
        if not (y_lo_win <= y <= y_hi_win):
            continue
        tier = g.tier(tick)
        a0, a1 = _mark_span(look, tier)
        if full_ring_major and tier == "major":
            a0, a1 = -180.0, 180.0
        v0, v1 = max(a0 + phi, -86.0), min(a1 + phi, 86.0)
        if v1 - v0 > 1.0:
            angles = np.linspace(v0, v1, max(4, int((v1 - v0) / 4)))
            top = [_surface_point(ro, a, y + half_t, look.elevation_deg) for a in angles]
            bottom = [_surface_point(ro, a, y - half_t, look.elevation_deg) for a in angles[::-1]]
            polygons.append(np.array(top + bottom))
            mid = (v0 + v1) / 2
            marks.append(MarkGeometry(
                tick, value, tier, g.label(tick), _surface_point(ro, mid, y, look.elevation_deg),
                (_surface_point(ro, v0, y, look.elevation_deg), _surface_point(ro, v1, y, look.elevation_deg))))
        if full_ring_major and tier == "major" and abs(look.elevation_deg) > 0.05:
            # the back half of the ring, seen faintly through the glass
            angles = np.linspace(-86, 86, 30)
            s = math.sin(math.radians(look.elevation_deg))
            top = [(ro * math.sin(math.radians(a)), y + half_t + ro * (1 + math.cos(math.radians(a))) * s) for a in angles]
            bottom = [(x, yy - 2 * half_t) for x, yy in top[::-1]]
            back_polygons.append(np.array(top + bottom))
        label = g.label(tick)
        if label is not None:
            if full_ring_major:  # burettes: the number sits right of the short marks, above the ring
                label_jobs.append((label, y, phi + look.mark_span_deg[1] / 2 + 5.0, 1.0))
            elif look.label_side == "right":
                label_jobs.append((label, y, a1 + phi + 6.0, 1.0))
            else:
                label_jobs.append((label, y, a0 + phi - 6.0, -1.0))
    canvas.fill(ink_u8, polygons)
    if back_polygons:
        back = np.zeros_like(ink_u8)
        canvas.fill(back, back_polygons, 90)
        np.maximum(ink_u8, back, out=ink_u8)
    _draw_labels(look, canvas, ink_u8, label_jobs, ro)
    _draw_extra_text(spec, look, canvas, ink_u8, ro)
    return marks


def _draw_labels(look: Look, canvas: Canvas, ink_u8: np.ndarray, jobs: list[tuple[str, float, float, float]],
                 ro: float) -> None:
    k = canvas.k
    height_px = look.text_height_mm * k
    for text, y, edge_angle, direction in jobs:
        if not -80 < edge_angle < 80:
            continue
        patch = text_mask(text, look.font, look.font_weight, height_px, look.text_squeeze)
        width_mm = patch.shape[1] / k
        # foreshortening on the curved surface at the label's centre
        centre_angle = edge_angle + direction * math.degrees(width_mm / 2 / ro)
        if not -75 < centre_angle < 75:
            continue
        fore = math.cos(math.radians(centre_angle))
        patch = cv2.resize(patch, (max(1, int(round(patch.shape[1] * fore))), patch.shape[0]),
                           interpolation=cv2.INTER_AREA)
        x_edge, _ = _surface_point(ro, edge_angle, y, look.elevation_deg)
        x_left = x_edge if direction > 0 else x_edge - patch.shape[1] / k
        if look.label_vertical == "above":
            y_bottom = y + look.mark_thickness_mm + 0.25 * look.text_height_mm
            top_mm = y_bottom + patch.shape[0] / k
        else:
            top_mm = y + patch.shape[0] / k / 2
        col, row = canvas.to_px(np.array([[x_left, top_mm]]))[0]
        _paste_max(ink_u8, patch, int(round(col)), int(round(row)))


def _draw_extra_text(spec: ApparatusSpec, look: Look, canvas: Canvas, ink_u8: np.ndarray, ro: float) -> None:
    """Unit, class and brand print near the top of the scale: distractors a reader must ignore."""
    if not look.extra_text:
        return
    g = spec.graduation
    top_value = g.first_ml if spec.increases_downward else g.last_ml
    y = spec.y_mm(top_value) + (1.2 if not spec.increases_downward else -1.2) * 0  # start at the top mark
    k = canvas.k
    for i, text in enumerate(look.extra_text):
        patch = text_mask(text, look.font, look.font_weight, look.text_height_mm * k * 0.8, look.text_squeeze)
        y_text = y + look.text_height_mm * (1.9 + 1.5 * i)
        x_left = -patch.shape[1] / k / 2 + ro * math.sin(math.radians(look.scale_turn_deg))
        col, row = canvas.to_px(np.array([[x_left, y_text]]))[0]
        _paste_max(ink_u8, patch, int(round(col)), int(round(row)))


# ----------------------------------------------------------------------------- tube optics

def _column_profiles(look: Look, canvas: Canvas, ri: float, ro: float) -> tuple[np.ndarray, np.ndarray]:
    """Transmission and specular highlight across the tube, per column."""
    ax = np.abs(canvas.x_mm)
    inner = 1.0 - 0.22 * np.clip(ax / ri, 0, 1) ** 10
    wall_pos = np.clip((ax - ri) / max(ro - ri, 1e-3), 0, 1)
    wall = look.wall_transmission * (1.0 - 0.55 * np.exp(-((1 - wall_pos) * (ro - ri) / 0.25) ** 2))
    wall += 0.18 * np.exp(-((ax - ri) / 0.12) ** 2)  # bright inner wall line
    trans = np.where(ax <= ri, inner, wall).astype(np.float32)
    sx = look.specular_pos * ri
    sw = max(look.specular_width * ri, 0.08)
    spec = look.specular_strength * np.exp(-((canvas.x_mm - sx) / sw) ** 2)
    spec += 0.35 * look.specular_strength * np.exp(-((canvas.x_mm + 0.8 * sx) / (1.6 * sw)) ** 2)
    return trans, spec.astype(np.float32)


def _refracted(bg: np.ndarray, canvas: Canvas, source_x_mm: np.ndarray) -> np.ndarray:
    map_x = ((source_x_mm - canvas.x0) * canvas.k).astype(np.float32)
    map_y = np.broadcast_to(np.arange(canvas.height, dtype=np.float32)[:, None], map_x.shape).copy()
    return cv2.remap(bg, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def _meniscus(look: Look, canvas: Canvas, ri: float, y_level: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(liquid coverage, band coverage, band darkness) for a concave meniscus at ``y_level``."""
    k = canvas.k
    xn = np.clip(np.abs(canvas.x_mm) / ri, 0, 1)[None, :]
    power = 2.0 if ri < 8 else 4.0
    low = y_level + look.meniscus_depth_mm * xn**power
    up = low + look.meniscus_band_mm + 0.6 * look.meniscus_depth_mm * xn**power
    y = canvas.y_mm[:, None]
    liquid = np.clip((low - y) * k + 0.5, 0, 1)
    band = np.clip((y - low) * k + 0.5, 0, 1) * np.clip((up - y) * k + 0.5, 0, 1)
    rel = np.clip((y - low) / (up - low), 0, 1)
    darkness = look.meniscus_darkness * (1.0 - 0.65 * rel)
    return liquid.astype(np.float32), band.astype(np.float32), darkness.astype(np.float32)


def draw_apparatus(spec: ApparatusSpec, look: Look, level_ml: float, canvas: Canvas, bg: np.ndarray) -> Drawing:
    """Draw the apparatus at ``level_ml`` over ``bg`` (the background seen from the canvas)."""
    ri, ro = spec.inner_radius_mm, spec.outer_radius_mm
    y_bot, y_top = _bottom_of_tube(spec), _top_of_tube(spec)
    y_level = spec.y_mm(level_ml)
    tube_rows = canvas.rows_between(y_bot, y_top)
    tube = tube_rows * canvas.cols_within(ro)
    bore = canvas.rows_between(y_bot if spec.kind == "burette" else 0.0, y_top) * canvas.cols_within(ri)

    # what fills the bore, row by row
    if spec.kind == "syringe":
        liquid = canvas.rows_between(0.0, y_level) * canvas.cols_within(ri) if look.liquid_in_syringe else None
        band = None
    else:
        liquid, band, darkness = _meniscus(look, canvas, ri, y_level)
        liquid = liquid * bore
        band = band * bore

    # refraction: squeezed behind air, mirrored behind liquid
    x = canvas.x_mm[None, :]
    src_air = np.broadcast_to(x * 0.93, canvas.shape)
    src = np.where(np.abs(x) > ri, x * 1.06, src_air).astype(np.float32)
    if liquid is not None:
        src = src + liquid * (-look.refraction_gain * x - src_air)
    color = _refracted(bg, canvas, src)

    trans, specular = _column_profiles(look, canvas, ri, ro)
    tint = np.asarray(look.glass_tint_bgr, np.float32)
    color *= (trans[None, :, None] * tint) * tube[..., None] + (1 - tube[..., None])
    over(color, (0.95, 0.95, 0.95), bore * look.glass_haze)
    if liquid is not None:
        path = np.sqrt(np.clip(1 - (canvas.x_mm / ri) ** 2, 0, 1))[None, :, None]
        absorb = np.asarray(look.liquid_bgr, np.float32) ** (look.liquid_density * 4 * path)
        color *= 1 - liquid[..., None] * (1 - absorb)
    if band is not None:
        # the meniscus looks dark against a light background and silvery against a dark one
        rows, cols = support(band)
        behind = float(np.mean(color[rows, cols])) if band.any() else 1.0
        band_color = np.asarray(look.liquid_bgr, np.float32) * 0.18 if behind > 0.4 else np.full(3, 0.85, np.float32)
        over(color, band_color, band * darkness)

    alpha = tube.copy()
    drawing = Drawing(color=color, alpha=alpha)
    if spec.kind == "syringe":
        _draw_syringe_parts(spec, look, canvas, bg, drawing, y_level, y_top)
        drawing.indicator_line_mm = ((-ri, y_level), (ri, y_level))
    else:
        drawing.indicator_line_mm = ((-ri, y_level + look.meniscus_depth_mm), (ri, y_level + look.meniscus_depth_mm))
        if spec.kind == "measuring_cylinder":
            _draw_cylinder_parts(spec, look, canvas, bg, drawing, y_top)
        else:
            _draw_burette_parts(spec, look, canvas, bg, drawing)
    drawing.indicator_mm = (0.0, y_level)

    # front-surface highlights, then the print on top of everything seen through the glass
    drawing.color += (specular[None, :, None] * tube[..., None]) * (1 - drawing.color)
    ink = np.zeros(canvas.shape, np.uint8)
    drawing.marks = draw_print(spec, look, canvas, ink, full_ring_major=spec.kind == "burette")
    ink_a = ink.astype(np.float32) * (look.ink_alpha / 255)
    texture = np.random.default_rng(look.ink_texture_seed).uniform(0.85, 1.0, size=canvas.shape).astype(np.float32)
    over(drawing.color, look.ink_bgr, ink_a * texture)
    np.maximum(drawing.alpha, ink_a, out=drawing.alpha)
    x0, x1, y0, y1 = extent_mm(spec, level_ml)
    drawing.outline_mm = rect(x0, x1, y0, y1)
    return drawing


def _plastic(canvas: Canvas, bg: np.ndarray, drawing: Drawing, coverage: np.ndarray, tint: BGR, opacity: float,
             shade_axis_mm: float = 1.0) -> None:
    """A translucent part: the background dimmed and tinted, shaded across x."""
    rows, cols = support(coverage)
    shade = (0.85 + 0.15 * np.cos(np.clip(canvas.x_mm[cols] / shade_axis_mm, -1.5, 1.5)))[None, :, None]
    part = (bg[rows, cols] * (1 - opacity) + np.asarray(tint, np.float32) * opacity) * shade
    a = coverage[rows, cols, None]
    region = drawing.color[rows, cols]
    region *= 1 - a
    region += part * a
    np.maximum(drawing.alpha, coverage, out=drawing.alpha)


def _draw_syringe_parts(spec: ApparatusSpec, look: Look, canvas: Canvas, bg: np.ndarray, drawing: Drawing,
                        y_level: float, y_top: float) -> None:
    ri, ro = spec.inner_radius_mm, spec.outer_radius_mm
    # stopper: leading sealing rib at the level, waist, trailing rib; conical nose below
    length = look.stopper_length_ratio * 2 * ri
    rib = 0.22 * length
    cone = look.stopper_cone_ratio * ri
    polys = [rect(-ri, ri, y_level, y_level + rib), rect(-0.93 * ri, 0.93 * ri, y_level + rib, y_level + length - rib),
             rect(-ri, ri, y_level + length - rib, y_level + length)]
    if cone > 0.05:
        polys.append(np.array([[-0.8 * ri, y_level + 0.01], [0.8 * ri, y_level + 0.01],
                               [0.25 * ri, max(y_level - cone, -1.4)], [-0.25 * ri, max(y_level - cone, -1.4)]]))
    stopper = canvas.mask(polys)
    shade = (0.55 + 0.45 * np.cos(np.clip(canvas.x_mm / ri, -1, 1) * 1.3))[None, :, None]
    rubber = np.asarray(look.stopper_bgr, np.float32) * shade
    rubber = rubber + 0.25 * np.exp(-((canvas.x_mm - look.specular_pos * ri * 0.7) / (0.12 * ri)) ** 2)[None, :, None]
    over(drawing.color, np.broadcast_to(rubber, drawing.color.shape), stopper)
    # plunger rod (translucent cross seen edge-on) and thumb press
    rod_top = y_level + y_top + 12.0
    rod = canvas.mask([rect(-0.82 * ri, 0.82 * ri, y_level + length, rod_top)]) * (1 - stopper)
    fin = canvas.mask([rect(-0.12 * ri, 0.12 * ri, y_level + length, rod_top)])
    over(drawing.color, look.rod_bgr, rod * look.rod_alpha)
    over(drawing.color, tuple(c * 0.85 for c in look.rod_bgr), fin * 0.5)
    np.maximum(drawing.alpha, rod, out=drawing.alpha)
    _plastic(canvas, bg, drawing, canvas.mask([rect(-1.35 * ro, 1.35 * ro, rod_top, rod_top + 2.2)]),
             look.rod_bgr, 0.7, 1.35 * ro)
    # flange and nozzle
    _plastic(canvas, bg, drawing, canvas.mask([rect(-2.2 * ro, 2.2 * ro, y_top - 2.0, y_top)]),
             (0.9, 0.9, 0.9), 0.35, 2.2 * ro)
    nozzle = np.array([[-2.0, -1.5], [2.0, -1.5], [1.6, -11.5], [-1.6, -11.5]])
    _plastic(canvas, bg, drawing, canvas.mask([nozzle, rect(-ro, ro, -1.5, 0.0)]), (0.9, 0.9, 0.9), 0.35, 2.0)


def _draw_cylinder_parts(spec: ApparatusSpec, look: Look, canvas: Canvas, bg: np.ndarray, drawing: Drawing,
                         y_top: float) -> None:
    ro = spec.outer_radius_mm
    fw = max(1.6 * ro + 4.0, ro + 5.0) - 0.5
    fh = 13.0
    yb = -4.0
    foot = np.array([[-fw, yb - fh], [fw, yb - fh], [fw * 0.97, yb - fh * 0.45], [fw * 0.72, yb],
                     [-fw * 0.72, yb], [-fw * 0.97, yb - fh * 0.45]])
    cov = canvas.mask([foot])
    if look.base_is_glass:
        _plastic(canvas, bg, drawing, cov, (0.85, 0.9, 0.85), 0.25, fw)
    else:
        _plastic(canvas, bg, drawing, cov, look.base_bgr, 0.92, fw)
    # thick glass bottom and the rim with its spout
    _plastic(canvas, bg, drawing, canvas.mask([rect(-ro, ro, yb, 0.0)]), (0.8, 0.88, 0.82), 0.3, ro)
    s = look.spout_side
    spout = np.array([[s * (ro - 0.5), y_top - 6.0], [s * (ro + 3.5), y_top + 1.0], [s * (ro - 0.5), y_top + 0.5]])
    _plastic(canvas, bg, drawing, canvas.mask([spout, rect(-ro - 0.6, ro + 0.6, y_top - 1.2, y_top)]),
             (0.85, 0.9, 0.86), 0.3, ro)


def _draw_burette_parts(spec: ApparatusSpec, look: Look, canvas: Canvas, bg: np.ndarray, drawing: Drawing) -> None:
    ro = spec.outer_radius_mm
    y_bot = _bottom_of_tube(spec)
    tip = np.array([[-ro, y_bot], [ro, y_bot], [1.5, y_bot - 14.0], [-1.5, y_bot - 14.0]])
    _plastic(canvas, bg, drawing, canvas.mask([tip]), (0.85, 0.9, 0.86), 0.3, ro)
    key = canvas.mask([rect(-ro - 5.0, ro + 5.0, y_bot - 9.0, y_bot - 5.0)])
    _plastic(canvas, bg, drawing, key, (0.93, 0.93, 0.93), 0.9, ro + 5)
