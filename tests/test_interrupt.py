"""Ctrl-C and SIGTERM during a real run: nothing already measured is lost.

The commands run as real subprocesses on the renderer's virtual camera (slow enough to be
interrupted mid-run); the CSV must be complete up to the last frame processed and the .rrd
must verify with ``rerun rrd verify``.
"""

from __future__ import annotations

import contextlib
import csv
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from streamread.run import Interrupts

COLUMNS = ["frame", "time_s", "level", "level_raw", "sigma", "rate", "state"]


def _rows(path: Path) -> list[list[str]]:
    if not path.is_file():
        return []
    with open(path, newline="") as f:
        return list(csv.reader(f))


def _sigint_as_from_a_terminal() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("command,sig", [("analyze", signal.SIGINT), ("watch", signal.SIGTERM),
                                         ("analyze", signal.SIGTERM), ("watch", signal.SIGINT)])
def test_interrupt_keeps_every_reading(command: str, sig: signal.Signals, tmp_path: Path) -> None:
    out, rrd = tmp_path / "r.csv", tmp_path / "r.rrd"
    argv = [sys.executable, "-m", "streamread.cli", command, "synth:staircase", "--apparatus", "syringe",
            "--csv", str(out), "--save", str(rrd), "--quiet"]
    # Ctrl-C as a terminal delivers it: a suite run in the background (a shell's job, nohup)
    # starts its children ignoring SIGINT, which the command rightly keeps ignoring
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=Path(__file__).resolve().parents[1], preexec_fn=_sigint_as_from_a_terminal)
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


def test_a_signal_while_a_frame_is_processed_stops_once_it_is_written() -> None:
    # an interrupt raised inside the Rerun SDK's or the CSV writer's calls could cut a row or
    # leave the recording unable to flush: the loop acts on it once the frame is done
    interrupts = Interrupts()
    done = []
    with _sigint_default():
        with interrupts.installed(), pytest.raises(KeyboardInterrupt):
            with interrupts.frame():
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)  # the handler runs here; the frame goes on
                done.append("written")
        assert done == ["written"]
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored on the way out


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_waiting_for_the_source_stops_at_once(sig: signal.Signals) -> None:
    interrupts = Interrupts()
    with _sigint_default(), interrupts.installed(), pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), sig)
        time.sleep(5)  # a camera's read blocking: interrupted, not waited out
        pytest.fail("the signal did not stop the wait")


def test_a_second_signal_stops_a_frame_that_does_not_end() -> None:
    interrupts = Interrupts()
    with _sigint_default(), interrupts.installed(), pytest.raises(KeyboardInterrupt):
        with interrupts.frame():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
            pytest.fail("the second signal did not stop the frame")


def test_a_sigint_ignored_from_the_start_stays_ignored() -> None:
    # a job run in the background by a shell starts ignoring SIGINT; Python leaves it so, and
    # so does the loop (SIGTERM still stops it)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with Interrupts().installed():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            assert signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def _sigint_default() -> Iterator[None]:
    """SIGINT as Python sets it in a process started from a terminal, whatever this one's is."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
