"""Faults and bad input: the reader keeps working, loses nothing, and never makes up a level.

Camera faults go through a fake of the capture interface that replays real frames of a sample
recording; bad files are made by cutting and overwriting bytes of a real recording.
"""

from __future__ import annotations

import csv
import json
import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from rerun.chunk import RrdReader

from streamread.cli import main
from streamread.detector import OnnxDetector
from streamread.reader import ReaderOptions, read_image
from streamread.run import run_loop
from streamread.sources import CameraSource, Frame, VideoFileSource
from streamread.stream import StreamConfig, StreamReader
from streamread.synth.background import make_background

RECORDINGS = Path(__file__).resolve().parents[1] / "recordings"
STAIRCASE = RECORDINGS / "syringe5ml_staircase.mp4"


def _frames(path: Path, n: int) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    out = []
    while len(out) < n:
        ok, image = cap.read()
        if not ok:
            break
        out.append(image)
    return out


class ReplayCapture:
    """A camera that plays ``frames`` and then drops (read fails), as an unplugged USB camera does."""

    def __init__(self, frames: list[np.ndarray]) -> None:
        self.frames = list(frames)

    def isOpened(self) -> bool:  # noqa: N802
        return True

    def read(self) -> tuple[bool, np.ndarray | None]:
        return (True, self.frames.pop(0)) if self.frames else (False, None)

    def set(self, prop: int, value: float) -> bool:
        return True

    def get(self, prop: int) -> float:
        return 0.0

    def release(self) -> None:
        pass


class Ticker:
    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        self.t += 1 / 15
        return self.t

    def sleep(self, s: float) -> None:
        self.t += s


# ----------------------------------------------------------------------------- camera faults

def test_camera_drop_and_return_loses_no_reading(tmp_path: Path) -> None:
    frames = _frames(STAIRCASE, 80)
    sessions = [ReplayCapture(frames[:40]), None, None, ReplayCapture(frames[40:])]  # gone for two attempts

    def factory(device: object) -> ReplayCapture:
        cap = sessions.pop(0)
        if cap is None:
            raise OSError("no such device")  # the device node vanished
        return cap

    ticker = Ticker()
    source = CameraSource("0", capture_factory=factory, max_frames=80, clock=ticker.now, sleep=ticker.sleep)
    out, rrd = tmp_path / "cam.csv", tmp_path / "cam.rrd"
    import rerun as rr

    from streamread.sink import RerunSink

    rec = rr.RecordingStream("streamread_fault_test")
    rec.save(rrd)
    summary = run_loop(source, StreamReader(StreamConfig(apparatus="syringe")), out, sink=RerunSink(rec))
    rec.disconnect()
    rows = list(csv.DictReader(open(out)))
    assert summary.frames == 80 and len(rows) == 80, "every frame before and after the drop is in the CSV"
    assert any("no frame; reopening" in e for e in summary.events) and any("reopened" in e for e in summary.events)
    assert sum(1 for r in rows if r["level"]) >= 75
    logged = set()
    for chunk in RrdReader(rrd).stream().filter(content="/level/filtered").to_chunks():
        if not chunk.is_static:
            logged |= set(chunk.to_record_batch().column("frame").to_pylist())
    assert logged == {int(r["frame"]) for r in rows if r["level"]}, "and in the .rrd"


def test_late_frames_and_a_resized_frame_are_survived() -> None:
    frames = _frames(STAIRCASE, 60)
    reader = StreamReader(StreamConfig(apparatus="syringe"))
    results = [reader.process(Frame(i, i / 15, f)) for i, f in enumerate(frames[:30])]
    # the camera stalls for 2 s, then frames come again
    results += [reader.process(Frame(i, 2.0 + i / 15, f)) for i, f in enumerate(frames[30:45], start=30)]
    # one frame of another size (a driver renegotiated), then the normal size again
    odd = reader.process(Frame(45, 5.0, cv2.resize(frames[45], (320, 240))))
    assert odd.level_raw is None and any("frame size changed" in e for e in odd.events)
    results += [reader.process(Frame(i, 2.0 + i / 15, f)) for i, f in enumerate(frames[46:], start=46)]
    assert all(r.level is not None for r in results[-10:]), "recalibrated and tracking again"


# ----------------------------------------------------------------------------- bad files

def _damaged(tmp_path: Path, how: str) -> Path:
    data = bytearray(STAIRCASE.read_bytes())
    path = tmp_path / f"{how}.mp4"
    if how == "truncated":
        data = data[: len(data) // 2]
    elif how == "overwritten":
        rng = np.random.default_rng(0)
        start = len(data) // 3
        data[start: start + 20000] = rng.integers(0, 256, 20000, dtype=np.uint8).tobytes()
    elif how == "header":
        data[:64] = bytes(64)
    path.write_bytes(bytes(data))
    return path


@pytest.mark.parametrize("how", ["truncated", "overwritten", "header"])
def test_damaged_videos_end_cleanly(how: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = _damaged(tmp_path, how)
    out = tmp_path / "r.csv"
    code = main(["analyze", str(video), "--apparatus", "syringe", "--csv", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if code == 2:  # refused up front: one line naming the file and what was expected
        line = err.strip().splitlines()[-1]
        assert line.startswith("streamread: error:") and str(video) in line and "expected" in line
        return
    assert code in (0, 1)
    rows = list(csv.DictReader(open(out)))
    assert rows, "what could be decoded was read"
    truth = {int(r["frame"]): float(r["level_ml"]) for r in csv.DictReader(open(STAIRCASE.with_suffix(".truth.csv")))}
    for r in rows:
        if r["state"] == "tracking" and r["level"] and int(r["frame"]) in truth:
            # frames may be dropped or shifted by a damaged container; a level is either right
            # for a frame near this one or absent
            near = [truth[i] for i in range(int(r["frame"]) - 30, int(r["frame"]) + 31) if i in truth]
            assert min(abs(float(r["level"]) - t) for t in near) <= 0.2


def _png_header_only(path: Path, width: int, height: int) -> None:
    """A real grey PNG of width x height (all zero), written without holding it in memory."""
    comp = zlib.compressobj(9)
    row = bytes(width + 1)
    idat = b"".join(comp.compress(row) for _ in range(height)) + comp.flush()

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b""))


def test_huge_and_tiny_images_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    huge, tiny = tmp_path / "huge.png", tmp_path / "tiny.png"
    _png_header_only(huge, 20000, 20000)
    cv2.imwrite(str(tiny), np.zeros((1, 1, 3), np.uint8))
    assert main(["read", str(huge), str(tiny), "--json"]) == 1
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["level"] for r in records] == [None, None]
    assert "at most 12000 pixels" in records[0]["error"] and "huge.png" in records[0]["error"]
    assert "at least 16x16" in records[1]["error"]


def test_missing_tesseract_gives_an_install_hint(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    import streamread.ocr

    monkeypatch.setenv("PATH", str(tmp_path))  # no tesseract binary on PATH ...
    monkeypatch.setattr(streamread.ocr, "_tessdata_dir", lambda: None)  # ... and no traineddata for tesserocr
    code = main(["analyze", str(STAIRCASE), "--apparatus", "syringe", "--csv", str(tmp_path / "r.csv"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "tesseract" in err and "apt-get install" in err


# ----------------------------------------------------------------------------- no false readings

@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), dark=st.booleans(), clutter=st.integers(0, 8))
def test_clutter_without_apparatus_gives_no_reading(seed: int, dark: bool, clutter: int) -> None:
    scene = make_background(np.random.default_rng(seed), 480, 360, dark=dark, n_distractors=clutter)
    image = np.clip(scene * 255, 0, 255).astype(np.uint8)
    assert read_image(image).level is None


@pytest.mark.parametrize("seed,dark,clutter", [(273, False, 8), (86, True, 5)])
def test_a_ruler_among_clutter_is_no_apparatus_on_two_numbers(seed: int, dark: bool, clutter: int) -> None:
    # no apparatus named and none detected: the rulers' "3", "4" (273) and "4", "2" (86) made a
    # scale, a box's edge across it its "meniscus" (read 3.87 and 6.00 until stop 43); the whole
    # image searched for no named kind needs three numbers that agree
    scene = make_background(np.random.default_rng(seed), 480, 360, dark=dark, n_distractors=clutter)
    image = np.clip(scene * 255, 0, 255).astype(np.uint8)
    reading = read_image(image)
    assert reading.level is None and reading.error


# the same examples every run: a noise image reads nothing only after every search, about a
# minute each (Tesseract on bands of noise), so examples drawn anew made this test take from
# 3 to over 16 minutes (stop 45)
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(seed=st.integers(0, 10_000), period=st.integers(4, 30), angle=st.floats(0, 180),
       kind=st.sampled_from(["noise", "stripes", "bars"]))
# noise whose "numbers" fit a cylinder's scale with no rows of its bore to search for a hue
# (CI at stop 35: OpenCV raised on the empty region)
@example(seed=576, period=4, angle=0.0, kind="noise")
def test_random_images_give_no_reading(seed: int, period: int, angle: float, kind: str) -> None:
    """Noise, gratings and random bars: regular patterns that look like marks but carry no numbers."""
    rng = np.random.default_rng(seed)
    h, w = 300, 400
    if kind == "noise":
        image = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    else:
        image = np.full((h, w, 3), 220, np.uint8)
        if kind == "stripes":
            for y in range(0, h, period):
                cv2.line(image, (40, y), (40 + int(rng.integers(20, 120)), y), (20, 20, 20), 2)
        else:
            for _ in range(60):
                x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
                cv2.line(image, (x, y), (x + int(rng.integers(5, 60)), y), (20, 20, 20), int(rng.integers(1, 4)))
        m = cv2.getRotationMatrix2D((w / 2, h / 2), angle, 1.0)
        image = cv2.warpAffine(image, m, (w, h), borderValue=(220, 220, 220))
    for apparatus in ("auto", "syringe"):
        assert read_image(image, ReaderOptions(apparatus=apparatus)).level is None


# with and without the detector: ``analyze`` crops with the bundled one by default, and a wrong
# level while tracking (frame 61 of the burette, 69 divisions off) once showed only with it
@pytest.mark.parametrize("with_detector", [False, True])
@pytest.mark.parametrize("name", ["syringe5ml_occlusion", "syringe5ml_leave", "burette25ml_leave"])
def test_no_wrong_level_while_tracking(name: str, with_detector: bool) -> None:
    meta = json.loads((RECORDINGS / f"{name}.truth.json").read_text())
    truth = {int(r["frame"]): float(r["level_ml"]) for r in csv.DictReader(open(RECORDINGS / f"{name}.truth.csv"))}
    kind = meta["kind"].replace("measuring_cylinder", "cylinder")
    reader = StreamReader(StreamConfig(apparatus=kind, detector=OnnxDetector() if with_detector else None))
    checked = 0
    for item in VideoFileSource(RECORDINGS / f"{name}.mp4"):
        if not isinstance(item, Frame):
            continue
        result = reader.process(item)
        if result.state == "tracking" and result.level is not None:
            assert abs(result.level - truth[item.index]) <= meta["minor_ml"], \
                f"{name} frame {item.index}: {result.level:.3f} while the truth is {truth[item.index]:.3f}"
            checked += 1
        if not meta["per_frame"][item.index]["visible"]:
            assert result.level_raw is None, f"{name} frame {item.index}: a raw level with nothing to see"
    if name.startswith("syringe"):
        assert checked > 100


def test_both_tesseract_engines_read_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    """tesserocr (in-process) and pytesseract (the binary) are one engine: the same numbers."""
    from streamread.reader import calibrate

    image = _frames(STAIRCASE, 1)[0]
    fast, _ = calibrate(image, ReaderOptions(apparatus="syringe"))
    monkeypatch.setenv("STREAMREAD_OCR", "pytesseract")
    slow, _ = calibrate(image, ReaderOptions(apparatus="syringe"))
    assert fast is not None and slow is not None
    assert [r.text for r in fast.reads] == [r.text for r in slow.reads]
    assert fast.fit.slope == pytest.approx(slow.fit.slope)
