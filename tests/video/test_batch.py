"""``mvtrack batch`` / :func:`mvtrack.video.batch.track_many`: parallel runs give the results of
sequential ``mvtrack track`` runs; failures are per video; batch.json; exit codes; Ctrl-C."""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import pytest

from _media import batch_signalled, box_video
from mvtrack.analytics.outputs import read_table
from mvtrack.cli import main
from mvtrack.cli.batch import expand_videos
from mvtrack.config import RunSettings
from mvtrack.sim.crossing import x7_crossing
from mvtrack.sim.nine_vehicles import x4_nine_vehicles
from mvtrack.sim.render import write_video
from mvtrack.video.batch import track_many
from mvtrack.video.jobs import BatchItem, output_names, track_one

NO_VIDEO = dataclasses.replace(RunSettings(), video=False)
#: a loopback cluster without dashboard whose HTTP server takes a free port
_QUIET_CLUSTER = {"processes": True, "host": "127.0.0.1", "dashboard_address": None,
                  "silence_logs": 40, "scheduler_kwargs": {"dashboard_address": "127.0.0.1:0"}}


@pytest.fixture(scope="module")
def videos(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Two rendered scenes (nine vehicles, a crossing) that share the stem ``cam`` in
    different folders, and a box video."""
    root = tmp_path_factory.mktemp("videos")
    (root / "a").mkdir()
    (root / "b").mkdir()
    scene = x4_nine_vehicles()
    return {
        "cam_a": write_video(scene.truncate(40), root / "a" / "cam.mp4", progress=False),
        "cam_b": write_video(x7_crossing(0).truncate(40), root / "b" / "cam.mp4",
                             progress=False),
        "boxes": box_video(root / "boxes.avi"),
    }


@pytest.fixture(scope="module")
def scheduler() -> str:
    """The address of a two-worker local Dask cluster shared by the tests of this module."""
    from distributed import LocalCluster

    from mvtrack.video.batch import _environ_kept

    with _environ_kept():  # the nanny would leave OMP_NUM_THREADS=1 etc. in this process
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, **_QUIET_CLUSTER)
    with cluster:
        yield cluster.scheduler_address


def _sequential(video: Path, out: Path, *extra: str) -> bytes:
    assert main(["track", str(video), "--out", str(out), "--no-video", *extra]) == 0
    return (out / "results.txt").read_bytes()


def test_output_names_unique_in_input_order() -> None:
    # a stem nobody shares stays; colliding stems (also by case) take their folders
    names = output_names(["x/cam.avi", "y/cam.avi", "cam-2.mp4", "z/CAM.mp4", "frames/"])
    assert names == ["x_cam", "y_cam", "cam-2", "z_CAM", "frames"]
    # MOT-layout image folders are named by their sequence, as deep as needed to differ
    seqs = output_names(["/d/US101-1/img1", "/d/US101-2/img1/", "/e/run/img1", "/f/run/img1"])
    assert seqs == ["US101-1_img1", "US101-2_img1", "e_run_img1", "f_run_img1"]
    # the same video twice, or folders that cannot tell two apart, fall back on -2, -3, ...
    twice = output_names(["/s/v.avi", "/s/v.avi", "s_v.mp4", "v/"])
    assert twice == ["s_v", "s_v-2", "s_v-3", "v"]


def test_parallel_local_cluster_gives_sequential_results(videos, tmp_path) -> None:
    order = [videos["cam_a"], videos["boxes"], videos["cam_b"]]
    environ = dict(os.environ)
    items = track_many(order, tmp_path / "batch", NO_VIDEO, workers=2, progress=False)
    assert dict(os.environ) == environ  # the workers' settings do not leak into the caller

    assert [it.status for it in items] == ["ok", "ok", "ok"], items
    assert [Path(it.out).name for it in items] == ["a_cam", "boxes", "b_cam"]
    data = json.loads((tmp_path / "batch" / "batch.json").read_text())
    assert (data["workers"], data["scheduler"], data["ok"]) == (2, None, 3)
    for i, (video, item) in enumerate(zip(order, items, strict=True)):
        expected = _sequential(video, tmp_path / f"seq{i}")
        assert (Path(item.out) / "results.txt").read_bytes() == expected, video
        summary = json.loads((Path(item.out) / "summary.json").read_text())
        assert (item.frames, item.tracks) == (summary["frames"], summary["tracks"])
        assert not (Path(item.out) / "tracks.mp4").exists()  # --no-video
    # the two scenes differ, so equal files above are not a coincidence of one input
    assert (Path(items[0].out) / "results.txt").read_bytes() != (
        Path(items[2].out) / "results.txt").read_bytes()
    # (the default front end on the first 40 frames of the nine-vehicle scene)
    assert items[0].frames == 40 and items[0].tracks >= 3


def test_missing_video_is_reported_and_others_complete(videos, tmp_path, scheduler) -> None:
    missing = tmp_path / "nope.mp4"
    bad = tmp_path / "bad.avi"
    bad.write_bytes(b"not a video" * 20)
    done: list[BatchItem] = []
    items = track_many([videos["boxes"], missing, bad, videos["cam_a"]], tmp_path / "out",
                       NO_VIDEO, scheduler=scheduler, on_result=done.append)

    assert [it.status for it in items] == ["ok", "failed", "failed", "ok"]
    assert "nope.mp4" in items[1].error and "does not exist" in items[1].error
    assert "bad.avi" in items[2].error
    assert all("\n" not in it.error for it in items[1:3])
    assert sorted(it.video for it in done) == sorted(it.video for it in items)

    data = json.loads((tmp_path / "out" / "batch.json").read_text())
    assert (data["total"], data["ok"], data["failed"], data["cancelled"]) == (4, 2, 2, 0)
    assert data["interrupted"] is False and data["scheduler"] == scheduler
    assert data["workers"] == 2  # the shared cluster's
    assert [v["status"] for v in data["videos"]] == ["ok", "failed", "failed", "ok"]
    assert data["videos"][1]["error"] == items[1].error
    good = data["videos"][3]
    assert set(good) == {"video", "out", "status", "frames", "tracks", "processing_speed",
                         "seconds", "error"}
    assert good["frames"] == 40 and good["tracks"] == items[3].tracks
    assert good["seconds"] > 0 and good["processing_speed"] > 0
    assert good["video"] == str(videos["cam_a"].absolute())
    assert data["settings"]["video"] is False
    assert not (tmp_path / "out" / "nope" / "results.txt").exists()
    assert [p.name for p in (tmp_path / "out").iterdir() if p.name.startswith(".")] == []


def test_interrupt_cancels_pending_and_writes_batch_json(videos, tmp_path, scheduler) -> None:
    """Ctrl-C (KeyboardInterrupt in the client) after the first finished video."""

    def stop(item: BatchItem) -> None:
        raise KeyboardInterrupt

    # six jobs (three of them copies under other folder names) on two workers
    many = [videos["boxes"], videos["cam_a"], videos["cam_b"]]
    many += [tmp_path / f"copy{i}" / "cam.mp4" for i in range(3)]
    for i in range(3):
        (tmp_path / f"copy{i}").mkdir()
        (tmp_path / f"copy{i}" / "cam.mp4").write_bytes(videos["cam_a"].read_bytes())
    items = track_many(many, tmp_path / "out", NO_VIDEO, scheduler=scheduler, on_result=stop)

    statuses = [it.status for it in items]
    assert set(statuses) <= {"ok", "cancelled"} and "ok" in statuses
    assert statuses.count("cancelled") >= 2, statuses
    data = json.loads((tmp_path / "out" / "batch.json").read_text())
    assert data["interrupted"] is True
    assert [v["status"] for v in data["videos"]] == statuses
    assert data["ok"] + data["cancelled"] == 6 and data["pending"] == 0
    for it in items:
        if it.status == "ok":
            assert (Path(it.out) / "results.txt").exists()


@pytest.mark.slow
def test_ctrl_c_in_a_terminal_stops_workers_and_exits_130(videos, tmp_path) -> None:
    """SIGINT to the whole process group, as a terminal sends it: only the client handles it
    (no worker tracebacks), the local workers stop, batch.json says what finished."""
    import signal
    import time

    import psutil  # installed with distributed

    proc, err, workers = batch_signalled(tmp_path, signal.SIGINT, group=True)
    out = tmp_path / "out"
    assert workers, "no worker processes"
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert "error: interrupted" in err
    time.sleep(0.5)
    assert not [p for p in workers if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    data = json.loads((out / "batch.json").read_text())
    assert data["interrupted"] is True and data["pending"] == 0
    assert data["ok"] >= 1 and data["cancelled"] >= 1 and data["ok"] + data["cancelled"] == 6
    assert [p for p in out.rglob(".*") if p.is_file()] == []  # no half-written files


def test_track_one_never_raises(tmp_path) -> None:
    out = track_one(str(tmp_path / "gone.avi"), str(tmp_path / "o"), NO_VIDEO)
    assert out["status"] == "failed" and "gone.avi" in out["error"]
    ok = track_one(str(box_video(tmp_path / "v.avi")), str(tmp_path / "o2"), NO_VIDEO,
                     max_frames=12)
    assert ok["status"] == "ok" and ok["frames"] == 12 and ok["error"] is None


def test_expand_videos_folders_globs_and_duplicates(tmp_path) -> None:
    clips = tmp_path / "clips"
    clips.mkdir()
    for name in ("b.mp4", "a.AVI", "notes.txt", ".hidden.mp4"):
        (clips / name).write_bytes(b"x")
    frames = tmp_path / "frames"
    frames.mkdir()
    (frames / "000.png").write_bytes(b"x")
    got = expand_videos([str(clips), str(tmp_path / "clips" / "*.mp4"), str(frames),
                         str(tmp_path / "missing.avi")])
    assert got == [str(clips / "a.AVI"), str(clips / "b.mp4"), str(frames),
                   str(tmp_path / "missing.avi")]
    with pytest.raises(ValueError, match="no file matches"):
        expand_videos([str(tmp_path / "*.mkv")])
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no videos in folder"):
        expand_videos([str(tmp_path / "empty")])


def test_cli_exit_codes_and_failure_lines(videos, tmp_path, scheduler, capsys) -> None:
    out = tmp_path / "ok"
    code = main(["batch", str(videos["boxes"]), str(videos["cam_a"]), "--out", str(out),
                 "--scheduler", scheduler, "--no-video", "--max-frames", "20"])
    assert code == 0, capsys.readouterr().err
    assert capsys.readouterr().err == ""
    data = json.loads((out / "batch.json").read_text())
    assert [v["frames"] for v in data["videos"]] == [20, 20]

    out = tmp_path / "some-failed"
    code = main(["batch", str(videos["boxes"]), str(tmp_path / "nope.avi"), "--out", str(out),
                 "--scheduler", scheduler, "--no-video", "--predictor", "rls"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    assert len(err) == 1 and err[0].startswith("error: ") and "nope.avi" in err[0]
    data = json.loads((out / "batch.json").read_text())
    assert [v["status"] for v in data["videos"]] == ["ok", "failed"]
    assert data["settings"]["tracker"]["predictor"] == "rls"
    # the same options as `mvtrack track` give the same results
    expected = _sequential(videos["boxes"], tmp_path / "seq", "--predictor", "rls")
    assert (out / "boxes" / "results.txt").read_bytes() == expected


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        ([], "VIDEO"),
        (["{empty}"], "no videos in folder"),
        (["{tmp}/*.mkv"], "no file matches"),
        (["{video}", "--workers", "0"], "--workers"),
        (["{video}", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "--scheduler"),
        (["{video}", "--predictor", "psychic"], "psychic"),
        (["{video}", "--detector", "yolo"], "yolo"),
        (["{video}", "--out-dir", "x"], "out-dir"),
        (["{video}", "--snapshot", "-1"], "--snapshot must be a frame index >= 0"),
        (["{video}", "--max-frames", "5", "--snapshot", "5"], "--snapshot 5 is past"),
    ],
)
def test_cli_bad_usage_exits_2_before_any_work(tmp_path, capsys, args, needle) -> None:
    (tmp_path / "empty").mkdir()
    video = tmp_path / "v.avi"
    video.write_bytes(b"x")
    fmt = {"empty": tmp_path / "empty", "tmp": tmp_path, "video": video}
    argv = ["batch", *(a.format(**fmt) for a in args), "--out", str(tmp_path / "out")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and needle in err and "\n" not in err
    assert not (tmp_path / "out").exists()


def test_unreachable_scheduler_is_one_line_oserror_and_writes_nothing(tmp_path) -> None:
    video = box_video(tmp_path / "v.avi", n=8)
    with pytest.raises(OSError, match=r"cannot connect to Dask scheduler tcp://127\.0\.0\.1:9"):
        track_many([video], tmp_path / "out", NO_VIDEO, scheduler="tcp://127.0.0.1:9",
                   timeout=1.0)
    assert not (tmp_path / "out").exists()


def test_scheduler_without_workers_is_an_error_not_a_hang(tmp_path) -> None:
    from distributed import LocalCluster

    from mvtrack.video.batch import _environ_kept

    video = box_video(tmp_path / "v.avi", n=8)
    with _environ_kept(), LocalCluster(n_workers=0, **_QUIET_CLUSTER) as empty:
        with pytest.raises(OSError, match="has no workers"):
            track_many([video], tmp_path / "out", NO_VIDEO, scheduler=empty.scheduler_address,
                       timeout=1.0)
    assert not (tmp_path / "out").exists()


def test_batch_folder_holds_the_files_of_track(videos, tmp_path, scheduler) -> None:
    """With an [analytics] table, each batch folder holds what `mvtrack track` writes for the
    same video and settings: states.csv, the analytics tables and the video drawn with them,
    the same bytes."""
    cfg = tmp_path / "scene.toml"
    cfg.write_text("[analytics]\ninterval = 1\nmin_frames = 3\n"
                   "[analytics.lines.middle]\npoints = [[48, 0], [48, 64]]\n"
                   "[analytics.zones.left]\npolygon = [[0, 0], [48, 0], [48, 64], [0, 64]]\n")
    out = tmp_path / "batch"
    code = main(["batch", str(videos["boxes"]), str(videos["cam_a"]), "--out", str(out),
                 "--scheduler", scheduler, "--config", str(cfg), "--max-frames", "30"])
    assert code == 0
    for name, video in (("boxes", videos["boxes"]), ("cam", videos["cam_a"])):
        seq = tmp_path / f"seq-{name}"
        assert main(["track", str(video), "--out", str(seq), "--config", str(cfg),
                     "--max-frames", "30"]) == 0
        files = sorted(p.name for p in (out / name).iterdir())
        assert files == sorted(p.name for p in seq.iterdir())
        assert {"results.txt", "states.csv", "counts.csv", "movements.csv", "speeds.csv",
                "tracks.csv", "tracks.mp4"} <= set(files)
        for f in ("results.txt", "states.csv", "counts.csv", "movements.csv", "speeds.csv",
                  "tracks.csv", "tracks.mp4"):
            assert (out / name / f).read_bytes() == (seq / f).read_bytes(), (name, f)
    # the box crosses the line once, leftwards, and enters the zone left of it once
    counts = read_table(out / "boxes" / "counts.csv")
    n = {(e, d): sum(int(c) for e2, d2, c in zip(counts["name"], counts["direction"],
                                                 counts["count"], strict=True)
                     if (e2, d2) == (e, d))
         for e, d in (("middle", "forward"), ("middle", "backward"), ("left", "entries"))}
    assert n == {("middle", "forward"): 0, ("middle", "backward"): 1, ("left", "entries"): 1}


def test_batch_offline_gives_the_files_of_track_offline(videos, tmp_path, scheduler) -> None:
    """``--offline`` reaches each worker: the revised rows and the video drawn in the second
    pass are those of ``mvtrack track --offline``, and differ from the online run's."""
    out = tmp_path / "batch"
    code = main(["batch", str(videos["boxes"]), "--out", str(out), "--scheduler", scheduler,
                 "--offline", "--max-frames", "30"])
    assert code == 0
    seq, online = tmp_path / "seq", tmp_path / "online"
    assert main(["track", str(videos["boxes"]), "--out", str(seq), "--offline",
                 "--max-frames", "30"]) == 0
    assert main(["track", str(videos["boxes"]), "--out", str(online),
                 "--max-frames", "30"]) == 0
    for f in ("results.txt", "states.csv", "tracks.mp4"):
        assert (out / "boxes" / f).read_bytes() == (seq / f).read_bytes(), f
    assert (seq / "results.txt").read_bytes() != (online / "results.txt").read_bytes()
    summary = json.loads((out / "boxes" / "summary.json").read_text())
    assert summary["settings"]["offline"] is True


def test_batch_snapshots_are_the_pictures_of_track(videos, tmp_path, scheduler, capsys) -> None:
    """``--snapshot`` (twice) saves in each video's folder the pictures `mvtrack track` saves
    for it, byte for byte; a video too short for one of them fails on its own, named."""
    out = tmp_path / "batch"
    code = main(["batch", str(videos["boxes"]), str(videos["cam_a"]), "--out", str(out),
                 "--scheduler", scheduler, "--no-video", "--snapshot", "35", "--snapshot",
                 "12"])
    assert code == 1  # the box video has 30 frames
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--snapshot 35 is past the last frame 29 of {videos['boxes']}" \
        in err[0]
    data = json.loads((out / "batch.json").read_text())
    assert [v["status"] for v in data["videos"]] == ["failed", "ok"]
    assert not (out / "boxes" / "results.txt").exists()
    seq = tmp_path / "seq"
    assert main(["track", str(videos["cam_a"]), "--out", str(seq), "--no-video",
                 "--snapshot", "12", "--snapshot", "35"]) == 0
    files = json.loads((out / "cam" / "summary.json").read_text())["files"]
    assert files["snapshot 12"] == "frame00012.png" and files["snapshot 35"] == "frame00035.png"
    for name in ("frame00012.png", "frame00035.png"):
        assert (out / "cam" / name).read_bytes() == (seq / name).read_bytes()


@pytest.mark.usefixtures("unknown_length")
def test_track_one_names_a_snapshot_an_unknown_length_source_never_reached(tmp_path) -> None:
    """A source without a known length is tracked to its end; the frame it never reached
    makes the video ``failed`` with that frame named, and its tracks and the pictures it did
    reach are kept."""
    video = box_video(tmp_path / "v.avi", n=30)
    out = tmp_path / "out"
    item = track_one(str(video), str(out), NO_VIDEO, snapshot=(12, 40))
    assert item["status"] == "failed"
    assert item["error"] == (f"--snapshot 40: {video} ended after 30 frames (0 to 29), so "
                             f"that frame was not saved; the tracks are in {out}")
    assert (out / "results.txt").exists()
    assert sorted(p.name for p in out.glob("frame*.png")) == ["frame00012.png"]
