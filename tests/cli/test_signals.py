"""SIGTERM ends a command the way Ctrl-C does, with exit status 143.

``timeout``, ``docker stop``, systemd and batch schedulers send SIGTERM; Python's default is to
die at once (no results file, no summary, a hidden temporary MP4 left behind).
"""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from _media import batch_signalled, stop_at_frame
from mvtrack.cli import main


def _write_avi(path: Path, n: int = 60) -> Path:
    """A small MJPG video with one bright box moving right."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15, (96, 64))
    assert writer.isOpened()
    for k in range(n):
        img = np.full((64, 96, 3), 80, np.uint8)
        if k >= 8:
            x = 10 + (k - 8) % 70  # back to the left edge every 70 frames
            img[28:36, x : x + 10] = 230
        writer.write(img)
    writer.release()
    return path


def test_sigterm_in_track_writes_what_was_tracked_and_exits_143(tmp_path, capsys,
                                                                monkeypatch) -> None:
    """The signal arrives in the frame loop (sent by the process to itself while frame 26 is
    detected): that frame is finished and kept, and the run ends after it."""
    stop_at_frame(monkeypatch, 26, lambda: signal.raise_signal(signal.SIGTERM))
    before = signal.getsignal(signal.SIGTERM)
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out)]) == 143
    assert signal.getsignal(signal.SIGTERM) is before  # the handler is the command's only
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: terminated after 26 frames"), err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 26 and summary["interrupted"] and summary["ended_early"]
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    assert len(rows) and rows[:, 0].max() <= 26 and rows.shape[1] == 10
    cap = cv2.VideoCapture(str(out / "tracks.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 26
    cap.release()
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


def test_ctrl_c_still_exits_130_after_a_sigterm_in_an_earlier_command(tmp_path, capsys,
                                                                       monkeypatch) -> None:
    send = {"sig": signal.SIGTERM}

    def stop() -> None:
        if send["sig"] == signal.SIGTERM:
            signal.raise_signal(signal.SIGTERM)
        else:
            raise KeyboardInterrupt

    stop_at_frame(monkeypatch, 10, stop)
    video = _write_avi(tmp_path / "v.avi")
    assert main(["track", str(video), "--out", str(tmp_path / "a"), "--no-video"]) == 143
    send["sig"] = signal.SIGINT
    assert main(["track", str(video), "--out", str(tmp_path / "b"), "--no-video"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    # the signal ends the run after the frame it arrived in; a KeyboardInterrupt raised in
    # the detector, before that frame is tracked
    assert err[0].startswith("error: terminated after 10 frames"), err
    assert err[1].startswith("error: interrupted after 9 frames"), err


def test_sigterm_outside_the_frame_loop_is_one_line_and_143(tmp_path, capsys,
                                                            monkeypatch) -> None:
    """A command with nothing to keep (here eval, signalled while scoring) still ends in one
    line, status 143 and no traceback."""
    import mvtrack.eval.metrics as metrics

    def scoring(*args, **kwargs):
        signal.raise_signal(signal.SIGTERM)
        time.sleep(5)  # the handler raises before this returns
        raise AssertionError("SIGTERM was not turned into an interrupt")

    monkeypatch.setattr(metrics, "score_sequence", scoring)
    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,10,10,20,40,1,-1,-1,-1\n")
    status = main(["eval", "--gt", str(gt), "--pred", str(gt)])
    err = capsys.readouterr().err.strip()
    assert status == 143 and err == "error: terminated", (status, err)


@pytest.mark.slow
def test_sigterm_to_batch_exits_143_and_says_so_in_batch_json(tmp_path) -> None:
    """SIGTERM to the batch client (what ``timeout`` and ``docker stop`` do): status 143, one
    error line, batch.json written with ``interrupted``, no worker process left running."""
    import psutil  # installed with distributed

    proc, err, workers = batch_signalled(tmp_path, signal.SIGTERM)
    assert proc.returncode == 143, err
    assert "Traceback" not in err, err
    assert [line for line in err.splitlines() if line.startswith("error:")] == [
        line for line in err.splitlines() if line.startswith("error: terminated;")
    ] != [], err
    time.sleep(0.5)
    assert not [p for p in workers if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    out = tmp_path / "out"
    data = json.loads((out / "batch.json").read_text())
    assert data["interrupted"] is True and data["pending"] == 0
    assert data["ok"] >= 1 and data["ok"] + data["cancelled"] == 6
    for v in data["videos"]:
        if v["status"] == "ok":
            assert (Path(v["out"]) / "results.txt").exists()
    assert [p for p in out.rglob(".*") if p.is_file()] == []


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_to_the_batch_client_alone_leaks_no_semaphore(tmp_path, sig) -> None:
    """``kill PID`` rather than a terminal's Ctrl-C: the workers are not signalled, the
    videos they are tracking stop on the batch's stop event, nothing is left to clean up."""
    proc, err, _ = batch_signalled(tmp_path, sig)
    assert proc.returncode == 128 + sig, err
    assert "leaked semaphore" not in err and "Traceback" not in err, err


def test_interrupted_batch_keeps_the_partial_results_of_the_video_being_tracked(
    tmp_path,
) -> None:
    """Ctrl-C (KeyboardInterrupt in the client) once a short video is done, while a long one
    is being tracked on the other worker: the long one stops and writes the results, video
    and summary of the frames it tracked."""
    from mvtrack.config import RunSettings
    from mvtrack.video.batch import track_many

    short = _write_avi(tmp_path / "short.avi", n=20)
    long = _write_avi(tmp_path / "long.avi", n=20000)

    def stop(item) -> None:
        raise KeyboardInterrupt

    items = track_many([short, long], tmp_path / "out", RunSettings(), workers=2,
                       on_result=stop)
    by_name = {Path(it.video).name: it for it in items}
    assert by_name["short.avi"].status == "ok", by_name
    cut = by_name["long.avi"]
    assert cut.status == "cancelled" and 0 < cut.frames < 20000, cut
    assert f"interrupted after {cut.frames} frames" in cut.error
    folder = Path(cut.out)
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["frames"] == cut.frames
    rows = np.loadtxt(folder / "results.txt", delimiter=",", ndmin=2)
    assert rows.shape[1] == 10 and 0 < rows[:, 0].max() <= cut.frames
    cap = cv2.VideoCapture(str(folder / "tracks.mp4"))
    assert cut.frames - 1 <= int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) <= cut.frames
    cap.release()
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]
    data = json.loads((tmp_path / "out" / "batch.json").read_text())
    assert data["interrupted"] is True and data["cancelled"] == 1 and data["ok"] == 1


@pytest.mark.parametrize("sig, status, word", [(signal.SIGTERM, 143, "terminated"),
                                               (signal.SIGINT, 130, "interrupted")])
def test_a_signal_in_track_detections_writes_the_frames_tracked(tmp_path, capsys, monkeypatch,
                                                                sig, status, word) -> None:
    """The signal arrives while frame 10 is tracked (sent by the process to itself): the run
    ends after that frame and its results file holds frames 1..11, whole."""
    import mvtrack.tracking as tracking
    from mvtrack.io.mot import write_detections
    from mvtrack.types import Detections

    det = tmp_path / "det.txt"
    write_detections(det, [Detections(k, [[10.0 + 2 * k, 50.0]], [[20.0, 40.0]])
                           for k in range(40)])
    real = tracking.track_detections

    def signalling(frames, config, **options):
        def frames_sending():
            for k, d in enumerate(frames):
                if k == 10:
                    signal.raise_signal(sig)
                yield d

        return real(frames_sending(), config, **options)

    monkeypatch.setattr(tracking, "track_detections", signalling)
    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    assert main(["track-detections", str(det), "--out", str(tmp_path / "o")]) == status
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith(f"error: {word} after 11 of 40 frames"), err
    rows = np.loadtxt(tmp_path / "o" / "det.txt", delimiter=",", ndmin=2)
    assert rows.shape == (11, 10) and rows[:, 0].tolist() == list(range(1, 12))
