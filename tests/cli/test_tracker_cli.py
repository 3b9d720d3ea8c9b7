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
    assert lines[1].startswith(
        "rows written: confirmed tracks, but those of the weakest boxes, from their first "
        "detection (backfill), a track that "
        "starts alone where an ended one was heading under its ID, the frames they "
        "bridged interpolated, positions and boxes smoothed over each track, coasting rows "
        "while the prediction is within 0.05 box sizes")
    table = read_tracks(out / "seq.txt")
    assert sorted(set(table.id.tolist())) == [1, 2]
    # confirmed on the 2nd frame and written from the 1st (backfill, the default); the
    # missed frame is bridged by an interpolated row
    assert table.frame.min() == 0 and len(table) == 2 * 30
    id_a = table.id[(table.frame == 5) & (np.abs(table.tlwh[:, 2] - 40.0) < 5)]
    rows_a = table.take(np.flatnonzero(table.id == id_a[0]))
    assert 10 in rows_a.frame.tolist()
    centre = rows_a.tlwh[:, :2] + rows_a.tlwh[:, 2:] / 2
    # smoothed over the whole track, the centres follow the 3 px/frame target from the start
    # (the first row within 1.5 px: its velocity is known from the rows after it only, and
    # the smoother still gives the manoeuvring mode its prior weight there)
    np.testing.assert_allclose(centre[1:], a[rows_a.frame][1:], atol=0.6)
    np.testing.assert_allclose(centre[0], a[rows_a.frame][0], atol=1.5)
    # filtered only, a new track's velocity is not known (velocity_prior): its centre lags
    # by up to 2 px (5 % of its box) at first, then follows the target
    assert main(["track-detections", str(det), "--out", str(out), "--no-smooth"]) == 0
    rows = read_tracks(out / "seq.txt")
    rows_a = rows.take(np.flatnonzero(rows.id == id_a[0]))
    centre = rows_a.tlwh[:, :2] + rows_a.tlwh[:, 2:] / 2
    lag = np.abs(centre - a[rows_a.frame]).max(axis=1)
    assert 1.0 < lag.max() < 2.5
    late = rows_a.frame >= 12
    assert late.sum() == 18 and lag[late].max() < 0.5
    # the bridged row is not a measurement: --no-coasting leaves it out, as --no-interpolate
    for flag in ("--no-coasting", "--no-interpolate"):
        assert main(["track-detections", str(det), "--out", str(out), flag]) == 0
        rows = read_tracks(out / "seq.txt")
        assert len(rows) == 2 * 30 - 1 and (rows.frame == 10).sum() == 1, flag
    assert main(["track-detections", str(det), "--out", str(out), "--no-backfill"]) == 0
    online = read_tracks(out / "seq.txt")
    assert online.frame.min() == 1 and len(online) == 2 * 29


def test_cli_results_equal_the_library_run(tmp_path) -> None:
    from mvtrack.io.mot import read_detections
    from mvtrack.tracking import preset, track_detections

    det = tmp_path / "d.txt"
    _det_file(det)
    default = preset("default", fps=30.0)
    for flag, config, kw in (([], default, {}),
                             (["--no-backfill"], default, {"backfill_rows": False}),
                             (["--no-interpolate"], default, {"interpolate": False}),
                             (["--birth-iou", "none"],
                              preset("default", fps=30.0, birth_iou=None), {}),
                             (["--birth-iou", "0.1"],
                              preset("default", fps=30.0, birth_iou=0.1), {})):
        assert main(["track-detections", str(det), "--out", str(tmp_path / "o"), *flag]) == 0
        got = read_tracks(tmp_path / "o" / "d.txt")
        want = np.asarray(track_detections(read_detections(det), config, **kw).to_mot())
        np.testing.assert_array_equal(got.frame, want[:, 0].astype(int) - 1)
        np.testing.assert_array_equal(got.id, want[:, 1].astype(int))
        np.testing.assert_allclose(got.tlwh, want[:, 2:6], atol=1e-3)


def test_weak_boxes_start_a_track_that_their_scores_confirm(tmp_path) -> None:
    """A person scored 0.3 for four frames, then 0.9: every box kept starts a track, which
    is confirmed once its scores sum to ``confirm_score`` (1.0, on the fourth box) and written
    from its first box; with ``--min-score 0.35`` the weak boxes are dropped and the track
    starts on the first strong one."""
    xy = np.array([100.0, 100.0]) + np.arange(20)[:, None] * [3.0, 1.0]
    score = np.where(np.arange(20) < 4, 0.3, 0.9)
    det = tmp_path / "s.txt"
    write_detections(det, [Detections(k, xy[k : k + 1], np.array([[30.0, 60.0]]), score[k : k + 1])
                           for k in range(20)])
    first = {}
    for value in ("0.1", "0.35"):
        out = tmp_path / value
        for backfill in ("--backfill", "--no-backfill"):
            assert main(["track-detections", str(det), "--out", str(out), "--score-scale",
                         "prob", "--min-score", value, backfill]) == 0
            rows = read_tracks(out / "s.txt")
            assert set(rows.id.tolist()) == {1}
            first[value, backfill] = int(rows.frame.min())
    assert first == {("0.1", "--backfill"): 0, ("0.1", "--no-backfill"): 3,
                     ("0.35", "--backfill"): 4, ("0.35", "--no-backfill"): 5}


def test_birth_iou_reaches_the_tracker(tmp_path) -> None:
    """A person tracked from frame 0 gets a second box on them from frame 5 on (IoU 0.6 with
    the first): the second box starts no track under the default ``birth_iou`` (0.3), and its
    own with ``--birth-iou none``."""
    xy = np.array([100.0, 100.0]) + np.arange(20)[:, None] * [3.0, 1.0]
    frames = [Detections(k, np.vstack([xy[k], xy[k] + [0.0, 15.0]])[: 1 + (k >= 5)],
                         np.array([[30.0, 60.0], [30.0, 60.0]])[: 1 + (k >= 5)],
                         np.array([0.9, 0.8])[: 1 + (k >= 5)])
              for k in range(20)]
    det = tmp_path / "s.txt"
    write_detections(det, frames)
    ids = {}
    for value in ([], ["--birth-iou", "none"]):
        out = tmp_path / f"o{len(ids)}"
        assert main(["track-detections", str(det), "--out", str(out), "--score-scale", "prob",
                     *value]) == 0
        ids[len(ids)] = len(set(read_tracks(out / "s.txt").id.tolist()))
    assert ids == {0: 1, 1: 2}


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
    for value, says in (("abc", "a number or 'none'"), ("5", "--birth-iou must be")):
        assert main(["track-detections", str(det), "--out", str(tmp_path / "o"),
                     "--birth-iou", value]) == 2
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
