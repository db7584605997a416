"""The Rerun sink: a short real stream logged to a .rrd and read back with ``rerun.chunk.RrdReader``."""

from __future__ import annotations

import argparse
import csv
import itertools
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from streamread.errors import InputError
from streamread.sink import RerunSink, add_rerun_args, close_recording, open_recording
from streamread.sources import Frame, SourceEvent, VideoFileSource
from streamread.stream import FrameResult, StreamConfig, StreamReader

RECORDING = Path(__file__).resolve().parents[1] / "recordings" / "syringe5ml_staircase.mp4"
FRAMES = 60


@dataclass
class Run:
    frames: list[Frame]
    results: list[FrameResult]


@pytest.fixture(scope="module")
def run() -> Run:
    source = VideoFileSource(RECORDING)
    reader = StreamReader(StreamConfig(apparatus="syringe"))
    frames, results = [], []
    try:
        for item in itertools.islice(source, FRAMES):
            assert isinstance(item, Frame)
            frames.append(item)
            results.append(reader.process(item))
    finally:
        source.close()
    return Run(frames, results)


def _log(run: Run, path: Path, **kwargs: object) -> RerunSink:
    rec = rr.RecordingStream("streamread_test", recording_id="sink-test")
    rec.save(path)
    sink = RerunSink(rec, **kwargs)  # type: ignore[arg-type]
    for frame, result in zip(run.frames, run.results, strict=True):
        sink.log_frame(frame, result)
    sink.close()
    rec.disconnect()  # writes the footer
    return sink


def _ints(column: pa.Array) -> list[int]:
    """Index columns: ``frame`` is int64, ``video_time`` a duration[ns] (cast: pyarrow won't give ns timedeltas)."""
    if pa.types.is_duration(column.type) or pa.types.is_timestamp(column.type):
        column = column.cast(pa.int64())
    return column.to_pylist()


def all_rows(reader: RrdReader, entity: str, component: str) -> list[tuple[int, object]]:
    """(frame, value of ``component``) for every temporal row of one entity, in frame order."""
    out: list[tuple[int, object]] = []
    for chunk in reader.stream().filter(content=entity).to_chunks():
        if chunk.is_static or chunk.entity_path != entity:
            continue
        batch = chunk.to_record_batch()
        if component not in batch.schema.names:
            continue
        out += zip(_ints(batch.column("frame")), batch.column(component).to_pylist(), strict=True)
    return sorted(out, key=lambda row: row[0])


def rows(reader: RrdReader, entity: str, component: str) -> dict[int, object]:
    """{frame: value}; the last row wins where a frame has several."""
    return dict(all_rows(reader, entity, component))


def texts_by_frame(reader: RrdReader, entity: str, component: str) -> dict[int, list[str]]:
    out: dict[int, list[str]] = {}
    for index, value in all_rows(reader, entity, component):
        out.setdefault(index, []).extend(value)  # type: ignore[arg-type]
    return out


@pytest.fixture(scope="module")
def logged(run: Run, tmp_path_factory: pytest.TempPathFactory) -> tuple[RrdReader, RerunSink]:
    path = tmp_path_factory.mktemp("rrd") / "run.rrd"
    sink = _log(run, path)
    return RrdReader(path), sink


def test_real_stream_is_tracked(run: Run) -> None:
    assert run.results[0].calibration is not None
    assert sum(r.state == "tracking" for r in run.results) >= FRAMES // 2


def test_filtered_level_round_trips(run: Run, logged: tuple[RrdReader, RerunSink]) -> None:
    reader, _ = logged
    filtered = rows(reader, "/level/filtered", "Scalars:scalars")
    expected = {r.index: r.level for r in run.results if r.level is not None}
    assert expected and set(filtered) == set(expected)
    for index, level in expected.items():
        assert filtered[index] == [pytest.approx(level, abs=1e-6)]
    raw = rows(reader, "/level/raw", "Scalars:scalars")
    assert set(raw) == {r.index for r in run.results if r.level_raw is not None}
    upper = rows(reader, "/level/upper", "Scalars:scalars")
    lower = rows(reader, "/level/lower", "Scalars:scalars")
    for r in run.results:
        if r.level is not None and r.sigma is not None:
            assert upper[r.index][0] - lower[r.index][0] == pytest.approx(2 * r.sigma, abs=1e-6)
    states = rows(reader, "/state", "Scalars:scalars")
    assert states == {r.index: [float({"calibrating": 0, "tracking": 1, "coasting": 2, "lost": 3}[r.state])]
                      for r in run.results}


def test_indicator_on_tracking_frames(run: Run, logged: tuple[RrdReader, RerunSink]) -> None:
    reader, _ = logged
    points = rows(reader, "/camera/indicator/point", "Points2D:positions")
    lines = rows(reader, "/camera/indicator/line", "LineStrips2D:strips")
    tracking = [r for r in run.results if r.state == "tracking"]
    assert tracking
    for r in tracking:
        assert r.index in points and r.index in lines
        assert r.reading is not None and r.reading.indicator_px is not None
        np.testing.assert_allclose(points[r.index][0], r.reading.indicator_px, atol=1e-3)  # float32 positions


def test_image_and_overlays(run: Run, logged: tuple[RrdReader, RerunSink]) -> None:
    reader, sink = logged
    blobs = rows(reader, "/camera/image", "EncodedImage:blob")
    assert sorted(blobs) == [r.index for r in run.results]
    media = rows(reader, "/camera/image", "EncodedImage:media_type")
    assert media[0] == ["image/jpeg"]
    image = cv2.imdecode(np.frombuffer(bytes(blobs[0][0]), np.uint8), cv2.IMREAD_COLOR)
    assert image.shape == run.frames[0].image.shape
    assert rows(reader, "/strip/image", "EncodedImage:blob")
    # the calibration never changes in these frames: its overlays are logged once and persist
    assert sink.calibrations_logged == 1
    for entity in ("/camera/box", "/camera/scale/axis", "/camera/scale/marks/major", "/camera/scale/marks/minor"):
        assert list(rows(reader, entity, "Boxes2D:half_sizes" if "box" in entity else "LineStrips2D:strips")) == [0]
    numbers = rows(reader, "/camera/scale/numbers", "Points2D:labels")[0]
    assert numbers == [r.text for r in run.results[0].calibration.reads]  # type: ignore[union-attr]
    values = rows(reader, "/camera/scale/values", "Points2D:labels")[0]
    assert len(values) == len(run.results[0].calibration.marks.majors)  # type: ignore[union-attr]
    reading = rows(reader, "/camera/reading", "Points2D:labels")
    r = run.results[-1]
    assert reading[r.index] == [f"{r.level:.2f} ± {r.sigma:.2f} ml ({r.state})"]
    events = texts_by_frame(reader, "/events", "TextLog:text")
    assert events[0] == ["state: tracking", *run.results[0].events]
    assert any(text.startswith("calibrated") for text in events[0])


def test_timelines_and_blueprint(run: Run, logged: tuple[RrdReader, RerunSink]) -> None:
    reader, _ = logged
    assert [s.application_id for s in reader.recordings()] == ["streamread_test"]
    temporal = [c for c in reader.stream().filter(content="/level/filtered").to_chunks() if not c.is_static]
    assert temporal and all({"frame", "video_time"} <= set(c.timeline_names) for c in temporal)
    times: dict[int, int] = {}
    for chunk in temporal:
        batch = chunk.to_record_batch()
        times.update(zip(_ints(batch.column("frame")), _ints(batch.column("video_time")), strict=True))
    for r in run.results:
        if r.level is not None:
            assert times[r.index] == pytest.approx(r.time_s * 1e9, abs=1.0)
    blueprints = reader.blueprints()
    assert len(blueprints) == 1
    entities = {c.entity_path for c in reader.stream(store=blueprints[0]).to_chunks()}
    assert "/viewport" in entities
    origins = []
    for chunk in reader.stream(store=blueprints[0]).to_chunks():
        batch = chunk.to_record_batch()
        if "ViewBlueprint:space_origin" in batch.schema.names:
            origins += [v for row in batch.column("ViewBlueprint:space_origin").to_pylist() for v in row]
    assert {"camera", "level", "rate", "strip", "events"} <= {o.strip("/") for o in origins}


def test_image_every_and_clears(run: Run, tmp_path: Path) -> None:
    """Images every 10th frame; losing the calibration clears the overlays; source events are logged."""
    results = list(run.results[:20])
    lost = [replace(r, index=r.index + 20, time_s=r.time_s + 20 / 15, level=None, level_raw=None, sigma=None,
                    rate=None, state="lost", reading=None, calibration=None, strip=None,
                    events=("calibration dropped",))
            for r in results[:5]]
    frames = list(run.frames[:20]) + [Frame(r.index, r.time_s, run.frames[0].image) for r in lost]
    path = tmp_path / "every10.rrd"
    sink = _log(Run(frames, results + lost), path, image_every=10)
    assert sink.images_logged == 3
    reader = RrdReader(path)
    assert sorted(rows(reader, "/camera/image", "EncodedImage:blob")) == [0, 10, 20]
    assert sorted(rows(reader, "/level/filtered", "Scalars:scalars")) == [r.index for r in results]
    assert sorted(rows(reader, "/rate", "Scalars:scalars")) == [r.index for r in results if r.rate is not None]
    for entity in ("/camera/indicator", "/camera/scale", "/camera/box", "/strip"):
        assert rows(reader, entity, "Clear:is_recursive") == {20: [True]}, entity
    levels = texts_by_frame(reader, "/events", "TextLog:level")
    texts = texts_by_frame(reader, "/events", "TextLog:text")
    assert "calibration dropped" in texts[20] and "state: tracking -> lost" in texts[20]
    assert set(levels[20]) == {"WARN"}

    rec = rr.RecordingStream("streamread_test")
    path = tmp_path / "event.rrd"
    rec.save(path)
    sink = RerunSink(rec, send_blueprint=False)
    sink.log_frame(run.frames[0], run.results[0])
    sink.log_source_event(SourceEvent("truncated", "video x: ended early", 0.5))
    sink.close()
    rec.disconnect()
    reader = RrdReader(path)
    assert rows(reader, "/events", "TextLog:text")[1] == ["truncated: video x: ended early"]
    assert reader.blueprints() == []


def test_unbatched_rows_match(run: Run, tmp_path: Path) -> None:
    """``max_delay_s=0`` sends every row at once (``log``, not columns): the same data, at the same times."""
    path = tmp_path / "now.rrd"
    _log(run, path, max_delay_s=0.0, image_every=30)
    reader = RrdReader(path)
    filtered = rows(reader, "/level/filtered", "Scalars:scalars")
    assert filtered == {r.index: [pytest.approx(r.level, abs=1e-6)] for r in run.results if r.level is not None}
    points = rows(reader, "/camera/indicator/point", "Points2D:positions")
    for r in run.results:
        if r.state == "tracking":
            np.testing.assert_allclose(points[r.index][0], r.reading.indicator_px, atol=1e-3)  # type: ignore[union-attr]
    assert rows(reader, "/camera/reading", "Points2D:labels")[run.results[-1].index] == [
        f"{run.results[-1].level:.2f} ± {run.results[-1].sigma:.2f} ml (tracking)"]


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser()
    add_rerun_args(parser)
    return parser


def test_open_recording_without_flags_is_none() -> None:
    args = _parser().parse_args([])
    assert args.log_image_every == 1
    assert open_recording(args) is None
    args = _parser().parse_args(["--headless", "--log-image-every", "10"])
    assert args.log_image_every == 10 and open_recording(args) is None
    with pytest.raises(SystemExit):
        _parser().parse_args(["--log-image-every", "0"])


def test_open_recording_save_writes_file(tmp_path: Path) -> None:
    path = tmp_path / "cli.rrd"
    args = _parser().parse_args(["--save", str(path)])
    rec = open_recording(args)
    assert isinstance(rec, rr.RecordingStream)
    assert rec is not rr.get_global_data_recording()
    rec.set_time("frame", sequence=0)
    rec.log("level/filtered", rr.Scalars(1.25))
    close_recording(args, rec)
    reader = RrdReader(path)
    assert [s.application_id for s in reader.recordings()] == ["streamread"]
    assert rows(reader, "/level/filtered", "Scalars:scalars") == {0: [1.25]}


def test_stdout_must_be_alone(tmp_path: Path) -> None:
    args = _parser().parse_args(["--stdout", "--save", str(tmp_path / "x.rrd")])
    with pytest.raises(InputError, match="--stdout"):
        open_recording(args)


def test_unwritable_save_is_an_input_error(tmp_path: Path) -> None:
    args = _parser().parse_args(["--save", str(tmp_path / "no" / "such" / "dir" / "x.rrd")])
    with pytest.raises(InputError, match="--save"):
        open_recording(args)


def test_analyze_rrd_matches_its_csv(tmp_path: Path) -> None:
    """The issue's check end to end: ``analyze --save`` writes an .rrd whose filtered level equals
    the CSV of the same run frame by frame, with overlays on the frames the reader tracked."""
    from streamread.cli import main

    out, rrd = tmp_path / "r.csv", tmp_path / "r.rrd"
    video = Path(__file__).resolve().parents[1] / "recordings" / "syringe5ml_bump.mp4"
    assert main(["analyze", str(video), "--apparatus", "syringe", "--csv", str(out), "--save", str(rrd),
                 "--quiet", "--log-image-every", "5"]) == 0
    table = list(csv.DictReader(open(out)))
    reader = RrdReader(rrd)
    filtered = rows(reader, "/level/filtered", "Scalars:scalars")
    from_csv = {int(r["frame"]): float(r["level"]) for r in table if r["level"]}
    assert set(filtered) == set(from_csv)
    for frame, level in from_csv.items():
        assert filtered[frame][0] == pytest.approx(level, abs=1e-5)  # type: ignore[index]
    points = rows(reader, "/camera/indicator/point", "Points2D:positions")
    tracked = {int(r["frame"]) for r in table if r["state"] == "tracking" and r["level_raw"]}
    assert tracked and tracked <= set(points)
