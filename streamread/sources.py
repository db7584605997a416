"""Frame sources behind one interface: V4L2 cameras, video files, image sequences, the renderer.

A source is iterated; it yields :class:`Frame` items and, between them, :class:`SourceEvent`
items that say what happened to the stream (a camera lost and reopened, a file that ended
before its declared length, an unreadable image skipped). The loop decides what to do.

Cameras go through a *capture factory* (``cv2.VideoCapture`` by default) so tests can pass a
fake with the same small interface: ``isOpened()``, ``read()``, ``set()``, ``get()``,
``release()``.
"""

from __future__ import annotations

import glob
import math
import os
import queue
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Protocol

import cv2
import numpy as np

from streamread.errors import InputError, expected

EventKind = Literal["lost", "reopened", "truncated", "skipped", "gave_up"]


@dataclass(frozen=True)
class Frame:
    """One decoded frame: its index in the stream, its time in seconds, BGR pixels.

    A decoder may hand over only its luma plane (a syringe's per-frame path needs no colour, and
    skipping the conversion to BGR saves about a third of decoding). Then ``image`` is that
    plane, ``luma_lut`` maps it to the grey ``cv2.cvtColor`` gives for the BGR frame (video
    range 16-235 to 0-255; None: already full range), and ``colour`` decodes the frame in
    colour for the rare steps that need it (calibration, a meniscus).
    """

    index: int
    time_s: float
    image: np.ndarray
    luma_lut: np.ndarray | None = field(default=None, compare=False, repr=False)
    colour: Callable[[], np.ndarray] | None = field(default=None, compare=False, repr=False)

    def in_colour(self) -> np.ndarray:
        """The frame's BGR pixels (decoded again when only its luma was)."""
        return self.image if self.colour is None else self.colour()

    def __post_init__(self) -> None:
        if self.index < 0:
            raise ValueError(expected("frame", "index", ">= 0", self.index))
        if not math.isfinite(self.time_s):
            raise ValueError(expected("frame", "time_s", "a finite number", self.time_s))
        if self.luma_lut is not None and (self.luma_lut.shape != (256,) or self.luma_lut.dtype != np.uint8):
            raise ValueError(expected("frame", "luma_lut", "a 256-entry uint8 table",
                                      f"{self.luma_lut.dtype} {self.luma_lut.shape}"))
        if (self.colour is not None or self.luma_lut is not None) and self.image.ndim != 2:
            raise ValueError(expected("frame", "image", "a luma plane (2-D) with colour or luma_lut",
                                      f"shape {self.image.shape}"))


@dataclass(frozen=True)
class SourceEvent:
    """Something that happened to the stream between frames."""

    kind: EventKind
    message: str
    time_s: float


SourceItem = Frame | SourceEvent


class Capture(Protocol):
    """The part of ``cv2.VideoCapture`` a source uses (fakes in tests implement this)."""

    def isOpened(self) -> bool: ...  # noqa: N802 (OpenCV's name)
    def read(self) -> tuple[bool, np.ndarray | None]: ...
    def set(self, prop: int, value: float) -> bool: ...
    def get(self, prop: int) -> float: ...
    def release(self) -> None: ...


CaptureFactory = Callable[..., Capture]


class Source(Protocol):
    name: str
    fps: float
    frame_count: int | None  # known for files, None for live sources

    def __iter__(self) -> Iterator[SourceItem]: ...

    def close(self) -> None: ...


def _bgr(image: np.ndarray) -> np.ndarray:
    if image.ndim == 2:
        return cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    return image[..., :3] if image.shape[2] == 4 else image


# ----------------------------------------------------------------------------- video files

class VideoFileSource:
    """A recorded video; frame times come from the frame index and the file's frame rate."""

    def __init__(self, path: str | Path, capture_factory: CaptureFactory = cv2.VideoCapture,
                 prefetch: bool = False) -> None:
        self.path = Path(path)
        self.prefetch = prefetch  # decode in a background thread
        self.name = str(path)
        if not self.path.exists():
            raise InputError(expected("video", self.path, "an existing video file", "no such file"))
        if self.path.is_dir():
            raise InputError(expected("video", self.path, "a video file", "a directory"))
        self._cap = capture_factory(str(self.path))
        first: np.ndarray | None = None
        if self._cap.isOpened():
            ok, first = self._cap.read()
            if not ok or first is None or getattr(first, "size", 0) == 0:
                first = None
        if first is None:
            self._cap.release()
            raise InputError(expected("video", self.path, "a video OpenCV can decode (mp4, avi, mkv, ...)",
                                      "no decodable frame"))
        self._first: np.ndarray | None = first
        fps = float(self._cap.get(cv2.CAP_PROP_FPS) or 0.0)
        self.fps = fps if math.isfinite(fps) and 0 < fps < 1000 else 30.0
        count = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        self.frame_count = count if count > 0 else None

    def _decoded(self) -> Iterator[np.ndarray]:
        if self._first is not None:
            first, self._first = self._first, None
            yield first
        while True:
            try:
                ok, image = self._cap.read()
            except cv2.error:  # a corrupt packet can make the decoder throw
                ok, image = False, None
            if not ok or image is None:
                return
            yield image

    def _prefetched(self) -> Iterator[np.ndarray]:
        """Decode in a background thread (OpenCV releases the GIL) while frames are read.

        The decoder then keeps one core busy, so OpenCV's own thread pool is trimmed by one for
        the run (on a two-core machine the per-frame resampling otherwise fights the decoder).
        """
        buffer: queue.Queue[np.ndarray | None] = queue.Queue(maxsize=16)
        stop = threading.Event()

        def put(item: np.ndarray | None) -> bool:
            while not stop.is_set():
                try:
                    buffer.put(item, timeout=0.1)
                    return True
                except queue.Full:
                    continue
            return False

        def work() -> None:
            try:
                for image in self._decoded():
                    if not put(image):
                        return
            finally:
                put(None)

        threads = cv2.getNumThreads()
        cv2.setNumThreads(max(1, min(threads, (os.cpu_count() or 2) - 1)))
        worker = threading.Thread(target=work, name="decode", daemon=True)
        worker.start()
        try:
            while (image := buffer.get()) is not None:
                yield image
        finally:
            stop.set()
            worker.join(timeout=2.0)
            cv2.setNumThreads(threads)

    def __iter__(self) -> Iterator[SourceItem]:
        index = 0
        for image in (self._prefetched() if self.prefetch else self._decoded()):
            yield Frame(index, index / self.fps, _bgr(image))
            index += 1
        if self.frame_count is not None and index < self.frame_count - 1:
            yield SourceEvent("truncated", f"video {self.path}: ended at frame {index} of the "
                              f"{self.frame_count} its header declares (truncated or corrupt)", index / self.fps)

    def close(self) -> None:
        self._cap.release()


# ----------------------------------------------------------------------------- cameras

def parse_device(device: str) -> str | int:
    """``/dev/video2`` or ``2`` (an index): what OpenCV's V4L2 backend opens."""
    text = str(device).strip()
    if text.isdigit():
        return int(text)
    if text.startswith("/dev/"):
        return text
    raise InputError(expected("camera", repr(device), "a V4L2 device such as /dev/video0, or an index such as 0",
                              "neither"))


class CameraSource:
    """A live camera through OpenCV's V4L2 backend, reopened with backoff when it drops.

    Frame times are seconds since the source started (monotonic clock). While the camera is
    gone the source yields ``lost`` once, retries with exponential backoff, yields
    ``reopened`` when it is back, and ``gave_up`` (then ends) after ``give_up_s``.
    """

    def __init__(self, device: str, size_wh: tuple[int, int] | None = None, fps: float | None = None,
                 capture_factory: CaptureFactory | None = None, give_up_s: float = 60.0,
                 backoff_s: tuple[float, float] = (0.25, 4.0), max_frames: int | None = None,
                 clock: Callable[[], float] = time.monotonic, sleep: Callable[[float], None] = time.sleep) -> None:
        self.device = parse_device(device)
        self.name = str(device)
        self.size_wh, self.fps, self.frame_count = size_wh, fps or 30.0, None
        self._requested_fps = fps
        self._factory = capture_factory or (lambda dev: cv2.VideoCapture(dev, cv2.CAP_V4L2))
        self._give_up_s, self._backoff = give_up_s, backoff_s
        self._max_frames = max_frames
        self._clock, self._sleep = clock, sleep
        if isinstance(self.device, str) and capture_factory is None and not os.path.exists(self.device):
            raise InputError(expected("camera", self.device, "an existing V4L2 device", "no such device"))
        self._cap: Capture | None = self._open()
        if self._cap is None:
            raise InputError(expected("camera", self.name, "a V4L2 camera that opens and delivers frames",
                                      "it did not open (missing, busy, or not a camera)"))
        self._t0 = self._clock()

    def _open(self) -> Capture | None:
        try:
            cap = self._factory(self.device)
        except Exception:  # noqa: BLE001 - a backend may throw for a vanished device
            return None
        if not cap.isOpened():
            cap.release()
            return None
        if self.size_wh is not None:
            cap.set(cv2.CAP_PROP_FRAME_WIDTH, self.size_wh[0])
            cap.set(cv2.CAP_PROP_FRAME_HEIGHT, self.size_wh[1])
        if self._requested_fps is not None:
            cap.set(cv2.CAP_PROP_FPS, self._requested_fps)
        reported = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        if math.isfinite(reported) and 0 < reported < 1000:
            self.fps = reported
        return cap

    def _read(self) -> np.ndarray | None:
        if self._cap is None:
            return None
        try:
            ok, image = self._cap.read()
        except Exception:  # noqa: BLE001 - the device vanished under the backend
            return None
        return image if ok and image is not None and getattr(image, "size", 0) else None

    def __iter__(self) -> Iterator[SourceItem]:
        index = 0
        while self._max_frames is None or index < self._max_frames:
            image = self._read()
            if image is not None:
                yield Frame(index, self._clock() - self._t0, _bgr(image))
                index += 1
                continue
            lost_at = self._clock()
            yield SourceEvent("lost", f"camera {self.name}: no frame; reopening", lost_at - self._t0)
            if self._cap is not None:
                self._cap.release()
                self._cap = None
            delay = self._backoff[0]
            while self._cap is None:
                if self._clock() - lost_at > self._give_up_s:
                    yield SourceEvent("gave_up", f"camera {self.name}: gone for over {self._give_up_s:g} s; stopping",
                                      self._clock() - self._t0)
                    return
                self._sleep(delay)
                delay = min(2 * delay, self._backoff[1])
                self._cap = self._open()
                if self._cap is not None and (first := self._read()) is not None:
                    yield SourceEvent("reopened", f"camera {self.name}: reopened", self._clock() - self._t0)
                    yield Frame(index, self._clock() - self._t0, _bgr(first))
                    index += 1
                elif self._cap is not None:
                    self._cap.release()
                    self._cap = None

    def close(self) -> None:
        if self._cap is not None:
            self._cap.release()
            self._cap = None


# ----------------------------------------------------------------------------- image sequences

class ImageSequenceSource:
    """Images matched by a glob, in name order, at a nominal frame rate."""

    def __init__(self, pattern: str, fps: float = 10.0) -> None:
        self.name = pattern
        self.paths = sorted(glob.glob(pattern))
        if not self.paths:
            raise InputError(expected("images", repr(pattern), "a glob that matches image files", "no match"))
        self.fps = fps
        self.frame_count = len(self.paths)

    def __iter__(self) -> Iterator[SourceItem]:
        for i, path in enumerate(self.paths):
            image = cv2.imread(path, cv2.IMREAD_COLOR)
            if image is None:
                yield SourceEvent("skipped", f"image {path}: expected an image file, could not decode it", i / self.fps)
                continue
            yield Frame(i, i / self.fps, image)

    def close(self) -> None:
        pass


# ----------------------------------------------------------------------------- the renderer

class SynthSource:
    """A scripted synthetic recording rendered on the fly (e.g. ``synth:staircase``)."""

    def __init__(self, protocol: str = "staircase", apparatus: str = "syringe_5ml", seed: int = 11,
                 fps: float = 15.0, frame_wh: tuple[int, int] = (640, 480)) -> None:
        from streamread.synth.samples import SampleRecording, sample_params
        from streamread.synth.video import script

        self.name = f"synth:{protocol}"
        self.fps = fps
        self.params = sample_params(SampleRecording(self.name, apparatus, protocol, seed=seed, fps=fps,
                                                    frame_wh=frame_wh, roll_deg=90.0))
        self.script = script(protocol, self.params, fps, seed=seed)
        self.frame_count = len(self.script)

    def __iter__(self) -> Iterator[SourceItem]:
        from streamread.synth.video import render_frames

        for i, (image, _) in enumerate(render_frames(self.params, self.script)):
            yield Frame(i, i / self.fps, image)

    def close(self) -> None:
        pass


def open_source(spec: str, *, camera: bool = False, size_wh: tuple[int, int] | None = None,
                fps: float | None = None, prefetch: bool = False) -> Source:
    """A source from a command-line string: a device, a video file, an image glob or ``synth:PROTOCOL``.

    ``prefetch`` decodes a video file in a background thread (offline analysis).
    """
    if camera:
        return CameraSource(spec, size_wh=size_wh, fps=fps)
    if spec.startswith("synth:"):
        return SynthSource(spec.split(":", 1)[1] or "staircase", fps=fps or 15.0)
    if any(ch in spec for ch in "*?["):
        return ImageSequenceSource(spec, fps=fps or 10.0)
    return VideoFileSource(spec, prefetch=prefetch)
