"""The command line: real outputs for good input, one clear line and exit 2 for bad input."""

from __future__ import annotations

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
