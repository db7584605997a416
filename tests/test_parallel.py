"""Offline analysis split over worker processes gives the same CSV as one reader.

The bundled staircase recording (904 frames) is measured with two workers and with one
reader; the rows must be identical, since the parent's tracker sees the same measurements in
the same order. Failures and interruptions must lose nothing.
"""

from __future__ import annotations

import csv
import multiprocessing as mp
from pathlib import Path

import cv2
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
    assert rows == one_reader, "same measurements, same order, same Kalman and RTS smoothing"
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
    assert _rows(out) == one_reader
