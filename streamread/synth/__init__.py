"""Photographic synthetic renderer of graduated lab apparatus, with exact ground truth.

No camera or data set ships with the project, so these scenes are its laboratory:
every accuracy figure is measured against the truth they carry.

``render_still(seed)`` gives one random scene; ``sample_scene`` + ``render`` give control;
``streamread.synth.video`` scripts recordings (staircase, ramp, occlusion, bump, leave).
"""

from streamread.synth.scene import SceneParams, render, render_still, sample_scene
from streamread.synth.truth import MarkTruth, SceneTruth

__all__ = ["MarkTruth", "SceneParams", "SceneTruth", "render", "render_still", "sample_scene"]
