"""The command line: real outputs for good input, one clear line and exit 2 for bad input."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import cv2
import pytest

from streamread.cli import main

RECORDINGS = Path(__file__).resolve().parents[1] / "recordings"


def test_contact_sheet(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "sheet.png"
    assert main(["synth", "--contact-sheet", str(out), "--count", "4", "--columns", "2"]) == 0
    sheet = cv2.imread(str(out))
    assert sheet.shape == (2 * 240, 2 * 320, 3)


def test_inspect_bundled_sample(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["inspect", str(RECORDINGS / "syringe5ml_staircase.mp4")]) == 0
    out = capsys.readouterr().out
    assert "aspirating" in out and "dispensing" in out
    assert "dwell steps (24)" in out


@pytest.mark.parametrize("argv,needle", [
    (["inspect", "no/such/video.mp4"], "no such file"),
    (["synth", "--video", "x.mp4", "--protocol", "wobble"], "protocol 'wobble'"),
    (["synth", "--stills", "x", "--apparatus", "syringe_7ml"], "apparatus 'syringe_7ml'"),
])
def test_bad_input_is_one_line(argv: list[str], needle: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                               monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("streamread: error:") and needle in err


def test_not_a_video(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fake = tmp_path / "notes.mp4"
    fake.write_text("this is text, not a video")
    assert main(["inspect", str(fake)]) == 2
    assert "expected" in capsys.readouterr().err


def test_analyze_writes_csv_and_compares_with_truth(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "r.csv"
    cal = tmp_path / "bench.json"
    code = main(["analyze", str(RECORDINGS / "syringe5ml_staircase.mp4"), "--apparatus", "syringe", "--csv", str(out),
                 "--calibration", str(cal), "--quiet"])
    assert code == 0
    rows = list(csv.DictReader(open(out)))
    assert len(rows) == 904 and list(rows[0]) == ["frame", "time_s", "level", "level_raw", "sigma", "rate", "state"]
    assert all(r["level"] for r in rows)
    printed = capsys.readouterr().out
    assert "Table 4" in printed and "| 4.60 |" in printed, "the readings are printed against the ground truth"
    assert cal.is_file(), "the calibration was saved for the next run"
    # second run: starts from the saved calibration, no OCR, same readings
    again = tmp_path / "r2.csv"
    assert main(["analyze", str(RECORDINGS / "syringe5ml_staircase.mp4"), "--apparatus", "syringe", "--csv",
                 str(again), "--calibration", str(cal), "--quiet",
                 "--truth", str(RECORDINGS / "syringe5ml_staircase.truth.csv")]) == 0
    err = capsys.readouterr().err
    assert "OCR ran 0 time(s)" in err


def test_analyze_jsonl_and_smooth(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "r.csv"
    assert main(["analyze", str(RECORDINGS / "syringe5ml_bump.mp4"), "--apparatus", "syringe", "--csv", str(out),
                 "--jsonl", "--smooth"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    records = [json.loads(line) for line in lines]
    assert len(records) == 182 and set(records[0]) == {"frame", "time_s", "level", "level_raw", "sigma", "rate", "state"}
    smoothed = list(csv.DictReader(open(out)))
    assert len(smoothed) == 182
    changed = sum(1 for r, j in zip(smoothed, records) if r["level"] and j["level"] is not None
                  and abs(float(r["level"]) - j["level"]) > 1e-6)
    assert changed > 50, "--smooth rewrote the CSV with the RTS-smoothed level"


@pytest.mark.parametrize("argv,needle", [
    (["analyze", "no/such/video.mp4"], "no such file"),
    (["analyze", "frames/*.png"], "no match"),
    (["watch", "/dev/video42"], "/dev/video42"),
    (["watch", "webcam"], "expected a V4L2 device"),
    (["eval", "missing.csv", "missing.truth.csv"], "missing.csv"),
])
def test_stream_bad_input_is_one_line(argv: list[str], needle: str, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("streamread: error:") and needle in err
