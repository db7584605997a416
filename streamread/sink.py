"""The Rerun sink: what the streaming reader sees and reads, live in the Rerun viewer or in a ``.rrd``.

This is the only module that imports ``rerun``; the core (``stream``, ``run``) talks to it
through the small ``Sink`` interface (``log_frame``, ``log_source_event``, ``close``).
Everything is logged to an explicit :class:`rerun.RecordingStream` handed in by the caller,
never to Rerun's global recording, so a library user's own Rerun logging is left alone.

Entities (all on the ``frame`` sequence timeline and the ``video_time`` duration timeline):

- ``camera/image``: the frame as a JPEG (:class:`rerun.EncodedImage`), every ``image_every`` frames;
- ``camera/box``, ``camera/outline``, ``camera/scale/axis``, ``camera/scale/marks/major``,
  ``camera/scale/marks/minor``, ``camera/scale/numbers`` (the OCR text where it was read),
  ``camera/scale/values`` (the fit's value at each major mark): the calibration, in image
  pixels, logged only when the calibration changes (a new one, or a re-registration shift);
  Rerun's latest-at semantics keep them on screen for the frames after;
- ``camera/indicator/point``, ``camera/indicator/line``, ``camera/reading``: per frame;
- ``strip/image`` (the rectified strip, JPEG) and ``strip/indicator`` (the indicator row);
- ``level/filtered``, ``level/raw``, ``level/upper``, ``level/lower`` (filtered +- sigma),
  ``rate`` (ml/s), ``state`` (calibrating 0, tracking 1, coasting 2, lost 3): scalars, only
  on frames where the value exists;
- ``events``: the reader's and the source's events, and state changes, as text logs.

Overlays are cleared (:class:`rerun.Clear`) on the frame they stop being true (no
calibration, no indicator) so stale marks never sit on a newer image.

Cost: a ``RecordingStream.log`` call is 0.1-0.4 ms of Python, so the small per-frame rows
(series, indicator, reading label) are buffered and sent as columns (``send_columns``) at
least every ``max_delay_s`` (0.1 s) of wall time, and their colours and sizes are logged
once as static data. What is left per frame is mostly the JPEG encoding of the images
(``image_every`` thins those out).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass, field

import cv2
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from streamread.apparatus import format_value
from streamread.argtypes import at_least_one
from streamread.errors import InputError, expected
from streamread.sources import Frame, SourceEvent
from streamread.stream import FrameResult
from streamread.types import Calibration, Reading

STATE_CODES: dict[str, int] = {"calibrating": 0, "tracking": 1, "coasting": 2, "lost": 3}

# RGB
MAJOR = (230, 40, 40)
MEDIUM = (255, 165, 0)
MINOR = (0, 140, 255)
AXIS = (200, 200, 200)
BOX = (120, 220, 120)
READ_OK = (0, 200, 0)
READ_BAD = (230, 0, 0)
VALUE = (255, 220, 0)
INDICATOR = (255, 0, 255)
FILTERED = (30, 120, 255)
RAW = (150, 150, 150)
BAND = (140, 180, 255)

_WARN_WORDS = ("lost", "dropped", "failed", "no longer matches", "jumped", "changed", "gave up", "truncated")


def event_level(text: str) -> str:
    """INFO for calibrations, OCR re-runs, re-registrations; WARN for losses, drops and failures."""
    lowered = text.lower()
    if lowered.startswith(("calibrated", "calibration loaded", "re-registered", "print matches again")):
        return rr.TextLogLevel.INFO
    return rr.TextLogLevel.WARN if any(word in lowered for word in _WARN_WORDS) else rr.TextLogLevel.INFO


def default_blueprint() -> rrb.Blueprint:
    """Camera with overlays (events below) beside the level and rate plots, and the strip."""
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial2DView(origin="camera", name="camera"),
                rrb.TextLogView(origin="events", name="events"),
                row_shares=[4, 1],
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="level", name="level (ml)"),
                rrb.TimeSeriesView(origin="rate", name="rate (ml/s)"),
                rrb.TimeSeriesView(origin="state", name="state (0 calibrating, 1 tracking, 2 coasting, 3 lost)"),
                row_shares=[3, 1.5, 1],
            ),
            rrb.Spatial2DView(origin="strip", name="strip"),
            column_shares=[3, 3, 1],
        ),
    )


def _jpeg(image: np.ndarray, quality: int) -> rr.EncodedImage:
    ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:  # pragma: no cover - OpenCV encodes any uint8 image
        raise RuntimeError("OpenCV could not encode a JPEG")
    return rr.EncodedImage(contents=buf.tobytes(), media_type="image/jpeg")


def _same_calibration(a: Calibration | None, b: Calibration | None) -> bool:
    if a is b:
        return True
    if a is None or b is None:
        return False
    return (a.marks is b.marks and a.fit is b.fit and a.reads is b.reads and a.bore_x_up == b.bore_x_up
            and a.box_xyxy == b.box_xyxy and a.upright.strip_wh == b.upright.strip_wh
            and np.array_equal(a.upright.to_upright, b.upright.to_upright))


def reading_text(result: FrameResult) -> str:
    """``2.40 ± 0.01 ml (tracking)``; ``no reading (lost)`` without a level."""
    unit = result.reading.unit if result.reading is not None else "ml"
    if result.level is None:
        return f"no reading ({result.state})"
    minor = result.calibration.fit.minor_ml if result.calibration is not None else 0.1
    digits = 2 if minor >= 0.1 else 3
    sigma = "" if result.sigma is None else f" ± {result.sigma:.{digits}f}"
    return f"{result.level:.{digits}f}{sigma} {unit} ({result.state})"


@dataclass
class _Rows:
    archetype: type
    frames: list[int] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    fields: dict[str, list[object]] = field(default_factory=dict)


class _ColumnBuffer:
    """Per-frame rows of small entities, sent as columns (``send_columns``) a few times a second.

    One ``RecordingStream.log`` costs 0.1-0.4 ms of Python (arrow conversion per component);
    a column of many rows costs about the same as one row. Rows wait at most ``max_delay_s``
    of wall time (checked once per frame) or ``max_rows`` frames, so a live viewer lags by at
    most that; the viewer orders everything by the timelines, not by arrival.
    """

    def __init__(self, recording: rr.RecordingStream, max_delay_s: float, max_rows: int = 256) -> None:
        self.recording = recording
        self.max_delay_s = max_delay_s
        self.max_rows = max_rows
        self._rows: dict[str, _Rows] = {}
        self._since: float | None = None
        self._frames = 0
        self._now: tuple[int, float] | None = None  # the sink's current time, restored after a one-row log

    def add(self, entity: str, archetype: type, index: int, time_s: float, **fields: object) -> None:
        rows = self._rows.get(entity)
        if rows is not None and (rows.archetype is not archetype or rows.fields.keys() != fields.keys()):
            self._send(entity)
            rows = None
        if rows is None:
            rows = self._rows[entity] = _Rows(archetype, fields={name: [] for name in fields})
        rows.frames.append(index)
        rows.times.append(time_s)
        self._now = (index, time_s)
        for name, value in fields.items():
            rows.fields[name].append(value)

    def end_frame(self) -> None:
        self._frames += 1
        now = time.perf_counter()
        if self._since is None:
            self._since = now
        if now - self._since >= self.max_delay_s or self._frames >= self.max_rows:
            self.flush()

    def flush(self) -> None:
        for entity in list(self._rows):
            self._send(entity)
        self._since = None
        self._frames = 0

    def _send(self, entity: str) -> None:
        rows = self._rows.pop(entity)
        if len(rows.frames) == 1:  # one row: ``log`` is several times cheaper than ``send_columns``
            rec = self.recording
            rec.set_time("frame", sequence=rows.frames[0])
            rec.set_time("video_time", duration=rows.times[0])
            rec.log(entity, rows.archetype.from_fields(  # type: ignore[attr-defined]
                **{name: [values[0]] for name, values in rows.fields.items()}))
            if self._now is not None:
                rec.set_time("frame", sequence=self._now[0])
                rec.set_time("video_time", duration=self._now[1])
            return
        fields = {name: np.asarray(values, np.float64) if name in ("scalars", "positions") else values
                  for name, values in rows.fields.items()}
        self.recording.send_columns(
            entity,
            indexes=[rr.TimeColumn("frame", sequence=rows.frames), rr.TimeColumn("video_time", duration=rows.times)],
            columns=rows.archetype.columns(**fields),  # type: ignore[attr-defined]
        )


class RerunSink:
    """Logs each frame's image, overlays, series and events to ``recording``.

    ``image_every``: log the camera image and the strip every this many frames (overlays and
    series are logged every frame). ``jpeg_quality``: OpenCV's 0-100. ``max_delay_s``: the
    per-frame series and indicator overlays are sent in columns at least this often (wall
    time; 0 sends every frame), which makes logging several times cheaper; images,
    calibration overlays, clears and events are sent at once.
    """

    def __init__(self, recording: rr.RecordingStream, image_every: int = 1, jpeg_quality: int = 80,
                 send_blueprint: bool = True, max_delay_s: float = 0.1) -> None:
        if image_every < 1:
            raise InputError(expected("rerun", "image_every", "a whole number >= 1", image_every))
        if not 0 <= jpeg_quality <= 100:
            raise InputError(expected("rerun", "jpeg_quality", "0 to 100", jpeg_quality))
        if not max_delay_s >= 0:
            raise InputError(expected("rerun", "max_delay_s", ">= 0 seconds", max_delay_s))
        self.recording = recording
        self.image_every = int(image_every)
        self.jpeg_quality = int(jpeg_quality)
        self._rows = _ColumnBuffer(recording, max_delay_s)
        self.frames_logged = 0
        self.images_logged = 0
        self.calibrations_logged = 0
        self._calibration: Calibration | None = None
        self._reading_at = (4.0, 4.0)  # where the reading's label sits: the strip's top-left corner
        self._indicator_shown = False
        self._strip_shown = False
        self._strip_indicator_shown = False
        self._state: str | None = None
        self._last_index: int | None = None
        if send_blueprint:
            recording.send_blueprint(default_blueprint(), make_active=True, make_default=True)
        self._log_styles()

    # -- static styling --------------------------------------------------------------------------
    def _log_styles(self) -> None:
        """Colours, sizes and names, once and static: per-frame rows then carry only what changes."""
        rec = self.recording
        rec.log("level/filtered", rr.SeriesLines(colors=[FILTERED], widths=[2.0], names=["filtered"]), static=True)
        rec.log("level/raw", rr.SeriesPoints(colors=[RAW], marker_sizes=[1.5], names=["raw"]), static=True)
        rec.log("level/upper", rr.SeriesLines(colors=[BAND], widths=[0.75], names=["+sigma"]), static=True)
        rec.log("level/lower", rr.SeriesLines(colors=[BAND], widths=[0.75], names=["-sigma"]), static=True)
        rec.log("rate", rr.SeriesLines(colors=[(0, 170, 120)], widths=[1.5], names=["rate"]), static=True)
        rec.log("state", rr.SeriesLines(colors=[(120, 120, 120)], widths=[1.5], names=["state"],
                                        interpolation_mode="StepAfter"), static=True)
        rec.log("camera/reading", rr.Points2D.from_fields(colors=[INDICATOR], radii=[0.5], show_labels=True),
                static=True)
        rec.log("camera/indicator/point", rr.Points2D.from_fields(colors=[INDICATOR], radii=[3.0], show_labels=True),
                static=True)
        rec.log("camera/indicator/line", rr.LineStrips2D.from_fields(colors=[INDICATOR], radii=[0.75]), static=True)
        rec.log("strip/indicator", rr.LineStrips2D.from_fields(colors=[INDICATOR], radii=[0.75]), static=True)

    # -- time ------------------------------------------------------------------------------------
    def _set_time(self, index: int, time_s: float) -> None:
        self.recording.set_time("frame", sequence=index)
        self.recording.set_time("video_time", duration=time_s)

    # -- the per-frame call ----------------------------------------------------------------------
    def log_frame(self, frame: Frame, result: FrameResult) -> None:
        rec = self.recording
        self._set_time(result.index, result.time_s)
        self._last_index = result.index
        image_frame = self.frames_logged % self.image_every == 0
        if image_frame:
            rec.log("camera/image", _jpeg(frame.image, self.jpeg_quality))
            self.images_logged += 1
        self._log_calibration(result.calibration)
        self._log_indicator(result)
        self._log_strip(result, image_frame)
        self._log_series(result)
        for text in result.events:
            rec.log("events", rr.TextLog(text, level=event_level(text)))
        self.frames_logged += 1
        self._rows.end_frame()

    def _log_calibration(self, cal: Calibration | None) -> None:
        rec = self.recording
        if _same_calibration(cal, self._calibration):
            return
        self._calibration = cal
        if cal is None:
            self._reading_at = (4.0, 4.0)
            rec.log("camera/box", rr.Clear(recursive=True))
            rec.log("camera/outline", rr.Clear(recursive=True))
            rec.log("camera/scale", rr.Clear(recursive=True))
            return
        self.calibrations_logged += 1
        up = cal.upright
        w, h = up.strip_wh
        corners = up.to_input(np.array([[0, 0], [w, 0], [w, h], [0, h], [0, 0]], float))
        self._reading_at = (float(corners[:, 0].min()), float(corners[:, 1].min()))
        if cal.box_xyxy is not None:
            box = np.asarray(cal.box_xyxy, float)
        else:
            box = np.concatenate([corners.min(axis=0), corners.max(axis=0)])
        rec.log("camera/box", rr.Boxes2D(array=box, array_format=rr.Box2DFormat.XYXY, colors=[BOX],
                                         labels=[cal.apparatus]))
        rec.log("camera/outline", rr.LineStrips2D([corners], colors=[AXIS], radii=[0.5]))

        marks = cal.marks.marks
        x0 = np.array([m.x0_up for m in marks])
        x1 = np.array([m.x1_up for m in marks])
        ys = np.array([m.y_up for m in marks])
        # the marks' common edge is the axis; the long (major) end is where the numbers are printed
        right_aligned = float(np.std(x1)) <= float(np.std(x0))
        axis_x = float(np.median(x1 if right_aligned else x0))
        axis = up.to_input(np.array([[axis_x, ys.min()], [axis_x, ys.max()]]))
        rec.log("camera/scale/axis", rr.LineStrips2D([axis], colors=[AXIS], radii=[0.5]))

        def segments(tiers: tuple[str, ...]) -> tuple[list[np.ndarray], list[tuple[int, int, int]]]:
            strips, colors = [], []
            for m in marks:
                if m.tier in tiers:
                    strips.append(up.to_input(np.array([[m.x0_up, m.y_up], [m.x1_up, m.y_up]])))
                    colors.append(MEDIUM if m.tier == "medium" else MAJOR if m.tier == "major" else MINOR)
            return strips, colors

        for name, tiers in (("major", ("major",)), ("minor", ("minor", "medium"))):
            strips, colors = segments(tiers)
            if strips:
                rec.log(f"camera/scale/marks/{name}", rr.LineStrips2D(strips, colors=colors, radii=[0.6]))
            else:
                rec.log(f"camera/scale/marks/{name}", rr.Clear(recursive=False))

        fit = cal.fit
        spacing = cal.marks.spacing_up
        majors = [m for m in marks if m.tier == "major"] or list(marks)
        long_end = min(m.x0_up for m in majors) if right_aligned else max(m.x1_up for m in majors)
        text_x = long_end - spacing if right_aligned else long_end + spacing
        reads = list(cal.reads)
        if reads:
            pts = up.to_input(np.array([[text_x, r.y_up] for r in reads]))
            colors = [READ_OK if r.value is not None and abs(fit.value_at(r.y_up) - r.value) <= 0.3 * fit.minor_ml
                      else READ_BAD for r in reads]
            rec.log("camera/scale/numbers", rr.Points2D(pts, labels=[r.text for r in reads], colors=colors,
                                                        radii=[1.5], show_labels=True))
        else:
            rec.log("camera/scale/numbers", rr.Clear(recursive=False))
        value_x = axis_x + spacing if right_aligned else axis_x - spacing
        pts = up.to_input(np.array([[value_x, m.y_up] for m in majors]))
        labels = [format_value(round(fit.value_at(m.y_up) / fit.minor_ml) * fit.minor_ml) for m in majors]
        rec.log("camera/scale/values", rr.Points2D(pts, labels=labels, colors=[VALUE], radii=[1.0],
                                                   show_labels=True))

    def _log_indicator(self, result: FrameResult) -> None:
        rec, i, t = self.recording, result.index, result.time_s
        cal = result.calibration
        reading: Reading | None = result.reading
        self._rows.add("camera/reading", rr.Points2D, i, t, positions=self._reading_at, labels=reading_text(result))
        ind = None if reading is None else reading.indicator
        if cal is None or reading is None or ind is None:
            if self._indicator_shown:
                rec.log("camera/indicator", rr.Clear(recursive=True))
                self._indicator_shown = False
            return
        up = cal.upright
        point = (reading.indicator_px if reading.indicator_px is not None
                 else up.to_input(np.array([[ind.x_up, ind.y_up]]))[0])
        label = "" if reading.level is None else format_value(reading.level)
        self._rows.add("camera/indicator/point", rr.Points2D, i, t, positions=tuple(point), labels=label)
        left, right = cal.bore_x_up
        line = up.to_input(np.array([[left, ind.y_up], [right, ind.y_up]]))
        self._rows.add("camera/indicator/line", rr.LineStrips2D, i, t, strips=line)
        self._indicator_shown = True

    def _log_strip(self, result: FrameResult, image_frame: bool) -> None:
        rec = self.recording
        strip = result.strip
        if strip is None or result.calibration is None:
            if self._strip_shown:
                rec.log("strip", rr.Clear(recursive=True))
                self._strip_shown = self._strip_indicator_shown = False
            return
        if image_frame or not self._strip_shown:
            rec.log("strip/image", _jpeg(strip, self.jpeg_quality))
            self._strip_shown = True
        ind = None if result.reading is None else result.reading.indicator
        if ind is None:
            if self._strip_indicator_shown:
                rec.log("strip/indicator", rr.Clear(recursive=False))
                self._strip_indicator_shown = False
            return
        left, right = result.calibration.bore_x_up
        self._rows.add("strip/indicator", rr.LineStrips2D, result.index, result.time_s,
                       strips=np.array([[left, ind.y_up], [right, ind.y_up]]))
        self._strip_indicator_shown = True

    def _log_series(self, result: FrameResult) -> None:
        i, t = result.index, result.time_s
        add = self._rows.add
        if result.level is not None:
            add("level/filtered", rr.Scalars, i, t, scalars=result.level)
            if result.sigma is not None:
                add("level/upper", rr.Scalars, i, t, scalars=result.level + result.sigma)
                add("level/lower", rr.Scalars, i, t, scalars=result.level - result.sigma)
        if result.level_raw is not None:
            add("level/raw", rr.Scalars, i, t, scalars=result.level_raw)
        if result.rate is not None:
            add("rate", rr.Scalars, i, t, scalars=result.rate)
        add("state", rr.Scalars, i, t, scalars=float(STATE_CODES.get(result.state, -1)))
        if result.state != self._state:
            text = f"state: {result.state}" if self._state is None else f"state: {self._state} -> {result.state}"
            level = rr.TextLogLevel.WARN if result.state == "lost" else rr.TextLogLevel.INFO
            self.recording.log("events", rr.TextLog(text, level=level))
            self._state = result.state

    # -- between frames --------------------------------------------------------------------------
    def log_source_event(self, event: SourceEvent) -> None:
        """A source event (camera lost/reopened, file truncated, image skipped) at its time."""
        index = 0 if self._last_index is None else self._last_index + 1
        self._set_time(index, event.time_s)
        level = rr.TextLogLevel.INFO if event.kind == "reopened" else rr.TextLogLevel.WARN
        self.recording.log("events", rr.TextLog(f"{event.kind}: {event.message}", level=level))
        if event.kind in ("lost", "gave_up", "truncated"):  # what was measured reaches the sink now
            self._rows.flush()
            self.recording.flush(timeout_sec=2.0)

    def flush(self) -> None:
        """Send the buffered per-frame rows now."""
        self._rows.flush()

    def close(self) -> None:
        """Send what is buffered and flush the stream; the caller disconnects (``close_recording``)."""
        self._rows.flush()
        self.recording.flush()


# ----------------------------------------------------------------------------- command line

def add_rerun_args(parser: argparse.ArgumentParser) -> None:
    """Rerun's usual flags (``rr.script_add_args``) plus ``--spawn`` and ``--log-image-every``.

    ``rr.script_add_args`` gives ``--headless``, ``--connect``, ``--serve``, ``--url``,
    ``--save FILE.rrd`` and ``--stdout``.
    """
    rr.script_add_args(parser)
    parser.add_argument("--serve-web", dest="serve", action="store_true",
                        help="same as --serve: host a web viewer (the name older rerun examples use)")
    parser.add_argument("--spawn", action="store_true", help="start a Rerun viewer and log to it")
    parser.add_argument("--log-image-every", type=at_least_one, default=1, metavar="N",
                        help="with Rerun: log the camera image every N frames (default 1; overlays every frame)")


def wants_rerun(args: argparse.Namespace) -> bool:
    """Whether any flag asked for Rerun output (``--headless`` alone does not)."""
    return any(getattr(args, name, None) for name in ("save", "connect", "url", "serve", "spawn", "stdout"))


def open_recording(args: argparse.Namespace, application_id: str = "streamread",
                   recording_id: str | None = None) -> rr.RecordingStream | None:
    """A recording stream with the sinks the flags ask for, or None when no Rerun flag was given.

    Unlike ``rr.script_setup`` (which spawns a viewer when given no flag and uses the global
    recording), this returns None without a flag, so the loop runs without logging unless the
    user asks, and it makes an explicit :class:`rerun.RecordingStream`. Flags combine (``--save
    run.rrd --spawn`` writes the file and shows the viewer): ``--save`` is a file sink,
    ``--connect [--url URL]`` and ``--spawn`` gRPC clients, ``--serve`` a gRPC server with the
    web viewer (the browser opens unless ``--headless``). ``--stdout`` must be alone.
    """
    if not wants_rerun(args):
        return None
    if getattr(args, "stdout", False):
        others = [f"--{n}" for n in ("save", "connect", "url", "serve", "spawn", "jsonl") if getattr(args, n, None)]
        if others:
            raise InputError(expected("rerun", "--stdout", "no other output flag (it takes the standard output)",
                                      " ".join(others)))
    rec = rr.RecordingStream(application_id, recording_id=recording_id)
    if getattr(args, "stdout", False):
        rec.stdout()
        return rec
    sinks: list[object] = []
    if getattr(args, "save", None):
        sinks.append(rr.FileSink(args.save))
    url = getattr(args, "url", None)
    spawn = bool(getattr(args, "spawn", False))
    if spawn:
        rr.spawn(connect=False, hide_welcome_screen=True)
        sinks.append(rr.GrpcSink())  # the spawned viewer listens on the default address
    if (getattr(args, "connect", False) and not spawn) or url is not None:
        sinks.append(rr.GrpcSink(url))
    server = None
    if getattr(args, "serve", False):
        server = rr.GrpcServerSink()
        sinks.append(server)
    try:
        rec.set_sinks(*sinks)
    except RuntimeError as exc:  # e.g. --save into a folder that does not exist
        raise InputError(expected("rerun", "output", "a writable --save path and reachable viewer", exc)) from None
    if server is not None:
        rr.serve_web_viewer(open_browser=not getattr(args, "headless", False), connect_to=server.uri)
    return rec


def close_recording(args: argparse.Namespace, recording: rr.RecordingStream) -> None:
    """Flush and disconnect (a ``.rrd`` gets its footer); with ``--serve``, keep serving until Ctrl-C."""
    recording.flush()
    if getattr(args, "serve", False):
        print("rerun: serving the recording to the web viewer; Ctrl-C to stop", file=sys.stderr)
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass
    recording.disconnect()
