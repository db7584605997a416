"""``streamread eval``: metrics checked by hand on tiny tables, dwell steps, directions, divisions, bad input, plots."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
import pytest

from streamread.errors import InputError
from streamread.evaluate import (
    EvalReport,
    add_eval_parser,
    evaluate,
    format_markdown,
    infer_directions,
    write_outputs,
)

READ_HEADER = "frame,time_s,level,level_raw,sigma,rate,state"
Value = float | str | None


def write_readings(path: Path, rows: Sequence[tuple[int, Value] | tuple[int, Value, Value]]) -> Path:
    """Readings CSV from (frame, level[, level_raw]); None or "" is an empty cell (no reading)."""
    lines = [READ_HEADER]
    for row in rows:
        frame, level = row[0], row[1]
        raw = row[2] if len(row) > 2 else level
        cell = ["" if v is None else str(v) for v in (level, raw)]
        state = "tracking" if cell[0] else "lost"
        lines.append(f"{frame},{frame / 15:.4f},{cell[0]},{cell[1]},{'0.01' if cell[0] else ''},,{state}")
    path.write_text("\n".join(lines) + "\n")
    return path


def write_truth(path: Path, rows: Sequence[tuple[int, float, str] | tuple[int, float]]) -> Path:
    """Truth CSV from (frame, level[, direction]); without directions the column is left out."""
    with_dir = all(len(r) == 3 for r in rows)
    lines = ["frame,time_s,level_ml" + (",direction" if with_dir else "")]
    for r in rows:
        lines.append(f"{r[0]},{r[0] / 15:.4f},{r[1]:.5f}" + (f",{r[2]}" if with_dir else ""))
    path.write_text("\n".join(lines) + "\n")
    return path


# ----------------------------------------------------------------------------- per-frame metrics by hand

def small_run(tmp_path: Path) -> tuple[Path, Path]:
    truth = write_truth(tmp_path / "run.truth.csv", [
        (0, 0.0, "aspirating"), (1, 1.0, "aspirating"), (2, 2.0, "aspirating"), (3, 3.0, "aspirating"),
        (4, 2.0, "dispensing"), (5, 1.0, "dispensing"), (6, 0.0, "dispensing"), (7, 0.0, "dispensing")])
    readings = write_readings(tmp_path / "run.csv", [
        (0, 0.1, 0.0), (1, 1.1, 1.0), (2, 1.8, 2.0), (3, 3.0, 3.0),
        (4, 1.9, 2.0), (5, None, 1.0), (6, -0.1, 0.0),  # frame 5: empty cell; frame 7: no row at all
        (9, 5.0, 5.0)])  # no truth for frame 9: ignored
    return readings, truth


def test_per_frame_metrics_by_hand(tmp_path: Path) -> None:
    readings, truth = small_run(tmp_path)
    report = evaluate(readings, truth)
    asp, disp, every = (report.per_frame[g] for g in ("aspirating", "dispensing", "all"))
    # aspirating errors 0.1, 0.1, -0.2, 0.0 against truth 0, 1, 2, 3 (mean 1.5, SS_tot 5)
    assert (asp.n, asp.total, asp.coverage) == (4, 4, 1.0)
    assert asp.mae == pytest.approx(0.1)
    assert asp.rmse == pytest.approx(math.sqrt(0.06 / 4))
    assert asp.bias == pytest.approx(0.0, abs=1e-12)
    assert asp.sd == pytest.approx(math.sqrt(0.06 / 4))
    assert asp.sd_abs == pytest.approx(math.sqrt(0.02 / 4))  # |e| = .1 .1 .2 0, mean .1
    assert asp.r2 == pytest.approx(1 - 0.06 / 5)
    assert asp.max_abs == pytest.approx(0.2)
    # dispensing: frame 5 empty, frame 7 missing -> 2 of 4 read, errors -0.1, -0.1 at truth 2 and 0
    assert (disp.n, disp.total, disp.coverage) == (2, 4, 0.5)
    assert disp.mae == pytest.approx(0.1) and disp.rmse == pytest.approx(0.1) and disp.bias == pytest.approx(-0.1)
    assert disp.sd == pytest.approx(0.0, abs=1e-12)
    assert disp.r2 == pytest.approx(1 - 0.02 / 2)
    # all: errors .1 .1 -.2 0 -.1 -.1 over 6 of 8 frames; truth 0 1 2 3 2 0 (SS_tot 18 - 6 * (4/3)^2)
    assert (every.n, every.total, every.coverage) == (6, 8, 0.75)
    assert every.mae == pytest.approx(0.1)
    assert every.rmse == pytest.approx(math.sqrt(0.08 / 6))
    assert every.bias == pytest.approx(-0.2 / 6)
    assert every.r2 == pytest.approx(1 - 0.08 / (18 - 6 * (4 / 3) ** 2))
    assert report.truth_frames == 8 and report.read_frames == 6
    assert report.states == {"tracking": 6, "lost": 1, "missing": 1}
    assert report.steps == () and report.rows == ()


def test_level_raw_column(tmp_path: Path) -> None:
    readings, truth = small_run(tmp_path)
    report = evaluate(readings, truth, column="level_raw")
    assert report.column == "level_raw"
    assert report.per_frame["all"].n == 7  # frame 5 has a raw value though no filtered one
    assert report.per_frame["all"].mae == pytest.approx(0.0, abs=1e-12)
    assert report.per_frame["all"].r2 == pytest.approx(1.0)


def test_nan_and_blank_are_no_reading(tmp_path: Path) -> None:
    truth = write_truth(tmp_path / "t.csv", [(i, 1.0 * i, "aspirating") for i in range(4)])
    readings = write_readings(tmp_path / "r.csv", [(0, "nan"), (1, " "), (2, 2.5), (3, "")])
    m = evaluate(readings, truth).per_frame["aspirating"]
    assert (m.n, m.total, m.coverage, m.mae) == (1, 4, 0.25, pytest.approx(0.5))
    assert m.r2 is None  # a single truth value: R^2 undefined


# ----------------------------------------------------------------------------- dwell steps (Table 4)

def staircase(tmp_path: Path) -> tuple[Path, Path]:
    """Up 0 -> 1 -> 2 and back down, dwells of 3-4 frames with a settling outlier first."""
    plan: list[tuple[float, str, list[Value]]] = [
        (0.0, "aspirating", [0.1, 0.0, 0.05]),  # 3 frames: nothing skipped, median 0.05
        (0.5, "aspirating", [0.5]),
        (1.0, "aspirating", [5.0, 1.1, 1.2, 1.1]),  # 4 frames: skip 1 -> median 1.1 (1.15 without the skip)
        (1.5, "aspirating", [1.5]),
        (2.0, "aspirating", [9.9, None, 2.1, 2.0]),  # skip 1, one empty -> median of 2.1, 2.0
        (2.0, "dispensing", [2.0, 1.9, 1.9, 1.9]),
        (1.5, "dispensing", [1.5]),
        (1.0, "dispensing", [1.0, 0.9, 0.95, 0.9]),
        (0.5, "dispensing", [0.5]),
        (0.0, "dispensing", [None, None, None]),  # a dwell without any reading
    ]
    truth_rows: list[tuple[int, float, str]] = []
    read_rows: list[tuple[int, Value]] = []
    for level, direction, values in plan:
        for v in values:
            truth_rows.append((len(truth_rows), level, direction))
            read_rows.append((len(read_rows), v))
    return write_readings(tmp_path / "stairs.csv", read_rows), write_truth(tmp_path / "stairs.truth.csv", truth_rows)


def test_steps_and_table4_rows(tmp_path: Path) -> None:
    report = evaluate(*staircase(tmp_path))
    got = [(s.direction, s.truth_ml, s.frames, s.used, s.measured) for s in report.steps]
    assert got == [("aspirating", 0.0, 3, 3, pytest.approx(0.05)), ("aspirating", 1.0, 4, 3, pytest.approx(1.1)),
                   ("aspirating", 2.0, 4, 2, pytest.approx(2.05)), ("dispensing", 2.0, 4, 3, pytest.approx(1.9)),
                   ("dispensing", 1.0, 4, 3, pytest.approx(0.9)), ("dispensing", 0.0, 3, 0, None)]
    rows = [(r.truth_ml, r.aspirating, r.dispensing, r.steps) for r in report.rows]
    assert rows == [(0.0, pytest.approx(0.05), None, ("aspirating", "dispensing")),
                    (1.0, pytest.approx(1.1), pytest.approx(0.9), ("aspirating", "dispensing")),
                    (2.0, pytest.approx(2.05), pytest.approx(1.9), ("aspirating", "dispensing"))]
    assert report.rows[1].hysteresis == pytest.approx(0.2)
    assert report.rows[2].error("aspirating") == pytest.approx(0.05)
    asp, disp = report.per_step["aspirating"], report.per_step["dispensing"]
    assert (asp.n, asp.total) == (3, 3) and asp.mae == pytest.approx(0.2 / 3) and asp.bias == pytest.approx(0.2 / 3)
    assert (disp.n, disp.total, disp.coverage) == (2, 3, pytest.approx(2 / 3))
    assert disp.mae == pytest.approx(0.1) and disp.bias == pytest.approx(-0.1)
    md = format_markdown(report)
    assert "| 1.00 | 1.100 | 0.900 | 0.100 | -0.100 | 0.200 |" in md
    assert "| 0.00 | 0.050 | no reading | 0.050 | no reading |  |" in md


def test_paper_table4_gives_its_table5(tmp_path: Path) -> None:
    """The paper's Table 4 readings, played as dwells, give back its Table 5 (3 decimals)."""
    truth_levels = [round(0.2 * i, 2) for i in range(24)]
    asp = [0, 0.2, 0.36, 0.59, 0.86, 1.08, 1.21, 1.46, 1.63, 1.82, 1.94, 2.07, 2.38, 2.55, 2.74, 2.9, 3.11, 3.33,
           3.46, 3.86, 3.92, 3.97, 4.3, 4.43]
    disp = [0, 0.26, 0.49, 0.56, 0.75, 0.99, 1.12, 1.49, 1.58, 1.7, 1.89, 2.07, 2.35, 2.54, 2.72, 2.92, 3.05, 3.34,
            3.49, 3.64, 3.81, 3.99, 4.22, 4.46]
    truth_rows: list[tuple[int, float, str]] = []
    read_rows: list[tuple[int, Value]] = []
    for direction, order in (("aspirating", range(24)), ("dispensing", range(23, -1, -1))):
        for i in order:
            for _ in range(4):
                truth_rows.append((len(truth_rows), truth_levels[i], direction))
                read_rows.append((len(read_rows), (asp if direction == "aspirating" else disp)[i]))
    report = evaluate(write_readings(tmp_path / "p.csv", read_rows), write_truth(tmp_path / "p.truth.csv", truth_rows))
    assert len(report.rows) == 24
    paper = {"aspirating": (0.070, 0.089, -0.043, 0.055, 0.996), "dispensing": (0.094, 0.109, -0.074, 0.055, 0.994)}
    for direction, (mae, rmse, bias, sd, r2) in paper.items():
        m = report.per_step[direction]
        assert (round(m.mae, 3), round(m.rmse, 3), round(m.bias, 3), round(m.sd_abs, 3), round(m.r2, 3)) == \
            (mae, rmse, bias, sd, r2)
    assert report.per_step["aspirating"].max_abs == pytest.approx(0.23)  # 4.20 read 3.97 (the text says 0.22)


# ----------------------------------------------------------------------------- direction without the column

def test_infer_directions() -> None:
    levels = [0, 0, 0, 0.5, 1, 1, 1, 1, 1.5, 2, 2, 2, 2, 2, 2, 1.5, 1, 1, 1, 0.5, 0, 0, 0]
    got = infer_directions(levels)
    assert got[:3] == ["still"] * 3  # before the first movement
    assert got[3:12] == ["aspirating"] * 9  # up, dwells of the up sweep, and the first half of the top dwell
    assert got[12:] == ["dispensing"] * 11  # the second half of the top dwell and the way down, last dwell included


def test_direction_from_truth_level(tmp_path: Path) -> None:
    levels = [0, 0, 0, 0.5, 1, 1, 1, 1, 1.5, 2, 2, 2, 2, 2, 2, 1.5, 1, 1, 1, 0.5, 0, 0, 0]
    truth = write_truth(tmp_path / "t.csv", list(enumerate(levels)))
    readings = write_readings(tmp_path / "r.csv", [(i, v + 0.01) for i, v in enumerate(levels)])
    report = evaluate(readings, truth)
    assert "inferred" in report.direction_source
    assert [(s.direction, s.truth_ml, s.frames) for s in report.steps] == [
        ("still", 0.0, 3), ("aspirating", 1.0, 4), ("aspirating", 2.0, 3), ("dispensing", 2.0, 3),
        ("dispensing", 1.0, 3), ("dispensing", 0.0, 3)]
    assert report.per_frame["aspirating"].total == 9 and report.per_frame["all"].total == len(levels)
    assert "Measured still (ml)" in format_markdown(report)  # the still dwell gets its own column


# ----------------------------------------------------------------------------- divisions

def test_division_argument_and_sidecar(tmp_path: Path) -> None:
    readings, truth = small_run(tmp_path)
    plain = evaluate(readings, truth)
    assert plain.minor_ml is None and "(div)" not in format_markdown(plain)
    assert "mae_div" not in plain.to_json()["per_frame"]["all"]  # type: ignore[index]

    given = evaluate(readings, truth, minor_ml=0.05)
    assert given.minor_source == "argument"
    assert given.to_json()["per_frame"]["aspirating"]["mae_div"] == pytest.approx(2.0)  # type: ignore[index]
    assert "| MAE (div) | 2.00 | 2.00 | 2.00 |" in format_markdown(given)

    truth.with_suffix(".json").write_text(json.dumps({"minor_ml": 0.2, "unit": "ml"}))  # run.truth.json
    side = evaluate(readings, truth)
    assert side.minor_ml == 0.2 and side.minor_source.endswith("run.truth.json")
    assert side.to_json()["per_frame"]["aspirating"]["max_abs_div"] == pytest.approx(1.0)  # type: ignore[index]
    assert evaluate(readings, truth, minor_ml=0.1).minor_ml == 0.1  # the argument wins over the sidecar


# ----------------------------------------------------------------------------- bad input

def test_missing_file(tmp_path: Path) -> None:
    _, truth = small_run(tmp_path)
    missing = tmp_path / "nope.csv"
    with pytest.raises(InputError, match="no such file") as err:
        evaluate(missing, truth)
    assert str(missing) in str(err.value)


def test_wrong_header(tmp_path: Path) -> None:
    readings, truth = small_run(tmp_path)
    with pytest.raises(InputError) as err:
        evaluate(truth, truth)  # the truth CSV passed as readings
    assert str(truth) in str(err.value) and "frame,time_s,level,level_raw" in str(err.value)
    assert "columns frame,time_s,level_ml,direction" in str(err.value)
    with pytest.raises(InputError) as err:
        evaluate(readings, readings)
    assert str(readings) in str(err.value) and "level_ml" in str(err.value)
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(InputError, match="empty file"):
        evaluate(empty, truth)


def test_bad_cells_and_no_overlap(tmp_path: Path) -> None:
    _, truth = small_run(tmp_path)
    bad = tmp_path / "bad.csv"
    bad.write_text(READ_HEADER + "\n0,0,1.0,1.0,,,tracking\n1,0,one,1.0,,,tracking\n")
    with pytest.raises(InputError, match="line 3"):
        evaluate(bad, truth)
    far = write_readings(tmp_path / "far.csv", [(100, 1.0), (101, 1.0)])
    with pytest.raises(InputError, match="none in common"):
        evaluate(far, truth)
    baddir = write_truth(tmp_path / "d.csv", [(0, 0.0, "sideways")])
    with pytest.raises(InputError, match="sideways"):
        evaluate(far, baddir)


def parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="streamread")
    add_eval_parser(parser.add_subparsers(dest="command", required=True))
    return parser.parse_args(argv)


def test_cli_prints_markdown(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    readings, truth = small_run(tmp_path)
    args = parse(["eval", str(readings), str(truth), "--column", "level_raw", "--division", "0.5"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert out.startswith("## Evaluation of `level_raw`") and "| MAE (div) |" in out
    with pytest.raises(SystemExit):
        parse(["eval", str(readings), str(truth), "--division", "-1"])
    with pytest.raises(SystemExit):
        parse(["eval", str(readings), str(truth), "--column", "sigma"])


# ----------------------------------------------------------------------------- outputs

def check_png(path: Path) -> np.ndarray:
    image = cv2.imread(str(path))
    assert image is not None, path
    assert image.shape == (600, 800, 3)
    assert np.count_nonzero(np.any(image < 200, axis=2)) > 2000  # text, axes and data, not a blank page
    return image


def test_write_outputs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    args = parse(["eval", *map(str, staircase(tmp_path)), "--out", str(out)])
    assert args.func(args) == 0
    assert "wrote 7 files" in capsys.readouterr().err
    names = {p.name for p in out.iterdir()}
    assert names == {"report.json", "measured_vs_truth.png", "error_vs_truth.png", "hysteresis.png",
                     "aspirating_vs_dispensing.png", "bland_altman.png", "bland_altman_directions.png"}
    for name in names - {"report.json"}:
        image = check_png(out / name)
        b, g, r = (image[..., i].astype(int) for i in range(3))
        assert np.count_nonzero((np.abs(b - g) > 60) | (np.abs(g - r) > 60)) > 30, name  # coloured data drawn
    data = json.loads((out / "report.json").read_text())
    assert data["per_step"]["dispensing"]["mae_ml"] == pytest.approx(0.1)
    assert [row["truth_ml"] for row in data["table4"]] == [0.0, 1.0, 2.0]
    assert data["table4"][1]["aspirating_minus_dispensing_ml"] == pytest.approx(0.2)


def test_write_outputs_without_readings(tmp_path: Path) -> None:
    truth = write_truth(tmp_path / "t.csv", [(i, 1.0, "still") for i in range(5)])
    readings = write_readings(tmp_path / "r.csv", [(i, None) for i in range(5)])
    report: EvalReport = evaluate(readings, truth)
    assert report.per_frame["all"].coverage == 0.0 and report.per_frame["all"].mae is None
    assert "| MAE (ml) | - | - | - |" in format_markdown(report)
    paths = write_outputs(report, tmp_path / "o")
    assert len(paths) == 7
    for p in paths[1:]:
        check_png(p)
