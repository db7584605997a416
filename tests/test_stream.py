"""The streaming reader on the bundled synthetic recordings, against their ground truth.

Tolerances are the issue's targets (MAE 0.02 ml on the paper's staircase; one division at
most through an occlusion) on shorter stretches so the suite stays quick.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from streamread.calibfile import load_calibration, save_calibration
from streamread.errors import ConfigError
from streamread.sources import Frame, VideoFileSource
from streamread.stream import FrameResult, StreamConfig, StreamReader

RECORDINGS = Path(__file__).resolve().parents[1] / "recordings"


def _truth(name: str) -> tuple[dict[int, float], dict]:
    rows = {int(r["frame"]): float(r["level_ml"]) for r in csv.DictReader(open(RECORDINGS / f"{name}.truth.csv"))}
    return rows, json.loads((RECORDINGS / f"{name}.truth.json").read_text())


def _run(name: str, limit: int | None = None, reader: StreamReader | None = None) -> tuple[StreamReader, list[FrameResult]]:
    reader = reader or StreamReader(StreamConfig(apparatus="syringe"))
    results = []
    for item in VideoFileSource(RECORDINGS / f"{name}.mp4"):
        if isinstance(item, Frame):
            results.append(reader.process(item))
            if limit is not None and len(results) >= limit:
                break
    return reader, results


@pytest.fixture(scope="module")
def staircase() -> tuple[StreamReader, list[FrameResult]]:
    return _run("syringe5ml_staircase", limit=240)


def test_staircase_is_read_within_target(staircase: tuple[StreamReader, list[FrameResult]]) -> None:
    reader, results = staircase
    truth, _ = _truth("syringe5ml_staircase")
    err = np.array([r.level - truth[r.index] for r in results if r.level is not None])
    assert len(err) == len(results), "every frame of a clear recording has a level"
    assert np.abs(err).mean() <= 0.02, "issue 4 target: MAE at most 0.02 ml"
    assert abs(err.mean()) <= 0.01, "issue 4 target: bias within 0.01 ml"
    assert np.abs(err).max() <= 0.1, "no frame off by half a division"
    assert reader.ocr_runs == 1, "OCR runs once; every later frame reuses the calibration"
    assert {r.state for r in results[1:]} <= {"tracking", "coasting"}


def test_results_carry_what_the_sink_needs(staircase: tuple[StreamReader, list[FrameResult]]) -> None:
    _, results = staircase
    first, later = results[0], results[100]
    assert any("calibrated" in e for e in first.events)
    assert later.calibration is not None and later.reading is not None and later.reading.indicator is not None
    assert later.strip is not None and later.frame_wh == (640, 480)
    record = later.record()
    assert list(record) == ["frame", "time_s", "level", "level_raw", "sigma", "rate", "state"]
    assert record["sigma"] is not None and 0 < record["sigma"] < 0.05


def test_occlusion_coasts_and_resumes() -> None:
    name = "syringe5ml_occlusion"
    truth, meta = _truth(name)
    div = meta["minor_ml"]
    occluded = [i for i, f in enumerate(meta["per_frame"]) if f["occluded"]]
    _, results = _run(name)
    for r in results:
        if r.state == "tracking" and r.level is not None:
            assert abs(r.level - truth[r.index]) <= div, f"frame {r.index}: tracking but off by over a division"
    # no reported level jumps by more than a division from one frame to the next
    levels = [(r.index, r.level) for r in results if r.level is not None]
    for (i0, a), (i1, b) in zip(levels, levels[1:]):
        moved = abs(truth[i1] - truth[i0])
        assert abs(b - a) <= div + moved, f"jump of {b - a:.3f} ml at frame {i1}"
    end = max(occluded)
    resumed = next(r.index for r in results if r.index > end and r.state == "tracking")
    assert (resumed - end) / meta["fps"] <= 0.5, "tracking resumes within 0.5 s after the occlusion"


def test_bump_is_recalibrated_within_a_second() -> None:
    name = "syringe5ml_bump"
    truth, meta = _truth(name)
    moved = next(i for i in range(1, len(meta["per_frame"]))
                 if meta["per_frame"][i]["box_xyxy"] != meta["per_frame"][i - 1]["box_xyxy"]
                 and abs(meta["per_frame"][i]["indicator_px"][1] - meta["per_frame"][i - 1]["indicator_px"][1]) > 5)
    reader, results = _run(name)
    after = [r for r in results if r.index >= moved]
    good = next(r.index for r in after if r.level is not None and r.state == "tracking"
                and abs(r.level - truth[r.index]) <= 0.5 * meta["minor_ml"])
    assert (good - moved) / meta["fps"] <= 1.0
    assert reader.ocr_runs <= 3
    late = [abs(r.level - truth[r.index]) for r in after[15:] if r.level is not None]
    assert late and max(late) <= meta["minor_ml"]


def test_saved_calibration_starts_without_ocr(staircase: tuple[StreamReader, list[FrameResult]], tmp_path: Path) -> None:
    reader, _ = staircase
    assert reader.calibration is not None and reader.signature is not None
    path = save_calibration(tmp_path / "bench.json", reader.calibration, reader.signature, (640, 480))
    loaded = load_calibration(path, "syringe")
    assert loaded[0].fit.slope == pytest.approx(reader.calibration.fit.slope)
    fresh, results = _run("syringe5ml_staircase", limit=60, reader=StreamReader(StreamConfig(apparatus="syringe"),
                                                                               calibration=loaded))
    assert fresh.ocr_runs == 0
    truth, _ = _truth("syringe5ml_staircase")
    assert all(r.level is not None and abs(r.level - truth[r.index]) < 0.05 for r in results)
    with pytest.raises(ConfigError, match="expected a calibration of a burette"):
        load_calibration(path, "burette")


@pytest.mark.parametrize("damage,message", [
    (lambda d: d.pop("fit"), "key 'fit'"),
    (lambda d: d["fit"].update(slope="steep"), "key 'fit.slope'"),
    (lambda d: d.update(format="other/9"), "key 'format'"),
    (lambda d: d["upright"].update(to_upright=[[1, 0], [0, 1]]), "2x3"),
])
def test_damaged_calibration_files_are_clear_errors(staircase: tuple[StreamReader, list[FrameResult]],
                                                   tmp_path: Path, damage, message: str) -> None:  # type: ignore[no-untyped-def]
    reader, _ = staircase
    path = save_calibration(tmp_path / "c.json", reader.calibration, reader.signature, (640, 480))  # type: ignore[arg-type]
    data = json.loads(path.read_text())
    damage(data)
    path.write_text(json.dumps(data))
    with pytest.raises(ConfigError, match=message):
        load_calibration(path)
    path.write_text("{not json")
    with pytest.raises(ConfigError, match="JSON"):
        load_calibration(path)


def test_frame_of_another_size_drops_the_calibration(staircase: tuple[StreamReader, list[FrameResult]]) -> None:
    reader, results = staircase
    small = np.zeros((240, 320, 3), np.uint8)
    result = reader.process(Frame(results[-1].index + 1, results[-1].time_s + 0.07, small))
    assert any("frame size changed" in e for e in result.events)
    assert result.level_raw is None


def _frames(name: str, limit: int) -> list[Frame]:
    frames: list[Frame] = []
    for item in VideoFileSource(RECORDINGS / f"{name}.mp4"):
        if isinstance(item, Frame):
            frames.append(item)
            if len(frames) >= limit:
                break
    return frames


def _moved(frame: Frame, dx_px: float, dy_px: float) -> Frame:
    """The frame as a camera moved by (dx, dy) px would see it."""
    import cv2

    h, w = frame.image.shape[:2]
    shift = np.float32([[1, 0, dx_px], [0, 1, dy_px]])
    return Frame(frame.index, frame.time_s, cv2.warpAffine(frame.image, shift, (w, h), borderMode=cv2.BORDER_REPLICATE))


def test_frames_measured_in_batches_are_measured_as_one_at_a_time() -> None:
    # the camera creeps by a pixel and a half at frame 20 and again at 45: both land inside a
    # batch, whose later frames were cut before the calibration moved
    frames = [f if f.index < 20 else _moved(f, 1.5, 0.0) if f.index < 45 else _moved(f, 1.5, 2.0)
              for f in _frames("syringe5ml_staircase", 80)]
    one = StreamReader(StreamConfig(apparatus="syringe"))
    alone = [one.measure(f) for f in frames]
    many = StreamReader(StreamConfig(apparatus="syringe"))
    batched = many.measure_many(frames[:1]) + many.measure_many(frames[1:33]) + many.measure_many(frames[33:])
    assert [m.index for m in batched] == [f.index for f in frames]
    moved_at = [m.index for m in alone if any("re-registered" in e for e in m.events)]
    assert 20 in moved_at and 45 in moved_at  # the scene does move the calibration
    for a, b in zip(alone, batched):
        assert a.events == b.events
        assert (a.level_raw is None) == (b.level_raw is None)
        if a.level_raw is not None:
            assert abs(a.level_raw - b.level_raw) <= 1e-9 and abs(a.sigma_raw - b.sigma_raw) <= 1e-9
    assert many.ocr_runs == one.ocr_runs == 1


def test_the_check_of_a_stack_is_the_check_of_each_strip() -> None:
    from streamread.indicator import stopper_profiles
    from streamread.registration import check, print_responses, register

    reader = StreamReader(StreamConfig(apparatus="syringe"))
    results = [reader.process(f) for f in _frames("syringe5ml_staircase", 120)]
    cal, signature = reader.calibration, reader.signature
    assert cal is not None and signature is not None
    strips = np.stack([r.strip for r in results[100:120] if r.strip is not None])
    assert len(strips) == 20
    rows = (150.0, 200.0)
    for strip, response in zip(strips, print_responses(strips, signature)):
        alone = register(strip, signature, rows)
        together = check(response, signature, rows)
        assert together.score == alone.score and together.majors_ok == alone.majors_ok
        assert abs(together.dx_px - alone.dx_px) <= 1e-4 and abs(together.dy_px - alone.dy_px) <= 1e-6
        assert abs(together.score_x - alone.score_x) <= 1e-5
    bodies = stopper_profiles(strips, cal.marks, cal.bore_x_up)
    for strip, body in zip(strips, bodies):
        assert np.array_equal(stopper_profiles(strip[None], cal.marks, cal.bore_x_up)[0], body)
