"""Frame sources: files, image globs, and cameras through a fake of the capture interface."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from streamread.errors import InputError
from streamread.sources import CameraSource, Frame, ImageSequenceSource, SourceEvent, VideoFileSource, parse_device


class FakeCapture:
    """Stands in for cv2.VideoCapture: delivers ``frames`` then fails (the camera dropped)."""

    def __init__(self, frames: int, shape: tuple[int, int] = (48, 64), opened: bool = True) -> None:
        self.left = frames
        self.shape = shape
        self.opened = opened
        self.released = False
        self.props: dict[int, float] = {}

    def isOpened(self) -> bool:  # noqa: N802
        return self.opened

    def read(self) -> tuple[bool, np.ndarray | None]:
        if self.left <= 0:
            return False, None
        self.left -= 1
        return True, np.full(self.shape + (3,), 100, np.uint8)

    def set(self, prop: int, value: float) -> bool:
        self.props[prop] = value
        return True

    def get(self, prop: int) -> float:
        return self.props.get(prop, 0.0)

    def release(self) -> None:
        self.released = True


class Clock:
    def __init__(self) -> None:
        self.t = 0.0
        self.sleeps: list[float] = []

    def now(self) -> float:
        return self.t

    def sleep(self, s: float) -> None:
        self.sleeps.append(s)
        self.t += s


def test_camera_drop_is_reported_and_reopened_with_backoff() -> None:
    # opens: 1st delivers 5 frames then drops; the next 3 opens fail; the 5th delivers 4 frames
    plan = [FakeCapture(5), FakeCapture(0, opened=False), FakeCapture(0, opened=False),
            FakeCapture(0, opened=False), FakeCapture(4)]
    clock = Clock()
    source = CameraSource("0", capture_factory=lambda dev: plan.pop(0), max_frames=9, clock=clock.now,
                          sleep=clock.sleep, backoff_s=(0.25, 4.0))
    items = list(source)
    frames = [i for i in items if isinstance(i, Frame)]
    events = [i.kind for i in items if isinstance(i, SourceEvent)]
    assert [f.index for f in frames] == list(range(9)), "indices continue across the drop"
    assert events == ["lost", "reopened"]
    assert clock.sleeps == [0.25, 0.5, 1.0, 2.0], "exponential backoff between reopen attempts"


def test_camera_that_stays_gone_gives_up() -> None:
    opens = iter([FakeCapture(2)] + [FakeCapture(0, opened=False) for _ in range(100)])
    clock = Clock()
    source = CameraSource("/dev/video7", capture_factory=lambda dev: next(opens), give_up_s=5.0,
                          clock=clock.now, sleep=clock.sleep)
    items = list(source)
    assert sum(isinstance(i, Frame) for i in items) == 2
    assert [i.kind for i in items if isinstance(i, SourceEvent)] == ["lost", "gave_up"]


def test_camera_that_does_not_open_is_a_clear_error() -> None:
    with pytest.raises(InputError, match="camera 3: expected a V4L2 camera"):
        CameraSource("3", capture_factory=lambda dev: FakeCapture(0, opened=False))
    with pytest.raises(InputError, match="/dev/video99"):
        CameraSource("/dev/video99")  # no such device on this machine
    with pytest.raises(InputError, match="expected a V4L2 device"):
        parse_device("webcam")


def test_camera_size_and_fps_are_requested() -> None:
    cap = FakeCapture(1)
    CameraSource("0", size_wh=(320, 240), fps=30, capture_factory=lambda dev: cap, max_frames=1)
    assert cap.props[cv2.CAP_PROP_FRAME_WIDTH] == 320 and cap.props[cv2.CAP_PROP_FRAME_HEIGHT] == 240
    assert cap.props[cv2.CAP_PROP_FPS] == 30


def _write_video(path: Path, n: int = 20) -> None:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 10.0, (64, 48))
    for i in range(n):
        writer.write(np.full((48, 64, 3), 10 * i % 255, np.uint8))
    writer.release()


def test_video_file_frames_and_times(tmp_path: Path) -> None:
    path = tmp_path / "v.mp4"
    _write_video(path)
    for prefetch in (False, True):
        source = VideoFileSource(path, prefetch=prefetch)
        frames = [i for i in source if isinstance(i, Frame)]
        source.close()
        assert len(frames) == 20 and source.fps == pytest.approx(10.0)
        assert frames[3].time_s == pytest.approx(0.3) and frames[3].image.shape == (48, 64, 3)


def test_bad_video_files_are_clear_errors(tmp_path: Path) -> None:
    text = tmp_path / "notes.mp4"
    text.write_text("this is not a video\n")
    with pytest.raises(InputError, match="notes.mp4: expected a video OpenCV can decode"):
        VideoFileSource(text)
    with pytest.raises(InputError, match="no such file"):
        VideoFileSource(tmp_path / "missing.mp4")
    with pytest.raises(InputError, match="a directory"):
        VideoFileSource(tmp_path)


def test_truncated_video_ends_with_an_event(tmp_path: Path) -> None:
    path = tmp_path / "v.mp4"
    _write_video(path, 60)
    data = path.read_bytes()
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(data[: int(len(data) * 0.6)])
    try:
        source = VideoFileSource(cut)
    except InputError:
        return  # the container index was lost: refused up front, also a clean outcome
    items = list(source)
    frames = [i for i in items if isinstance(i, Frame)]
    assert len(frames) < 60
    events = [i for i in items if isinstance(i, SourceEvent)]
    if source.frame_count and len(frames) < source.frame_count - 1:
        assert events and events[-1].kind == "truncated" and "cut.mp4" in events[-1].message


def test_image_sequence_skips_unreadable(tmp_path: Path) -> None:
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"f{i}.png"), np.zeros((20, 20, 3), np.uint8))
    (tmp_path / "f9.png").write_text("broken")
    items = list(ImageSequenceSource(str(tmp_path / "f*.png")))
    assert sum(isinstance(i, Frame) for i in items) == 3
    assert [i.kind for i in items if isinstance(i, SourceEvent)] == ["skipped"]
    with pytest.raises(InputError, match="no match"):
        ImageSequenceSource(str(tmp_path / "none*.png"))
