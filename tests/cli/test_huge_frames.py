"""A two-line file whose last frame is 10⁶: every command that reads it stays under 5 s and
500 MB, as the readers do (their memory grows with the rows, not with the last frame)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

LAST = 1_000_000
LIMIT_S, LIMIT_MB = 5.0, 500.0


def _run(args: list[str], timeout: float, tmp_path: Path) -> tuple[int | None, float, float, str]:
    """Run ``mvtrack ARGS`` in a child; (exit status, or None if killed at ``timeout``;
    the child's CPU seconds (the machine may be shared, so not wall time); its own peak RSS
    in MB; stderr). Startup (imports) counts too."""
    err_path = tmp_path / "stderr.txt"
    with err_path.open("w") as err_file:
        proc = subprocess.Popen([sys.executable, "-m", "mvtrack", *args],
                                stdout=subprocess.DEVNULL, stderr=err_file)
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        try:
            _, wait_status, usage = os.wait4(proc.pid, 0)
        finally:
            timer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(wait_status)
    seconds = usage.ru_utime + usage.ru_stime
    status = None if proc.returncode == -signal.SIGKILL else proc.returncode
    return status, seconds, usage.ru_maxrss / 1024, err_path.read_text()  # kB on Linux


@pytest.fixture
def files(tmp_path: Path) -> dict[str, Path]:
    gt = tmp_path / "gt.txt"
    gt.write_text(f"1,1,10,10,20,40,1,-1,-1,-1\n{LAST},1,10,10,20,40,1,-1,-1,-1\n")
    det = tmp_path / "det.txt"
    det.write_text(f"1,-1,10,10,20,40,0.9,-1,-1,-1\n{LAST},-1,10,10,20,40,0.9,-1,-1,-1\n")
    return {"gt": gt, "det": det}


def test_eval_of_a_file_whose_last_frame_is_a_million(files, tmp_path) -> None:
    status, seconds, mb, err = _run(
        ["eval", "--gt", str(files["gt"]), "--pred", str(files["gt"])], 60, tmp_path
    )
    assert status == 0, err
    assert seconds < LIMIT_S and mb < LIMIT_MB, (seconds, mb)


def test_track_detections_of_a_file_whose_last_frame_is_a_million(files, tmp_path) -> None:
    # the first run on a machine compiles the tracker's step (mvtrack.tracking.compiled, about
    # 10 s, then cached): one run on a short file first, so that the limits measure the file
    small = tmp_path / "small.txt"
    small.write_text("1,-1,10,10,20,40,0.9,-1,-1,-1\n2,-1,11,10,20,40,0.9,-1,-1,-1\n")
    assert _run(["track-detections", str(small), "--out", str(tmp_path / "warm")], 120,
                tmp_path)[0] == 0
    status, seconds, mb, err = _run(
        ["track-detections", str(files["det"]), "--out", str(tmp_path / "out")], 3 * LIMIT_S,
        tmp_path,
    )
    assert status == 0, err
    assert seconds < LIMIT_S and mb < LIMIT_MB, (seconds, mb)
