"""Offline analysis on several cores: a video file's frames measured by worker processes.

The image work of a frame (``StreamReader.measure``: cut, check, indicator), one frame at a
time, costs about twice its decoding and runs in Python on one core. A recorded video's frames
are all there in advance, so the file is split into contiguous parts and each part is decoded
and measured by its own worker process. Workers are forked, so they start in milliseconds with everything
imported, and they are forked before the parent runs any OCR.

- The parent decodes frame 0 and calibrates on it exactly as a single reader would. It hands
  that calibration to every worker, so each part starts where a single reader would be:
  calibrated, with no OCR. A worker decodes its first frames while it waits.
- The parent's reader runs the Kalman step over all the measurements in frame order
  (``StreamReader.track``). The filtered levels, the states and the RTS smoothing therefore
  see one continuous stream.
- What differs from one reader: at the first frame of a part, the worker does not know the
  registration shift and indicator position of the frames before it. It checks that frame
  against frame 0's calibration. If the camera moved before that part, the worker
  recalibrates at once, as a single reader did when the camera moved.
- A worker measures its frames 32 at a time (``StreamReader.measure_many``): the check's and
  the stopper search's array work is done for the whole batch at once, with the same results.
- A syringe's per-frame path reads grey only, so its workers take the decoder's luma plane as
  it is and skip the conversion to BGR, about a third of decoding (``_Part``). A frame that
  needs colour (the worker recalibrates) is decoded again in colour.
- A worker that fails (it cannot seek, or it dies) is replaced by the parent, which decodes and
  measures that part itself.
- Workers ignore Ctrl-C. The parent stops them, and ``backlog`` still hands over what they
  had measured, so it reaches the CSV.

Only video files are split. Cameras, image sequences, the renderer and runs that log images
(the Rerun sink needs every frame's pixels) use one reader.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import multiprocessing as mp
import os
import queue
import signal
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from streamread.errors import ConfigError, expected
from streamread.sources import Frame, SourceEvent, SourceItem, VideoFileSource
from streamread.stream import CalibrationState, Measurement, StreamConfig, StreamReader

MIN_FRAMES_PER_JOB = 200  # shorter parts are not worth a process
_BATCH = 32  # measurements per message
_READ_AHEAD_BYTES = 128 << 20  # a worker decodes up to this much while the parent calibrates


def default_jobs() -> int:
    """One worker per core (the parent's Kalman step is light), at most 8."""
    return max(1, min(os.cpu_count() or 1, 8))


def jobs_for(frame_count: int | None, jobs: int, min_frames_per_job: int = MIN_FRAMES_PER_JOB) -> int:
    """How many workers a file of ``frame_count`` frames gets (1: none, one reader does it all)."""
    if jobs < 1:
        raise ConfigError(expected("analyze", "jobs", ">= 1", jobs))
    if frame_count is None or jobs == 1 or not hasattr(os, "fork"):
        return 1
    return max(1, min(jobs, (frame_count - 1) // min_frames_per_job))


@dataclass
class _Worker:
    start: int
    stop: int
    process: Any  # multiprocessing Process (fork context)
    results: Any  # multiprocessing Queue: worker -> parent
    seed: Connection  # parent -> worker: the calibration to start from
    buffer: deque[Measurement] = field(default_factory=deque)
    received: int = 0
    finished: bool = False
    error: str | None = None
    end_of_file: bool = False
    ocr_runs: int = 0


def _work(path: str, start: int, stop: int | None, fps: float, config: StreamConfig, seed: Connection,
          results: Any) -> None:
    """A worker: decode frames ``start``..``stop - 1`` (None: to the end of the file) and send
    their measurements in order."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when to stop
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    count = ocr = 0
    part: _Part | None = None
    try:
        part = _Part(path, start, stop, fps)
        if config.apparatus == "syringe":
            part.to_luma()  # known before the calibration: read ahead in luma too
        decoded = part.frames()
        ahead: list[Frame] = []
        size = 0
        while size < _READ_AHEAD_BYTES and not seed.poll():
            frame = next(decoded, None)
            if frame is None:
                break
            ahead.append(frame)
            size += frame.image.nbytes
        state: CalibrationState | None = seed.recv()
        reader = StreamReader(config, calibration=state, continues=True) if state else StreamReader(config)
        if state is not None and state[0].apparatus == "syringe":
            part.to_luma()
        frames = itertools.chain(ahead, decoded)
        while chunk := list(itertools.islice(frames, _BATCH)):
            results.put(("m", [m.light() for m in reader.measure_many(chunk)]))
            count += len(chunk)
        ocr = reader.ocr_runs
        end_of_file = stop is None or count < stop - start  # the decoder stopped before the part's end
        results.put(("end", ocr, None, end_of_file))
    except Exception as exc:  # noqa: BLE001 - reported to the parent, which measures the rest itself
        results.put(("end", ocr, f"{type(exc).__name__}: {exc}", False))
    finally:
        if part is not None:
            part.close()
        results.close()
        results.join_thread()


# video range (16-235) luma to the full-range grey cv2.cvtColor(BGR2GRAY) gives
_VIDEO_RANGE = np.clip(np.round((np.arange(256) - 16) * 255 / 219), 0, 255).astype(np.uint8)
_LUMA_TOLERANCE = 3  # grey levels: the 99th percentile of |mapped luma - grey| must stay within


def luma_table(luma: np.ndarray, bgr: np.ndarray) -> tuple[bool, np.ndarray | None]:
    """Whether a decoder's luma plane stands for the frame's grey, and the table that maps it.

    Checked on one frame decoded both ways: video-range luma (most files) takes
    ``_VIDEO_RANGE``, full-range luma (JPEG-style) none. Anything else (a luma plane of another
    size, a pixel format whose first plane is not luma) is refused and the part decodes in colour.
    """
    if luma.ndim != 2 or luma.dtype != np.uint8 or luma.shape != bgr.shape[:2] or bgr.ndim != 3:
        return False, None
    grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY).astype(np.int16)
    for table in (_VIDEO_RANGE, None):
        mapped = luma if table is None else cv2.LUT(luma, table)
        if float(np.percentile(np.abs(mapped.astype(np.int16) - grey), 99)) <= _LUMA_TOLERANCE:
            return True, table
    return False, None


class _Part:
    """A worker's frames, decoded in order, as luma only once the reader needs no colour.

    A syringe's per-frame path reads grey only. FFmpeg decodes to planar YUV, and converting
    that to BGR is about a third of the decoding cost (measured: 0.40 against 0.27 ms a 640x480
    frame), so ``to_luma`` switches the decoder to hand over its luma plane as it is. The switch
    is checked on the first frame against a colour decode of the same frame (``luma_table``).
    A frame that then needs colour (the reader recalibrates) is decoded again in colour from a
    second capture, which stays in step while the frames asking for colour follow each other.
    """

    def __init__(self, path: str, start: int, stop: int | None, fps: float) -> None:
        self.path, self.stop, self.fps = path, stop, fps
        self.next = start
        self.cap = _open_single_threaded(path)
        at = _seek(self.cap, start)
        if at != start:
            raise RuntimeError(f"cannot seek to frame {start} (at {at})")
        self.luma = False
        self._refused = False  # this file's luma was checked and does not stand for its grey
        self._table: np.ndarray | None = None
        self._pending: Frame | None = None  # decoded by to_luma, not yet handed over
        self._colour_cap: Any = None

    def frames(self) -> Iterator[Frame]:
        """The part's frames in order, until its end or the decoder stops."""
        while self.stop is None or self.next < self.stop:
            frame, self._pending = self._pending, None
            if frame is None:
                ok, image = self.cap.read()
                if not ok or image is None:
                    return
                frame = self._frame(self.next, image)
            self.next += 1
            yield frame

    def _frame(self, index: int, image: np.ndarray) -> Frame:
        if not self.luma:
            return Frame(index, index / self.fps, image)
        return Frame(index, index / self.fps, image, luma_lut=self._table,
                     colour=functools.partial(self._colour, index))

    def to_luma(self) -> None:
        """Decode luma only from the next frame on, if this file's luma stands for its grey."""
        if self.luma or self._refused or (self.stop is not None and self.next >= self.stop):
            return
        with _quiet_opencv():  # it warns on opening and on each frame that it hands over planes as they are
            luma_cap = _open_single_threaded(self.path, luma=True)
            if _seek(luma_cap, self.next) != self.next:
                luma_cap.release()
                return
            ok_luma, luma = luma_cap.read()
        ok, bgr = self.cap.read()
        fits, table = luma_table(luma, bgr) if ok_luma and ok else (False, None)
        if not fits:
            self._refused = True
            luma_cap.release()
            if ok:
                self._pending = Frame(self.next, self.next / self.fps, bgr)
            return
        self.cap.release()
        self.cap, self.luma, self._table = luma_cap, True, table
        # the luma capture warns on every frame that it hands over a plane as is: quiet it for
        # this process (a worker; its own errors still come back to the parent)
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
        self._pending = self._frame(self.next, luma)

    def _colour(self, index: int) -> np.ndarray:
        """Frame ``index`` decoded in colour."""
        if self._colour_cap is None:
            self._colour_cap = _open_single_threaded(self.path)
        if _seek(self._colour_cap, index) != index:  # no seek while the frames asked follow each other
            raise RuntimeError(f"cannot seek to frame {index} to decode it in colour")
        ok, image = self._colour_cap.read()
        if not ok or image is None:
            raise RuntimeError(f"cannot decode frame {index} in colour")
        return image

    def close(self) -> None:
        self.cap.release()
        if self._colour_cap is not None:
            self._colour_cap.release()


@contextlib.contextmanager
def _quiet_opencv() -> Iterator[None]:
    level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    try:
        yield
    finally:
        cv2.utils.logging.setLogLevel(level)


def _seek(cap: Any, start: int) -> int:
    """Move ``cap`` to frame ``start``; the frame it is at after (``start`` when it could).
    A capture already there (frame 0 of one just opened) is not asked to seek."""
    if int(round(cap.get(cv2.CAP_PROP_POS_FRAMES))) != start:
        cap.set(cv2.CAP_PROP_POS_FRAMES, start)
    return int(round(cap.get(cv2.CAP_PROP_POS_FRAMES)))


def _frames(cap: Any, start: int, stop: int | None, fps: float) -> Iterator[Frame]:
    """Frames ``start``..``stop - 1`` (None: to the end) from ``cap``, until the decoder stops."""
    for index in itertools.count(start) if stop is None else range(start, stop):
        ok, image = cap.read()
        if not ok or image is None:
            return
        yield Frame(index, index / fps, image)


def _open_single_threaded(path: str, luma: bool = False) -> cv2.VideoCapture:
    """The file with FFmpeg's decoder on one thread: the workers already fill the cores, and
    FFmpeg's own threads cost some 30 % more CPU for the same frames (measured). With ``luma``
    the decoder's planes are not converted to BGR (``CAP_PROP_CONVERT_RGB`` off)."""
    params = [cv2.CAP_PROP_N_THREADS, 1] + ([cv2.CAP_PROP_CONVERT_RGB, 0] if luma else [])
    cap = cv2.VideoCapture(path, cv2.CAP_FFMPEG, params)
    return cap if cap.isOpened() or luma else cv2.VideoCapture(path)


class ParallelVideoSource:
    """A video file whose frames after the first are measured by worker processes.

    It yields the parent's :class:`Frame` items (frame 0, and any part a worker failed to do)
    and the workers' :class:`~streamread.stream.Measurement` items, in frame order. The loop
    gives frames to ``reader.process`` and measurements to ``reader.track``; it must call
    :meth:`bind_reader` first, since the workers start from the reader's calibration of frame 0.
    ``jobs`` 0 means one per core (``default_jobs``); files too short for two parts of
    ``min_frames_per_job`` get one, and with one job it is the plain (prefetched) video source.
    """

    def __init__(self, path: str | Path, jobs: int = 0, min_frames_per_job: int = MIN_FRAMES_PER_JOB) -> None:
        self._video = VideoFileSource(path, prefetch=True)
        self.path = self._video.path
        self.name = self._video.name
        self.fps = self._video.fps
        self.frame_count = self._video.frame_count
        self.jobs = jobs_for(self.frame_count, jobs or default_jobs(), min_frames_per_job)
        self._reader: StreamReader | None = None
        self._workers: list[_Worker] = []
        self._current = 0
        self.ocr_runs = 0  # OCR runs in the workers (the parent's reader counts its own)
        self._here = 0  # frames the parent decoded itself

    @property
    def frames_measured(self) -> int:
        """Frames measured so far, here and in the workers (the progress bar counts these)."""
        return self._here + sum(w.received for w in self._workers)

    def bind_reader(self, reader: StreamReader) -> None:
        self._reader = reader

    # -- workers -------------------------------------------------------------------------------
    def _start_workers(self) -> None:
        assert self.frame_count is not None
        ctx = mp.get_context("fork")
        first, total = 1, self.frame_count
        n = self.jobs
        # the parent follows the parts in order: the last part ends a little later, so the
        # parent catches up on it while it is still being measured
        weights = [1.0] * (n - 1) + [1.08] if n > 1 else [1.0]
        edges = np.cumsum([0.0] + weights) / sum(weights)
        bounds = [first + int(round((total - first) * e)) for e in edges]
        config = self._reader.config if self._reader is not None else StreamConfig()
        # each worker is one core's worth: OpenCV's own thread pool would oversubscribe the
        # cores. It is trimmed here, before the fork: a forked child cannot resize the pool it
        # inherited (OpenCV waits there for threads that do not exist in the child).
        threads = cv2.getNumThreads()
        cv2.setNumThreads(1)
        try:
            self._fork(ctx, bounds, config)
        finally:
            cv2.setNumThreads(threads)

    def _fork(self, ctx: Any, bounds: list[int], config: StreamConfig) -> None:
        for start, stop in zip(bounds[:-1], bounds[1:]):
            results = ctx.Queue()
            theirs, ours = ctx.Pipe(duplex=False)
            # the last part reads to the end: a header may count fewer frames than the file has
            last = None if stop == bounds[-1] else stop
            process = ctx.Process(target=_work, name=f"streamread-part-{start}",
                                  args=(str(self.path), start, last, self.fps, config, theirs, results), daemon=True)
            process.start()
            theirs.close()
            self._workers.append(_Worker(start, stop, process, results, ours))

    def _take(self, worker: _Worker, message: tuple[Any, ...]) -> None:
        if message[0] == "m":
            worker.buffer.extend(message[1])
            worker.received += len(message[1])
        else:
            _, worker.ocr_runs, worker.error, worker.end_of_file = message
            worker.finished = True
            self.ocr_runs += worker.ocr_runs

    def _poll(self, wait_for: _Worker | None, timeout_s: float) -> None:
        """Move what the workers sent into their buffers; wait up to ``timeout_s`` for ``wait_for``."""
        if wait_for is not None and not wait_for.finished:
            try:
                self._take(wait_for, wait_for.results.get(timeout=timeout_s))
            except queue.Empty:
                if not wait_for.process.is_alive() and wait_for.results.empty():
                    wait_for.finished = True
                    wait_for.error = f"worker exited with code {wait_for.process.exitcode}"
        for worker in self._workers:  # keep every pipe flowing
            while not worker.finished:
                try:
                    self._take(worker, worker.results.get_nowait())
                except queue.Empty:
                    break

    def _measure_here(self, start: int, stop: int | None) -> Iterator[Frame]:
        """Decode a part a worker could not do (the parent's reader measures it)."""
        cap = cv2.VideoCapture(str(self.path))
        try:
            if _seek(cap, start) != start:  # not seekable: decode from the start and skip
                cap.release()
                cap = cv2.VideoCapture(str(self.path))
                for _ in range(start):
                    if not cap.grab():
                        return
            yield from _frames(cap, start, stop, self.fps)
        finally:
            cap.release()

    # -- iteration -------------------------------------------------------------------------------
    def __iter__(self) -> Iterator[SourceItem | Measurement]:
        if self.jobs <= 1 or self._reader is None:
            yield from self._video
            return
        self._video.prefetch = False  # only frame 0 is decoded here
        frames = iter(self._video)
        first = next(frames)
        self._start_workers()
        self._here = 1
        yield first  # the parent's reader calibrates on it
        state = self._reader.calibration_state
        for worker in self._workers:
            try:
                worker.seed.send(state)
            except OSError:  # the worker already failed (it says why on its queue)
                pass
            worker.seed.close()
        last = 0
        for k, worker in enumerate(self._workers):
            self._current = k
            while True:
                if worker.buffer:
                    item = worker.buffer.popleft()
                    last = item.index
                    yield item
                    continue
                if worker.finished:
                    break
                self._poll(worker, 0.05)
            if worker.end_of_file:
                break  # the file ended in this part (early, if not the last): later parts have no frames
            done = worker.start + worker.received
            last_part = worker is self._workers[-1]
            if worker.error is not None and (done < worker.stop or last_part):
                what = f"frames {done}-{worker.stop - 1}" if not last_part else f"frames from {done} on"
                yield SourceEvent("skipped", f"video {self.path}: the worker for frames from {worker.start} "
                                  f"failed ({worker.error}); measuring {what} here", done / self.fps)
                for frame in self._measure_here(done, None if last_part else worker.stop):
                    last = frame.index
                    self._here += 1
                    yield frame
        seen = last + 1
        if self.frame_count is not None and seen < self.frame_count - 1:
            yield SourceEvent("truncated", f"video {self.path}: ended at frame {seen} of the "
                              f"{self.frame_count} its header declares (truncated or corrupt)", seen / self.fps)

    def backlog(self, wait_s: float = 0.3) -> list[Measurement]:
        """After an interrupt: what the workers had measured and was not yet yielded, in order.

        Waits up to ``wait_s`` for messages already on their way; the rows after the
        interruption point are then written with a gap before them, none is lost.
        """
        deadline = time.monotonic() + wait_s
        while time.monotonic() < deadline and any(not w.finished for w in self._workers):
            before = sum(w.received for w in self._workers)
            self._poll(None, 0.0)
            if sum(w.received for w in self._workers) == before:
                time.sleep(0.02)
        out: list[Measurement] = []
        for worker in self._workers[self._current:]:
            out.extend(worker.buffer)
            worker.buffer.clear()
        return out

    def close(self) -> None:
        for worker in self._workers:
            if worker.process.is_alive():
                worker.process.terminate()
        for worker in self._workers:
            worker.process.join(timeout=2.0)
            worker.results.cancel_join_thread()
            worker.results.close()
            if not worker.seed.closed:
                worker.seed.close()
        self._workers.clear()
        self._video.close()
