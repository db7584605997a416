"""Scripted recordings with ground truth: the paper's staircase, ramps, occlusion, bump, leave.

Each protocol is a list of ``FrameScript`` (level, direction, camera offset, hand); the
writer renders them into an mp4v video, a ground-truth CSV ``frame,time_s,level_ml,direction``
and a JSON sidecar with the per-frame geometry (indicator point, box, visibility).

``direction`` is the sweep a frame belongs to: ``aspirating`` while the level goes up
(including the dwells of the up sweep), ``dispensing`` on the way down, ``still`` before the
first and after the last movement. So the dwells of each sweep are the paper's Table 4 rows.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import cv2
import numpy as np

from streamread.apparatus import ApparatusSpec, format_value
from streamread.errors import InputError, expected
from streamread.synth import camera
from streamread.synth.scene import Hand, SceneParams, level_range, render
from streamread.synth.truth import SceneTruth

Direction = Literal["aspirating", "dispensing", "still"]
PROTOCOLS = ("staircase", "ramp", "occlusion", "bump", "leave")


@dataclass(frozen=True)
class FrameScript:
    level_ml: float
    direction: Direction
    offset_px: tuple[float, float] = (0.0, 0.0)
    roll_offset_deg: float = 0.0
    hand: Hand | None = None


def _smoothstep(t: float) -> float:
    return 0.5 - 0.5 * math.cos(math.pi * min(max(t, 0.0), 1.0))


def staircase_levels(spec: ApparatusSpec, step_ml: float | None = None, top_ml: float | None = None) -> list[float]:
    """Dwell levels of one sweep: the paper's 0, 0.2, ..., 4.6 ml for a 5 ml syringe."""
    lo, hi = level_range(spec)
    minor = spec.minor_ml
    if step_ml is None:
        step_ml = max(minor, round(spec.capacity_ml / 25 / minor) * minor)
    if top_ml is None:
        top_ml = lo + math.floor((0.92 * hi - lo) / step_ml + 1e-9) * step_ml
    if step_ml <= 0 or not lo <= top_ml <= hi:
        raise InputError(expected("staircase", "top_ml/step_ml", f"a top within [{lo}, {hi}] and a step > 0",
                                  f"top {top_ml}, step {step_ml}"))
    n = int(round((top_ml - lo) / step_ml))
    return [round(lo + i * step_ml, 6) for i in range(n + 1)]


def staircase(spec: ApparatusSpec, fps: float, dwell_s: float = 1.0, move_s: float = 0.3,
              step_ml: float | None = None, top_ml: float | None = None) -> list[FrameScript]:
    """Up by steps with a dwell at each (aspirating), dwell again at the top, then down (dispensing)."""
    levels = staircase_levels(spec, step_ml, top_ml)
    dwell, move = max(1, round(dwell_s * fps)), max(1, round(move_s * fps))
    frames: list[FrameScript] = []

    def sweep(seq: list[float], direction: Direction) -> None:
        for i, level in enumerate(seq):
            if i > 0:
                prev = seq[i - 1]
                for j in range(1, move + 1):
                    frames.append(FrameScript(prev + (level - prev) * _smoothstep(j / (move + 1)), direction))
            frames.extend(FrameScript(level, direction) for _ in range(dwell))

    sweep(levels, "aspirating")
    sweep(levels[::-1], "dispensing")
    return frames


def ramp(spec: ApparatusSpec, fps: float, duration_s: float = 12.0, hold_s: float = 0.5) -> list[FrameScript]:
    """Hold, a constant-rate rise to 90 % of the scale, hold, a constant-rate fall, hold."""
    lo, hi = level_range(spec)
    top = lo + 0.9 * (hi - lo)
    hold = max(1, round(hold_s * fps))
    leg = max(2, round((duration_s - 3 * hold_s) / 2 * fps))
    frames = [FrameScript(lo, "still") for _ in range(hold)]
    frames += [FrameScript(lo + (top - lo) * (i + 1) / leg, "aspirating") for i in range(leg)]
    frames += [FrameScript(top, "aspirating") for _ in range(hold)]
    frames += [FrameScript(top - (top - lo) * (i + 1) / leg, "dispensing") for i in range(leg)]
    frames += [FrameScript(lo, "still") for _ in range(hold)]
    return frames


def _with(frames: list[FrameScript], index: int, **changes: object) -> None:
    f = frames[index]
    frames[index] = FrameScript(**{**f.__dict__, **changes})  # type: ignore[arg-type]


def occlusion(spec: ApparatusSpec, params: SceneParams, fps: float, start_s: float = 4.0,
              covered_s: float = 1.0) -> list[FrameScript]:
    """A ramp with a hand passing in front of the level: in over 0.2 s, still for ``covered_s``, out."""
    frames = ramp(spec, fps)
    h = camera.homography_mm_to_px(params.pose)
    width, height = params.frame_wh
    size = 0.55 * min(width, height)
    enter, stay = max(1, round(0.2 * fps)), max(1, round(covered_s * fps))
    first = round(start_s * fps)
    for i in range(first, min(len(frames), first + 2 * enter + stay)):
        target = camera.apply(h, np.array([[0.0, spec.y_mm(frames[i].level_ml)]]))[0]
        t = i - first
        frac = min(t / enter, 1.0) if t < enter + stay else max(0.0, 1 - (t - enter - stay) / enter)
        start = np.array([-0.6 * size, target[1] + 0.3 * size])
        goal = np.array([target[0] + 0.1 * size, target[1] + 0.3 * size])
        center = start + (goal - start) * _smoothstep(frac)
        _with(frames, i, hand=Hand(center_px=(float(center[0]), float(center[1])), size_px=size, angle_deg=15.0))
    return frames


def bump(spec: ApparatusSpec, params: SceneParams, fps: float, at_s: float = 5.0,
         rng: np.random.Generator | None = None) -> list[FrameScript]:
    """A ramp during which the camera is knocked: a sudden shift of 20-40 px and 2-5 degrees."""
    rng = rng or np.random.default_rng(0)
    frames = ramp(spec, fps)
    angle = rng.uniform(0, 2 * math.pi)
    dist = rng.uniform(20, 40) * max(params.frame_wh) / 640
    shift = (dist * math.cos(angle), dist * math.sin(angle))
    droll = float(rng.choice([-1, 1]) * rng.uniform(2, 5))
    for i in range(round(at_s * fps), len(frames)):
        _with(frames, i, offset_px=shift, roll_offset_deg=droll)
    return frames


def leave(spec: ApparatusSpec, params: SceneParams, fps: float, at_s: float = 4.0, out_s: float = 1.0,
          travel_s: float = 0.7) -> list[FrameScript]:
    """A ramp during which the apparatus slides out of the frame, stays out, and comes back."""
    frames = ramp(spec, fps)
    width = params.frame_wh[0]
    travel, out = max(1, round(travel_s * fps)), max(1, round(out_s * fps))
    first = round(at_s * fps)
    far = 1.6 * width
    for t in range(2 * travel + out):
        i = first + t
        if i >= len(frames):
            break
        if t < travel:
            dx = far * _smoothstep(t / travel)
        elif t < travel + out:
            dx = far
        else:
            dx = far * (1 - _smoothstep((t - travel - out) / travel))
        _with(frames, i, offset_px=(dx, 0.0))
    return frames


def script(protocol: str, params: SceneParams, fps: float, seed: int = 0) -> list[FrameScript]:
    spec = params.spec
    makers: dict[str, Callable[[], list[FrameScript]]] = {
        "staircase": lambda: staircase(spec, fps),
        "ramp": lambda: ramp(spec, fps),
        "occlusion": lambda: occlusion(spec, params, fps),
        "bump": lambda: bump(spec, params, fps, rng=np.random.default_rng(seed)),
        "leave": lambda: leave(spec, params, fps),
    }
    if protocol not in makers:
        raise InputError(expected("protocol", repr(protocol), "one of " + ", ".join(PROTOCOLS), "an unknown name"))
    return makers[protocol]()


def render_frames(params: SceneParams, frames: list[FrameScript]) -> Iterator[tuple[np.ndarray, SceneTruth]]:
    """Render each scripted frame (temporal sensor noise: a new noise seed every frame)."""
    for i, f in enumerate(frames):
        pose = params.pose.moved(f.offset_px[0], f.offset_px[1], f.roll_offset_deg)
        yield render(params, level_ml=f.level_ml, pose=pose, hand=f.hand, noise_seed=params.noise_seed + i)


def write_recording(params: SceneParams, frames: list[FrameScript], video_path: Path, fps: float,
                    meta: dict[str, object] | None = None, progress: Callable[[int, int], None] | None = None,
                    ) -> tuple[Path, Path]:
    """Write ``video_path`` (mp4v), its truth CSV and JSON sidecar; returns (csv, json) paths."""
    video_path = Path(video_path)
    video_path.parent.mkdir(parents=True, exist_ok=True)
    width, height = params.frame_wh
    writer = cv2.VideoWriter(str(video_path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (width, height))
    if not writer.isOpened():
        raise InputError(expected("video", video_path, "a writable .mp4 path (mp4v codec)", "a writer that did not open"))
    csv_path = video_path.with_suffix(".truth.csv")
    json_path = video_path.with_suffix(".truth.json")
    per_frame: list[dict[str, object]] = []
    try:
        with csv_path.open("w", newline="") as fh:
            out = csv.writer(fh)
            out.writerow(["frame", "time_s", "level_ml", "direction"])
            for i, ((image, truth), f) in enumerate(zip(render_frames(params, frames), frames, strict=True)):
                writer.write(image)
                out.writerow([i, f"{i / fps:.4f}", f"{f.level_ml:.5f}", f.direction])
                per_frame.append({
                    "indicator_px": [round(truth.indicator_px[0], 2), round(truth.indicator_px[1], 2)],
                    "visible": truth.visible, "occluded": truth.occluded,
                    "box_xyxy": None if truth.box_xyxy is None else [round(v, 1) for v in truth.box_xyxy],
                    "px_per_division": round(truth.px_per_division, 3),
                })
                if progress:
                    progress(i + 1, len(frames))
    finally:
        writer.release()
    spec = params.spec
    sidecar = {
        "apparatus": spec.name, "kind": spec.kind, "minor_ml": spec.minor_ml, "unit": "ml", "fps": fps,
        "frame_wh": list(params.frame_wh), "frames": len(frames),
        "level_range_ml": [format_value(v) for v in level_range(spec)], **(meta or {}), "per_frame": per_frame,
    }
    json_path.write_text(json.dumps(sidecar, separators=(",", ":")))
    return csv_path, json_path


def read_truth_csv(path: Path) -> list[tuple[int, float, float, str]]:
    """Rows (frame, time_s, level_ml, direction) of a ground-truth CSV."""
    path = Path(path)
    try:
        with path.open(newline="") as fh:
            reader = csv.DictReader(fh)
            if reader.fieldnames is None or not {"frame", "time_s", "level_ml", "direction"} <= set(reader.fieldnames):
                raise InputError(expected("truth CSV", path, "columns frame,time_s,level_ml,direction",
                                          ",".join(reader.fieldnames or [])))
            return [(int(r["frame"]), float(r["time_s"]), float(r["level_ml"]), r["direction"]) for r in reader]
    except OSError as exc:
        raise InputError(expected("truth CSV", path, "a readable file", exc.strerror)) from None
    except ValueError as exc:
        raise InputError(expected("truth CSV", path, "numeric frame, time_s and level_ml", exc)) from None
