"""Scripted protocols follow the paper, and recordings carry consistent ground truth."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from streamread.apparatus import get_spec
from streamread.synth.samples import video_params
from streamread.synth.scene import sample_scene
from streamread.synth.video import (bump, leave, occlusion, ramp, render_frames, staircase, staircase_levels,
                                    write_recording)


def test_staircase_levels_are_the_papers() -> None:
    levels = staircase_levels(get_spec("syringe_5ml"))
    assert levels == pytest.approx([round(0.2 * i, 1) for i in range(24)])  # 0.0 .. 4.6 by 0.2


def test_staircase_dwells_and_directions() -> None:
    fps = 10
    frames = staircase(get_spec("syringe_5ml"), fps, dwell_s=1.0, move_s=0.3)
    runs: list[tuple[str, float, int]] = []
    for f in frames:
        if runs and runs[-1][0] == f.direction and runs[-1][1] == f.level_ml:
            runs[-1] = (f.direction, f.level_ml, runs[-1][2] + 1)
        else:
            runs.append((f.direction, f.level_ml, 1))
    dwells = [r for r in runs if r[2] >= fps]
    up = [round(r[1], 6) for r in dwells if r[0] == "aspirating"]
    down = [round(r[1], 6) for r in dwells if r[0] == "dispensing"]
    assert up == pytest.approx([round(0.2 * i, 1) for i in range(24)])
    assert down == pytest.approx(up[::-1])  # 4.6 read again on the way down, as in Table 4
    assert all(r[2] == fps for r in dwells)
    moves = [f.level_ml for f in frames if f.direction == "aspirating"]
    assert all(b >= a - 1e-12 for a, b in zip(moves, moves[1:]))  # aspirating never goes down


def test_ramp_directions_follow_the_slope() -> None:
    frames = ramp(get_spec("cylinder_50ml"), fps=10, duration_s=6)
    for a, b in zip(frames, frames[1:]):
        if b.level_ml > a.level_ml:
            assert b.direction == "aspirating"
        elif b.level_ml < a.level_ml:
            assert b.direction == "dispensing"


def test_events_hide_and_move_the_apparatus() -> None:
    params = video_params(sample_scene(3, "syringe_5ml", frame_wh=(320, 240), roll_deg=90, size_fraction=0.8,
                                       centered=True))
    fps = 5
    hidden = [t for _, t in render_frames(params, occlusion(params.spec, params, fps, start_s=2, covered_s=1))]
    assert sum(t.occluded for t in hidden) >= fps // 2, "the hand never covered the level"
    assert not hidden[0].occluded and not hidden[-1].occluded
    gone = [t for _, t in render_frames(params, leave(params.spec, params, fps, at_s=2, out_s=1))]
    assert any(t.box_xyxy is None for t in gone) and gone[-1].box_xyxy is not None
    knocked = [t for _, t in render_frames(params, bump(params.spec, params, fps, at_s=2))]
    shift = np.hypot(*(np.array(knocked[-1].indicator_px) - np.array(knocked[0].indicator_px)))
    assert shift > 5, "the bump did not move the image"


def test_write_recording(tmp_path: Path) -> None:
    params = video_params(sample_scene(5, "syringe_5ml", frame_wh=(320, 240), size_fraction=0.8))
    frames = staircase(params.spec, fps=4, dwell_s=0.5, move_s=0.25, step_ml=1.0, top_ml=2.0)
    video = tmp_path / "s.mp4"
    csv_path, json_path = write_recording(params, frames, video, fps=4)
    with csv_path.open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["frame"] for r in rows] == [str(i) for i in range(len(frames))]
    assert {r["direction"] for r in rows} == {"aspirating", "dispensing"}
    assert float(rows[0]["level_ml"]) == 0.0 and max(float(r["level_ml"]) for r in rows) == 2.0
    cap = cv2.VideoCapture(str(video))
    decoded = 0
    while cap.read()[0]:
        decoded += 1
    assert decoded == len(frames)
    sidecar = json.loads(json_path.read_text())
    assert sidecar["apparatus"] == "syringe_5ml" and len(sidecar["per_frame"]) == len(frames)
