"""One TOML file for tracking and analytics: ``mvtrack track --config`` with an [analytics]
table writes the analytics CSV files beside results.txt; a bad analytics key stops the run
before any tracking."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from _media import box_video
from mvtrack.analytics.outputs import read_table
from mvtrack.cli import main
from mvtrack.config import load_config
from mvtrack.errors import InputError

SCENE = """\
[tracker]
preset = "default"

[analytics]
interval = 1
min_frames = 5

[analytics.calibration]
metres_per_pixel = 0.5

[analytics.lines.middle]
points = [[48, 0], [48, 64]]
hysteresis = 3
labels = ["westbound", "eastbound"]
"""


def test_config_keeps_the_analytics_table(tmp_path: Path) -> None:
    f = tmp_path / "scene.toml"
    f.write_text(SCENE)
    s = load_config(f)
    assert s.tracker == {"preset": "default"}
    assert s.analytics is not None and s.analytics["lines"]["middle"]["hysteresis"] == 3
    f.write_text("[tracker]\npreset = \"default\"\n")
    assert load_config(f).analytics is None


@pytest.mark.parametrize("text, key", [
    ("[analytics]\nintervall = 5\n", "analytics.intervall"),
    ("[analytics.lines.a]\npoints = [[0, 0]]\n", "analytics.lines.a.points"),
])
def test_config_refuses_a_bad_analytics_key(tmp_path: Path, text: str, key: str) -> None:
    f = tmp_path / "scene.toml"
    f.write_text(text)
    with pytest.raises(InputError) as err:
        load_config(f)
    assert key in str(err.value) and str(f) in str(err.value)


def test_track_with_analytics_table_writes_counts(tmp_path: Path) -> None:
    video = box_video(tmp_path / "box.avi", n=40)
    cfg = tmp_path / "scene.toml"
    cfg.write_text(SCENE)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video",
                 "--config", str(cfg)]) == 0
    for name in ("results.txt", "counts.csv", "movements.csv", "speeds.csv", "tracks.csv"):
        assert (out / name).exists(), name
    counts = read_table(out / "counts.csv")
    got: dict[str, int] = {}
    for el, d, n in zip(counts["element"], counts["direction"], counts["count"], strict=True):
        if el == "line":
            got[d] = got.get(d, 0) + int(n)
    # the box moves +x: across a line whose a -> b points down, from its right to its left
    assert got == {"westbound": 0, "eastbound": 1}
    tracks = read_table(out / "tracks.csv")
    counted = [i for i, c in enumerate(tracks["counted"]) if c == "1"]
    assert len(counted) == 1 and tracks["crossings"][counted[0]] == "middle:eastbound"


def test_track_writes_every_rows_state_and_evidence(tmp_path: Path) -> None:
    from mvtrack.io.mot import read_tracks

    video = box_video(tmp_path / "box.avi", n=30)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video"]) == 0
    st = read_table(out / "states.csv")
    res = read_tracks(out / "results.txt", "results")
    pairs = {(int(f), int(i)) for f, i, s in zip(st["frame"], st["id"], st["state"],
                                                 strict=True) if s != "coasting"}
    # results.txt leaves out the coasting rows: every other row has its state in states.csv
    assert pairs == set(zip((res.frame + 1).tolist(), res.id.tolist(), strict=True))
    assert len(pairs) == len(res.frame)
    ok = {("confirmed", "detection"), ("stopped", "template"), ("coasting", "prediction")}
    assert set(zip(st["state"], st["evidence"], strict=True)) <= ok
    speed = np.array([float(v) for v in st["speed_px_per_frame"]])
    assert np.median(speed) > 1.0  # the box moves 2 px/frame


def test_track_stops_before_tracking_on_a_bad_analytics_key(tmp_path: Path, capsys) -> None:
    video = box_video(tmp_path / "box.avi", n=40)
    cfg = tmp_path / "scene.toml"
    cfg.write_text("[analytics.calibration]\nmetres_per_pixel = -1\n")
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video",
                 "--config", str(cfg)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "analytics.calibration" in err[0]
    assert not (out / "results.txt").exists()


def _queue_files(tmp_path: Path, drop: int | None) -> tuple[Path, Path, Path, dict[str, int]]:
    """gt.txt of the stop-and-go scene, a results file of its visible rows with the IDs
    renumbered (and object ``drop`` left out), and its [analytics] TOML."""
    import json

    from mvtrack.analytics.accuracy import truth_movement_counts
    from mvtrack.io.mot import write_mot, write_results
    from mvtrack.sim.queue import queue_scene, queue_settings

    sc = queue_scene(0)
    gt = write_mot(tmp_path / "gt.txt", sc.gt_mot(), "gt")
    vis = sc.visible & (sc.id != (drop if drop is not None else -1))
    rows = np.column_stack([sc.frame[vis] + 1, 100 + sc.id[vis],
                            sc.xy[vis] - sc.wh[vis] / 2, sc.wh[vis], np.ones(vis.sum())])
    pred_dir = tmp_path / "run"
    pred_dir.mkdir()
    pred = write_results(pred_dir / "results.txt", rows)
    (pred_dir / "summary.json").write_text(json.dumps({"frames": sc.n_frames,
                                                       "video_fps": 30.0}))
    q = queue_settings()
    lines = ["[analytics]", "interval = 10", "min_frames = 10",
             "[analytics.calibration]", "metres_per_pixel = 0.25"]
    for group in ("approaches", "zones"):
        for name, spec in q[group].items():
            lines += [f"[analytics.{group}.{name}]", f"polygon = {spec['polygon']}"]
    for name, spec in q["lines"].items():
        lines += [f"[analytics.lines.{name}]", f"points = {spec['points']}",
                  f"hysteresis = {spec['hysteresis']}", f"labels = {json.dumps(spec['labels'])}"]
    cfg = tmp_path / "scene.toml"
    cfg.write_text("\n".join(lines) + "\n")
    truth = truth_movement_counts(sc.meta["origin"], sc.meta["destination"])
    return gt, pred, cfg, truth


def test_eval_config_counts_and_speeds_against_truth(tmp_path: Path) -> None:
    import json

    gt, pred, cfg, truth = _queue_files(tmp_path, drop=3)
    out = tmp_path / "scores.json"
    assert main(["eval", "--gt", str(gt), "--pred", str(pred), "--config", str(cfg),
                 "--json", str(out)]) == 0
    acc = json.loads(out.read_text())["analytics"]
    mv = acc["movements"]
    # the ground truth's own tracks give the scene's true movements
    assert {k: v["truth"] for k, v in mv.items() if k != "total" and v["truth"]} == truth
    # object 3 is missing from the results: exactly its movement is one short
    wrong = {k: v["error"] for k, v in mv.items() if k != "total" and v["error"]}
    assert list(wrong.values()) == [-1] and mv["total"]["abs_error"] == 1
    assert acc["lines"]["stopline:eastbound"]["truth"] == 10
    assert acc["lines"]["stopline:eastbound"]["error"] == -1
    # the results' rows are the truth's own boxes: every speed equals the true one
    assert acc["speed"]["rows"] > 1000 and acc["speed"]["rmse_kmh"] < 1e-6


def test_eval_config_folder_refused(tmp_path: Path, capsys) -> None:
    cfg = tmp_path / "scene.toml"
    cfg.write_text("[analytics]\ninterval = 10\n")
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    assert main(["eval", "--gt", str(tmp_path / "a"), "--pred", str(tmp_path / "b"),
                 "--config", str(cfg)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--config" in err[0]


def test_x5_example_file_holds_the_x5_approaches() -> None:
    from mvtrack.analytics import load_settings, settings_from_dict
    from mvtrack.analytics.accuracy import x5_settings

    doc = load_settings(Path(__file__).resolve().parents[2] / "docs" / "analytics-x5.toml")
    ref = settings_from_dict(x5_settings())
    assert [a.name for a in doc.approaches] == [a.name for a in ref.approaches]
    for a, b in zip(doc.approaches, ref.approaches, strict=True):
        np.testing.assert_allclose(np.asarray(a.polygon), np.asarray(b.polygon))


def test_track_draws_the_analytics_on_the_video_and_snapshot(tmp_path: Path) -> None:
    """The count line is drawn (amber, the line's pixels) on the annotated frame and on every
    frame of tracks.mp4."""
    import cv2

    from mvtrack.viz.scene import LINE_COLOR

    n = 40
    video = box_video(tmp_path / "box.avi", n=n)
    cfg = tmp_path / "scene.toml"
    cfg.write_text(SCENE)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--config", str(cfg),
                 "--snapshot", "10"]) == 0
    shot = cv2.imread(str(out / "frame00010.png"))
    # the line x = 48, far from the box (rows 28-35) and from the labels at the top
    assert (shot[50:60, 48] == LINE_COLOR).all(axis=1).sum() >= 8
    assert (shot[50:60, 20] != LINE_COLOR).any(axis=1).all()  # not drawn elsewhere
    cap = cv2.VideoCapture(str(out / "tracks.mp4"))
    frames = 0
    while True:
        ok, img = cap.read()
        if not ok:
            break
        frames += 1
        # rows below the speed label (box foot y = 36, label baseline 14 px lower)
        amber = np.abs(img[55:63, 47:50].astype(int) - LINE_COLOR).sum(axis=2) < 90
        assert amber.any(axis=1).all(), f"frame {frames - 1}: no line drawn"
    cap.release()
    assert frames == n


def _line_totals(counts: dict[str, np.ndarray]) -> dict[str, tuple[int, int]]:
    out: dict[str, tuple[int, int]] = {}
    line = counts["element"] == "line"
    for name in np.unique(counts["name"][line]):
        sel = line & (counts["name"] == name)
        dirs = list(dict.fromkeys(counts["direction"][sel].tolist()))  # forward label first
        out[str(name)] = tuple(int(counts["count"][sel & (counts["direction"] == d)].sum())
                               for d in dirs)  # type: ignore[assignment]
    return out


def test_live_counts_end_at_the_totals_of_counts_csv() -> None:
    """Tracks crossing a line both ways, one flickering over it, one too short to count, one
    crossing before it has min_frames rows: the counts shown frame by frame are 0 before the
    first crossing and at the last frame equal the totals that the analytics of the whole run
    write (the rows fed to both are the same)."""
    from mvtrack.analytics import analyse, settings_from_dict
    from mvtrack.analytics.tracks import TrackPoints
    from mvtrack.types import TrackFrame, TrackState
    from mvtrack.viz.overlay import LiveAnalytics

    scene = settings_from_dict({
        "min_frames": 5,
        "lines": {"mid": {"points": [[50, 0], [50, 100]], "hysteresis": 2}},
        "zones": {"left": {"polygon": [[0, 0], [40, 0], [40, 100], [0, 100]]}},
    })
    n = 60
    k = np.arange(n, dtype=float)
    paths = {  # id -> (frames, x)
        1: (np.arange(n), 10 + 1.5 * k),  # left to right
        2: (np.arange(n), 95 - 1.2 * k),  # right to left
        3: (np.arange(n), 50 + 1.8 * np.sin(k)),  # flickers inside the band
        4: (np.arange(20, 24), np.array([45.0, 48, 52, 55])),  # crosses, 4 rows: too short
        5: (np.arange(30, 45), 46 + 4.0 * np.arange(15)),  # crosses at its 3rd row
    }
    live = LiveAnalytics(scene, 10.0)
    shown = []
    rows_f, rows_id, rows_x = [], [], []
    for f in range(n):
        ids = [i for i, (fr, _) in paths.items() if f in fr]
        xs = [paths[i][1][list(paths[i][0]).index(f)] for i in ids]
        m = len(ids)
        xy = np.column_stack([xs, np.full(m, 30.0 + 10 * np.arange(m))]) if m else np.zeros((0, 2))
        tf = TrackFrame(f, np.array(ids, np.int64), np.full(m, int(TrackState.CONFIRMED)),
                        np.zeros(m, np.int64), xy, xy, xy, np.full((m, 2), 8.0),
                        np.zeros((m, 2)))
        live.push(tf)
        shown.append(live.counts()["mid"])
        rows_f += [f] * m
        rows_id += ids
        rows_x += list(xy)
    pts = TrackPoints.from_arrays(np.array(rows_f), np.array(rows_id), np.array(rows_x),
                                  np.full((len(rows_f), 2), 8.0))
    res = analyse(pts, scene, 10.0, n)
    totals = _line_totals(res.counts)["mid"]
    assert shown[-1] == totals
    # a -> b points down the screen, so +x is "backward": tracks 1 and 5; track 2 forward;
    # 3 never leaves the band, 4 has 4 rows
    assert totals == (1, 2)
    assert shown[0] == (0, 0)
    assert shown.index((0, 1)) == 29  # track 1: x = 10 + 1.5 k > 52 from k = 29
    assert shown[33] == (0, 1)  # track 5 crossed at frame 32, its 3rd row: held ...
    assert shown[34] == (0, 2)  # ... until its 5th row, frame 34
    assert shown.index((1, 2)) == 40  # track 2: x = 95 - 1.2 k < 48 from k = 40


# --------------------------------------------------- analyze / report without --config
def _walkers_folder(folder: Path) -> Path:
    """A run folder of two walkers on a 200×100 image: track 1 enters at the left border and
    leaves at the right one, track 2 enters at the top and leaves at the bottom."""
    import json

    folder.mkdir()
    rows = []
    for f in range(40):
        rows.append(f"{f + 1},1,{2 + 5 * f - 4},{50 - 8},8,16,1,-1,-1,-1")
    for f in range(20):
        rows.append(f"{f + 1},2,{60 - 4},{1 + 5 * f - 8},8,16,1,-1,-1,-1")
    (folder / "results.txt").write_text("\n".join(sorted(rows, key=lambda r: int(
        r.split(",")[0]))) + "\n")
    (folder / "summary.json").write_text(json.dumps({
        "source": "walkers", "frames": 40, "video_fps": 10.0, "size": [200, 100],
        "files": {}}))
    return folder


def _counts(folder: Path) -> dict[str, int]:
    counts = read_table(folder / "counts.csv")
    return {f"{n}:{d}": int(c) for n, d, c in zip(counts["name"], counts["direction"],
                                                  counts["count"], strict=True)}


def _movements(folder: Path) -> dict[str, int]:
    mv = read_table(folder / "movements.csv")
    return {f"{o}->{d}": int(c) for o, d, c in zip(mv["origin"], mv["destination"],
                                                   mv["count"], strict=True) if int(c)}


def test_analyze_without_config_counts_through_the_default_geometry(tmp_path: Path,
                                                                    capsys) -> None:
    out = _walkers_folder(tmp_path / "run")
    assert main(["analyze", str(out)]) == 0
    text = capsys.readouterr().out
    first = text.splitlines()[0]
    assert first.startswith("analytics settings: no --config")
    assert "approaches at the four borders" in first and "200×100" in first
    assert _movements(out) == {"west->east": 1, "north->south": 1}
    assert _counts(out) == {"vertical:westbound": 0, "vertical:eastbound": 1,
                            "horizontal:southbound": 1, "horizontal:northbound": 0}
    assert (out / "analytics.json").exists()


def test_analyze_without_config_redoes_the_earlier_analysis(tmp_path: Path, capsys) -> None:
    """Counts made with a scene's lines are never replaced by others when the command is run
    again without --config: the folder's analytics.json says which settings made them."""
    out = _walkers_folder(tmp_path / "run")
    cfg = tmp_path / "scene.toml"
    cfg.write_text("[analytics]\n[analytics.lines.gate]\npoints = [[100, 0], [100, 100]]\n"
                   'labels = ["out", "in"]\n')
    assert main(["report", str(out), "--config", str(cfg)]) == 0
    before = (out / "counts.csv").read_text()
    assert _counts(out) == {"gate:out": 0, "gate:in": 1}
    capsys.readouterr()
    assert main(["report", str(out)]) == 0
    assert capsys.readouterr().out.startswith(
        f"analytics settings: those of the earlier analysis (analytics.json: the [analytics] "
        f"table of {cfg})")
    assert (out / "counts.csv").read_text() == before


def test_analyze_uses_the_table_the_run_was_tracked_with(tmp_path: Path, capsys) -> None:
    video = box_video(tmp_path / "box.avi", n=40)
    cfg = tmp_path / "scene.toml"
    cfg.write_text(SCENE)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video",
                 "--config", str(cfg)]) == 0
    tracked = (out / "counts.csv").read_text()
    capsys.readouterr()
    assert main(["analyze", str(out)]) == 0
    assert "the [analytics] table the run was tracked with" in capsys.readouterr().out
    assert (out / "counts.csv").read_text() == tracked


def test_analyze_refuses_when_there_is_nothing_to_count_on(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    out.mkdir()
    (out / "results.txt").write_text("1,1,10,10,8,16,1,-1,-1,-1\n")
    (out / "summary.json").write_text('{"frames": 1, "video_fps": 10}')  # no image size
    for command in ("analyze", "report"):
        assert main([command, str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "nothing to count on" in err and "--config" in err
        assert sorted(p.name for p in out.iterdir()) == ["results.txt", "summary.json"]


def test_the_report_says_tracks_not_vehicles(tmp_path: Path, capsys) -> None:
    """A report on people: the movement colour bar and the speed table count tracks."""
    from mvtrack.analytics import analyse_folder
    from mvtrack.analytics.defaults import choose_settings
    from mvtrack.analytics.report import od_figure

    out = _walkers_folder(tmp_path / "run")
    cfg = tmp_path / "scene.toml"
    cfg.write_text("[analytics.calibration]\nmetres_per_pixel = 0.02\n")
    assert main(["report", str(out), "--config", str(cfg)]) == 0
    html = (out / "report.html").read_text()
    assert "vehicles" not in html and "<th>tracks</th>" in html
    assert "tracks" in read_table(out / "speeds.csv")
    result = analyse_folder(out, choose_settings(out).settings)
    fig = od_figure(result)
    assert fig.axes[-1].get_ylabel() == "tracks"
