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


#: ``python -m mvtrack ARGS`` that writes its peak resident memory (``VmHWM``, kB) to the file
#: given first when it exits: the ``ru_maxrss`` of a child counts the memory of the process
#: that started it (the pytest worker, hundreds of MB after compiling the tracker's kernels)
_CHILD = """
import atexit, runpy, sys
out = sys.argv.pop(1)
def peak():
    with open("/proc/self/status") as f:
        kb = next(line.split()[1] for line in f if line.startswith("VmHWM:"))
    with open(out, "w") as f:
        f.write(kb)
atexit.register(peak)
runpy.run_module("mvtrack", run_name="__main__", alter_sys=True)
"""


def _run(args: list[str], timeout: float, tmp_path: Path) -> tuple[int | None, float, float, str]:
    """Run ``mvtrack ARGS`` in a child; (exit status, or None if killed at ``timeout``;
    the child's CPU seconds (the machine may be shared, so not wall time); its own peak RSS
    in MB; stderr). Startup (imports) counts too."""
    err_path = tmp_path / "stderr.txt"
    peak_path = tmp_path / "peak_kb.txt"
    peak_path.unlink(missing_ok=True)
    with err_path.open("w") as err_file:
        proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(peak_path), *args],
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
    kb = float(peak_path.read_text()) if peak_path.exists() else usage.ru_maxrss  # kB
    return status, seconds, kb / 1024, err_path.read_text()


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
    # the first run on a machine compiles the tracker's kernels (mvtrack.jit, about 10 s, then
    # cached): one run on a short file first, so that the limits measure the file
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
