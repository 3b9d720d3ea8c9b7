"""An offline video run (``--offline``): the online rows untouched by the wrapping, the
tentative rows of confirmed tracks written under the ID they got, every row smoothed."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from _media import box_video, squares_video
from mvtrack.config import RunSettings
from mvtrack.errors import InputError
from mvtrack.tracking import TrackerConfig, TrackLog
from mvtrack.tracking.log import ROW_FIELDS
from mvtrack.tracking.smooth import smooth_tracks
from mvtrack.types import Detections, TrackFrame, TrackState
from mvtrack.video import track_to_folder
from mvtrack.video.offline import OfflineRows
from mvtrack.video.run import source_reader

TENT, CONF = int(TrackState.TENTATIVE), int(TrackState.CONFIRMED)


def _settings(**kw) -> RunSettings:
    return RunSettings(tracker={"preset": "default"}, detector="disturbance-map",
                       templates=False, **kw)


def _rows(log: TrackLog) -> dict[tuple[int, int], np.ndarray]:
    """(frame, id) -> (x, y, w, h, state) of every row of ``log``."""
    out = {}
    for f in log:
        for j in range(len(f)):
            out[f.frame, int(f.track_id[j])] = np.r_[f.filtered_xy[j], f.wh[j], f.state[j]]
    return out


def test_the_offline_run_keeps_the_online_rows_and_adds_the_confirmed_tracks_first_ones(
        tmp_path) -> None:
    frames, _ = squares_video(60)
    online = track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(video=False),
                             out=tmp_path / "on", progress=False)
    off = track_to_folder(frames, fps=30.0, size=(160, 120),
                          settings=_settings(video=False, offline=True), out=tmp_path / "off",
                          progress=False)
    on_rows, off_rows = _rows(online.log), _rows(off.log)
    assert len(online.log) == len(off.log) == 60
    assert set(on_rows) < set(off_rows)  # every online row is there, and more
    late = set(off_rows) - set(on_rows)
    first_online = {}
    for f, i in on_rows:
        first_online[i] = min(first_online.get(i, f), f)
    for f, i in late:  # rows before the track was confirmed, of tracks written online
        assert i in first_online and f < first_online[i]
        assert off_rows[f, i][4] == TENT
    assert len(late) >= 2  # each square's track is confirmed on its second detection
    # the online rows are smoothed: near, not equal, and the states kept
    d = np.array([np.abs(off_rows[k][:2] - on_rows[k][:2]).max() for k in on_rows])
    assert np.median(d) < 1.0 and d.max() > 0
    assert all(off_rows[k][4] == on_rows[k][4] for k in on_rows)
    assert off.summary["settings"]["offline"] is True


def _frame(k: int, ids, states, xs, det) -> TrackFrame:
    n = len(ids)
    xy = np.column_stack([np.asarray(xs, float), np.full(n, 50.0)])
    return TrackFrame(k, np.asarray(ids, np.int64), np.asarray(states, np.int64),
                      np.asarray(det, np.int64), xy.copy(), xy.copy(), xy.copy(),
                      np.full((n, 2), 10.0), np.zeros((n, 2)))


class _FakeTracker:
    """Replays prepared steps: every row (tentative ones with ID −1) and their uids."""

    def __init__(self, steps) -> None:
        self.config = TrackerConfig(fps=10.0, output_tentative=True)
        self.steps = list(steps)
        self.row_uids = np.zeros(0, np.int64)

    def step(self, dets, rescue=None):
        tf, uids = self.steps.pop(0)
        self.row_uids = np.asarray(uids, np.int64)
        return tf


def test_backfilled_rows_take_the_shown_id_and_only_of_tracks_written() -> None:
    # uid 7: tentative at frames 0-1, confirmed as tracker ID 1 at frame 2 (shown as 40).
    # uid 8: tentative at frames 0-2, never confirmed. uid 9: tentative at frame 1, confirmed
    # as ID 2 at frame 2, but never written online (say a front end hid it).
    steps = [
        (_frame(0, [-1, -1], [TENT, TENT], [10, 60], [0, 1]), [7, 8]),
        (_frame(1, [-1, -1, -1], [TENT, TENT, TENT], [12, 60, 90], [0, 1, 2]), [7, 8, 9]),
        (_frame(2, [1, -1, 2], [CONF, TENT, CONF], [14, 60, 91], [0, 1, 2]), [7, 8, 9]),
        (_frame(3, [1, 2], [CONF, CONF], [16, 92], [0, 1]), [7, 9]),
    ]
    tracker = OfflineRows(_FakeTracker(steps))
    log = TrackLog()
    shown = {1: 40, 2: 41}
    for k in range(4):
        dets = Detections(k, np.zeros((3, 2)), np.full((3, 2), [10.0, 12.0]))
        rows = tracker.public(tracker.step(dets), dets)
        assert (rows.track_id > 0).all()
        keep = np.flatnonzero(rows.track_id == 1)  # the online run writes ID 1 only, as 40
        out = TrackFrame(k, np.full(keep.size, 40, np.int64),
                         *(getattr(rows, n)[keep] for n in ROW_FIELDS[1:]))
        log.append(out)
        tracker.add(out, dets)
    result = tracker.finish(log, lambda ids: np.array([shown[int(i)] for i in ids]))
    got = {(f.frame, int(i)) for f in result for i in f.track_id}
    assert got == {(0, 40), (1, 40), (2, 40), (3, 40)}
    # the reference: the same four rows of the one track, smoothed by smooth_tracks itself
    ref_frames = [_frame(k, [40], [TENT if k < 2 else CONF], [10 + 2 * k], [0]) for k in range(4)]
    ref = smooth_tracks(ref_frames, [np.array([[10.0, 12.0]])] * 4, tracker.config)
    for a, b in zip(result, ref, strict=True):
        assert np.allclose(a.filtered_xy, b.filtered_xy) and np.allclose(a.wh, b.wh)
        assert np.array_equal(a.state, b.state)


def test_public_rows_keep_the_uids_aligned() -> None:
    steps = [(_frame(0, [-1, 3, -1, 4], [TENT, CONF, TENT, CONF], [1, 2, 3, 4], [0, 1, 2, 3]),
              [11, 12, 13, 14])]
    tracker = OfflineRows(_FakeTracker(steps))
    dets = Detections(0, np.zeros((4, 2)), np.ones((4, 2)))
    rows = tracker.public(tracker.step(dets), dets)
    assert rows.track_id.tolist() == [3, 4] and tracker.row_uids.tolist() == [12, 14]
    assert tracker.config.output_tentative  # everything else is the tracker's


def test_a_tracker_that_hides_tentative_rows_cannot_go_offline() -> None:
    fake = _FakeTracker([])
    fake.config = dataclasses.replace(fake.config, output_tentative=False)
    with pytest.raises(ValueError, match="tentative"):
        OfflineRows(fake)


def test_offline_cannot_stream_nor_draw_a_source_read_once(tmp_path) -> None:
    frames, _ = squares_video(5)
    with pytest.raises(InputError, match="--flush"):
        track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(offline=True),
                        out=tmp_path / "a", progress=False, flush=1.0)
    with pytest.raises(InputError, match="--no-video"):
        track_to_folder(frames, fps=30.0, size=(160, 120), settings=_settings(offline=True),
                        out=tmp_path / "b", progress=False)
    assert source_reader(0, None) is None and source_reader("rtsp://camera/1", None) is None
    assert source_reader("2", None) is None and source_reader("clip.mp4", None) is not None


def test_cli_offline_draws_the_revised_rows_in_a_second_pass(tmp_path) -> None:
    import cv2

    from mvtrack.io.mot import read_mot

    video = box_video(tmp_path / "box.avi", n=30)
    for mode in ("online", "offline"):
        proc = subprocess.run([sys.executable, "-m", "mvtrack", "track", str(video), "--out",
                               str(tmp_path / mode), f"--{mode}", "--no-templates"],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
    on = read_mot(tmp_path / "online" / "results.txt", "results")
    off = read_mot(tmp_path / "offline" / "results.txt", "results")
    assert len(off) > len(on) > 0 and off.frame.min() < on.frame.min()
    cap = cv2.VideoCapture(str(tmp_path / "offline" / "tracks.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 30
    cap.release()
    proc = subprocess.run([sys.executable, "-m", "mvtrack", "track", str(video), "--out",
                           str(tmp_path / "s"), "--offline", "--flush", "1"],
                          capture_output=True, text=True)
    assert proc.returncode != 0 and "--flush" in proc.stderr
    assert "Traceback" not in proc.stderr and not (tmp_path / "s" / "results.txt").exists()


def test_source_kind_decides_what_can_be_read_twice() -> None:
    from mvtrack.io.video import source_kind

    assert [source_kind(s) for s in (0, "1", " 2 ", "rtsp://cam/1", "http://x/v.mp4",
                                     "clip.mp4", "frames/", "my://", "ftp_clip.avi")] == [
        "camera", "camera", "camera", "stream", "stream", "file", "file", "stream", "file"]
    assert source_reader(" 2 ", None) is None  # a camera index with spaces, as open_source
