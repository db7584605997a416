"""Offline analysis split over worker processes gives the CSV of one reader.

The bundled staircase recording (904 frames) is measured with two workers and with one
reader. The parent's tracker sees the same measurements in the same order, so frames and
states are identical; the workers decode a syringe's frames as luma only (no conversion to
BGR), which moves the levels by rounding only: within 0.002 ml (a hundredth of a division).
Failures and interruptions must lose nothing.
"""

from __future__ import annotations

import csv
import multiprocessing as mp
from pathlib import Path

import cv2
import numpy as np
import pytest

import streamread.parallel as parallel
from streamread.cli import main
from streamread.parallel import ParallelVideoSource, jobs_for
from streamread.run import run_loop
from streamread.sources import VideoFileSource
from streamread.stream import StreamConfig, StreamReader

RECORDINGS = Path(__file__).resolve().parents[1] / "recordings"
STAIRCASE = RECORDINGS / "syringe5ml_staircase.mp4"


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


LUMA_TOLERANCE_ML = 0.002  # luma against BGR-to-grey: rounding of the grey levels only


def _assert_rows_of_one_reader(rows: list[dict[str, str]], one_reader: list[dict[str, str]]) -> None:
    assert [(r["frame"], r["time_s"], r["state"]) for r in rows] == \
        [(r["frame"], r["time_s"], r["state"]) for r in one_reader], "same frames, same order, same states"
    for column, tolerance in (("level", LUMA_TOLERANCE_ML), ("level_raw", LUMA_TOLERANCE_ML), ("sigma", 0.001),
                              ("rate", 0.02)):
        pairs = [(a[column], b[column]) for a, b in zip(rows, one_reader)]
        assert all((x == "") == (y == "") for x, y in pairs), f"{column}: present in the same rows"
        worst = max(abs(float(x) - float(y)) for x, y in pairs if x)
        assert worst <= tolerance, f"{column}: differs by {worst} (tolerance {tolerance})"


def _truth() -> dict[int, float]:
    return {int(r["frame"]): float(r["level_ml"]) for r in _rows(STAIRCASE.with_suffix(".truth.csv"))}


@pytest.fixture(scope="module")
def one_reader(tmp_path_factory: pytest.TempPathFactory) -> list[dict[str, str]]:
    out = tmp_path_factory.mktemp("one") / "r.csv"
    run_loop(VideoFileSource(STAIRCASE, prefetch=True), StreamReader(StreamConfig(apparatus="syringe", keep_history=True)),
             out, smooth=True)
    return _rows(out)


def test_two_workers_give_the_rows_of_one_reader(one_reader: list[dict[str, str]], tmp_path: Path) -> None:
    source = ParallelVideoSource(STAIRCASE, jobs=2)
    assert source.jobs == 2
    out = tmp_path / "r.csv"
    summary = run_loop(source, StreamReader(StreamConfig(apparatus="syringe", keep_history=True)), out, smooth=True)
    rows = _rows(out)
    assert summary.ocr_runs == 1, "the workers start from frame 0's calibration: no OCR of their own"
    _assert_rows_of_one_reader(rows, one_reader)  # the same Kalman and RTS smoothing
    truth = _truth()
    errors = [abs(float(r["level"]) - truth[int(r["frame"])]) for r in rows if r["level"]]
    assert len(errors) == len(rows)
    assert sum(errors) / len(errors) <= 0.02
    assert not mp.active_children(), "no worker outlives the run"


class _NoSeek:
    """A capture that cannot seek (some containers and streams cannot)."""

    def __init__(self, path: str) -> None:
        self._cap = cv2.VideoCapture(path)

    def set(self, prop: int, value: float) -> bool:
        return False

    def get(self, prop: int) -> float:
        return 0.0 if prop == cv2.CAP_PROP_POS_FRAMES else float(self._cap.get(prop))

    def read(self) -> tuple[bool, object]:
        return self._cap.read()


def test_a_worker_that_fails_is_replaced_by_the_parent(one_reader: list[dict[str, str]], tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    # workers are forked, so they see the patched opener; the parent's fallback does not use it
    monkeypatch.setattr(parallel, "_open_single_threaded", _NoSeek)
    events: list[str] = []
    out = tmp_path / "r.csv"
    summary = run_loop(ParallelVideoSource(STAIRCASE, jobs=2), StreamReader(StreamConfig(apparatus="syringe")), out,
                       log=events.append)
    rows = _rows(out)
    assert [int(r["frame"]) for r in rows] == list(range(904)), "every frame, in order"
    assert sum("failed (RuntimeError: cannot seek" in e for e in events) == 2, events
    assert summary.readings == 904
    raw = {int(r["frame"]): float(r["level_raw"]) for r in one_reader}
    assert max(abs(float(r["level_raw"]) - raw[int(r["frame"])]) for r in rows) <= 0.01


def test_an_interrupt_keeps_what_the_workers_measured(tmp_path: Path) -> None:
    out = tmp_path / "r.csv"

    def interrupt_after_frame_60(_done: int, _total: int | None, _elapsed: float, result: object) -> None:
        if getattr(result, "index") >= 60:
            raise KeyboardInterrupt

    source = ParallelVideoSource(STAIRCASE, jobs=2)
    summary = run_loop(source, StreamReader(StreamConfig(apparatus="syringe")), out,
                       progress=interrupt_after_frame_60)
    assert summary.interrupted
    frames = [int(r["frame"]) for r in _rows(out)]
    assert frames == sorted(set(frames)), "in order, none twice"
    assert frames[:61] == list(range(61)), "every frame up to the interruption"
    assert len(frames) > 61, "and what the workers had measured beyond it"
    truth = _truth()
    rows = _rows(out)
    assert all(abs(float(r["level_raw"]) - truth[int(r["frame"])]) <= 0.05 for r in rows if r["level_raw"])
    assert not mp.active_children(), "the workers are stopped"


def test_short_files_and_unknown_lengths_use_one_reader() -> None:
    assert jobs_for(None, 4) == 1
    assert jobs_for(182, 4) == 1, "under two parts' worth of frames"
    assert jobs_for(904, 8) == 4, "parts of at least 200 frames"
    assert jobs_for(904, 2) == 2
    assert jobs_for(904, 1) == 1
    assert ParallelVideoSource(RECORDINGS / "syringe5ml_bump.mp4", jobs=4).jobs == 1


@pytest.mark.parametrize("value", ["0", "-2", "two"])
def test_jobs_must_be_a_positive_whole_number(value: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["analyze", str(STAIRCASE), "--jobs", value])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "--jobs" in err and "expected a whole number >= 1" in err and "Traceback" not in err


def test_progress_counts_what_the_workers_measured_and_finishes_once(tmp_path: Path) -> None:
    calls: list[tuple[int, int | None, int]] = []

    def progress(done: int, total: int | None, _elapsed: float, result: object) -> None:
        calls.append((done, total, getattr(result, "index")))

    run_loop(ParallelVideoSource(STAIRCASE, jobs=2), StreamReader(StreamConfig(apparatus="syringe")), tmp_path / "r.csv",
             progress=progress)
    assert len(calls) == 904
    assert any(done > index + 1 for done, _, index in calls), "frames measured ahead of those written are counted"
    finished = [c for c in calls if c[0] >= 904]
    assert finished == [(904, 904, 903)], "the run is reported done once, when the last frame is written"


def test_a_header_that_counts_too_few_frames_loses_none(one_reader: list[dict[str, str]], tmp_path: Path) -> None:
    source = ParallelVideoSource(STAIRCASE, jobs=2)
    source.frame_count = 800  # as a container whose header undercounts: the last part reads to the end
    out = tmp_path / "r.csv"
    run_loop(source, StreamReader(StreamConfig(apparatus="syringe", keep_history=True)), out, smooth=True)
    _assert_rows_of_one_reader(_rows(out), one_reader)


def test_a_syringe_part_is_decoded_as_luma_and_in_colour_on_demand() -> None:
    part = parallel._Part(str(STAIRCASE), 100, 140, 15.0)
    part.to_luma()
    frames = list(part.frames())
    part.close()
    assert part.luma, "this file's luma stands for its grey"
    assert [f.index for f in frames] == list(range(100, 140)), "the frame the switch was checked on is not lost"
    cap = cv2.VideoCapture(str(STAIRCASE))
    cap.set(cv2.CAP_PROP_POS_FRAMES, 100)
    bgr = [cap.read()[1] for _ in range(40)]
    cap.release()
    for frame, colour in zip(frames, bgr):
        assert frame.image.shape == colour.shape[:2]
        grey = cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY)
        assert frame.luma_lut is not None
        mapped = cv2.LUT(frame.image, frame.luma_lut)
        assert np.percentile(np.abs(mapped.astype(int) - grey), 99) <= 3, "the table maps luma to grey"
    part = parallel._Part(str(STAIRCASE), 100, 140, 15.0)
    part.to_luma()
    frames = list(part.frames())
    # out of order too: a worker that recalibrates asks for the frame it is on
    assert np.array_equal(frames[25].in_colour(), bgr[25])
    assert np.array_equal(frames[3].in_colour(), bgr[3])
    assert np.array_equal(frames[4].in_colour(), bgr[4])
    part.close()


def test_luma_that_does_not_stand_for_grey_is_refused() -> None:
    rng = np.random.default_rng(0)
    bgr = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8)
    grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    video_range = np.round(16 + grey.astype(float) * 219 / 255).astype(np.uint8)
    assert parallel.luma_table(video_range, bgr)[0]
    assert parallel.luma_table(grey, bgr) == (True, None), "full range needs no table"
    assert not parallel.luma_table(255 - grey, bgr)[0], "not the frame's grey"
    assert not parallel.luma_table(grey[:24], bgr)[0], "a plane of another size"


def test_a_worker_that_recalibrates_reads_colour(tmp_path: Path) -> None:
    """The second part is another recording (a camera bump): its worker must calibrate anew,
    on a colour decode of a frame it had decoded as luma only."""
    video = tmp_path / "two_scenes.avi"
    truth: dict[int, float] = {}
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (640, 480))
    index = 0
    for name, count in (("syringe5ml_staircase", 300), ("syringe5ml_bump", 182), ("syringe5ml_bump", 182)):
        levels = [float(r["level_ml"]) for r in _rows(RECORDINGS / f"{name}.truth.csv")]
        cap = cv2.VideoCapture(str(RECORDINGS / f"{name}.mp4"))
        for k in range(count):
            ok, image = cap.read()
            assert ok
            writer.write(image)
            truth[index] = levels[k]
            index += 1
        cap.release()
    writer.release()
    source = ParallelVideoSource(video, jobs=2)
    assert source.jobs == 2
    out = tmp_path / "r.csv"
    run_loop(source, StreamReader(StreamConfig(apparatus="syringe")), out)
    assert source.ocr_runs >= 1, "the second part's worker calibrated itself"
    rows = _rows(out)
    assert [int(r["frame"]) for r in rows] == list(range(index))
    read = [(int(r["frame"]), float(r["level_raw"])) for r in rows if r["level_raw"] and int(r["frame"]) >= 340]
    assert len(read) >= 0.8 * (index - 340), "the second scene is read"
    errors = sorted(abs(level - truth[f]) for f, level in read)
    assert errors[len(errors) // 2] <= 0.02 and errors[int(0.95 * len(errors))] <= 0.1, "and read right (ml)"
