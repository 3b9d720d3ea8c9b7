"""``mvtrack track-detections``: a det file in, MOTChallenge results out, one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.cli import main
from mvtrack.cli.track_detections import results_name
from mvtrack.io.mot import read_tracks, write_detections
from mvtrack.types import Detections


def _det_file(path, n_frames=30):
    a = np.array([100.0, 100.0]) + np.arange(n_frames)[:, None] * [3.0, 1.0]
    b = np.array([400.0, 300.0]) + np.arange(n_frames)[:, None] * [-2.0, 2.0]
    frames = [
        Detections(k, np.vstack([a[k], b[k]]), np.array([[40.0, 30.0], [30.0, 60.0]]))
        for k in range(n_frames)
    ]
    frames[10] = frames[10].take(np.array([1]))  # target a missed once
    write_detections(path, frames)
    return a, b


def test_track_detections_writes_results_and_prints_a_summary(tmp_path, capsys) -> None:
    det = tmp_path / "seq" / "det" / "det.txt"
    det.parent.mkdir(parents=True)
    a, _ = _det_file(det)
    out = tmp_path / "res"
    assert main(["track-detections", str(det), "--out", str(out)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2 and "30 frames, 59 detections -> 2 tracks" in lines[0]
    assert lines[1].startswith("rows written: confirmed tracks, coasting rows up to 0.08 s")
    table = read_tracks(out / "seq.txt")
    assert sorted(set(table.id.tolist())) == [1, 2]
    # confirmed on the 2nd frame and written from the 1st (backfill, the default); the
    # missed frame is bridged by a coasting row
    assert table.frame.min() == 0 and len(table) == 2 * 30
    id_a = table.id[(table.frame == 5) & (np.abs(table.tlwh[:, 2] - 40.0) < 5)]
    rows_a = table.take(np.flatnonzero(table.id == id_a[0]))
    centre = rows_a.tlwh[:, :2] + rows_a.tlwh[:, 2:] / 2
    np.testing.assert_allclose(centre, a[rows_a.frame], atol=1.5)
    assert main(["track-detections", str(det), "--out", str(out), "--no-coasting"]) == 0
    assert len(read_tracks(out / "seq.txt")) == 2 * 30 - 1
    assert main(["track-detections", str(det), "--out", str(out), "--no-backfill"]) == 0
    online = read_tracks(out / "seq.txt")
    assert online.frame.min() == 1 and len(online) == 2 * 29


def test_cli_results_equal_the_library_run(tmp_path) -> None:
    from mvtrack.io.mot import read_detections
    from mvtrack.tracking import preset, track_detections

    det = tmp_path / "d.txt"
    _det_file(det)
    for flag, config in (([], preset("default", fps=30.0)),
                         (["--no-backfill"], preset("default", fps=30.0, backfill=False)),
                         (["--low-birth-iou", "none"],
                          preset("default", fps=30.0, low_birth_iou=None)),
                         (["--low-birth-iou", "0.3"],
                          preset("default", fps=30.0, low_birth_iou=0.3))):
        assert main(["track-detections", str(det), "--out", str(tmp_path / "o"), *flag]) == 0
        got = read_tracks(tmp_path / "o" / "d.txt")
        want = np.asarray(track_detections(read_detections(det), config).to_mot())
        np.testing.assert_array_equal(got.frame, want[:, 0].astype(int) - 1)
        np.testing.assert_array_equal(got.id, want[:, 1].astype(int))
        np.testing.assert_allclose(got.tlwh, want[:, 2:6], atol=1e-3)


def test_low_birth_iou_reaches_the_tracker(tmp_path) -> None:
    """A person scored low for four frames, then high: with low-score births the offline
    track starts on the last weak box, with ``--low-birth-iou none`` on the first strong one."""
    xy = np.array([100.0, 100.0]) + np.arange(20)[:, None] * [3.0, 1.0]
    score = np.where(np.arange(20) < 4, 0.3, 0.9)
    det = tmp_path / "s.txt"
    write_detections(det, [Detections(k, xy[k : k + 1], np.array([[30.0, 60.0]]), score[k : k + 1])
                           for k in range(20)])
    first = {}
    for value in ("0.1", "none"):
        out = tmp_path / value
        assert main(["track-detections", str(det), "--out", str(out), "--score-scale", "prob",
                     "--low-birth-iou", value]) == 0
        first[value] = int(read_tracks(out / "s.txt").frame.min())
    assert first == {"0.1": 3, "none": 4}


@pytest.mark.parametrize(
    "option, value",
    [("--predictor", "kalman-xyz"), ("--distance", "manhattan"), ("--assign", "hungarian")],
)
def test_unknown_names_are_one_line_errors(tmp_path, capsys, option, value) -> None:
    det = tmp_path / "d.txt"
    _det_file(det)
    assert main(["track-detections", str(det), "--out", str(tmp_path / "o"), option, value]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and value in err and "\n" not in err
    assert not (tmp_path / "o").exists()


def test_options_reach_the_tracker(tmp_path, capsys) -> None:
    det = tmp_path / "d.txt"
    _det_file(det)
    args = ["track-detections", str(det), "--out", str(tmp_path / "o"), "--preset", "paper1",
            "--predictor", "rls", "--fps", "15"]
    assert main(args) == 0
    assert "(rls, euclidean, nearest, 15 fps;" in capsys.readouterr().out
    assert main([*args[:-4], "--distance", "mahalanobis", "--gate", "20"]) == 0
    assert "(kalman-ca, mahalanobis, nearest, 30 fps;" in capsys.readouterr().out


def test_bad_file_and_bad_values_are_one_line_errors(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.txt"
    bad.write_text("1,-1,10,10,5\n")
    assert main(["track-detections", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "bad.txt:1" in capsys.readouterr().err
    det = tmp_path / "d.txt"
    _det_file(det)
    assert main(["track-detections", str(det), "--out", str(tmp_path / "o"), "--fps", "0"]) == 2
    assert "fps" in capsys.readouterr().err
    for value, says in (("abc", "a number or 'none'"), ("5", "--low-birth-iou must be")):
        assert main(["track-detections", str(det), "--out", str(tmp_path / "o"),
                     "--low-birth-iou", value]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error:") and says in err and "\n" not in err


def test_results_name() -> None:
    from pathlib import Path

    assert results_name(Path("MOT17-02/det/det.txt")) == "MOT17-02.txt"
    assert results_name(Path("x/cam1.txt")) == "cam1.txt"


def test_gate_takes_a_radius_in_pixels_like_track(tmp_path) -> None:
    det = tmp_path / "d.txt"
    _det_file(det)
    base = ["track-detections", str(det), "--preset", "paper1"]
    # a 1 px circle loses target a (3.2 px per frame); 20px is the same gate as 400 px²
    for out, gate in (("tiny", "1px"), ("r", "20px"), ("sq", "400")):
        assert main([*base, "--out", str(tmp_path / out), "--gate", gate]) == 0
    tiny, r, sq = (read_tracks(tmp_path / o / "d.txt") for o in ("tiny", "r", "sq"))
    assert len(np.unique(tiny.id)) > len(np.unique(r.id)) == 2
    np.testing.assert_array_equal(r.id, sq.id)
    np.testing.assert_allclose(r.tlwh, sq.tlwh)
    assert main([*base, "--out", str(tmp_path / "x"), "--gate", "-3px"]) == 2
