"""``mvtrack simulate``: files written for each scene, one-line errors for bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtrack.cli import main
from mvtrack.io.mot import read_detections, read_mot
from mvtrack.sim.scenes import build


def test_x4_writes_gt_video_and_scene_json(tmp_path, capsys) -> None:
    out = tmp_path / "x4"
    assert main(["simulate", "x4", "--out", str(out), "--frames", "40"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["gt.txt", "scene.json", "video.mp4"]
    gt = read_mot(out / "gt.txt", "gt")
    sc = build("x4", frames=40)
    assert len(gt) == int(sc.visible.sum()) and gt.frame.max() == 39
    assert set(gt.id) == set(range(1, 9))  # V9 enters the image only at frame 41
    info = json.loads((out / "scene.json").read_text())
    assert info["frames"] == 40 and info["fps"] == 30 and info["category"]["9"] == "fast"
    assert str(out / "gt.txt") in capsys.readouterr().out


def test_crowd_with_detections_and_no_video_by_default(tmp_path) -> None:
    out = tmp_path / "c"
    args = ["simulate", "crowd", "--n", "40", "--frames", "25", "--seed", "3", "--detections"]
    assert main([*args, "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["det.txt", "gt.txt", "scene.json"]
    gt = read_mot(out / "gt.txt", "gt")
    assert len(gt) == 40 * 25
    dets = read_detections(out / "det.txt", num_frames=25)
    n = sum(len(d) for d in dets)
    assert 0.8 * 1000 < n < 1000 + 3 * 25 + 40  # 10 % missed, Poisson(3) clutter per frame
    # Same seed, same files.
    assert main([*args, "--out", str(tmp_path / "d")]) == 0
    assert (out / "det.txt").read_text() == (tmp_path / "d" / "det.txt").read_text()


def test_video_switch_overrides_the_default(tmp_path) -> None:
    assert main(["simulate", "x7", "--out", str(tmp_path / "a"), "--video"]) == 0
    assert (tmp_path / "a" / "video.mp4").stat().st_size > 0
    assert main(["simulate", "x8", "--out", str(tmp_path / "b"), "--no-video"]) == 0
    assert not (tmp_path / "b" / "video.mp4").exists()
    gt = read_mot(tmp_path / "b" / "gt.txt", "gt")
    assert np.isin(gt.cls, [1, 3, 5]).all()


def test_out_that_is_a_file_is_refused(tmp_path, capsys) -> None:
    target = tmp_path / "file"
    target.write_text("x")
    assert main(["simulate", "x4", "--out", str(target)]) == 2
    assert "not a folder" in capsys.readouterr().err
    assert target.read_text() == "x"


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["simulate", "x6"], "unknown scene"),
        (["simulate", "x4", "--n", "5"], "--n"),
        (["simulate", "x4", "--frames", "0"], "--frames"),
        (["simulate", "x4", "--frames", "241"], "frames"),
        (["simulate", "crowd", "--n", "0"], "--n"),
        (["simulate", "crowd", "--seed", "abc"], "seed"),
    ],
)
def test_bad_input_is_one_line_error_and_writes_nothing(tmp_path, capsys, args, needle) -> None:
    out = tmp_path / "o"
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "\n" not in err and needle in err
    assert not out.exists()
