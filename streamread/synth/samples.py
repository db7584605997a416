"""The bundled sample recordings: how each is made, so ``streamread synth --recordings`` remakes them."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from streamread.synth.scene import SceneParams, sample_scene
from streamread.synth.video import script, write_recording


@dataclass(frozen=True)
class SampleRecording:
    name: str
    apparatus: str
    protocol: str
    seed: int
    fps: float = 15.0
    frame_wh: tuple[int, int] = (640, 480)
    roll_deg: float = 90.0
    size_fraction: float = 0.85
    min_px_per_division: float = 6.0


SAMPLES: tuple[SampleRecording, ...] = (
    SampleRecording("syringe5ml_staircase", "syringe_5ml", "staircase", seed=11, roll_deg=92.0),
    SampleRecording("syringe5ml_occlusion", "syringe_5ml", "occlusion", seed=14, roll_deg=-86.0),
    SampleRecording("syringe5ml_bump", "syringe_5ml", "bump", seed=15, roll_deg=-86.0),
    SampleRecording("cylinder50ml_ramp", "cylinder_50ml", "ramp", seed=29, roll_deg=2.0),
    SampleRecording("syringe5ml_leave", "syringe_5ml", "leave", seed=16, roll_deg=-86.0),
    SampleRecording("burette25ml_leave", "burette_25ml", "leave", seed=31, roll_deg=-3.0),
)


def video_params(params: SceneParams) -> SceneParams:
    """A video camera's sensor: light temporal noise, no per-frame JPEG (the codec is the artefact)."""
    p = params.photometry
    return replace(params, photometry=replace(p, read_noise=min(p.read_noise, 0.003), shot_noise=0.0, jpeg_quality=0))


def sample_params(sample: SampleRecording) -> SceneParams:
    return video_params(sample_scene(sample.seed, sample.apparatus, frame_wh=sample.frame_wh, roll_deg=sample.roll_deg,
                                     size_fraction=sample.size_fraction, tilt_scale=0.4, centered=True,
                                     min_px_per_division=sample.min_px_per_division))


def make_sample(sample: SampleRecording, out_dir: Path, progress: Callable[[int, int], None] | None = None) -> Path:
    params = sample_params(sample)
    frames = script(sample.protocol, params, sample.fps, seed=sample.seed)
    video = Path(out_dir) / f"{sample.name}.mp4"
    meta = {"protocol": sample.protocol, "seed": sample.seed, "roll_deg": sample.roll_deg,
            "regenerate": f"streamread synth --recordings {out_dir} --only {sample.name}"}
    write_recording(params, frames, video, sample.fps, meta=meta, progress=progress)
    return video
