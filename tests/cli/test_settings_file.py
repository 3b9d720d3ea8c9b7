"""The settings file (--config) as a user meets it: fps in the file, the defaults printed as a
TOML file that changes nothing, the same file for track-detections, the options of other
trackers on mvtrack track, and one line naming the file and key for every bad value."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from _media import box_video
from mvtrack.cli import main
from mvtrack.config import RunSettings, load_config
from mvtrack.tracking import preset
from mvtrack.video import REFERENCE_SIZE, build_tracker_config, resolve_settings


def _err(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: "), err
    assert "Traceback" not in err and "TrackerConfig" not in err
    return err


@pytest.mark.parametrize("command", ["track", "batch"])
def test_fps_in_the_file_is_the_runs_frame_rate(tmp_path: Path, capsys, command: str) -> None:
    video = box_video(tmp_path / "v.avi", n=20)  # a 15 fps file
    cfg = tmp_path / "c.toml"
    cfg.write_text("[tracker]\nfps = 10\n")
    out = tmp_path / "out"
    args = [command, str(video), "--out", str(out), "--config", str(cfg), "--no-video"]
    if command == "batch":
        args += ["--workers", "1"]
    assert main(args) == 0, capsys.readouterr().err
    summary = out / "summary.json" if command == "track" else out / "v" / "summary.json"
    s = json.loads(summary.read_text())
    assert s["video_fps"] == 10.0 and s["tracker"]["fps"] == 10
    # the option wins over the file
    assert main([*args, "--fps", "20"]) == 0
    s = json.loads(summary.read_text())
    assert s["video_fps"] == 20.0 and s["tracker"]["fps"] == 20.0


def test_fps_in_the_settings_is_given_to_the_preset_once() -> None:
    cfg = build_tracker_config(RunSettings(tracker={"fps": 10, "preset": "paper1"}), fps=25.0)
    assert cfg == preset("paper1", fps=10)
    assert build_tracker_config(RunSettings(), fps=25.0).fps == 25.0


def test_the_printed_defaults_change_nothing(tmp_path: Path, capsys) -> None:
    """`mvtrack config --show > f.toml`, then the same tracker, front end and outputs with
    --config f.toml as without, for every preset, at several image sizes, offline too."""
    for name in ("default", "paper1", "paper2"):
        for det in ("scene", "disturbance-map", "mog2"):
            assert main(["config", "--show", "--preset", name, "--detector", det]) == 0
            text = capsys.readouterr().out
            assert text.startswith("# mvtrack settings") and "[tracker]" in text
            f = tmp_path / f"{name}-{det}.toml"
            f.write_text(text)
            s = load_config(f)
            base = RunSettings(tracker={"preset": name}, detector=det)
            for size in (REFERENCE_SIZE, (768, 576), (1920, 1080)):
                a, b = resolve_settings(s, size), resolve_settings(base, size)
                assert build_tracker_config(a, 25.0) == build_tracker_config(b, 25.0)
                assert (a.detector, a.detector_params) == (b.detector, b.detector_params)
                assert dataclass_rest(a) == dataclass_rest(b)
            assert build_tracker_config(RunSettings(tracker=s.tracker), 30.0) == preset(
                name, fps=30.0)


def dataclass_rest(s: RunSettings) -> tuple:
    return (s.templates, s.template_params, s.video, s.trail, s.gates, s.relink, s.analytics)


def test_the_printed_defaults_follow_the_tracker_config(capsys) -> None:
    """Every field of TrackerConfig is in the printed file (set, or commented where the video
    pipeline sets it), so a renamed or new field appears without an edit here."""
    import dataclasses

    from mvtrack.tracking import TrackerConfig

    assert main(["config", "--show"]) == 0
    text = capsys.readouterr().out
    tracker = text.split("[tracker]", 1)[1].split("[detector]", 1)[0]
    for f in dataclasses.fields(TrackerConfig):
        assert f"\n{f.name} = " in tracker or f"\n# {f.name} = " in tracker, f.name
    assert "\n# fps = " in tracker  # the source's unless given
    # a module named in a description keeps its full name (not "the gate (gate)")
    assert "(mvtrack.association.gate)" in tracker and "(gate)" not in tracker


def test_config_check_and_usage(tmp_path: Path, capsys) -> None:
    f = tmp_path / "c.toml"
    f.write_text('[tracker]\npreset = "paper1"\npredictor = "rls"\n')
    assert main(["config", "--check", str(f)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{f}: valid") and "predictor = 'rls'" in out
    f.write_text("[tracker]\nmax_misses = -1\n")
    assert main(["config", "--check", str(f)]) == 2
    assert f"{f}: tracker.max_misses must be a whole number of frames" in _err(capsys)
    f.write_text("[tracker]\nmax_coast = 0.3\n")  # a setting of the engine before max_misses
    assert main(["config", "--check", str(f)]) == 2
    assert f"{f}: unknown key 'tracker.max_coast'" in _err(capsys)
    assert main(["config"]) == 2
    assert "--show" in _err(capsys)
    assert main(["config", "--show", "--preset", "paper9"]) == 2
    assert "--preset 'paper9'" in _err(capsys)


BAD_TOML = {
    "negative max_misses": ("[tracker]\nmax_misses = -1\n", "tracker.max_misses must be"),
    "negative lost_std": ("[tracker]\nlost_std = -0.3\n", "tracker.lost_std must be"),
    "removed field": ("[tracker]\nsecond_gate = 20.0\n", "unknown key 'tracker.second_gate'"),
    "string confirm_hits": ('[tracker]\nconfirm_hits = "x"\n', "tracker.confirm_hits must be"),
    "unknown predictor": ('[tracker]\npredictor = "psychic"\n',
                          "tracker.predictor 'psychic' is not a predictor"),
    "unknown preset": ('[tracker]\npreset = "paper9"\n', "tracker.preset 'paper9' is not"),
    "fps zero": ("[tracker]\nfps = 0\n", "tracker.fps must be a frame rate"),
    "fps string": ('[tracker]\nfps = "fast"\n', "tracker.fps must be a frame rate"),
    "fps absurd": ("[tracker]\nfps = 1e12\n", "tracker.fps must be a frame rate"),
    "score_high > 1": ("[tracker]\nscore_high = 2.0\n", "tracker.score_high must be"),
    "gate string": ('[tracker]\ngate = "wide"\n', "tracker.gate must be"),
    "detector type": ('[detector]\nname = "disturbance-map"\nthreshold = "x"\n',
                      "detector.threshold must be a number, got 'x'"),
    "detector bool": ("[detector]\nlearn = 3\n", "detector.learn must be true or false"),
    "detector unknown": ("[detector]\nfoo = 1\n", "unknown parameter 'foo'"),
    "detector range": ("[detector]\nmin_area = -5\n", "min_area"),
    "template type": ('[templates]\nmin_score = "x"\n', "templates.min_score must be a number"),
    "max_shift type": ('[templates]\nmax_shift = "x"\n', "templates.max_shift must be a number"),
    "video trail": ("[video]\ntrail = 1\n", "video.trail"),
    "relink": ("[relink]\nwindow = -1.0\n", "relink.window"),
    "not TOML": ("[tracker\n", "invalid TOML"),
    "analytics": ("[analytics]\nintervall = 5\n", "analytics.intervall"),
}


@pytest.mark.parametrize("case", sorted(BAD_TOML))
def test_a_bad_value_names_the_file_and_the_key(tmp_path: Path, capsys, case: str) -> None:
    text, fragment = BAD_TOML[case]
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    video = box_video(tmp_path / "v.avi", n=10)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--config", str(cfg)]) == 2
    err = _err(capsys)
    assert str(cfg) in err and fragment in err, err
    assert not out.exists()


def test_none_reads_as_none_in_the_front_ends_table(tmp_path: Path) -> None:
    cfg = tmp_path / "c.toml"
    # parameters of the scene front end (the default is the road-user front end)
    cfg.write_text('[detector]\nname = "scene"\nverify = "none"\ncomplete = "none"\n')
    assert load_config(cfg).detector_params == {"verify": None, "complete": None}


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--fps", "inf"], "--fps must be a frame rate"),
        (["--fps", "0"], "--fps must be a frame rate"),
        (["--fps", "1e9"], "--fps must be a frame rate"),
        (["--score-high", "2"], "--score-high must be a number in [0, 1]"),
        (["--min-score", "-1"], "--min-score must be a number in [0, 1]"),
        (["--predictor", "psychic"], "--predictor 'psychic' is not one of"),
        (["--preset", "paper9"], "--preset 'paper9' is not one of"),
        (["--gate", "wide"], "--gate must be a number"),
    ],
)
@pytest.mark.parametrize("command", ["track", "track-detections", "batch"])
def test_a_bad_option_is_named(tmp_path: Path, capsys, args: list[str], fragment: str,
                               command: str) -> None:
    video = box_video(tmp_path / "v.avi", n=10)
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,40,0.9\n")
    out = tmp_path / "out"
    source = str(video) if command == "track" else str(det)
    assert main([command, source, "--out", str(out), *args]) == 2
    assert fragment in _err(capsys)
    assert not out.exists()


def _gap_video(path: Path, n: int = 40) -> Path:
    """A 96×64 video: one bright box moving right 2 px a frame from frame 5, hidden in frames
    20 and 21."""
    import cv2

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15, (96, 64))
    for k in range(n):
        img = np.full((64, 96, 3), 80, np.uint8)
        if k >= 5 and k not in (20, 21):
            x = 6 + 2 * (k - 5)
            img[28:36, x : x + 10] = 230
        writer.write(img)
    writer.release()
    return path


def test_track_takes_the_score_and_coasting_options(tmp_path: Path, capsys) -> None:
    video = _gap_video(tmp_path / "v.avi")
    out = tmp_path / "out"
    base = ["track", str(video), "--out", str(out), "--no-video", "--detector",
            "disturbance-map", "--preset", "paper1"]
    assert main([*base, "--score-high", "0.7", "--min-score", "0.1"]) == 0
    tracker = json.loads((out / "summary.json").read_text())["tracker"]
    assert (tracker["score_high"], tracker["min_score"]) == (0.7, 0.1)
    plain = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    assert main([*base, "--coasting"]) == 0
    assert json.loads((out / "summary.json").read_text())["settings"]["coasting"] is True
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    # the box hidden in frames 20 and 21 (MOT frames 21, 22): its track coasts there, and
    # only --coasting writes those rows (conf 0.5)
    assert set(np.unique(plain[:, 6])) == {1.0}
    assert not np.isin([21, 22], plain[:, 0]).any()
    coasting = rows[rows[:, 6] == 0.5]
    assert set(coasting[:, 0].astype(int)) >= {21, 22}
    assert len(rows) == len(plain) + len(coasting)


def test_track_detections_reads_the_tracker_table(tmp_path: Path, capsys) -> None:
    det = tmp_path / "det.txt"
    rows = [f"{k + 1},-1,{10 + 3 * k},20,10,20,0.9" for k in range(30)]
    det.write_text("\n".join(rows) + "\n")
    cfg = tmp_path / "c.toml"
    cfg.write_text('[tracker]\npreset = "paper1"\nfps = 10\n[video]\nwrite = false\n')
    out = tmp_path / "res"
    assert main(["track-detections", str(det), "--out", str(out), "--config", str(cfg)]) == 0
    text = capsys.readouterr().out
    assert "(kalman-ca, euclidean, nearest, 10 fps;" in text
    assert main(["track-detections", str(det), "--out", str(out), "--config", str(cfg),
                 "--fps", "25", "--predictor", "rls"]) == 0
    assert "(rls, euclidean, nearest, 25 fps;" in capsys.readouterr().out
    cfg.write_text("[tracker]\nmax_misses = -1\n")
    assert main(["track-detections", str(det), "--out", str(out), "--config", str(cfg)]) == 2
    assert f"{cfg}: tracker.max_misses must be" in _err(capsys)


DOCS = Path(__file__).resolve().parents[2] / "docs"


@pytest.mark.parametrize("page", ["config.md", "other-trackers.md"])
def test_every_toml_block_of_the_docs_is_a_valid_settings_file(tmp_path: Path,
                                                               page: str) -> None:
    """The examples of the settings pages load and build a tracker (a renamed or removed
    setting fails here first)."""
    import re

    blocks = re.findall(r"```toml\n(.*?)```", (DOCS / page).read_text(), flags=re.S)
    assert blocks
    for k, block in enumerate(blocks):
        f = tmp_path / f"{k}.toml"
        f.write_text(block)
        s = load_config(f)
        assert s.tracker
        build_tracker_config(s, s.frame_rate or 30.0)


def test_the_settings_pages_are_linked_from_the_help(capsys) -> None:
    assert main(["track", "--help"]) == 0
    assert "docs/config.md" in " ".join(capsys.readouterr().out.split())
    assert (DOCS / "config.md").exists() and (DOCS / "other-trackers.md").exists()


def test_toml_values_read_back() -> None:
    """Every value a preset may hold is written as TOML that reads back as itself (None as
    the settings file's "none")."""
    import math
    import tomllib

    from mvtrack.config_show import toml_value

    values = {"a": 0.3, "b": float("inf"), "c": -float("inf"), "d": 3, "e": True, "f": "x\"y",
              "g": {"q": 0.05, "r": [1.0, 2.0]}, "h": (320.0, 240.0), "i": {}, "j": 1e-12}
    text = "\n".join(f"{k} = {toml_value(v)}" for k, v in values.items())
    back = tomllib.loads(text + "\nn = " + toml_value(float("nan")) + "\nz = "
                        + toml_value(None))
    for k, v in values.items():
        assert back[k] == (list(v) if isinstance(v, tuple) else v), k
    assert math.isnan(back["n"]) and back["z"] == "none"
