"""``interpolate_gaps``: linear interpolation of a track's gaps, on hand-built rows."""

from __future__ import annotations

import numpy as np

from mvtrack.tracking.log import drop_short_tracks, interpolate_gaps
from mvtrack.types import TrackFrame, TrackState

C, M, S, T = TrackState.CONFIRMED, TrackState.COASTING, TrackState.STOPPED, TrackState.TENTATIVE


def _frame(k: int, rows: list[tuple[int, int, int, float, float]]) -> TrackFrame:
    """Rows ``(track_id, state, det_index, x, w)``; y = 2x, h = w."""
    tid = np.array([r[0] for r in rows], dtype=np.int64)
    state = np.array([int(r[1]) for r in rows], dtype=np.int64)
    det = np.array([r[2] for r in rows], dtype=np.int64)
    x = np.array([r[3] for r in rows], dtype=np.float64)
    w = np.array([r[4] for r in rows], dtype=np.float64)
    xy = np.stack([x, 2 * x], axis=1).reshape(-1, 2)
    wh = np.stack([w, w], axis=1).reshape(-1, 2)
    meas = np.where((det >= 0)[:, None], xy, np.nan)
    return TrackFrame(k, tid, state, det, meas, xy, xy + 0.5, wh, np.zeros_like(xy))


def test_two_interleaved_tracks_are_filled_from_their_own_rows() -> None:
    # track 1: measured at 0 (x 0, w 10) and 3 (x 30, w 16), coasting at 1 and 2 with
    # predictions far off; track 2: measured at 0 and 2 (x 100 -> 80), coasting at 1
    frames = [
        _frame(0, [(1, C, 0, 0.0, 10.0), (2, C, 1, 100.0, 40.0)]),
        _frame(1, [(2, M, -1, 999.0, 1.0), (1, M, -1, 500.0, 1.0)]),
        _frame(2, [(1, M, -1, 600.0, 1.0), (2, C, 0, 80.0, 44.0)]),
        _frame(3, [(1, C, 0, 30.0, 16.0)]),
    ]
    out = interpolate_gaps(frames)
    assert [f.track_id.tolist() for f in out] == [[1, 2], [2, 1], [1, 2], [1]]
    np.testing.assert_allclose(out[1].filtered_xy, [[90.0, 180.0], [10.0, 20.0]])
    np.testing.assert_allclose(out[1].wh, [[42.0, 42.0], [12.0, 12.0]])
    np.testing.assert_allclose(out[1].velocity, [[-10.0, -20.0], [10.0, 20.0]])
    np.testing.assert_allclose(out[2].filtered_xy[0], [20.0, 40.0])
    np.testing.assert_allclose(out[2].wh[0], [14.0, 14.0])
    # states, detection links, measurements and predictions are kept; inputs are not changed
    assert out[1].state.tolist() == [M, M] and out[1].det_index.tolist() == [-1, -1]
    np.testing.assert_array_equal(out[1].predicted_xy, frames[1].predicted_xy)
    assert frames[1].filtered_xy[0, 0] == 999.0


def test_tails_are_cut_to_tail_rows_and_stopped_rows_are_anchors() -> None:
    frames = [
        _frame(0, [(1, C, 0, 0.0, 10.0)]),
        _frame(1, [(1, S, -1, 0.0, 10.0)]),  # held by template matching: an anchor
        _frame(2, [(1, M, -1, 5.0, 10.0)]),
        _frame(3, [(1, M, -1, 6.0, 10.0)]),
        _frame(4, [(1, M, -1, 7.0, 10.0)]),
    ]
    for tail, kept in ((None, [1, 1, 1, 1, 1]), (2, [1, 1, 1, 1, 0]), (0, [1, 1, 0, 0, 0])):
        out = interpolate_gaps(frames, tail)
        assert [len(f) for f in out] == kept
        for f, g in zip(out, frames, strict=True):  # a tail is not moved
            np.testing.assert_array_equal(f.filtered_xy, g.filtered_xy[: len(f)])


def test_rows_without_a_public_id_are_left_alone() -> None:
    frames = [
        _frame(0, [(-1, T, 0, 0.0, 10.0)]),
        _frame(1, [(-1, T, -1, 50.0, 10.0)]),
        _frame(2, [(-1, T, 0, 10.0, 10.0)]),
    ]
    out = interpolate_gaps(frames, tail=0)
    assert [len(f) for f in out] == [1, 1, 1]
    assert out[1].filtered_xy[0, 0] == 50.0
    assert interpolate_gaps([]) == []


def test_drop_short_tracks_leaves_out_whole_short_tracks_only() -> None:
    # track 1: 3 rows, track 2: 2 rows, a tentative row (-1) in frame 1
    frames = [
        _frame(0, [(1, C, 0, 0.0, 10.0), (2, C, 1, 50.0, 10.0)]),
        _frame(1, [(2, M, -1, 52.0, 10.0), (-1, T, 0, 90.0, 10.0), (1, C, 1, 1.0, 10.0)]),
        _frame(2, [(1, C, 0, 2.0, 10.0)]),
    ]
    out = drop_short_tracks(frames, 3)
    assert [f.track_id.tolist() for f in out] == [[1], [-1, 1], [1]]
    np.testing.assert_array_equal(out[1].filtered_xy, [[90.0, 180.0], [1.0, 2.0]])
    assert [f.track_id.tolist() for f in drop_short_tracks(frames, 2)] == [
        f.track_id.tolist() for f in frames]
    assert [len(f) for f in drop_short_tracks(frames, 4)] == [0, 1, 0]


def test_min_track_length_in_seconds_scales_with_the_frame_rate() -> None:
    from mvtrack.tracking import TrackerConfig, track_detections
    from mvtrack.types import Detections

    def run(fps: float) -> set[int]:
        # a target seen for 0.5 s and one seen for 2 s, far apart
        n = round(2 * fps)
        frames = []
        for k in range(n):
            xy = [[100.0 + k, 100.0]] + ([[400.0, 300.0]] if k < n // 4 else [])
            frames.append(Detections(k, xy, [[20.0, 40.0]] * len(xy)))
        cfg = TrackerConfig(fps=fps, min_track_length=1.0)
        return set(track_detections(frames, cfg).track_ids.tolist())

    assert run(10.0) == run(30.0) == {1}
    n_all = set(track_detections(
        [Detections(k, [[5.0 * k, 0.0]], [[20.0, 40.0]]) for k in range(6)],
        TrackerConfig(fps=10.0, min_track_length=None)).track_ids.tolist())
    assert n_all == {1}
