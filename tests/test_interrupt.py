"""Ctrl-C and SIGTERM during a real run: nothing already measured is lost.

The commands run as real subprocesses on the renderer's virtual camera (slow enough to be
interrupted mid-run); the CSV must be complete up to the last frame processed and the .rrd
must verify with ``rerun rrd verify``.
"""

from __future__ import annotations

import csv
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

COLUMNS = ["frame", "time_s", "level", "level_raw", "sigma", "rate", "state"]


def _rows(path: Path) -> list[list[str]]:
    if not path.is_file():
        return []
    with open(path, newline="") as f:
        return list(csv.reader(f))


@pytest.mark.parametrize("command,sig", [("analyze", signal.SIGINT), ("watch", signal.SIGTERM),
                                         ("analyze", signal.SIGTERM), ("watch", signal.SIGINT)])
def test_interrupt_keeps_every_reading(command: str, sig: signal.Signals, tmp_path: Path) -> None:
    out, rrd = tmp_path / "r.csv", tmp_path / "r.rrd"
    argv = [sys.executable, "-m", "streamread.cli", command, "synth:staircase", "--apparatus", "syringe",
            "--csv", str(out), "--save", str(rrd), "--quiet"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=Path(__file__).resolve().parents[1])
    deadline = time.monotonic() + 90
    while len(_rows(out)) < 6 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.2)
    assert proc.poll() is None, f"ended early: {proc.communicate()[1]}"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert "interrupted after" in err
    rows = _rows(out)
    assert rows[0] == COLUMNS
    body = rows[1:]
    assert len(body) >= 5
    assert [int(r[0]) for r in body] == list(range(len(body))), "every processed frame, in order, none cut"
    assert all(len(r) == len(COLUMNS) for r in body)
    assert any(r[2] for r in body), "readings made before the signal are kept"
    rerun = shutil.which("rerun", path=os.path.dirname(sys.executable)) or shutil.which("rerun")
    assert rerun is not None
    verify = subprocess.run([rerun, "rrd", "verify", str(rrd)], capture_output=True, text=True, timeout=60)
    assert verify.returncode == 0, verify.stderr
