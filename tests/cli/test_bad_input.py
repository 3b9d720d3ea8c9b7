"""Bad input files through the command line: exit 2, one line naming file and line, no file.

Each case is one a user has met: a frame number of 10⁹ or 10²⁰, ``1_0``, full-width digits,
``nan``, ``inf``, an empty field, too few columns, a negative or absurd size, IDs too large to
tell apart. An empty detection file is not an error: one warning line and an empty result.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mvtrack.cli import main

OK_DET = "1,-1,10,10,20,40,0.9\n"
OK_GT = "1,1,10,10,20,40,1,1,1\n2,1,12,10,20,40,1,1,1\n"
OK_RES = "1,1,10,10,20,40,1,-1,-1,-1\n2,1,12,10,20,40,1,-1,-1,-1\n"

DET_CASES = {
    "frame 1e9": ("1000000000,-1,12,10,20,40,0.8", "frame (column 1) is 1000000000, above"),
    "frame 1e20": ("1e20,-1,12,10,20,40,0.8", "frame (column 1) is 1e+20, above"),
    "underscore": ("1_0,-1,12,10,20,40,0.8", "column 1 is not a number: '1_0'"),
    "full-width": ("\uff12,-1,12,10,20,40,0.8", "column 1 is not a number: '\uff12'"),
    "nan": ("2,-1,nan,10,20,40,0.8", "column 3 is nan"),
    "inf": ("2,-1,12,inf,20,40,0.8", "column 4 is inf"),
    "overflow": ("2,-1,12,10,20,40,1e999", "column 7 is inf"),
    "empty field": ("2,-1,12,,20,40,0.8", "column 4 is empty"),
    "leading comma": (",2,-1,12,10,20,40", "column 1 is empty"),
    "too few columns": ("2,-1,12,10,20", "expected 7 to 10 columns"),
    "negative size": ("2,-1,12,10,-20,40,0.8", "negative width (column 5): -20"),
    "absurd size": ("2,-1,12,10,1e20,40,0.8", "width (column 5) is 1e+20, above"),
    "fractional frame": ("0.5,-1,12,10,20,40,0.8", "frame (column 1) is 0.5, not an integer"),
}


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(args)
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize("case", sorted(DET_CASES))
def test_bad_detection_file_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str
) -> None:
    line, fragment = DET_CASES[case]
    det = tmp_path / "det.txt"
    det.write_text(OK_DET + line + "\n", encoding="utf-8")
    out = tmp_path / "out"
    status, _, err = _run(["track-detections", str(det), "--out", str(out)], capsys)
    assert status == 2
    assert err.count("\n") == 1 and err.startswith(f"error: {det}:2: "), err
    assert fragment in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    ("gt", "pred", "where", "fragment"),
    [
        ("1,1,10,10,20,40,1,1,1\n1e20,2,12,10,20,40,1,1,1\n", OK_RES, "gt:2", "above the limit"),
        ("1,1,10,10,20,40,1,1,1\n1000000,2,1e7,10,20,40,1,1,1\n", OK_RES, "gt:2", "left"),
        (OK_GT, "1,100000000000000000000,10,10,20,40,1,-1,-1,-1\n", "pred:1", "beyond ±"),
        (OK_GT, "1,1,10,10,20,40,1,-1,-1,-1\n1,1,12,10,20,40,1,-1,-1,-1\n", "pred:2", "twice"),
    ],
)
def test_bad_eval_input_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], gt: str, pred: str, where: str,
    fragment: str,
) -> None:
    files = {"gt": tmp_path / "gt", "pred": tmp_path / "pred"}
    files["gt"].write_text(gt)
    files["pred"].write_text(pred)
    scores = tmp_path / "scores.json"
    status, _, err = _run(
        ["eval", "--gt", str(files["gt"]), "--pred", str(files["pred"]), "--json", str(scores)],
        capsys,
    )
    name, line = where.split(":")
    assert status == 2
    assert err.count("\n") == 1 and err.startswith(f"error: {files[name]}:{line}: "), err
    assert fragment in err, err
    assert not scores.exists()


def test_empty_detection_file_warns_in_one_line_and_gives_an_empty_result(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    det = tmp_path / "det.txt"
    det.write_text("# no detections\n")
    status, out, err = _run(["track-detections", str(det), "--out", str(tmp_path / "o")], capsys)
    assert status == 0
    assert err == f"warning: {det}: the file has no rows (it is empty or holds only comments)\n"
    assert (tmp_path / "o" / "det.txt").read_text() == ""
    assert "0 frames, 0 detections" in out


def _mvtrack(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "mvtrack", *args], capture_output=True, text=True, check=False
    )


def test_ffmpeg_lines_stay_off_the_terminal_unless_verbose(tmp_path: Path) -> None:
    """An MP4 without its index: FFmpeg says "moov atom not found" only under --verbose."""
    video = tmp_path / "broken.mp4"
    video.write_bytes(b"not a video\n")
    quiet = _mvtrack("track", str(video), "--out", str(tmp_path / "q"))
    assert quiet.returncode == 2
    assert quiet.stderr.count("\n") == 1 and quiet.stderr.startswith("error: "), quiet.stderr
    loud = _mvtrack("--verbose", "track", str(video), "--out", str(tmp_path / "v"))
    assert loud.returncode == 2
    lines = loud.stderr.splitlines()
    assert len(lines) > 1 and lines[-1] == quiet.stderr.strip(), loud.stderr
    assert not (tmp_path / "q").exists() and not (tmp_path / "v").exists()


def test_bad_detection_file_on_a_fresh_install_is_told_before_compiling(tmp_path: Path) -> None:
    """On a machine whose compile cache is empty, a bad file is still one line, at once: the
    file is read before the tracker (whose settings are checked by building one) compiles."""
    det = tmp_path / "det.txt"
    det.write_text(OK_DET + DET_CASES["fractional frame"][0] + "\n", encoding="utf-8")
    out = tmp_path / "out"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "empty-cache")}
    proc = subprocess.run(
        [sys.executable, "-m", "mvtrack", "track-detections", str(det), "--out", str(out)],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert proc.returncode == 2
    assert proc.stderr == f"error: {det}:2: frame (column 1) is 0.5, not an integer\n"
    assert not out.exists()
