"""``mvtrack track``: files written for a good video, one-line errors and no files for bad input."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from _media import stop_at_frame
from mvtrack.cli import main
from mvtrack.cli._options import parse_gate
from mvtrack.config import RunSettings, load_config
from mvtrack.errors import InputError
from mvtrack.types import TrackState
from mvtrack.viz.annotate import STATE_COLORS


def _write_avi(path: Path, n: int = 40) -> Path:
    """A small MJPG video with one bright box moving right."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15, (96, 64))
    assert writer.isOpened()
    for k in range(n):
        img = np.full((64, 96, 3), 80, np.uint8)
        if k >= 8:
            x = 10 + 2 * (k - 8)
            img[28:36, x : x + 10] = 230
        writer.write(img)
    writer.release()
    return path


def _one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error:"), err
    assert "Traceback" not in err
    return err


def test_missing_video_is_one_line_error_and_writes_nothing(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    code = main(["track", str(tmp_path / "nope.avi"), "--out", str(out)])
    assert code == 2
    assert "nope.avi" in _one_line_error(capsys)
    assert not out.exists()


def test_unreadable_video_is_one_line_error(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.avi"
    bad.write_bytes(b"this is not a video" * 10)
    out = tmp_path / "out"
    assert main(["track", str(bad), "--out", str(out)]) == 2
    assert "bad.avi" in _one_line_error(capsys)
    assert not out.exists()


def test_bad_config_key_is_one_line_error_and_writes_nothing(tmp_path, capsys) -> None:
    video = _write_avi(tmp_path / "v.avi")
    cfg = tmp_path / "c.toml"
    cfg.write_text('[tracker]\npredictor = "rls"\ngaet = 4.0\n')
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--config", str(cfg)]) == 2
    err = _one_line_error(capsys)
    assert "gaet" in err and "c.toml" in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("[trackr]\n", "trackr"),
        ('[detector]\nname = "yolo"\n', "yolo"),
        ("[video]\ntrail = 1\n", "trail"),
        ("[video]\nwrite = 3\n", "video.write"),
        ("[tracker\n", "invalid TOML"),
        ("[relink]\nwindow = -1.0\n", "relink.window"),
        ("[relink]\nwidnow = 1.0\n", "widnow"),
        ('[relink]\nenabled = "yes"\n', "relink.enabled"),
        ('[relink]\nreach = "x"\n', "relink.reach"),
    ],
)
def test_config_errors_name_the_key(tmp_path, text: str, needle: str) -> None:
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    with pytest.raises(InputError, match=needle):
        load_config(cfg)


def test_detector_option_refuses_to_drop_the_configs_detector_parameters(tmp_path,
                                                                        capsys) -> None:
    video = _write_avi(tmp_path / "v.avi")
    cfg = tmp_path / "c.toml"
    cfg.write_text("[detector]\ntrack_split = true\n")  # no name: the default front end
    out = tmp_path / "out"
    args = ["track", str(video), "--out", str(out), "--config", str(cfg), "--no-video"]
    assert main([*args, "--detector", "disturbance-map"]) == 2
    err = _one_line_error(capsys)
    assert "track_split" in err and "name = 'disturbance-map'" in err
    assert not out.exists()
    cfg.write_text('[detector]\nname = "disturbance-map"\ntrack_split = true\n')
    assert main([*args, "--max-frames", "3"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["detector_params"]["track_split"] is True
    # the same name on the command line keeps them
    assert main([*args, "--max-frames", "3", "--detector", "disturbance-map"]) == 0


def test_config_values_are_read(tmp_path) -> None:
    cfg = tmp_path / "c.toml"
    cfg.write_text(
        '[tracker]\npreset = "paper1"\npredictor = "rls"\ngate = 100.0\n'
        '[detector]\nname = "mog2"\n[templates]\nenabled = false\n'
        "[video]\nwrite = false\ntrail = 12\n"
    )
    s = load_config(cfg)
    assert s.tracker == {"preset": "paper1", "predictor": "rls", "gate": 100.0}
    assert (s.detector, s.templates, s.video, s.trail) == ("mog2", False, False, 12)
    assert s.with_overrides(gate=None, predictor="kalman-ca").tracker["predictor"] == "kalman-ca"
    assert RunSettings().detector == "road-users"


def test_gate_option_accepts_a_radius_in_pixels() -> None:
    assert parse_gate("20px") == 400.0
    assert parse_gate("9.21") == 9.21
    assert parse_gate(None) is None
    for bad in ("-3", "0px", "wide", "nan"):
        with pytest.raises(ValueError, match="--gate"):
            parse_gate(bad)


def test_track_writes_all_files(tmp_path, capsys) -> None:
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    code = main(["track", str(video), "--out", str(out), "--preset", "paper1",
                 "--predictor", "kalman-ca", "--gate", "10px"])
    assert code == 0, capsys.readouterr().err
    names = sorted(p.name for p in out.iterdir())
    assert names == ["results.txt", "states.csv", "summary.json", "tracks.mp4",
                     "trajectories.png"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 40 and summary["ended_early"] is False
    assert summary["tracker"]["predictor"] == "kalman-ca" and summary["tracker"]["gate"] == 100.0
    assert summary["tracker"]["distance"] == "euclidean"
    assert summary["video_fps"] == 15.0
    # the moving box (visible from frame 8) is followed in every frame, by few tracks
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    _, counts = np.unique(rows[:, 1], return_counts=True)
    assert len(np.unique(rows[:, 0])) >= 30 and counts.max() >= 15 and len(counts) <= 3
    assert "tracks" in capsys.readouterr().out


def test_max_frames_and_no_video(tmp_path, capsys) -> None:
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--max-frames", "12", "--no-video"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 12 and summary["ended_early"] is False
    assert not (out / "tracks.mp4").exists()
    assert main(["track", str(video), "--out", str(out), "--max-frames", "0"]) == 2
    assert "--max-frames" in _one_line_error(capsys)


def test_unknown_detector_and_predictor_are_one_line_errors(tmp_path, capsys) -> None:
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--detector", "yolo"]) == 2
    assert "yolo" in _one_line_error(capsys)
    assert main(["track", str(video), "--out", str(out), "--predictor", "psychic"]) == 2
    assert "psychic" in _one_line_error(capsys)
    assert not out.exists()


def test_ctrl_c_writes_what_was_tracked_and_exits_130(tmp_path, capsys, monkeypatch) -> None:
    def interrupt() -> None:
        raise KeyboardInterrupt  # what Ctrl-C raises in the frame loop

    stop_at_frame(monkeypatch, 26, interrupt)
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out)]) == 130
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: interrupted after 25 frames"), err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 25 and summary["interrupted"] and summary["ended_early"]
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    assert len(rows) and rows[:, 0].max() <= 25
    cap = cv2.VideoCapture(str(out / "tracks.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 25
    cap.release()
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


def test_source_failing_mid_way_keeps_tracks_and_says_why(tmp_path, capsys) -> None:
    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(30):
        img = np.full((64, 96, 3), 80, np.uint8)
        img[28:36, 10 + 2 * k : 20 + 2 * k] = 230
        cv2.imwrite(str(folder / f"{k:04d}.png"), img)
    (folder / "0020.png").write_bytes(b"not a png")  # a corrupt frame in the middle
    out = tmp_path / "out"
    assert main(["track", str(folder), "--out", str(out), "--no-video"]) == 2
    err = _one_line_error(capsys)
    assert "0020.png" in err and str(out) in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 20 and summary["ended_early"] and not summary["interrupted"]
    assert "0020.png" in summary["error"]
    assert (out / "results.txt").exists()


def test_snapshot_saves_one_annotated_frame(tmp_path, capsys) -> None:
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video", "--snapshot", "30"]) == 0
    shot = cv2.imread(str(out / "frame00030.png"))
    assert shot is not None and shot.shape == (64, 96, 3)
    # the moving box is at x = 54..63, y = 28..35 in frame 30: a box in the colour of the
    # confirmed state is drawn around it (the raw frame holds no such colour)
    confirmed = (shot == np.array(STATE_COLORS[int(TrackState.CONFIRMED)], np.uint8)).all(axis=2)
    ys, xs = np.nonzero(confirmed)
    assert xs.size > 10
    assert xs.min() <= 56 and xs.max() >= 61 and ys.min() <= 31 and ys.max() >= 32
    # (the filtered box may lag the blob by a few px right after the detector's streak ends)
    assert abs(xs.mean() - 58.5) < 8 and abs(ys.mean() - 31.5) < 6
    files = json.loads((out / "summary.json").read_text())["files"]
    assert files["snapshot 30"] == "frame00030.png"
    assert main(["track", str(video), "--out", str(tmp_path / "o2"), "--snapshot", "-1"]) == 2


def test_snapshot_given_twice_saves_both_frames(tmp_path) -> None:
    """``--snapshot`` repeated saves each frame (in any order, a repeat once), and each is
    the frame of its index: the box moves 2 px a frame, so the two pictures differ by it."""
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video", "--snapshot", "34",
                 "--snapshot", "20", "--snapshot", "34"]) == 0
    assert sorted(p.name for p in out.glob("frame*.png")) == ["frame00020.png",
                                                              "frame00034.png"]
    files = json.loads((out / "summary.json").read_text())["files"]
    assert files["snapshot 20"] == "frame00020.png" and files["snapshot 34"] == "frame00034.png"
    # the bright blob (the raw frame's box, 230 grey) moves right by 2 px per frame: 28 px
    xs = [np.nonzero((cv2.imread(str(out / f"frame{k:05d}.png")) > 200).all(axis=2)
                     [30])[0] for k in (20, 34)]
    assert xs[0].size and xs[1].size
    assert 20 <= xs[1].min() - xs[0].min() <= 36
    assert main(["track", str(video), "--out", str(tmp_path / "o3"), "--snapshot", "5",
                 "--snapshot", "40"]) == 2  # past the 40 frames of the video, before any file
    assert not (tmp_path / "o3" / "results.txt").exists()


def test_preset_arguments_go_to_the_preset(tmp_path) -> None:
    """``--preset paper1 --predictor rls`` builds paper1 for RLS (its own parameters), not the
    Kalman preset with the predictor name swapped."""
    from mvtrack.tracking import paper1
    from mvtrack.video import build_tracker_config

    cfg = build_tracker_config(RunSettings(tracker={"preset": "paper1", "predictor": "rls",
                                                    "gate": 100.0}), fps=15.0)
    ref = paper1("rls", fps=15.0).replace(gate=100.0)
    assert cfg == ref
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--preset", "paper1", "--predictor",
                 "rls", "--no-video", "--max-frames", "10"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tracker"]["predictor"] == "rls"
    assert summary["tracker"]["predictor_params"] == dict(ref.predictor_params)
    with pytest.raises(InputError, match="preset"):
        build_tracker_config(RunSettings(tracker={"preset": "paper9"}), fps=15.0)


def test_none_in_the_tracker_table_unsets_a_field(tmp_path) -> None:
    """TOML has no null: ``"none"`` stands for ``None``; a field that cannot be None says so."""
    from mvtrack.video import build_tracker_config

    cfg = build_tracker_config(RunSettings(tracker={"size_noise": "none",
                                                    "birth_iou": "None"}), fps=10.0)
    assert cfg.size_noise is None and cfg.birth_iou is None
    default = build_tracker_config(RunSettings(), fps=10.0)
    assert default.size_noise == 0.25 and default.birth_iou == 0.3
    with pytest.raises(InputError, match="fps"):
        build_tracker_config(RunSettings(tracker={"fps": "none"}), fps=10.0)
    config = tmp_path / "c.toml"
    config.write_text('[tracker]\nlost_std = "none"\n')
    video = _write_avi(tmp_path / "v.avi")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--config", str(config),
                 "--no-video", "--max-frames", "5"]) == 0
    assert json.loads((out / "summary.json").read_text())["tracker"]["lost_std"] is None


def test_changing_the_distance_resets_the_gate() -> None:
    from mvtrack.association.distances import default_gate
    from mvtrack.video import build_tracker_config

    cfg = build_tracker_config(RunSettings(tracker={"preset": "paper1",
                                                    "distance": "mahalanobis"}), fps=30.0)
    assert cfg.distance == "mahalanobis" and cfg.gate in (None, default_gate("mahalanobis"))
    cfg = build_tracker_config(RunSettings(tracker={"distance": "coupled", "gate": 5.0}), 30.0)
    assert cfg.gate == 5.0


def test_naming_the_presets_own_distance_changes_nothing() -> None:
    """``--distance mahalanobis`` (the default distance, named) keeps the default's χ² gate;
    ``--distance euclidean`` on ``paper1`` keeps its 20 px circle."""
    from mvtrack.association import resolve_gate
    from mvtrack.tracking import preset
    from mvtrack.video import build_tracker_config

    named = build_tracker_config(RunSettings(tracker={"distance": "mahalanobis"}), 30.0)
    assert named == build_tracker_config(RunSettings(), 30.0)
    assert resolve_gate(named.distance, named.gate) == 9.21
    assert preset("default", fps=30.0, distance="mahalanobis") == preset("default", fps=30.0)
    paper = build_tracker_config(RunSettings(tracker={"preset": "paper1",
                                                      "distance": "euclidean"}), 30.0)
    assert paper == preset("paper1", fps=30.0) and paper.gate == 400.0  # 20 px
    assert preset("default", fps=30.0, distance="euclidean").gate is None  # its own: in box sizes
    assert preset("default", fps=30.0, distance="iou").gate is None  # another distance: its own
