"""``interpolate_gaps``: linear interpolation of a track's gaps, on hand-built rows."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking.log import END_REACH, interpolate_gaps
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
    # track 1: measured at 1 (x 0, w 10) and 4 (x 30, w 16), coasting at 2 and 3 with
    # predictions far off; track 2: measured at 1 and 3 (x 100 -> 80), coasting at 2; both
    # measured in the frames next to their gaps' ends as well (frames 0, 4 and 5)
    frames = [
        _frame(0, [(1, C, 0, -7.0, 3.0), (2, C, 1, 200.0, 3.0)]),
        _frame(1, [(1, C, 0, 0.0, 10.0), (2, C, 1, 100.0, 40.0)]),
        _frame(2, [(2, M, -1, 999.0, 1.0), (1, M, -1, 500.0, 1.0)]),
        _frame(3, [(1, M, -1, 600.0, 1.0), (2, C, 0, 80.0, 44.0)]),
        _frame(4, [(1, C, 0, 30.0, 16.0), (2, C, 0, 70.0, 44.0)]),
        _frame(5, [(1, C, 0, 44.0, 16.0)]),
    ]
    out = interpolate_gaps(frames)
    # the tracker's own rows first, then the interpolated ones by track ID
    assert [f.track_id.tolist() for f in out] == [[1, 2], [1, 2], [1, 2], [2, 1], [1, 2], [1]]
    np.testing.assert_allclose(out[2].filtered_xy, [[10.0, 20.0], [90.0, 180.0]])
    np.testing.assert_allclose(out[2].wh, [[12.0, 12.0], [42.0, 42.0]])
    np.testing.assert_allclose(out[2].velocity, [[10.0, 20.0], [-10.0, -20.0]])
    np.testing.assert_allclose(out[3].filtered_xy[1], [20.0, 40.0])
    np.testing.assert_allclose(out[3].wh[1], [14.0, 14.0])
    np.testing.assert_array_equal(out[3].filtered_xy[0], frames[3].filtered_xy[1])
    # coasting without measurement; the inputs are not changed
    assert out[2].state.tolist() == [M, M] and out[2].det_index.tolist() == [-1, -1]
    assert frames[2].filtered_xy[0, 0] == 999.0


def test_frames_without_rows_in_a_gap_get_rows() -> None:
    """The online tracker writes a coasting row only while its prediction is certain: the
    frames of a gap it did not write get their rows, in frames that had none."""
    frames = [
        _frame(0, [(1, C, 0, -10.0, 10.0)]),
        _frame(1, [(1, C, 0, 0.0, 10.0)]),
        _frame(2, [(1, M, -1, 11.0, 10.0)]),
        _frame(5, [(1, C, 0, 40.0, 20.0), (2, C, 1, 90.0, 10.0)]),
        _frame(6, [(1, C, 0, 50.0, 20.0)]),
    ]
    out = interpolate_gaps(frames)
    assert [f.frame for f in out] == [0, 1, 2, 3, 4, 5, 6]
    np.testing.assert_allclose([f.filtered_xy[0, 0] for f in out],
                               [-10.0, 0.0, 10.0, 20.0, 30.0, 40.0, 50.0])
    np.testing.assert_allclose(out[3].wh[0], [15.0, 15.0])
    assert out[4].state.tolist() == [M] and out[4].det_index.tolist() == [-1]
    assert np.isnan(out[4].measured_xy).all() and np.isnan(out[4].predicted_xy).all()
    assert out[5].track_id.tolist() == [1, 2]


@pytest.mark.parametrize("lone", ["start", "end", "both"])
@pytest.mark.parametrize("away", [1, END_REACH])
def test_a_gap_to_a_lone_measurement_is_not_filled(lone: str, away: int) -> None:
    """A gap is interpolated only between ends confirmed by another measurement of the track
    at most ``END_REACH`` frames beyond them: a single detection at either end may be a
    false alarm the track took; its coasting rows stay as written."""
    far = END_REACH + 1  # a measurement this far from the end does not confirm it
    first = [_frame(10, [(1, C, 0, 0.0, 10.0)])]
    first.insert(0, _frame(10 - (far if lone in ("start", "both") else away),
                           [(1, C, 0, -10.0, 10.0)]))
    last = [_frame(13, [(1, C, 0, 30.0, 10.0)])]
    last.append(_frame(13 + (far if lone in ("end", "both") else away),
                       [(1, C, 0, 40.0, 10.0)]))
    frames = [*first, _frame(11, [(1, M, -1, 500.0, 10.0)]), *last]
    out = interpolate_gaps(frames)
    assert 12 not in [f.frame for f in out]  # the gap's frame without a row gets none
    assert next(f for f in out if f.frame == 11).filtered_xy[0, 0] == 500.0
    # confirmed at both ends, the same gap is filled
    first[0] = _frame(10 - away, [(1, C, 0, -10.0, 10.0)])
    last[1] = _frame(13 + away, [(1, C, 0, 40.0, 10.0)])
    out = interpolate_gaps([*first, _frame(11, [(1, M, -1, 500.0, 10.0)]), *last])
    filled = {f.frame: f.filtered_xy[0, 0] for f in out}
    assert filled[11] == pytest.approx(10.0) and filled[12] == pytest.approx(20.0)


def test_runs_of_measurements_are_counted_per_track() -> None:
    """Track 2's measurement in the frame next to track 1's gap does not confirm it."""
    frames = [
        _frame(0, [(2, C, 1, 90.0, 10.0)]),
        _frame(1, [(1, C, 0, 0.0, 10.0)]),
        _frame(3, [(1, C, 0, 20.0, 10.0)]),
        _frame(4, [(1, C, 0, 30.0, 10.0), (2, C, 1, 60.0, 10.0)]),
    ]
    assert [f.frame for f in interpolate_gaps(frames)] == [0, 1, 3, 4]
    frames.insert(1, _frame(1, [(1, C, 0, -10.0, 10.0)]))
    frames[0] = _frame(0, [(2, C, 1, 90.0, 10.0), (1, C, 0, -10.0, 10.0)])
    del frames[1]
    out = interpolate_gaps(frames)
    assert [f.frame for f in out] == [0, 1, 2, 3, 4]
    np.testing.assert_allclose(out[2].filtered_xy[0], [10.0, 20.0])


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
