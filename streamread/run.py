"""The frame loop that ``analyze`` and ``watch`` share: source -> StreamReader -> CSV, JSONL, sink.

Nothing measured is lost: every row is flushed to the CSV as it is made, SIGTERM is turned into
the same orderly stop as Ctrl-C, a signal that comes while a frame is processed stops the loop
once that frame is written (``Interrupts``), and the sink (Rerun) is closed on every way out,
so the ``.rrd`` gets its footer. Optional outputs (a JSONL stream for a robot, a sink) are objects
with a small interface so this module never imports rerun.
"""

from __future__ import annotations

import csv
import json
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Protocol

from streamread.calibfile import save_calibration
from streamread.errors import InputError, expected
from streamread.sources import Frame, Source, SourceEvent
from streamread.stream import FrameResult, Measurement, StreamReader

COLUMNS = ("frame", "time_s", "level", "level_raw", "sigma", "rate", "state")


class Sink(Protocol):
    """Where results go besides the CSV (the Rerun sink implements this)."""

    def log_frame(self, frame: Frame, result: FrameResult) -> None: ...
    def log_source_event(self, event: SourceEvent) -> None: ...
    def close(self) -> None: ...


def csv_row(record: dict[str, object]) -> list[object]:
    """A record as a CSV row in COLUMNS order; an empty cell where there is no value."""
    return ["" if record[c] is None else record[c] for c in COLUMNS]


class CsvWriter:
    """The readings CSV, one row per frame; empty cells where there is no value.

    Rows reach the file at least every ``flush_every_s`` (and on close, which every way out of
    the loop runs): a live run's file is never more than that behind, and an offline run does
    not pay a system call per frame.
    """

    def __init__(self, path: str | Path, flush_every_s: float = 0.2) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file: IO[str] = open(self.path, "w", newline="")
        except OSError as exc:
            raise InputError(expected("csv", self.path, "a writable file path", exc.strerror or exc)) from None
        self._writer = csv.writer(self._file)
        self._writer.writerow(COLUMNS)
        self._file.flush()
        self._flush_every_s = flush_every_s
        self._last_flush = time.monotonic()
        self.rows = 0

    def write(self, record: dict[str, object]) -> None:
        self._writer.writerow(csv_row(record))
        self.rows += 1
        now = time.monotonic()
        if now - self._last_flush >= self._flush_every_s:
            self._file.flush()
            self._last_flush = now

    def flush(self) -> None:
        if not self._file.closed:
            self._file.flush()
            self._last_flush = time.monotonic()

    def close(self) -> None:
        if not self._file.closed:
            self._file.flush()
            self._file.close()


def rewrite_smoothed(path: Path, records: list[dict[str, object]],
                     smoothed: list[tuple[float, float, float] | None]) -> None:
    """Replace level, sigma and rate by the RTS-smoothed values (atomically: never a half file)."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        for record, smooth in zip(records, smoothed):
            row = dict(record)
            if smooth is not None and row["level"] is not None:
                row["level"], row["rate"], row["sigma"] = (round(smooth[0], 5), round(smooth[1], 5),
                                                           round(smooth[2], 5))
            writer.writerow(csv_row(row))
    tmp.replace(path)


class Interrupts:
    """Ctrl-C and SIGTERM, held back while a frame is being processed and written.

    A signal that comes while the loop waits for the source (a camera's next frame, a
    reconnection) stops it at once. One that comes while a frame is processed, written to the
    CSV or logged to the sink is held until that frame is done, so that no Rerun SDK or CSV
    writer call is cut short: the frame's row and entities are whole. A second signal while a
    frame is processed stops at once all the same. A SIGINT the process was started ignoring
    (a job run in the background by a shell, ``nohup``) stays ignored, as Python leaves it.
    """

    def __init__(self) -> None:
        self.busy = False
        self.requested = False

    def handle(self, signum: int, frame: object) -> None:
        if self.busy and not self.requested:
            self.requested = True
            return
        raise KeyboardInterrupt

    @contextmanager
    def installed(self) -> Iterator[Interrupts]:
        """The handler for SIGINT and SIGTERM, the previous ones restored on the way out; in a
        thread other than the main one (where signals cannot be handled), nothing is changed."""
        try:
            previous = {sig: signal.signal(sig, self.handle) for sig in (signal.SIGINT, signal.SIGTERM)
                        if signal.getsignal(sig) is not signal.SIG_IGN}
        except ValueError:  # not the main thread: leave signals alone
            yield self
            return
        try:
            yield self
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    @contextmanager
    def frame(self) -> Iterator[None]:
        """One frame's processing and writing: a signal now is acted on once it is done."""
        self.busy = True
        try:
            yield
        finally:
            self.busy = False
        if self.requested:
            raise KeyboardInterrupt


@dataclass
class RunSummary:
    frames: int = 0
    readings: int = 0
    ocr_runs: int = 0
    interrupted: bool = False
    seconds: float = 0.0
    events: list[str] = field(default_factory=list)
    states: dict[str, int] = field(default_factory=dict)


def run_loop(source: Source, reader: StreamReader, csv_path: Path, *, jsonl: IO[str] | None = None,
             sink: Sink | None = None, calibration_path: Path | None = None, smooth: bool = False,
             progress: Callable[[int, int | None, float, FrameResult], None] | None = None,
             log: Callable[[str], None] | None = None) -> RunSummary:
    """Process every frame of ``source``; outputs are complete on every way out."""
    summary = RunSummary()
    writer = CsvWriter(csv_path)
    records: list[dict[str, object]] = []
    start = time.perf_counter()
    bind = getattr(source, "bind_reader", None)
    if callable(bind):  # a source whose workers start from the reader's calibration (parallel)
        bind(reader)

    def emit(result: FrameResult) -> None:
        record = result.record()
        writer.write(record)
        if smooth:
            records.append(record)
        if jsonl is not None:
            jsonl.write(json.dumps(record) + "\n")
            jsonl.flush()
        if calibration_path is not None and result.new_calibration is not None:
            save_calibration(calibration_path, *result.new_calibration)
        for event in result.events:
            summary.events.append(f"frame {result.index}: {event}")
            if log:
                log(f"frame {result.index}: {event}")
        summary.frames += 1
        summary.readings += result.level is not None
        summary.states[result.state] = summary.states.get(result.state, 0) + 1

    try:
        with Interrupts().installed() as interrupts:
            for item in source:
                with interrupts.frame():
                    if isinstance(item, SourceEvent):
                        writer.flush()  # a camera that drops (or a file that ends early): all rows on disk now
                        summary.events.append(item.message)
                        if log:
                            log(item.message)
                        if sink is not None:
                            sink.log_source_event(item)
                        continue
                    if isinstance(item, Measurement):  # measured by a worker process: only the Kalman step here
                        result = reader.track(item)
                    else:
                        result = reader.process(item)
                    emit(result)
                    if sink is not None and isinstance(item, Frame):
                        sink.log_frame(item, result)
                    if progress is not None:
                        # worker processes measure ahead of the frames written: count what is
                        # measured, but the run is done only when every frame is written
                        done = summary.frames
                        measured = int(getattr(source, "frames_measured", 0))
                        if measured > done:
                            done = measured if source.frame_count is None else min(measured, source.frame_count - 1)
                        progress(done, source.frame_count, time.perf_counter() - start, result)
    except KeyboardInterrupt:
        summary.interrupted = True
        backlog = getattr(source, "backlog", None)
        if callable(backlog):  # measured by workers, not yet written: nothing measured is lost
            try:
                for measurement in backlog():
                    emit(reader.track(measurement))
            except KeyboardInterrupt:
                pass
    finally:
        writer.close()
        source.close()
        if sink is not None:
            sink.close()
        summary.seconds = time.perf_counter() - start
        summary.ocr_runs = reader.ocr_runs + int(getattr(source, "ocr_runs", 0))
    if smooth and not summary.interrupted and records:
        rewrite_smoothed(csv_path, records, reader.smoothed())
    return summary


def progress_bar(label: str, stream: IO[str] = sys.stderr, every_s: float = 0.5
                 ) -> Callable[[int, int | None, float, FrameResult], None]:
    """A one-line progress report: frames, frames/s, time left (files) or the live level (cameras)."""
    last = [0.0]

    def report(done: int, total: int | None, elapsed: float, result: FrameResult) -> None:
        finished = total is not None and done >= total
        if elapsed - last[0] < every_s and not finished:
            return
        last[0] = elapsed
        rate = done / max(elapsed, 1e-6)
        level = "no reading" if result.level is None else f"{result.level:.3f} ml"
        if total:
            left = max(total - done, 0) / max(rate, 1e-6)
            text = f"{label}: {done}/{total} frames, {rate:.0f} frames/s, {left:.0f} s left, {level} ({result.state})"
        else:
            text = f"{label}: {done} frames, {rate:.0f} frames/s, {level} ({result.state})"
        end = "\n" if finished else ""
        stream.write(f"\r{text:<100}{end}")
        stream.flush()
    return report
