"""Which tracks have travelled (:mod:`mvtrack.detection.travel`), with hand-made track rows and
with the tracker's own rows."""

from __future__ import annotations

import numpy as np

from mvtrack.detection.travel import Travel
from mvtrack.tracking import Tracker, preset
from mvtrack.types import Detections, TrackFrame, TrackState


def rows(k: int, ids, xy, wh, predicted=None, measured=True) -> TrackFrame:
    ids = np.asarray(ids, np.int64)
    xy = np.asarray(xy, float).reshape(-1, 2)
    wh = np.asarray(wh, float).reshape(-1, 2)
    n = len(ids)
    pred = xy if predicted is None else np.asarray(predicted, float).reshape(-1, 2)
    meas = xy if measured else np.full((n, 2), np.nan)
    return TrackFrame(k, ids, np.full(n, int(TrackState.CONFIRMED)), np.arange(n), meas,
                      xy.copy(), pred, wh, np.zeros((n, 2)))


def test_a_track_travels_from_the_row_reach_box_sizes_from_where_it_was_born() -> None:
    t = Travel(0.5)
    # born at x = 100 (the prediction of its first row), box 20 × 40
    assert not t.update(rows(1, [3], [105, 50], [20, 40], predicted=[100, 50]))[0]
    assert not t.update(rows(2, [3], [109, 50], [20, 40]))[0]  # 9 px < 10 px
    assert t.update(rows(3, [3], [110, 50], [20, 40]))[0]  # half a width
    # and stays so while it waits, or comes back
    assert t.update(rows(4, [3], [100, 50], [20, 40], measured=False))[0]
    assert t.travelled(np.array([3, 4, 0, 99])).tolist() == [True, False, False, False]


def test_along_either_axis_in_its_own_box_sizes() -> None:
    t = Travel(0.5)
    t.update(rows(1, [1, 2], [[50, 50], [50, 150]], [[10, 40], [40, 10]],
                  predicted=[[50, 50], [50, 150]]))
    out = t.update(rows(2, [1, 2], [[50, 69], [50, 156]], [[10, 40], [40, 10]]))
    assert out.tolist() == [False, True]  # 19 px < 20 px of height; 6 px >= 5 px of height


def test_clutter_that_jitters_never_travels() -> None:
    rng = np.random.default_rng(1)
    t = Travel(0.25)
    for k in range(200):
        xy = np.array([300.0, 80.0]) + rng.uniform(-1.2, 1.2, 2)  # ±1.2 px on a 12-px box
        assert not t.update(rows(k, [7], xy, [12, 12], predicted=[300, 80]))[0]


def test_a_track_born_at_the_border_came_in_from_outside() -> None:
    t = Travel(0.5)
    out = t.update(rows(1, [1, 2], [[6, 50], [60, 50]], [[14, 20], [14, 20]]), size=(100, 80))
    assert out.tolist() == [True, False]  # the first box touches the left edge
    assert Travel(0.5).update(rows(1, [1], [6, 50], [14, 20])).tolist() == [False]  # no size


def test_with_the_trackers_rows_a_mover_travels_a_still_blob_does_not() -> None:
    tracker = Tracker(preset("default", fps=10))
    travel = Travel(0.25)
    seen = {}
    for k in range(12):
        dets = Detections(k, np.array([[100.0 + 4 * k, 60.0], [300.0, 60.0]]),
                          np.array([[20.0, 40.0], [20.0, 40.0]]))
        tf = tracker.step(dets)
        for i, flag in zip(tf.track_id.tolist(), travel.update(tf).tolist(), strict=True):
            seen.setdefault(i, []).append(flag)
    moving, still = sorted(seen)
    assert seen[moving][0] is False and seen[moving][-1] is True  # 4 px a frame, 5 px needed
    assert not any(seen[still])
