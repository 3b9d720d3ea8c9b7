"""What a new user types wrong, or expects to be told: bare `mvtrack`, an unknown option, a
snapshot past the end of the video, ground truth and results given the other way round."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import motmetrics as mm
import pytest

from _media import box_video
from mvtrack.cli import main

TUD = Path(mm.__file__).parent / "data" / "TUD-Campus"


def _err(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: "), err
    return err


def test_bare_mvtrack_prints_the_help_and_exits_0() -> None:
    proc = subprocess.run([sys.executable, "-m", "mvtrack"], capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("Usage: mvtrack") and "track-detections" in proc.stdout
    assert proc.stderr == ""


def test_an_unknown_option_suggests_only_a_close_one(capsys) -> None:
    assert main(["track", "v.avi", "--bogus"]) == 2
    err = _err(capsys)
    assert err == ("error: mvtrack track: no such option --bogus; 'mvtrack track --help' "
                   "lists the options")
    assert main(["track", "v.avi", "--max-frame", "3"]) == 2
    assert "no such option --max-frame (did you mean --max-frames?)" in _err(capsys)


def test_a_snapshot_past_the_last_frame_is_refused_before_the_run(tmp_path: Path,
                                                                   capsys) -> None:
    video = box_video(tmp_path / "v.avi", n=30)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--snapshot", "5000"]) == 2
    assert f"--snapshot 5000 is past the last frame 29 of {video}" in _err(capsys)
    assert main(["track", str(video), "--out", str(out), "--snapshot", "20",
                 "--max-frames", "10"]) == 2
    assert "--snapshot 20 is past the last frame tracked (--max-frames 10" in _err(capsys)
    assert not out.exists()
    assert main(["track", str(video), "--out", str(out), "--snapshot", "29",
                 "--no-video"]) == 0
    assert (out / "frame00029.png").exists()


@pytest.mark.usefixtures("unknown_length")
def test_a_snapshot_never_reached_on_a_source_of_unknown_length_is_said(
        tmp_path: Path, capsys) -> None:
    """A camera or stream has no length to check first: the run is kept, and one line says
    that no frame was saved."""
    video = box_video(tmp_path / "v.avi", n=30)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--snapshot", "40",
                 "--no-video"]) == 2
    err = _err(capsys)
    assert (f"--snapshot 40: {video} ended after 30 frames (0 to 29), so that frame was not "
            "saved") in err
    assert (out / "results.txt").exists() and not list(out.glob("frame*.png"))
    # of two frames asked for, the one inside the video is saved and the other named
    out2 = tmp_path / "out2"
    assert main(["track", str(video), "--out", str(out2), "--snapshot", "40", "--snapshot",
                 "12", "--no-video"]) == 2
    assert f"--snapshot 40: {video} ended after 30 frames" in _err(capsys)
    assert sorted(p.name for p in out2.glob("frame*.png")) == ["frame00012.png"]


def test_swapped_ground_truth_and_results_get_a_warning(tmp_path: Path, capsys) -> None:
    assert main(["eval", "--gt", str(TUD / "test.txt"), "--pred", str(TUD / "gt.txt"),
                 "--no-hota"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("warning: ")
    assert "column 7 holds scores such as -1" in err[0] and "swapped?" in err[0]
    # the right way round: no warning
    assert main(["eval", "--gt", str(TUD / "gt.txt"), "--pred", str(TUD / "test.txt"),
                 "--no-hota"]) == 0
    assert capsys.readouterr().err == ""


def test_results_with_ground_truth_columns_get_a_warning(tmp_path: Path, capsys) -> None:
    """mvtrack's own files: a results file (conf 1, then -1 -1 -1) given as --gt and a
    simulated ground truth (class 1, visibility 1) given as --pred."""
    gt = tmp_path / "gt.txt"
    res = tmp_path / "results.txt"
    gt.write_text("".join(f"{f},1,{10 + f},10,20,40,1,1,1\n" for f in range(1, 6)))
    res.write_text("".join(f"{f},1,{10 + f},10,20,40,1,-1,-1,-1\n" for f in range(1, 6)))
    assert main(["eval", "--gt", str(res), "--pred", str(gt), "--no-hota"]) == 0
    err = capsys.readouterr().err.strip()
    assert "class and visibility columns (8, 9) of ground truth" in err and "swapped?" in err
    assert main(["eval", "--gt", str(gt), "--pred", str(res), "--no-hota"]) == 0
    assert capsys.readouterr().err == ""


def test_snapshot_ids_stay_readable_beside_the_header_and_each_other(tmp_path: Path) -> None:
    """`mvtrack track VIDEO --snapshot N` on a vehicle under the frame's header and two side by
    side: three ID labels, none under the header, none touching another, each with digits."""
    import cv2
    import numpy as np

    path = tmp_path / "v.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15, (320, 240))
    for k in range(30):
        img = np.full((240, 320, 3), 80, np.uint8)
        if k >= 5:
            img[22:40, 60 + k : 72 + k] = 230  # under the header's second line
            img[120 + k : 140 + k, 200:204] = 230  # two side by side, 9 px apart
            img[120 + k : 140 + k, 213:217] = 230
        writer.write(img)
    writer.release()
    out = tmp_path / "out"
    assert main(["track", str(path), "--out", str(out), "--snapshot", "25", "--no-video",
                 "--detector", "disturbance-map", "--preset", "paper1"]) == 0
    shot = cv2.imread(str(out / "frame00025.png"))
    dark = (shot == 20).all(axis=2).astype(np.uint8)
    _, _, stats, _ = cv2.connectedComponentsWithStats(dark, connectivity=8)
    patches = [(x, y, x + w - 1, y + h - 1) for x, y, w, h, a in stats[1:] if a > 20]
    header = [p for p in patches if p[0] <= 4]
    labels = [p for p in patches if p[0] > 4]
    assert len(labels) == 3, patches
    b, g, r = (shot[..., c].astype(int) for c in range(3))
    green = (g > 100) & (g > r + 40) & (g > b + 40)
    for x0, y0, x1, y1 in labels:
        assert green[y0 : y1 + 1, x0 : x1 + 1].sum() >= 5
        for h in header:
            assert x0 > h[2] or y0 > h[3] or y1 < h[1]
