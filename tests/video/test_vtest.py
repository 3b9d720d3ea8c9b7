"""The whole pipeline on the real campus video ../shared/data/vtest.avi (768×576, 10 fps).

Bounds are sanity bounds around measured values (default settings, full video: 132 tracks,
58 of them with ≥ 20 rows, median 15.5 rows per track, median 6 tracks per frame, largest
step 41 px per frame — within the 48 px second-stage gate the default gets at this size):
they fail on a broken pipeline (no tracks, one track per detection, tracks that jump across
the image), not on small changes of the parts.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from _media import default_signals
from mvtrack.cli import main

W, H = 768, 576


def _rows(out: Path) -> np.ndarray:
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    return rows[np.lexsort((rows[:, 0], rows[:, 1]))]


def _check_plausible(rows: np.ndarray, n_frames: int) -> dict[str, float]:
    ids, counts = np.unique(rows[:, 1], return_counts=True)
    centre = rows[:, 2:4] + rows[:, 4:6] / 2
    same = rows[1:, 1] == rows[:-1, 1]
    step = np.linalg.norm(centre[1:] - centre[:-1], axis=1)[same]
    gap = (rows[1:, 0] - rows[:-1, 0])[same]
    per_frame = np.bincount(rows[:, 0].astype(int), minlength=n_frames + 1)[1:]
    # boxes are people-sized and inside the picture (up to a margin for coasting at the edge)
    assert np.all((rows[:, 4] > 2) & (rows[:, 4] < W / 2) & (rows[:, 5] > 2) & (rows[:, 5] < H))
    assert np.all((centre > -50).all(axis=1) & (centre[:, 0] < W + 50) & (centre[:, 1] < H + 50))
    # no track teleports: at most 60 px per frame (a twelfth of the width) between
    # consecutive rows of one track
    assert np.all(gap >= 1) and (step / gap).max() <= 60.0
    return {"tracks": len(ids), "median_len": float(np.median(counts)),
            "long": int((counts >= 20).sum()), "per_frame": float(np.median(per_frame))}


def test_vtest_first_150_frames(vtest_path, tmp_path) -> None:
    out = tmp_path / "vtest"
    assert main(["track", str(vtest_path), "--out", str(out), "--max-frames", "150",
                 "--no-video"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 150 and summary["size"] == [W, H]
    assert summary["video_fps"] == 10.0 and summary["ended_early"] is False
    stats = _check_plausible(_rows(out), 150)
    assert 8 <= stats["tracks"] <= 80
    assert stats["long"] >= 3 and stats["per_frame"] >= 2


@pytest.mark.slow
def test_vtest_whole_video(vtest_path, tmp_path) -> None:
    out = tmp_path / "vtest"
    assert main(["track", str(vtest_path), "--out", str(out), "--no-video"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 795 and summary["ended_early"] is False
    stats = _check_plausible(_rows(out), 795)
    # about 20 people walk through; measured 33 tracks (48 without relinking)
    assert 20 <= stats["tracks"] <= 400, stats
    assert stats["long"] >= 20, stats  # tracks of ≥ 20 frames: about one per person (29)
    assert stats["median_len"] >= 8, stats
    assert 2 <= stats["per_frame"] <= 20, stats
    assert summary["tracks"] == stats["tracks"]
    assert sorted(p.name for p in out.iterdir()) == [
        "results.txt", "states.csv", "summary.json", "trajectories.png"
    ]


@pytest.mark.parametrize("sig, status, word", [("SIGINT", 130, "interrupted"),
                                               ("SIGTERM", 143, "terminated")])
def test_real_signal_stops_cleanly(vtest_path, tmp_path, sig, status, word) -> None:
    """SIGINT (what Ctrl-C sends) or SIGTERM (``timeout``, ``docker stop``) from another
    process to a running ``mvtrack track``: status 130 or 143, one line on stderr, the files of
    the frames tracked so far, valid, and no temporary file left."""
    import signal
    import subprocess
    import sys
    import time

    import cv2

    out = tmp_path / "vtest"
    proc = subprocess.Popen(
        [sys.executable, "-m", "mvtrack", "track", str(vtest_path), "--out", str(out)],
        preexec_fn=default_signals,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    deadline = time.monotonic() + 60
    while not out.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)  # the folder appears when the frame loop starts
    # frames are being tracked once the hidden video file holds more than its header (however
    # loaded the machine: a fixed sleep may end before the first frame)
    while proc.poll() is None and time.monotonic() < deadline and not any(
            p.stat().st_size > 4096 for p in out.iterdir() if p.name.startswith(".")):
        time.sleep(0.05)
    time.sleep(0.5)
    if proc.poll() is not None:
        pytest.skip("the whole video was tracked before the signal could be sent")
    proc.send_signal(getattr(signal, sig))
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {word} after"), err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and 0 < summary["frames"] < 795
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    assert rows.shape[1] == 10 and rows[:, 0].max() <= summary["frames"]
    cap = cv2.VideoCapture(str(out / "tracks.mp4"))
    # a signal between the frame's count and its drawing leaves it out of the video
    assert summary["frames"] - 1 <= int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) <= summary["frames"]
    cap.release()
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
