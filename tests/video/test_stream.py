"""``mvtrack track --flush SECONDS``: results.txt and states.csv grow while the run goes on,
are valid whenever they are read, and end byte for byte as without streaming."""

from __future__ import annotations

import itertools
import json
import os
import signal

import numpy as np
import pytest

from mvtrack.cli import main
from mvtrack.config import RunSettings
from mvtrack.io.mot import read_mot
from mvtrack.io.stream import LineAppender
from mvtrack.video import stream as stream_module
from mvtrack.video import track_to_folder
from mvtrack.video.stream import StreamingOutput, TrackStats, signals_held


def _squares(n: int = 80) -> list[np.ndarray]:
    """Two boxes crossing a textured background from frame 10 on (one leaves at frame 50)."""
    rng = np.random.default_rng(0)
    base = rng.normal(100, 2, (120, 160, 3)).clip(0, 255).astype(np.uint8)
    frames = []
    for k in range(n):
        img = base.copy()
        if k >= 10:
            x = 10 + 2 * (k - 10)
            img[36:44, x : x + 10] = 230
        if 10 <= k < 50:
            x = 140 - int(1.5 * (k - 10))
            img[80:88, x : x + 10] = 20
        frames.append(img)
    return frames


def _settings() -> RunSettings:
    return RunSettings(tracker={"preset": "default"}, templates=False, detector="disturbance-map",
                       video=False)


class _Ticking(StreamingOutput):
    """A clock that advances one second per reading: a flush every few frames."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs["clock"] = itertools.count().__next__
        super().__init__(*args, **kwargs)


def test_files_are_valid_whenever_read_and_end_as_without_streaming(tmp_path, monkeypatch):
    monkeypatch.setattr(stream_module, "StreamingOutput", _Ticking)
    frames = _squares()
    plain = track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(),
                            out=tmp_path / "plain", progress=False)
    out = tmp_path / "stream"
    seen: list[tuple[str, str]] = []

    def watched():
        for img in frames:  # before each frame, read both files as a watcher would
            text = (out / "results.txt").read_text() if seen else ""
            states = (out / "states.csv").read_text() if seen else ""
            seen.append((text, states))
            if text:
                assert text.endswith("\n")
                read_mot(out / "results.txt", "results")  # valid MOTChallenge results
            if seen[1:]:
                assert states.startswith("frame,id,state,") and states.endswith("\n")
            yield img

    run = track_to_folder(watched(), fps=30.0, size=(160, 120), settings=_settings(),
                          out=out, progress=False, flush=3.0)
    final = (out / "results.txt").read_text()
    assert final == (tmp_path / "plain" / "results.txt").read_text() != ""
    texts = [t for t, _ in seen]
    assert all(final.startswith(t) for t in texts)  # appended, never rewritten
    assert len(set(texts)) > 10  # it grew while the run went on
    assert texts[-1] != "" and texts[-1] != final  # ... and the last frames came at the end
    # the summary's figures are those of the run without streaming
    for key in ("frames", "tracks", "track_length_frames", "states", "detections"):
        assert run.summary[key] == plain.summary[key], key
    assert run.summary["flush_seconds"] == 3.0
    assert len(run.log) == 80 and run.log.n_rows == 0  # every frame released
    assert run.result.tracks == [] and run.result.flags == []  # nothing kept per frame
    assert sorted(p.name for p in out.iterdir()) == [
        "results.txt", "states.csv", "summary.json", "trajectories.png"]


def test_streamed_states_csv_equals_the_one_written_at_the_end(tmp_path, monkeypatch) -> None:
    from mvtrack.analytics.outputs import states_table, table_csv

    monkeypatch.setattr(stream_module, "StreamingOutput", _Ticking)
    frames = _squares(60)
    plain = track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(),
                            out=tmp_path / "plain", progress=False)
    track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(),
                    out=tmp_path / "s", progress=False, flush=2.0)
    expected = table_csv(states_table(plain.log, plain.result.flags, plain.result.scores))
    assert expected.count("\n") > 40
    assert (tmp_path / "s" / "states.csv").read_text() == expected


def test_streamed_template_scores_are_written_then_released(tmp_path) -> None:
    """The template score of a held row reaches states.csv at the flush of its frame, and the
    frame's scores are let go once written (memory stays flat on an endless stream)."""
    import gc
    import weakref

    from mvtrack.analytics.outputs import read_table
    from mvtrack.types import TrackFrame, TrackState
    from mvtrack.video.loop import HeldScores

    ticks = itertools.count()
    out = StreamingOutput(tmp_path, 4.0, clock=ticks.__next__)  # a flush every 4 frames
    xy, stopped = np.array([[50.0, 60.0], [90.0, 20.0]]), int(TrackState.STOPPED)
    refs = []
    for k in range(10):
        held = k % 3 == 0  # track 7 is held by template on frames 0, 3, 6, 9
        tf = TrackFrame(k, np.array([7, 8]), np.array([stopped if held else 1, 1]),
                        np.array([-1 if held else 0, 1]), xy, xy, xy, xy * 0 + 9, xy * 0)
        score = np.array([0.8 + k / 100]) if held else np.zeros(0)
        refs.append(weakref.ref(score))
        out.add(tf, np.zeros(2, np.int8), HeldScores(np.array([7] if held else [], np.int64),
                                                     score))
        del score
    gc.collect()
    assert out.flushes == 2 and all(r() is None for r in refs[:8])  # frames 0–7 written
    out.close()
    table = read_table(tmp_path / "states.csv")
    got = {(f, i): s for f, i, s in zip(table["frame"], table["id"], table["template_score"],
                                        strict=True) if s}
    assert got == {("1", "7"): "0.8", ("4", "7"): "0.83", ("7", "7"): "0.86",
                   ("10", "7"): "0.89"}


def test_cli_streamed_run_on_the_real_video_equals_the_plain_run(tmp_path, vtest_path) -> None:
    common = ["track", str(vtest_path), "--no-video", "--max-frames", "120"]
    assert main([*common, "--out", str(tmp_path / "a")]) == 0
    assert main([*common, "--out", str(tmp_path / "b"), "--flush", "0.05"]) == 0
    for name in ("results.txt", "states.csv"):
        a, b = (tmp_path / d / name for d in "ab")
        assert a.read_bytes() == b.read_bytes(), name
    sa, sb = (json.loads((tmp_path / d / "summary.json").read_text()) for d in "ab")
    for key in ("frames", "tracks", "track_length_frames", "states"):
        assert sa[key] == sb[key], key


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf"])
def test_flush_must_be_a_positive_number_of_seconds(tmp_path, capsys, value) -> None:
    out = tmp_path / "out"
    assert main(["track", "nothing.avi", "--out", str(out), f"--flush={value}"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: --flush must be"), err
    assert not out.exists()


def test_flush_into_an_unwritable_place_is_one_line_and_exit_2(tmp_path, capsys) -> None:
    from _media import box_video

    video = box_video(tmp_path / "v.avi")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "results.txt").mkdir()  # a folder where the file should go
    assert main(["track", str(video), "--out", str(tmp_path / "out"), "--flush", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error:") and "results.txt" in err, err
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["track", str(video), "--out", str(blocker), "--flush", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error:"), err


def test_sigterm_with_flush_keeps_what_was_streamed_and_writes_the_rest(
        tmp_path, capsys, monkeypatch) -> None:
    """SIGTERM while frame 40 is detected, in a run that flushes at every frame: exit 143, and
    the files hold frames 0 to 39 (the frame the signal arrived in is finished) exactly as a
    plain run of 40 frames writes them."""
    from _media import box_video, stop_at_frame

    video = box_video(tmp_path / "v.avi", n=80)
    assert main(["track", str(video), "--out", str(tmp_path / "plain"), "--no-video",
                 "--max-frames", "40"]) == 0
    stop_at_frame(monkeypatch, 40, lambda: signal.raise_signal(signal.SIGTERM))
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video", "--flush", "1e-9"]) == 143
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("error: terminated after 40 frames"), err
    for name in ("results.txt", "states.csv"):
        assert (out / name).read_bytes() == (tmp_path / "plain" / name).read_bytes(), name
    assert (out / "results.txt").read_text().count("\n") > 20
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] and summary["frames"] == 40
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


def test_line_appender_completes_a_batch_cut_by_an_interrupt(tmp_path, monkeypatch) -> None:
    import mvtrack.io.stream as io_stream

    path = tmp_path / "r.txt"
    writer = LineAppender(path, header="a,b\n")
    writer.append("1,2\n3,4\n")
    real_write = os.write
    calls = {"n": 0}

    def short_then_interrupted(fd, data):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return real_write(fd, bytes(data[:5]))  # a short write: part of a line

    monkeypatch.setattr(io_stream.os, "write", short_then_interrupted)
    with pytest.raises(KeyboardInterrupt):
        writer.append("5,6\n7,8\n")
    monkeypatch.setattr(io_stream.os, "write", real_write)
    assert path.read_text() == "a,b\n1,2\n3,4\n5,6\n7"  # cut mid-line, as a crash could
    writer.close()  # what the interrupted call left is written first
    assert path.read_text() == "a,b\n1,2\n3,4\n5,6\n7,8\n"
    assert writer.lines == 4
    with pytest.raises(ValueError, match="closed"):
        writer.append("9,9\n")
    with pytest.raises(ValueError, match="newline"):
        LineAppender(tmp_path / "x.txt").append("no end")


def test_signals_held_delivers_the_signal_after_the_block() -> None:
    done = []
    with pytest.raises(KeyboardInterrupt):
        with signals_held():
            signal.raise_signal(signal.SIGINT)
            done.append("the block ran to its end")
    assert done == ["the block ran to its end"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_track_stats_match_the_figures_of_the_whole_log() -> None:
    rng = np.random.default_rng(1)
    frame = np.repeat(np.arange(3000), 3)
    tid = np.where(rng.random(frame.size) < 0.8, frame // 40 + rng.integers(0, 3, frame.size),
                   -1)
    state = rng.integers(0, 4, frame.size)
    stats = TrackStats(gap=45)
    for lo in range(0, 3000, 7):  # flushes of 7 frames
        sel = (frame >= lo) & (frame < lo + 7)
        stats.add(frame[sel], tid[sel], state[sel], lo + 6)
    assert stats._ids.size < 10  # ended tracks leave only their length behind
    ids, lengths = np.unique(tid[tid > 0], return_counts=True)
    assert stats.n_tracks == ids.size
    assert stats.lengths() == {"median": float(np.median(lengths)), "max": int(lengths.max())}
    assert sum(stats.state_histogram().values()) == frame.size
