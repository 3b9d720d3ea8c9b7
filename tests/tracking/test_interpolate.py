"""``interpolate_gaps``: linear interpolation of a track's gaps, on hand-built rows."""

from __future__ import annotations

import numpy as np

from mvtrack.tracking.log import interpolate_gaps
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
    # the tracker's own rows first, then the interpolated ones by track ID
    assert [f.track_id.tolist() for f in out] == [[1, 2], [1, 2], [2, 1], [1]]
    np.testing.assert_allclose(out[1].filtered_xy, [[10.0, 20.0], [90.0, 180.0]])
    np.testing.assert_allclose(out[1].wh, [[12.0, 12.0], [42.0, 42.0]])
    np.testing.assert_allclose(out[1].velocity, [[10.0, 20.0], [-10.0, -20.0]])
    np.testing.assert_allclose(out[2].filtered_xy[1], [20.0, 40.0])
    np.testing.assert_allclose(out[2].wh[1], [14.0, 14.0])
    np.testing.assert_array_equal(out[2].filtered_xy[0], frames[2].filtered_xy[1])
    # coasting without measurement; the inputs are not changed
    assert out[1].state.tolist() == [M, M] and out[1].det_index.tolist() == [-1, -1]
    assert frames[1].filtered_xy[0, 0] == 999.0


def test_frames_without_rows_in_a_gap_get_rows() -> None:
    """The online tracker writes a coasting row only while its prediction is certain: the
    frames of a gap it did not write get their rows, in frames that had none."""
    frames = [
        _frame(0, [(1, C, 0, 0.0, 10.0)]),
        _frame(1, [(1, M, -1, 11.0, 10.0)]),
        _frame(4, [(1, C, 0, 40.0, 20.0), (2, C, 1, 90.0, 10.0)]),
    ]
    out = interpolate_gaps(frames)
    assert [f.frame for f in out] == [0, 1, 2, 3, 4]
    np.testing.assert_allclose([f.filtered_xy[0, 0] for f in out], [0.0, 10.0, 20.0, 30.0,
                                                                    40.0])
    np.testing.assert_allclose(out[2].wh[0], [15.0, 15.0])
    assert out[3].state.tolist() == [M] and out[3].det_index.tolist() == [-1]
    assert np.isnan(out[3].measured_xy).all() and np.isnan(out[3].predicted_xy).all()
    assert out[4].track_id.tolist() == [1, 2]


def test_tails_are_kept_and_stopped_rows_are_anchors() -> None:
    frames = [
        _frame(0, [(1, C, 0, 0.0, 10.0)]),
        _frame(1, [(1, S, -1, 0.0, 10.0)]),  # held by template matching: an anchor
        _frame(2, [(1, M, -1, 5.0, 10.0)]),
        _frame(3, [(1, M, -1, 6.0, 10.0)]),
    ]
    out = interpolate_gaps(frames)
    assert [len(f) for f in out] == [1, 1, 1, 1]
    for f, g in zip(out, frames, strict=True):  # nothing to bridge: unchanged
        np.testing.assert_array_equal(f.filtered_xy, g.filtered_xy)


def test_rows_without_a_public_id_are_left_alone() -> None:
    frames = [
        _frame(0, [(-1, T, 0, 0.0, 10.0)]),
        _frame(1, [(-1, T, -1, 50.0, 10.0)]),
        _frame(2, [(-1, T, 0, 10.0, 10.0)]),
    ]
    out = interpolate_gaps(frames)
    assert [len(f) for f in out] == [1, 1, 1]
    assert out[1].filtered_xy[0, 0] == 50.0
    assert interpolate_gaps([]) == []
