"""The tracker's table (:mod:`mvtrack.tracking.table`) and its row operations: slices equal
gathered rows, detection rows padded with NaN, births with consecutive uids, counters."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.filters.cv import KalmanCVPredictor
from mvtrack.filters.predictors import make_predictor


def _cluttered_frames(n: int, frames: int, seed: int) -> list:
    """Targets moving at constant velocity with missed detections and false alarms (rows
    shuffled): every frame has births, and most have deletions."""
    from mvtrack.types import Detections

    rng = np.random.default_rng(seed)
    p = rng.uniform(0, 400, (n, 2))
    v = rng.uniform(-3, 3, (n, 2))
    wh = rng.uniform(20, 40, (n, 2))
    out = []
    for k in range(frames):
        seen = rng.random(n) > 0.15
        xy = np.vstack([p[seen] + rng.normal(0, 1.0, (int(seen.sum()), 2)),
                        rng.uniform(0, 400, (3, 2))])
        bwh = np.vstack([wh[seen], rng.uniform(20, 40, (3, 2))])
        perm = rng.permutation(xy.shape[0])
        out.append(Detections(k, xy[perm], bwh[perm]))
        p = p + v
    return out


def _run(frames: list, config=None) -> tuple[list, list]:
    from mvtrack.tracking import Tracker

    tracker = Tracker(config)
    outs = [tracker.step(d) for d in frames]
    return outs, [tracker.row_uids.copy(), tracker.tracks, tracker.pstate]


def _assert_same_frames(a: list, b: list) -> None:
    for fa_, fb in zip(a, b, strict=True):
        for name in ("track_id", "state", "det_index", "measured_xy", "filtered_xy",
                     "predicted_xy", "wh", "velocity"):
            np.testing.assert_array_equal(getattr(fa_, name), getattr(fb, name))


@pytest.mark.parametrize("predictor", ["kalman-cv", "kalman-ca"])
def test_deleting_only_the_last_rows_by_slicing_equals_gathering_the_kept_rows(
    predictor: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mvtrack.tracking import TrackerConfig
    from mvtrack.tracking import tracker as tr

    frames = _cluttered_frames(8, 60, 3)
    config = TrackerConfig(predictor=predictor)
    fast, fast_end = _run(frames, config)
    kept_rows = tr.kept_rows
    sliced = []

    def as_indices(delete):  # the general path: the kept rows as indices, always
        keep = kept_rows(delete)
        if isinstance(keep, slice):
            sliced.append(keep)
        return (~delete).nonzero()[0]

    monkeypatch.setattr(tr, "kept_rows", as_indices)
    general, general_end = _run(frames, config)
    assert sliced, "the scene should delete only trailing rows in some frames"
    _assert_same_frames(fast, general)
    np.testing.assert_array_equal(fast_end[0], general_end[0])
    np.testing.assert_array_equal(fast_end[1].ints, general_end[1].ints)
    np.testing.assert_array_equal(fast_end[1].floats, general_end[1].floats)


def test_kept_rows_are_a_slice_only_when_the_last_rows_end() -> None:
    from mvtrack.tracking import table as tr

    rng = np.random.default_rng(4)
    masks = [rng.random(rng.integers(1, 9)) > rng.uniform(0.2, 0.9) for _ in range(300)]
    masks += [np.array([False, False, True, True]), np.array([True] * 3)]
    slices = 0
    for delete in masks:
        keep = tr.kept_rows(delete)
        rows = np.arange(delete.size)
        np.testing.assert_array_equal(rows[keep], (~delete).nonzero()[0])
        slices += isinstance(keep, slice)
    assert 0 < slices < len(masks)


def test_table_and_state_slices_equal_the_gathered_rows() -> None:
    from mvtrack.tracking import table as tr
    from mvtrack.types import n_rows

    rng = np.random.default_rng(0)
    tab = tr.TrackTable(rng.integers(0, 9, (7, tr.N_INT)), rng.normal(size=(7, tr.N_FLOAT)))
    for stop in (0, 3, 7):
        a, b = tab.take(slice(0, stop)), tab.take(np.arange(stop))
        np.testing.assert_array_equal(a.ints, b.ints)
        np.testing.assert_array_equal(a.floats, b.floats)
    fast = KalmanCVPredictor().init(rng.normal(size=(7, 2)))
    general = make_predictor("kalman-ca").init(rng.normal(size=(7, 2)))
    for state in (fast, general):
        a, b = tr.take_state(state, slice(0, 4)), tr.take_state(state, np.arange(4))
        assert type(a) is type(state)
        for name in ("x", "P"):
            if hasattr(state, name):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert n_rows(a) == 4


def test_counters_with_a_mask_equal_counters_with_row_indices() -> None:
    from mvtrack.tracking.lifecycle import count_hits

    rng = np.random.default_rng(1)
    ints = rng.integers(0, 20, (9, 8))
    matched = rng.random(9) > 0.5
    held = matched | (rng.random(9) > 0.7)
    a, b = ints.copy(), ints.copy()
    count_hits(a, matched, held)
    count_hits(b, matched, held.nonzero()[0])
    np.testing.assert_array_equal(a, b)


def test_detection_rows_pad_with_nan_for_tracks_without_a_detection() -> None:
    from mvtrack.tracking import table as tr
    from mvtrack.types import Detections

    dets = Detections(0, [[1.0, 2.0], [3.0, 4.0]], [[5.0, 6.0], [7.0, 8.0]])
    rows = tr.detection_rows(dets).take(np.array([1, -1, 0]), 0)
    np.testing.assert_array_equal(rows[0], [3.0, 4.0, 7.0, 8.0])
    assert np.isnan(rows[1]).all()
    np.testing.assert_array_equal(rows[2], [1.0, 2.0, 5.0, 6.0])
    assert tr.detection_rows(Detections.empty(0)).shape == (1, 4)


def test_many_births_in_one_frame_get_consecutive_uids() -> None:
    from mvtrack.tracking import Tracker
    from mvtrack.types import Detections

    rng = np.random.default_rng(2)
    tracker = Tracker()
    tracker.step(Detections(0, rng.uniform(0, 1000, (40, 2)), np.full((40, 2), 10.0)))
    np.testing.assert_array_equal(np.sort(tracker.tracks.uid), np.arange(40))
    tracker.step(Detections(1, rng.uniform(2000, 3000, (50, 2)), np.full((50, 2), 10.0)))
    np.testing.assert_array_equal(np.sort(tracker.tracks.uid), np.arange(40, 90))
    assert (tracker.tracks.last_k == 1).all() and (tracker.tracks.prev_k == 1).all()
    assert (tracker.tracks.hits == 1).all() and (tracker.tracks.track_id == -1).all()
