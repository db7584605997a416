"""``streamread eval``: score a readings CSV against ground truth, as the paper's Tables 4 and 5.

The paper reads the scale at dwells of the plunger on marks, going up (aspirating) and down
(dispensing), tabulates the readings per dwell (Table 4) and reports MAE, RMSE, bias, SD and
R^2 per direction (Table 5), with plots (Fig. 16). A streaming reader gives a value per frame,
so every figure is computed twice: per frame (all frames, moving ones included) and per dwell
step (what the paper did).

Definitions, chosen so that the paper's own Table 4 gives back its Table 5:

* error = measured - truth; bias = mean error; MAE, RMSE, max |error| as usual.
* SD is the population SD (ddof 0) of the error. The paper's "Std. Dev." (0.055 ml both ways)
  is the population SD of the *absolute* error, so that one is reported too (``sd_abs``).
* R^2 = 1 - SS_res / SS_tot with SS_tot about the mean truth; undefined (None) for constant truth.
* coverage = frames (or steps) with a value / frames (or steps) in truth. A frame with an empty
  or non-finite value, or missing from the readings file, is "no reading": it lowers coverage
  and is left out of every error figure.
* a dwell step is a maximal run of >= 3 consecutive truth frames of one direction whose level
  changes by less than 1e-6 from frame to frame; its measured value is the median of the
  readings in the run after skipping its first 25 % of frames (the reader settling).
* direction comes from the truth CSV's ``direction`` column. Where that is absent (or a cell is
  empty) it is inferred from the truth level: a frame whose level rose is aspirating, fell is
  dispensing; a dwell takes the direction of the sweep it sits in (a dwell at a turnaround is
  split half and half between the two sweeps); frames before the first movement are still.
  The readings' ``rate`` is not used: it lags and is noisy where the truth is exact.
* "all" is every frame (or step), still ones included.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from streamread.errors import InputError, expected

if TYPE_CHECKING:  # plots (and cv2) load only when plots are drawn
    from streamread.plots import Color, Figure

READINGS_COLUMNS = ("frame", "time_s", "level", "level_raw", "sigma", "rate", "state")
TRUTH_COLUMNS = ("frame", "time_s", "level_ml")  # and optionally "direction"
VALUE_COLUMNS = ("level", "level_raw")
DIRECTIONS = ("aspirating", "dispensing", "still")
GROUPS = ("aspirating", "dispensing", "all")
LEVEL_EPS = 1e-6  # two truth levels closer than this are the same level
MIN_DWELL_FRAMES = 3
SETTLE_FRACTION = 0.25  # share of a dwell's first frames left out of its median


# ----------------------------------------------------------------------------- results

@dataclass(frozen=True)
class Metrics:
    """Error figures of one group (a direction, per frame or per step); None where undefined."""

    n: int  # values compared (frames or steps with a reading)
    total: int  # frames or steps in truth
    coverage: float | None
    mae: float | None
    rmse: float | None
    bias: float | None
    sd: float | None  # population SD of the error
    sd_abs: float | None  # population SD of |error|: the paper's "Std. Dev."
    r2: float | None
    max_abs: float | None

    def to_json(self, minor_ml: float | None = None) -> dict[str, float | int | None]:
        """All fields, plus the error figures in scale divisions when the division is known."""
        out: dict[str, float | int | None] = {
            "n": self.n, "total": self.total, "coverage": self.coverage, "mae_ml": self.mae, "rmse_ml": self.rmse,
            "bias_ml": self.bias, "sd_ml": self.sd, "sd_abs_ml": self.sd_abs, "r2": self.r2,
            "max_abs_ml": self.max_abs}
        if minor_ml:
            for key in ("mae", "rmse", "bias", "sd", "sd_abs", "max_abs"):
                value = getattr(self, key)
                out[f"{key}_div"] = None if value is None else value / minor_ml
        return out


@dataclass(frozen=True)
class Frame:
    """One truth frame joined with its reading (None: no reading)."""

    frame: int
    time_s: float
    truth_ml: float
    measured: float | None
    direction: str
    state: str | None  # the reader's state; None where the readings file has no such frame


@dataclass(frozen=True)
class Step:
    """A dwell of the truth at one level within one direction, and what was read there."""

    direction: str
    truth_ml: float
    first_frame: int
    last_frame: int
    frames: int
    used: int  # readings that went into the median (after the settling skip)
    measured: float | None

    @property
    def error(self) -> float | None:
        return None if self.measured is None else self.measured - self.truth_ml


@dataclass(frozen=True)
class StepRow:
    """A Table 4 row: one truth level and the step value read there in each direction.

    ``steps`` names the directions that have a dwell in this row, so a blank (no dwell) can be
    told from a dwell without a reading. The k-th dwell at a level in one direction is paired
    with the k-th at that level in the other.
    """

    truth_ml: float
    aspirating: float | None
    dispensing: float | None
    still: float | None
    steps: tuple[str, ...]

    def measured(self, direction: str) -> float | None:
        return getattr(self, direction)

    def error(self, direction: str) -> float | None:
        value = self.measured(direction)
        return None if value is None else value - self.truth_ml

    @property
    def hysteresis(self) -> float | None:
        """Aspirating minus dispensing reading at this level."""
        if self.aspirating is None or self.dispensing is None:
            return None
        return self.aspirating - self.dispensing


@dataclass(frozen=True)
class EvalReport:
    """Everything ``eval`` computed; ``format_markdown`` and ``write_outputs`` only present it."""

    readings_path: str
    truth_path: str
    column: str
    minor_ml: float | None
    minor_source: str  # "argument", the sidecar path, or "none"
    direction_source: str
    frames: tuple[Frame, ...]
    per_frame: Mapping[str, Metrics]  # keys GROUPS
    per_step: Mapping[str, Metrics]
    steps: tuple[Step, ...]
    rows: tuple[StepRow, ...]
    states: Mapping[str, int]  # reader states over the truth frames ("missing": no row in the readings)

    @property
    def truth_frames(self) -> int:
        return len(self.frames)

    @property
    def read_frames(self) -> int:
        return sum(1 for f in self.frames if f.measured is not None)

    def to_json(self) -> dict[str, object]:
        """The whole report as plain JSON data."""
        return {
            "readings": self.readings_path, "truth": self.truth_path, "column": self.column,
            "minor_ml": self.minor_ml, "minor_source": self.minor_source, "direction_source": self.direction_source,
            "truth_frames": self.truth_frames, "read_frames": self.read_frames,
            "coverage": self.read_frames / self.truth_frames if self.truth_frames else None,
            "states": dict(self.states),
            "method": {"error": "measured - truth", "sd": "population SD (ddof 0) of the error",
                       "sd_abs": "population SD of |error| (the paper's Table 5 'Std. Dev.')",
                       "dwell": f">= {MIN_DWELL_FRAMES} consecutive frames, one direction, level change < {LEVEL_EPS}",
                       "step_value": f"median of the readings after the first {SETTLE_FRACTION:.0%} of the dwell"},
            "per_frame": {g: m.to_json(self.minor_ml) for g, m in self.per_frame.items()},
            "per_step": {g: m.to_json(self.minor_ml) for g, m in self.per_step.items()},
            "steps": [{"direction": s.direction, "truth_ml": s.truth_ml, "first_frame": s.first_frame,
                       "last_frame": s.last_frame, "frames": s.frames, "used": s.used, "measured_ml": s.measured,
                       "error_ml": s.error} for s in self.steps],
            "table4": [{"truth_ml": r.truth_ml, "steps": list(r.steps),
                        **{f"{d}_ml": r.measured(d) for d in DIRECTIONS},
                        **{f"error_{d}_ml": r.error(d) for d in DIRECTIONS},
                        "aspirating_minus_dispensing_ml": r.hysteresis} for r in self.rows],
        }


# ----------------------------------------------------------------------------- reading the inputs

def _rows(what: str, path: Path, required: Sequence[str], wanted: str) -> tuple[list[str], list[dict[str, str]]]:
    """Header and rows of a CSV, or an InputError naming the file and what was expected."""
    if not path.is_file():
        raise InputError(expected(what, path, "an existing CSV file", "no such file"))
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            fields = [f.strip() for f in reader.fieldnames or []]
            reader.fieldnames = fields
            if not set(required) <= set(fields):
                raise InputError(expected(what, path, wanted, f"columns {','.join(fields) or '(none: empty file)'}"))
            return fields, list(reader)
    except OSError as exc:
        raise InputError(expected(what, path, "a readable file", exc.strerror or exc)) from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(expected(what, path, "a UTF-8 CSV file", exc)) from None


def _number(what: str, path: Path, line: int, column: str, text: str | None, optional: bool) -> float | None:
    """A cell as a float; empty or non-finite is None where allowed."""
    text = (text or "").strip()
    if not text and optional:
        return None
    try:
        value = float(text)
    except ValueError:
        raise InputError(expected(what, f"{path} line {line}", f"a number in column {column}", repr(text))) from None
    if not math.isfinite(value):
        if optional:
            return None
        raise InputError(expected(what, f"{path} line {line}", f"a finite number in column {column}", repr(text)))
    return value


def _frame(what: str, path: Path, line: int, text: str | None) -> int:
    value = _number(what, path, line, "frame", text, optional=False)
    assert value is not None
    if value != int(value):
        raise InputError(expected(what, f"{path} line {line}", "a whole frame number", repr(text)))
    return int(value)


def read_readings(path: Path, column: str = "level") -> dict[int, tuple[float | None, str]]:
    """Per frame: the value of ``column`` (None: no reading) and the reader's state."""
    if column not in VALUE_COLUMNS:
        raise InputError(expected("column", column, f"one of {', '.join(VALUE_COLUMNS)}", repr(column)))
    path = Path(path)
    _, rows = _rows("readings", path, READINGS_COLUMNS, f"a CSV with columns {','.join(READINGS_COLUMNS)}")
    out: dict[int, tuple[float | None, str]] = {}
    for line, row in enumerate(rows, start=2):
        frame = _frame("readings", path, line, row.get("frame"))
        if frame in out:
            raise InputError(expected("readings", f"{path} line {line}", "each frame once", f"frame {frame} again"))
        out[frame] = (_number("readings", path, line, column, row.get(column), optional=True),
                      (row.get("state") or "").strip())
    return out


def read_truth(path: Path) -> tuple[list[tuple[int, float, float, str]], str]:
    """Truth rows (frame, time_s, level_ml, direction) sorted by frame, and where the directions came from."""
    path = Path(path)
    fields, rows = _rows("truth", path, TRUTH_COLUMNS,
                         "a CSV with columns frame,time_s,level_ml[,direction]")
    parsed: list[tuple[int, float, float, str]] = []
    seen: set[int] = set()
    for line, row in enumerate(rows, start=2):
        frame = _frame("truth", path, line, row.get("frame"))
        if frame in seen:
            raise InputError(expected("truth", f"{path} line {line}", "each frame once", f"frame {frame} again"))
        seen.add(frame)
        time_s = _number("truth", path, line, "time_s", row.get("time_s"), optional=True)
        level = _number("truth", path, line, "level_ml", row.get("level_ml"), optional=False)
        direction = (row.get("direction") or "").strip().lower()
        if direction and direction not in DIRECTIONS:
            raise InputError(expected("truth", f"{path} line {line}", f"direction one of {', '.join(DIRECTIONS)}",
                                      repr(direction)))
        assert level is not None  # not optional: a bad cell raised above
        parsed.append((frame, math.nan if time_s is None else time_s, level, direction))
    if not parsed:
        raise InputError(expected("truth", path, "at least one row of ground truth", "only a header"))
    parsed.sort(key=lambda r: r[0])
    inferred = infer_directions([r[2] for r in parsed])
    given = sum(1 for r in parsed if r[3])
    if "direction" not in fields or given == 0:
        source = "inferred from the truth level (no direction column)"
    elif given == len(parsed):
        source = "truth direction column"
    else:
        source = f"truth direction column ({len(parsed) - given} empty cells inferred from the truth level)"
    return [(f, t, lv, d or inferred[i]) for i, (f, t, lv, d) in enumerate(parsed)], source


def infer_directions(levels: Sequence[float]) -> list[str]:
    """Direction per frame from the sign of the truth level's change (see the module docstring)."""
    n = len(levels)
    sign = [0] * n
    for i in range(1, n):
        d = levels[i] - levels[i - 1]
        sign[i] = 1 if d > LEVEL_EPS else -1 if d < -LEVEL_EPS else 0
    name = {1: "aspirating", -1: "dispensing", 0: "still"}
    out = ["still"] * n
    i = 0
    while i < n:
        if sign[i]:
            out[i] = name[sign[i]]
            i += 1
            continue
        j = i
        while j < n and sign[j] == 0:
            j += 1
        before = sign[i - 1] if i > 0 else 0  # the run is maximal, so frame i-1 moved
        after = sign[j] if j < n else 0
        if before == 0:
            fill = ["still"] * (j - i)
        elif after in (0, before):
            fill = [name[before]] * (j - i)
        else:  # a turnaround: first half ends the old sweep, second half starts the new one
            half = (j - i) // 2  # the arrival frame (i - 1) also belongs to the old sweep
            fill = [name[before]] * half + [name[after]] * (j - i - half)
        out[i:j] = fill
        i = j
    return out


def sidecar_minor_ml(truth_path: Path) -> tuple[float | None, str]:
    """``minor_ml`` from the JSON beside the truth CSV (X.truth.csv -> X.truth.json), if there is one."""
    side = Path(truth_path).with_suffix(".json")
    try:
        data = json.loads(side.read_text(encoding="utf-8"))
        value = float(data["minor_ml"])
    except (OSError, ValueError, KeyError, TypeError):
        return None, "none"
    return (value, str(side)) if math.isfinite(value) and value > 0 else (None, "none")


# ----------------------------------------------------------------------------- computing

def compute_metrics(measured: Sequence[float | None], truth: Sequence[float]) -> Metrics:
    """Metrics of paired values; None in ``measured`` is no reading (counted in coverage only)."""
    total = len(truth)
    pairs = [(m, t) for m, t in zip(measured, truth, strict=True) if m is not None]
    n = len(pairs)
    if n == 0:
        return Metrics(0, total, 0.0 if total else None, None, None, None, None, None, None, None)
    m = np.array([p[0] for p in pairs], dtype=np.float64)
    t = np.array([p[1] for p in pairs], dtype=np.float64)
    e = m - t
    ss_res = float(np.sum(e ** 2))
    ss_tot = float(np.sum((t - t.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > n * LEVEL_EPS ** 2 else None
    return Metrics(n=n, total=total, coverage=n / total, mae=float(np.mean(np.abs(e))),
                   rmse=float(np.sqrt(np.mean(e ** 2))), bias=float(np.mean(e)), sd=float(np.std(e)),
                   sd_abs=float(np.std(np.abs(e))), r2=r2, max_abs=float(np.max(np.abs(e))))


def find_steps(frames: Sequence[Frame]) -> list[Step]:
    """Dwell steps of the truth (see the module docstring), in frame order."""
    steps: list[Step] = []
    i = 0
    while i < len(frames):
        j = i + 1
        while (j < len(frames) and frames[j].direction == frames[i].direction
               and abs(frames[j].truth_ml - frames[j - 1].truth_ml) < LEVEL_EPS):
            j += 1
        run = frames[i:j]
        if len(run) >= MIN_DWELL_FRAMES:
            skip = math.floor(SETTLE_FRACTION * len(run))
            values = [f.measured for f in run[skip:] if f.measured is not None]
            steps.append(Step(direction=run[0].direction, truth_ml=run[0].truth_ml, first_frame=run[0].frame,
                              last_frame=run[-1].frame, frames=len(run), used=len(values),
                              measured=float(np.median(values)) if values else None))
        i = j
    return steps


def step_rows(steps: Sequence[Step]) -> list[StepRow]:
    """Table 4: steps grouped by truth level (ascending); the k-th dwell of each direction pair up."""
    levels: list[tuple[float, dict[str, list[Step]]]] = []
    for s in sorted(steps, key=lambda s: s.truth_ml):
        if not levels or abs(levels[-1][0] - s.truth_ml) >= LEVEL_EPS:
            levels.append((s.truth_ml, {d: [] for d in DIRECTIONS}))
        levels[-1][1][s.direction].append(s)
    for _, by_dir in levels:  # frame order within a level, so pairs are first-with-first
        for lst in by_dir.values():
            lst.sort(key=lambda s: s.first_frame)
    rows: list[StepRow] = []
    for level, by_dir in levels:
        for k in range(max(len(v) for v in by_dir.values())):
            picked = {d: by_dir[d][k] if k < len(by_dir[d]) else None for d in DIRECTIONS}
            rows.append(StepRow(truth_ml=level,
                                aspirating=picked["aspirating"].measured if picked["aspirating"] else None,
                                dispensing=picked["dispensing"].measured if picked["dispensing"] else None,
                                still=picked["still"].measured if picked["still"] else None,
                                steps=tuple(d for d in DIRECTIONS if picked[d] is not None)))
    return rows


def _grouped(items: Sequence[Frame] | Sequence[Step], value: str) -> dict[str, Metrics]:
    out: dict[str, Metrics] = {}
    for group in GROUPS:
        chosen = [x for x in items if group == "all" or x.direction == group]
        out[group] = compute_metrics([getattr(x, value) for x in chosen], [x.truth_ml for x in chosen])
    return out


def evaluate(readings_path: Path | str, truth_path: Path | str, column: str = "level",
             minor_ml: float | None = None) -> EvalReport:
    """Join readings and truth on frame and compute the per-frame and per-step figures."""
    readings_path, truth_path = Path(readings_path), Path(truth_path)
    if minor_ml is not None and not (math.isfinite(minor_ml) and minor_ml > 0):
        raise InputError(expected("division", minor_ml, "a positive number of ml", minor_ml))
    readings = read_readings(readings_path, column)
    truth, direction_source = read_truth(truth_path)
    if not any(f in readings for f, *_ in truth):
        raise InputError(expected("readings", readings_path, f"frames that also appear in the truth {truth_path}",
                                  f"none in common ({len(readings)} readings, {len(truth)} truth frames)"))
    frames: list[Frame] = []
    states: dict[str, int] = {}
    for frame, time_s, level, direction in truth:
        value, state = readings.get(frame, (None, None))
        key = state or ("missing" if state is None else "(empty)")
        states[key] = states.get(key, 0) + 1
        frames.append(Frame(frame, time_s, level, value, direction, state))
    if minor_ml is not None:
        source = "argument"
    else:
        minor_ml, source = sidecar_minor_ml(truth_path)
    steps = find_steps(frames)
    return EvalReport(readings_path=str(readings_path), truth_path=str(truth_path), column=column,
                      minor_ml=minor_ml, minor_source=source, direction_source=direction_source,
                      frames=tuple(frames), per_frame=_grouped(frames, "measured"),
                      per_step=_grouped(steps, "measured"), steps=tuple(steps), rows=tuple(step_rows(steps)),
                      states=states)


# ----------------------------------------------------------------------------- presenting

def _f(value: float | None, digits: int = 3) -> str:
    if value is None:
        return "-"
    text = f"{value:.{digits}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


def _pct(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f} %"


def format_markdown(report: EvalReport) -> str:
    """Table 5 (metrics per direction, per frame and per step), then Table 4 (the dwell steps)."""
    cols = [(report.per_frame, g, "frame") for g in GROUPS] + [(report.per_step, g, "step") for g in GROUPS]
    header = "| Metric | " + " | ".join(f"{g.capitalize()} ({kind})" for _, g, kind in cols) + " |"
    lines = [f"## Evaluation of `{report.column}` in {report.readings_path} against {report.truth_path}", ""]
    states = ", ".join(f"{k} {v}" for k, v in sorted(report.states.items(), key=lambda kv: -kv[1]))
    coverage = report.read_frames / report.truth_frames
    lines.append(f"{report.truth_frames} truth frames, {report.read_frames} with a reading ({_pct(coverage)}); "
                 f"{len(report.steps)} dwell steps; direction: {report.direction_source}; states: {states}.")
    lines += ["", "### Metrics (Table 5)", "", header, "|---" * (len(cols) + 1) + "|"]

    def row(name: str, fmt: object) -> None:
        lines.append(f"| {name} | " + " | ".join(fmt(src[g]) for src, g, _ in cols) + " |")  # type: ignore[operator]

    row("n", lambda m: str(m.n))
    row("Coverage", lambda m: _pct(m.coverage))
    row("MAE (ml)", lambda m: _f(m.mae))
    row("RMSE (ml)", lambda m: _f(m.rmse))
    row("Bias (ml)", lambda m: _f(m.bias))
    row("SD of error (ml)", lambda m: _f(m.sd))
    row("SD of abs. error (ml)", lambda m: _f(m.sd_abs))
    row("R^2", lambda m: _f(m.r2))
    row("Max abs. error (ml)", lambda m: _f(m.max_abs))
    minor = report.minor_ml
    if minor:
        row("MAE (div)", lambda m: _f(None if m.mae is None else m.mae / minor, 2))
        row("RMSE (div)", lambda m: _f(None if m.rmse is None else m.rmse / minor, 2))
        row("Bias (div)", lambda m: _f(None if m.bias is None else m.bias / minor, 2))
        row("Max abs. error (div)", lambda m: _f(None if m.max_abs is None else m.max_abs / minor, 2))
        lines += ["", f"1 division = {minor:g} ml ({report.minor_source})."]

    lines += ["", "### Dwell steps (Table 4)", ""]
    if not report.rows:
        lines.append(f"No dwell steps (runs of >= {MIN_DWELL_FRAMES} frames at one truth level) in the truth.")
        return "\n".join(lines) + "\n"
    with_still = any("still" in r.steps for r in report.rows)
    dirs = ["aspirating", "dispensing"] + (["still"] if with_still else [])
    head = (["Truth (ml)"] + [f"Measured {d} (ml)" for d in dirs] + [f"Error {d} (ml)" for d in dirs]
            + ["Asp. - disp. (ml)"])
    lines += ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for r in report.rows:
        def cell(value: float | None, d: str) -> str:
            return "" if d not in r.steps else "no reading" if value is None else _f(value)
        cells = ([_f(r.truth_ml, 2)] + [cell(r.measured(d), d) for d in dirs] + [cell(r.error(d), d) for d in dirs]
                 + ["" if r.hysteresis is None else _f(r.hysteresis)])
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", f"Step value: median of the readings in the dwell after its first {SETTLE_FRACTION:.0%} of frames."]
    return "\n".join(lines) + "\n"


def _plots(report: EvalReport) -> dict[str, np.ndarray]:
    from streamread.plots import BLACK, BLUE, GREEN, GREY, ORANGE, RED, Figure

    colors = {"aspirating": BLUE, "dispensing": ORANGE, "still": GREY}
    read = [f for f in report.frames if f.measured is not None]
    done = [s for s in report.steps if s.measured is not None]

    def frame_xy(d: str, err: bool) -> tuple[list[float], list[float]]:
        fs = [f for f in read if f.direction == d]
        return [f.truth_ml for f in fs], [f.measured - f.truth_ml if err else f.measured for f in fs]  # type: ignore

    def step_xy(d: str, err: bool) -> tuple[list[float], list[float]]:
        ss = [s for s in done if s.direction == d]
        return [s.truth_ml for s in ss], [s.error if err else s.measured for s in ss]  # type: ignore

    figs: dict[str, np.ndarray] = {}
    for name, err in (("measured_vs_truth", False), ("error_vs_truth", True)):
        fig = Figure("Error vs truth" if err else f"Measured ({report.column}) vs truth", "truth (ml)",
                     "measured - truth (ml)" if err else "measured (ml)", equal_axes=not err)
        if err:
            fig.hline(0.0, GREY, None, dashed=True)
        else:
            fig.diagonal(GREY, "ideal (y = x)")
        for d in DIRECTIONS:
            x, y = frame_xy(d, err)
            if x:
                fig.scatter(x, y, colors[d], f"{d} (frames)", size=2)
        for d, marker in (("aspirating", "triangle"), ("dispensing", "square"), ("still", "diamond")):
            x, y = step_xy(d, err)
            if x:
                fig.scatter(x, y, colors[d], f"{d} (dwell steps)", marker=marker, size=6, filled=False)
        if not read:
            fig.note(f"no readings in column {report.column}")
        figs[name] = fig.render()

    fig = Figure("Hysteresis: dwell step readings", "truth (ml)", "measured (ml)", equal_axes=True)
    fig.diagonal(GREY, "ideal (y = x)")
    for d, marker in (("aspirating", "triangle"), ("dispensing", "square")):
        pts = sorted(zip(*step_xy(d, False)))
        if pts:
            fig.line([p[0] for p in pts], [p[1] for p in pts], colors[d], d, marker=marker, size=5)
    if not any(s.direction in ("aspirating", "dispensing") for s in done):
        fig.note("no aspirating or dispensing dwell steps with a reading")
    figs["hysteresis"] = fig.render()

    pairs = [r for r in report.rows if r.aspirating is not None and r.dispensing is not None]
    fig = Figure("Aspirating vs dispensing (same truth level)", "measured aspirating (ml)",
                 "measured dispensing (ml)", equal_axes=True)
    fig.diagonal(GREY, "ideal (y = x)")
    if pairs:
        fig.scatter([r.aspirating for r in pairs], [r.dispensing for r in pairs], GREEN, "dwell steps",
                    size=5)  # type: ignore[misc]
    else:
        fig.note("no truth level with a step in both directions")
    figs["aspirating_vs_dispensing"] = fig.render()

    # Bland-Altman of measured against truth: per dwell step where there are any, else per frame
    use_steps = len(done) >= 2
    items: list[tuple[str, float, float]] = (
        [(s.direction, s.measured, s.truth_ml) for s in done] if use_steps  # type: ignore[misc]
        else [(f.direction, f.measured, f.truth_ml) for f in read])  # type: ignore[misc]
    fig = Figure(f"Bland-Altman: measured vs truth ({'dwell steps' if use_steps else 'frames'})",
                 "mean of measured and truth (ml)", "measured - truth (ml)")
    _bland_altman(fig, items, colors, BLACK, RED, 5 if use_steps else 2)
    figs["bland_altman"] = fig.render()

    fig = Figure("Bland-Altman: aspirating vs dispensing (dwell steps)", "mean of aspirating and dispensing (ml)",
                 "aspirating - dispensing (ml)")
    _bland_altman(fig, [("pair", r.aspirating, r.dispensing) for r in pairs],  # type: ignore[misc]
                  {"pair": GREEN}, BLACK, RED, 5)
    figs["bland_altman_directions"] = fig.render()
    return figs


def _bland_altman(fig: Figure, items: Sequence[tuple[str, float, float]], colors: Mapping[str, Color],
                  bias_color: Color, limit_color: Color, size: int) -> None:
    """Points (a+b)/2 against a-b by group, the mean difference and the mean +- 1.96 SD lines."""
    if not items:
        fig.note("no data")
        return
    diff = np.array([a - b for _, a, b in items])
    mean = np.array([(a + b) / 2 for _, a, b in items])
    for group, color in colors.items():
        keep = np.array([g == group for g, _, _ in items])
        if keep.any():
            fig.scatter(mean[keep], diff[keep], color, group if group != "pair" else "dwell steps", size=size)
    bias, sd = float(diff.mean()), float(diff.std())
    fig.hline(bias, bias_color, f"mean {bias:+.3f} ml")
    fig.hline(bias + 1.96 * sd, limit_color, f"+1.96 SD {bias + 1.96 * sd:+.3f} ml", dashed=True)
    fig.hline(bias - 1.96 * sd, limit_color, f"-1.96 SD {bias - 1.96 * sd:+.3f} ml", dashed=True)


def write_outputs(report: EvalReport, out_dir: Path | str) -> list[Path]:
    """``report.json`` and the PNG plots in ``out_dir`` (created if needed); returns the paths written."""
    from streamread.plots import save_png

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "report.json"]
        paths[0].write_text(json.dumps(report.to_json(), indent=2) + "\n", encoding="utf-8")
        for name, image in _plots(report).items():
            paths.append(save_png(image, out / f"{name}.png"))
    except OSError as exc:
        raise InputError(expected("output directory", out, "a directory it can write", exc.strerror or exc)) from None
    return paths


# ----------------------------------------------------------------------------- command line

def _division(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number of ml, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of ml, got {text!r}")
    return value


def run_eval(args: argparse.Namespace) -> int:
    """Print the Markdown tables; with --out also write report.json and the plots (listed on stderr)."""
    report = evaluate(args.readings, args.truth, column=args.column, minor_ml=args.division)
    print(format_markdown(report), end="", flush=True)
    if args.out:
        paths = write_outputs(report, args.out)
        print(f"wrote {len(paths)} files to {args.out}: {', '.join(p.name for p in paths)}", file=sys.stderr)
    return 0


def add_eval_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:  # type: ignore[type-arg]
    """Add the ``eval`` subcommand to a ``add_subparsers()`` object; returns its parser."""
    p = subparsers.add_parser(
        "eval", help="score a readings CSV against ground truth (the paper's Tables 4 and 5)",
        description="Compare a streaming reader's CSV with ground truth: MAE, RMSE, bias, SD, R^2, max error and "
                    "coverage per direction, per frame and per dwell step (Table 5), the dwell steps read going up "
                    "and down (Table 4), and with --out a report.json and plots.")
    p.add_argument("readings", metavar="READINGS.csv", help="frame,time_s,level,level_raw,sigma,rate,state")
    p.add_argument("truth", metavar="TRUTH.csv", help="frame,time_s,level_ml[,direction]")
    p.add_argument("--out", metavar="DIR", help="write report.json and PNG plots here")
    p.add_argument("--column", choices=VALUE_COLUMNS, default="level",
                   help="which reading to score: level (filtered, default) or level_raw (single frame)")
    p.add_argument("--division", metavar="ML", type=_division,
                   help="minor division in ml, for errors in divisions (default: minor_ml from TRUTH.json beside "
                        "the truth CSV, if any)")
    p.set_defaults(func=run_eval)
    return p
