"""The streaming reader: calibrate once, then only the cheap work on every frame.

Per frame, with a cached calibration:

1. cut the strip (only the print and bore columns) with the cached rotation;
2. check the print still matches the calibration's signature (1-D correlations); a small
   shift is re-registered by moving the strip, no OCR;
3. find the indicator in the strip and read the level (``reader.read_with``);
4. one Kalman step (``tracker.LevelTracker``), with or without a measurement.

OCR (the full still reader, ``reader.calibrate``) runs only when there is no calibration
(start, or after losing it), when the print stops matching (the camera moved, something
covers the scale), or when the indicator has been missing for a while. Calibration attempts
are rate-limited so a scene without an apparatus does not run OCR on every frame.

An offline worker (``parallel``) hands frames over in batches (``StreamReader.measure_many``):
the frames of a batch are cut with the cached calibration and their print responses and
stopper profiles computed as one stack, then each frame is checked and read in order exactly
as alone. Most of a frame's cost one at a time is the overhead of some seventy small numpy
and OpenCV calls, which a stack pays once.

All mutable state lives in :class:`StreamReader`; the stages it calls are pure functions.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from streamread.errors import expected
from streamread.indicator import BACKGROUND_COLUMNS, stopper_profiles
from streamread.orientation import cut_strip
from streamread.profile import Profile, default_profile
from streamread.reader import Detector, ReaderOptions, calibrate, read_with
from streamread.registration import (
    PrintResponse,
    Registration,
    Signature,
    check,
    make_signature,
    print_responses,
    shifted,
)
from streamread.segment import to_gray
from streamread.sources import Frame
from streamread.tracker import LevelTracker, TrackerConfig, TrackState, rts_smooth
from streamread.types import Calibration, Reading


@dataclass(frozen=True)
class StreamConfig:
    """How eagerly the loop trusts its cached calibration and when it runs OCR again."""

    apparatus: str = "auto"
    profile: Profile | None = None
    detector: Detector | None = None
    tracker: TrackerConfig = field(default_factory=TrackerConfig)
    keep_history: bool = False  # keep the Kalman history for ``--smooth``
    match_min: float = 0.4  # share of marks visible below this: the calibration is in doubt
    min_shift_px: float = 0.5  # smaller registration shifts are noise
    recalibrate_every_s: float = 0.5  # at most one OCR attempt per this much stream time
    drop_after_s: float = 3.0  # print unmatched this long: forget the calibration
    indicator_lost_s: float = 2.0  # no indicator this long: try a fresh calibration

    def reader_options(self) -> ReaderOptions:
        return ReaderOptions(apparatus=self.apparatus, profile=self.profile, detector=self.detector)


@dataclass(frozen=True)
class FrameResult:
    """What the loop knows after one frame; ``level`` is the filtered level (None: no reading)."""

    index: int
    time_s: float
    level: float | None
    level_raw: float | None
    sigma: float | None
    rate: float | None
    state: TrackState
    reading: Reading | None = None
    calibration: Calibration | None = None
    registration: Registration | None = None
    events: tuple[str, ...] = ()
    strip: np.ndarray | None = None
    frame_wh: tuple[int, int] = (0, 0)
    timings_s: dict[str, float] = field(default_factory=dict)
    new_calibration: CalibrationState | None = None  # made on this frame (``--calibration`` saves it)

    def record(self) -> dict[str, object]:
        """The CSV/JSONL record: ``frame,time_s,level,level_raw,sigma,rate,state``."""
        return {"frame": self.index, "time_s": round(self.time_s, 4),
                "level": None if self.level is None else round(self.level, 5),
                "level_raw": None if self.level_raw is None else round(self.level_raw, 5),
                "sigma": None if self.sigma is None else round(self.sigma, 5),
                "rate": None if self.rate is None else round(self.rate, 5), "state": self.state}


CalibrationState = tuple[Calibration, Signature, tuple[int, int]]  # calibration, print signature, frame (w, h)


@dataclass(frozen=True)
class Measurement:
    """What the image work found in one frame, before the Kalman step.

    :meth:`StreamReader.measure` makes it and :meth:`StreamReader.track` consumes it, so the
    image work of an offline run can be done in other processes (``parallel``) while one
    tracker follows every frame in order. ``light()`` keeps only what the tracker and the CSV need.
    """

    index: int
    time_s: float
    level_raw: float | None
    sigma_raw: float | None
    calibrated: bool  # a calibration is held after this frame
    ever_calibrated: bool
    restart_tracker_div_ml: float | None = None  # a calibration with a new scale: restart the tracker
    events: tuple[str, ...] = ()
    new_calibration: CalibrationState | None = None
    reading: Reading | None = None
    calibration: Calibration | None = None
    registration: Registration | None = None
    strip: np.ndarray | None = None
    frame_wh: tuple[int, int] = (0, 0)
    timings_s: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if (self.level_raw is None) != (self.sigma_raw is None):
            raise ValueError(expected("measurement", "sigma_raw", "present exactly when level_raw is",
                                      self.sigma_raw))

    def light(self) -> Measurement:
        """Without the images and the per-frame objects: what a worker process sends back."""
        return Measurement(self.index, self.time_s, self.level_raw, self.sigma_raw, self.calibrated,
                           self.ever_calibrated, self.restart_tracker_div_ml, self.events, self.new_calibration)


def _cut(frame: Frame, cal: Calibration, columns: tuple[int, int] | None) -> tuple[np.ndarray | None, np.ndarray]:
    """The strip in grey, and in colour only where the indicator search uses colour (a meniscus).

    A frame decoded as luma only is cut as it is and its strip (not the whole frame) mapped to
    grey; a meniscus asks the frame for its colour.
    """
    image = frame.image
    if cal.apparatus == "syringe" or (image.ndim == 2 and frame.colour is None):
        return None, cut_strip(image, cal.upright, columns, gray=True, luma_lut=frame.luma_lut)
    strip_bgr = cut_strip(frame.in_colour(), cal.upright, columns)
    return strip_bgr, to_gray(strip_bgr)


_MAX_RUN = 32  # frames measure_many cuts and checks together at most
# a frame's strips, print response, stopper profile (a syringe) and its share of the batch's seconds
_PreCut = tuple[tuple[np.ndarray | None, np.ndarray], PrintResponse, np.ndarray | None, float]


@dataclass
class _Cache:
    calibration: Calibration
    signature: Signature
    frame_wh: tuple[int, int]
    columns: tuple[int, int]
    profile: Profile


class StreamReader:
    """Feed frames in order; each call returns the frame's result.

    ``process`` is ``track(measure(frame))``: ``measure`` does the image work (calibration,
    check, indicator) and ``track`` the Kalman step. A reader made with ``continues=True``
    takes over a stream another reader started (a worker measuring a later part of a video):
    its calibration is not announced and does not restart the tracker.
    """

    def __init__(self, config: StreamConfig = StreamConfig(),
                 calibration: CalibrationState | None = None, continues: bool = False) -> None:
        self.config = config
        self.tracker: LevelTracker | None = None
        self._cache: _Cache | None = None
        self._last_attempt_s: float | None = None
        self._doubt_since: float | None = None
        self._last_indicator_s: float | None = None
        self._last_indicator: Reading | None = None
        self._ever_calibrated = False
        self._pending: list[str] = []
        self._restart_div: float | None = None  # set by _install, passed on by the next measurement
        self._made: CalibrationState | None = None  # made on this frame, passed on by its measurement
        self.ocr_runs = 0
        self._steps: list[tuple[LevelTracker, int] | None] = []  # per frame, with keep_history
        self._run_len = _MAX_RUN  # frames measure_many checks together
        if calibration is not None:
            cal, signature, wh = calibration
            self._install(cal, signature, wh)
            if continues:
                self._restart_div = None
            else:
                self._pending.append("calibration loaded from file")

    # -- cache ---------------------------------------------------------------------------------
    @property
    def calibration(self) -> Calibration | None:
        return None if self._cache is None else self._cache.calibration

    @property
    def signature(self) -> Signature | None:
        return None if self._cache is None else self._cache.signature

    @property
    def calibration_state(self) -> CalibrationState | None:
        """The calibration held now, as ``--calibration`` saves it (and workers start from it)."""
        c = self._cache
        return None if c is None else (c.calibration, c.signature, c.frame_wh)

    def _install(self, cal: Calibration, signature: Signature, frame_wh: tuple[int, int]) -> None:
        profile = self.config.profile or default_profile(cal.apparatus)
        cols = signature.columns  # the print and walls the check reads
        # a meniscus is checked against the background just outside the walls (see
        # indicator._background_crosses): cylinders and burettes keep those columns
        reach_half = max(abs(lo) for lo, _ in BACKGROUND_COLUMNS)  # in half bore widths from the axis
        outside = 0.1 if cal.apparatus == "syringe" else round((reach_half - 1) / 2, 6)
        pad = int(2 + outside * (cal.bore_x_up[1] - cal.bore_x_up[0]))
        columns = (min(cols[0], int(cal.bore_x_up[0]) - pad), max(cols[1], int(cal.bore_x_up[1]) + pad + 1))
        old = self._cache
        self._cache = _Cache(cal, signature, frame_wh, columns, profile)
        self._ever_calibrated = True
        self._doubt_since = None
        if old is None or old.calibration.apparatus != cal.apparatus \
                or abs(old.calibration.fit.minor_ml - cal.fit.minor_ml) > 1e-9:
            self._restart_div = cal.fit.minor_ml  # a new scale: the tracker starts afresh

    def _indicator_rows(self, cal: Calibration, reading: Reading | None) -> tuple[float, float] | None:
        """Strip rows the indicator occupies (they move with the level and are no print)."""
        if reading is None or reading.indicator is None:
            return None
        y = reading.indicator.y_up
        d = cal.fit.division_px
        if cal.apparatus == "syringe":
            bore = cal.bore_x_up[1] - cal.bore_x_up[0]
            behind = 1.0 if cal.fit.slope < 0 else -1.0  # the rubber lies towards higher values
            lo, hi = sorted((y - behind * 1.5 * d, y + behind * 1.0 * bore))
            return lo, hi
        return y - 2.0 * d, y + 1.5 * d

    def _try_calibrate(self, frame: Frame, timings: dict[str, float], events: list[str], why: str) -> bool:
        t = frame.time_s
        if self._last_attempt_s is not None and t - self._last_attempt_s < self.config.recalibrate_every_s:
            return False
        self._last_attempt_s = t
        start = time.perf_counter()
        if frame.colour is not None:  # decoded as luma only: calibration reads colour
            frame = Frame(frame.index, frame.time_s, frame.in_colour())
        cal, reason = calibrate(frame.image, self.config.reader_options(), {})
        timings["calibrate"] = time.perf_counter() - start
        self.ocr_runs += 1
        if cal is None:
            events.append(f"calibration failed ({why}): {reason}")
            return False
        strip_bgr, strip = _cut(frame, cal, None)
        first = read_with(frame.image, cal, self.config.profile or default_profile(cal.apparatus),
                          strip_bgr=strip_bgr, strip_gray=strip, per_frame=True)
        if self._cache is not None and first.level is None:
            # a replacement must prove itself: one that cannot even find the indicator is more
            # likely a misreading than the view we had
            events.append(f"new calibration ({why}) rejected: {first.error}")
            return False
        self._last_indicator = first
        signature = make_signature(strip, cal)
        h, w = frame.image.shape[:2]
        self._install(cal, signature, (w, h))
        self._made = (cal, signature, (w, h))
        events.append(f"calibrated ({why}): {len(cal.marks)} marks, {len(cal.reads)} numbers, "
                      f"{cal.fit.slope:+.5f} ml/px, residual {cal.fit.residual_px:.2f} px")
        return True

    # -- the per-frame calls -----------------------------------------------------------------------
    def process(self, frame: Frame) -> FrameResult:
        """One frame: the image work, then the Kalman step."""
        return self.track(self.measure(frame))

    def measure(self, frame: Frame) -> Measurement:
        """The image work for one frame: calibrate if needed, check the print, find the indicator."""
        return self._measure(frame, None)

    def measure_many(self, frames: Sequence[Frame]) -> list[Measurement]:
        """``[measure(f) for f in frames]``, with the print check of a run of frames done together.

        Frames that follow each other under one calibration are cut and their print responses
        computed as one stack (``registration.print_responses``); each frame is then checked
        and read in order, as ``measure`` would. When a frame changes the calibration (it
        re-registers or recalibrates) the frames after it are cut again. A run that keeps
        breaking is shortened, down to one frame at a time.
        """
        out: list[Measurement] = []
        i = 0
        while i < len(frames):
            cache = self._cache
            run: list[Frame] = []
            if cache is not None:
                for f in frames[i: i + self._run_len]:
                    h, w = f.image.shape[:2]
                    if (w, h) != cache.frame_wh:
                        break
                    run.append(f)
            if cache is None or len(run) < 2:
                out.append(self._measure(frames[i], None))
                i += 1
                self._run_len = min(_MAX_RUN, 2 * self._run_len)
                continue
            start = time.perf_counter()
            cal = cache.calibration
            cuts = [_cut(f, cal, cache.columns) for f in run]
            stack = np.stack([gray for _, gray in cuts])
            responses = print_responses(stack, cache.signature)
            bodies: np.ndarray | list[None] = [None] * len(run)
            if cal.apparatus == "syringe":
                bodies = stopper_profiles(stack, cal.marks, cal.bore_x_up)
            share = (time.perf_counter() - start) / len(run)
            done = 0
            for frame, cut, response, body in zip(run, cuts, responses, bodies):
                if self._cache is not cache or cache.calibration is not cal:
                    break  # this calibration no longer holds: the rest is cut again
                out.append(self._measure(frame, (cut, response, body, share)))
                done += 1
            i += done
            self._run_len = min(_MAX_RUN, 2 * self._run_len) if done == len(run) else max(1, done // 2)
        return out

    def _measure(self, frame: Frame, precut: _PreCut | None) -> Measurement:
        """``measure``; ``precut``: the frame's strips, print response and stopper profile, already
        made for its batch (``measure_many``)."""
        timings: dict[str, float] = {}
        events: list[str] = self._pending
        self._pending = []
        self._made = None
        t = frame.time_s
        h, w = frame.image.shape[:2]
        if self._cache is not None and self._cache.frame_wh != (w, h):
            events.append(f"frame size changed from {self._cache.frame_wh[0]}x{self._cache.frame_wh[1]} to {w}x{h}: "
                          "calibration dropped")
            self._cache = None
        if self._cache is None:
            self._try_calibrate(frame, timings, events, "start" if not self._ever_calibrated else "lost")
        if self._cache is None:
            return self._measured(frame, None, None, None, events, timings)

        start = time.perf_counter()
        cache = self._cache
        cal = cache.calibration
        body: np.ndarray | None = None
        if precut is None:
            strip_bgr, strip = _cut(frame, cal, cache.columns)
            response, spent = print_responses(strip[None], cache.signature)[0], 0.0
        else:
            (strip_bgr, strip), response, body, spent = precut
        rows = self._indicator_rows(cal, self._last_indicator)
        reg = check(response, cache.signature, rows)
        timings["check"] = time.perf_counter() - start + spent
        if reg.score < self.config.match_min:
            if self._doubt_since is None:
                self._doubt_since = t
                events.append(f"print no longer matches the calibration (correlation {reg.score:.2f})")
            if self._try_calibrate(frame, timings, events, "view changed or scale covered"):
                cache = self._cache
                assert cache is not None
                strip_bgr, strip = _cut(frame, cache.calibration, cache.columns)
                return self._read(frame, cache, strip_bgr, strip, None, events, timings)
            if t - self._doubt_since > self.config.drop_after_s:
                events.append("calibration dropped: print unmatched for "
                              f"{t - self._doubt_since:.1f} s")
                self._cache = None
            return self._measured(frame, None, cal if self._cache else None, reg, events, timings)
        if self._doubt_since is not None:
            events.append(f"print matches again (correlation {reg.score:.2f})")
            self._doubt_since = None
        if max(abs(reg.dx_px), abs(reg.dy_px)) >= self.config.min_shift_px:
            cal = replace(cal, upright=shifted(cal.upright, reg.dx_px, reg.dy_px))
            cache.calibration = cal
            strip_bgr, strip = _cut(frame, cal, cache.columns)
            body = None  # made from the strip before it moved
            events.append(f"re-registered by ({reg.dx_px:+.1f}, {reg.dy_px:+.1f}) px")
        return self._read(frame, cache, strip_bgr, strip, reg, events, timings, body)

    def smoothed(self) -> list[tuple[float, float, float] | None]:
        """RTS-smoothed (level, rate, sigma) for every frame processed so far (needs keep_history)."""
        if not self.config.keep_history:
            raise ValueError("stream: expected keep_history=True for smoothing, got False")
        done: dict[int, list[tuple[float, float, float] | None]] = {}
        out: list[tuple[float, float, float] | None] = []
        for ref in self._steps:
            if ref is None:
                out.append(None)
                continue
            tracker, i = ref
            if id(tracker) not in done:
                done[id(tracker)] = rts_smooth(tracker.history)
            out.append(done[id(tracker)][i])
        return out

    def _read(self, frame: Frame, cache: _Cache, strip_bgr: np.ndarray | None, strip: np.ndarray,
              reg: Registration | None, events: list[str], timings: dict[str, float],
              stopper_profile: np.ndarray | None = None) -> Measurement:
        t = frame.time_s
        cal = cache.calibration
        reading = read_with(frame.image, cal, cache.profile, timings, strip_bgr=strip_bgr, strip_gray=strip,
                            stopper_profile=stopper_profile, per_frame=True)
        if reading.indicator is not None:
            self._last_indicator = reading
            self._last_indicator_s = t
        if reading.level is None and self._last_indicator_s is not None \
                and t - self._last_indicator_s > self.config.indicator_lost_s:
            if self._try_calibrate(frame, timings, events, "indicator lost"):
                cal = self._cache.calibration if self._cache else cal
        return self._measured(frame, reading, cal, reg, events, timings, strip)

    def _measured(self, frame: Frame, reading: Reading | None, cal: Calibration | None, reg: Registration | None,
                  events: list[str], timings: dict[str, float], strip: np.ndarray | None = None) -> Measurement:
        h, w = frame.image.shape[:2]
        restart, self._restart_div = self._restart_div, None
        return Measurement(
            index=frame.index, time_s=frame.time_s,
            level_raw=None if reading is None else reading.level,
            sigma_raw=None if reading is None or reading.level is None else reading.sigma,
            calibrated=self._cache is not None, ever_calibrated=self._ever_calibrated,
            restart_tracker_div_ml=restart, events=tuple(events), new_calibration=self._made,
            reading=reading, calibration=cal, registration=reg, strip=strip, frame_wh=(w, h), timings_s=timings)

    def track(self, m: Measurement) -> FrameResult:
        """The Kalman step for one measured frame; frames must come in order."""
        start = time.perf_counter()
        timings = m.timings_s
        events = list(m.events)
        if m.restart_tracker_div_ml is not None:
            self.tracker = LevelTracker(m.restart_tracker_div_ml, self.config.tracker,
                                        keep_history=self.config.keep_history)
        if self.config.keep_history:
            self._steps.append(None)
        if self.tracker is None:
            state: TrackState = "calibrating" if not m.ever_calibrated else "lost"
            return FrameResult(m.index, m.time_s, None, m.level_raw, None, None, state, m.reading, m.calibration,
                               m.registration, tuple(events), m.strip, m.frame_wh, timings, m.new_calibration)
        was_active = self.tracker.active
        estimate = self.tracker.step(m.time_s, m.level_raw, m.sigma_raw, calibrated=m.calibrated)
        if self.config.keep_history:
            self._steps[-1] = (self.tracker, len(self.tracker.history) - 1)
        timings["track"] = time.perf_counter() - start
        if estimate.outlier and estimate.fused:
            events.append("level jumped: tracker restarted on the new level")
        elif was_active and estimate.state == "lost":
            events.append("tracking lost: no indicator for "
                          f"{self.tracker.config.coast_limit_s:g} s")
        state = estimate.state
        if state == "lost" and not m.ever_calibrated:
            state = "calibrating"
        return FrameResult(m.index, m.time_s, estimate.level, m.level_raw, estimate.sigma, estimate.rate, state,
                           m.reading, m.calibration, m.registration, tuple(events), m.strip, m.frame_wh, timings,
                           m.new_calibration)
