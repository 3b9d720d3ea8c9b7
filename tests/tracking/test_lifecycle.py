"""The life cycle's kernels by hand: advance, births, measurements, commit; the conversion of
the settings to frames; the presets; the track log."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking import TrackerConfig, TrackLog, paper1, paper2, preset
from mvtrack.tracking import lifecycle as lc
from mvtrack.tracking.lifecycle import (
    AGE,
    HITS,
    LAST_K,
    MISSES,
    N_FLOAT,
    N_INT,
    SCORE,
    STATE,
    TID,
    UID,
    H,
    W,
    advance,
    births,
    commit,
    measurements,
)
from mvtrack.types import TrackFrame, TrackState

T, C, K, S = (int(s) for s in (TrackState.TENTATIVE, TrackState.CONFIRMED,
                               TrackState.COASTING, TrackState.STOPPED))


def _table(state, hits, misses, score=None, wh=(40.0, 90.0)):
    n = len(state)
    ints = np.zeros((n, N_INT), dtype=np.int64)
    ints[:, UID] = np.arange(n)
    ints[:, TID] = np.where(np.array(state) == T, -1, np.arange(1, n + 1))
    ints[:, STATE], ints[:, HITS], ints[:, MISSES] = state, hits, misses
    ints[:, AGE] = np.maximum(hits, 1) + misses
    floats = np.zeros((n, N_FLOAT))
    floats[:, W], floats[:, H] = wh
    floats[:, SCORE] = hits if score is None else score
    return ints, floats


def _advance(ints, floats, det_index, rescued=None, std=None, centre=None, config=None,
             frame_size=None):
    n = ints.shape[0]
    config = config or TrackerConfig()
    det_index = np.asarray(det_index, np.intp)
    rescued = np.zeros(n, bool) if rescued is None else np.asarray(rescued, bool)
    z = np.where(det_index[:, None] >= 0, 100.0, np.nan)
    zwh = np.where(det_index[:, None] >= 0, [[40.0, 90.0]], np.nan)
    zscore = np.where(det_index >= 0, 1.0, 0.0)
    std = np.full((n, 2), 1.0) if std is None else np.asarray(std, float)
    centre = np.full((n, 2), 100.0) if centre is None else np.asarray(centre, float)
    return advance(ints, floats, det_index, rescued, z, zwh, zscore, std, centre, 7,
                   config.life_cycle(frame_size))


def test_state_transitions() -> None:
    # rows: tentative confirmed now; tentative one hit short; tentative missed; confirmed
    # hit; confirmed missed (coasting, certain: kept); coasting beyond max_misses (lost);
    # coasting too uncertain after min_misses (lost); coasting too uncertain but within
    # min_misses (kept); stopped (held by template matching); coasting that gets a detection
    state = [T, T, T, C, C, K, K, K, K, K]
    hits = [1, 0, 1, 9, 9, 9, 9, 9, 9, 9]
    misses = [0, 0, 0, 0, 0, 10, 3, 1, 0, 2]
    det = [0, 1, -1, 2, -1, -1, -1, -1, -1, 3]
    rescued = [0, 0, 0, 0, 0, 0, 0, 0, 1, 0]
    std = np.full((10, 2), 1.0)
    std[6] = std[7] = (40.0, 1.0)  # 1 box width along x: beyond lost_std = 0.3
    ints, floats = _table(state, hits, misses)
    floats[1, SCORE] = 0.0
    delete, conf, show = _advance(ints, floats, det, rescued, std)
    assert ints[:, STATE].tolist() == [C, T, T, C, K, K, K, K, S, C]
    assert delete.tolist() == [False, False, True, False, False, True, True, False, False,
                               False]
    assert conf.tolist() == [True] + [False] * 9
    # rows: the confirmed, the certain coasting, the stopped and the re-found ones; not the
    # tentative, the lost, nor the uncertain coasting one
    assert show.tolist() == [True, False, False, True, True, False, False, False, True, True]
    assert ints[:, MISSES].tolist() == [0, 0, 1, 0, 1, 11, 4, 2, 0, 0]
    assert ints[:, HITS].tolist() == [2, 1, 1, 10, 9, 9, 9, 9, 9, 10]
    assert (ints[:, LAST_K] == 7).tolist() == [True, True, False, True, False, False, False,
                                               False, True, True]


def test_confirmation_needs_the_scores_to_add_up() -> None:
    ints, floats = _table([T, T], [1, 1], [0, 0], score=[0.3, 0.6])
    zscore = np.array([0.3, 0.6])
    p = TrackerConfig(confirm_hits=2, confirm_score=1.0).life_cycle()
    delete, conf, _ = advance(ints, floats, np.array([0, 1], np.intp), np.zeros(2, bool),
                              np.full((2, 2), 5.0), np.full((2, 2), 40.0), zscore,
                              np.ones((2, 2)), np.zeros((2, 2)), 3, p)
    assert conf.tolist() == [False, True] and not delete.any()
    np.testing.assert_allclose(floats[:, SCORE], [0.6, 1.2])


def test_the_box_is_an_exponential_average_of_the_detections() -> None:
    ints, floats = _table([C], [5], [0], wh=(40.0, 90.0))
    advance(ints, floats, np.array([0], np.intp), np.zeros(1, bool), np.zeros((1, 2)),
            np.array([[60.0, 100.0]]), np.ones(1), np.ones((1, 2)), np.zeros((1, 2)), 1,
            TrackerConfig().life_cycle())
    np.testing.assert_allclose(floats[0, [W, H]], [50.0, 95.0])  # weight 0.5


def test_a_track_whose_prediction_leaves_the_image_ends_there() -> None:
    ints, floats = _table([C, C, C], [9, 9, 9], [0, 0, 0])
    centre = [[639.0, 200.0], [641.0, 200.0], [641.0, 200.0]]
    delete, _, _ = _advance(ints, floats, [-1, -1, 0], centre=centre,
                            frame_size=(640.0, 480.0))
    assert delete.tolist() == [False, True, False]  # the matched one stays, wherever


def test_births_are_the_unused_kept_boxes_that_overlap_no_track() -> None:
    dxy = np.array([[300.0, 100.0], [100.0, 100.0], [104.0, 100.0], [500.0, 500.0],
                    [200.0, 300.0], [200.0, 100.0]])
    dwh = np.full((6, 2), 40.0)
    dclass = np.array([2, 2, 1, 0, 1, 2], np.int8)
    used = np.array([False, False, False, False, False, True])
    txy, twh = np.array([[102.0, 100.0]]), np.array([[40.0, 40.0]])
    # row 1 and 2 overlap the track (IoU 0.9), row 3 is dropped, row 5 is used: 0 and 4 are
    # left, in (x, y) order
    assert births(dxy, dwh, dclass, used, txy, twh, 0.3).tolist() == [4, 0]
    # without the overlap rule the boxes on the track start tracks too
    assert births(dxy, dwh, dclass, used, txy, twh, np.inf).tolist() == [1, 2, 4, 0]


def test_birth_order_does_not_depend_on_row_order() -> None:
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 100, (12, 2))
    perm = rng.permutation(12)
    wh, cls = np.full((12, 2), 5.0), np.full(12, 2, np.int8)
    none = np.zeros((0, 2))
    a = births(xy, wh, cls, np.zeros(12, bool), none, none, 0.3)
    b = births(xy[perm], wh, cls, np.zeros(12, bool), none, none, 0.3)
    np.testing.assert_array_equal(xy[a], xy[perm][b])


def test_measurements_are_the_detections_or_the_rescue() -> None:
    det = np.array([1, -1, -1, 0], np.intp)
    dxy, dwh = np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[5.0, 6.0], [7.0, 8.0]])
    cscore = np.array([0.2, 0.7])
    found = np.array([True, True, False, True])
    fxy = np.array([[9.0, 9.0], [10.0, 11.0], [0.0, 0.0], [np.nan, 1.0]])
    z, zwh, zs, rescued, held = measurements(det, dxy, dwh, cscore, found, fxy)
    np.testing.assert_array_equal(z[[0, 1, 3]], [[3.0, 4.0], [10.0, 11.0], [1.0, 2.0]])
    assert np.isnan(z[2]).all() and np.isnan(zwh[1]).all()
    assert zs.tolist() == [0.7, 0.0, 0.0, 0.2]
    assert rescued.tolist() == [False, True, False, False]  # a detection wins over a rescue
    assert held.tolist() == [True, True, False, True]


def test_commit_hands_out_ids_in_birth_order_and_writes_the_rows() -> None:
    ints, floats = _table([T, C, T, T], [1, 9, 1, 1], [0, 0, 0, 0])
    ints[1, TID] = 1
    n = 4
    det = np.array([2, 0, -1, 1], np.intp)  # track 2 missed: it dies
    dxy = np.array([[10.0, 10.0], [30.0, 30.0], [50.0, 50.0], [400.0, 400.0]])
    dwh = np.full((4, 2), 40.0)
    dclass = np.full(4, 2, np.int8)
    cscore = np.ones(4)
    z, zwh, zs, rescued, _ = measurements(det, dxy, dwh, cscore, np.zeros(n, bool),
                                          np.zeros((n, 2)))
    pos = np.where(np.isfinite(z), z, 0.0)
    out = commit(ints, floats, det, rescued, z, zwh, zs, np.ones((n, 2)), pos, pos,
                 np.zeros((n, 2)), dxy, dwh, dclass, cscore, 5, TrackerConfig().life_cycle(),
                 2, 4)
    ints2, _, keep, new, tid, _, _, meas, _, pred, _, _, uid, next_id, next_uid, speed2, \
        n_speed = out
    assert keep.tolist() == [0, 1, 3] and new.tolist() == [3]  # the far box starts a track
    assert ints2[:, TID].tolist() == [2, 1, 3, -1]  # tracks 0 and 3 confirmed, in uid order
    assert ints2[3, UID] == 4 and next_uid == 5 and next_id == 4
    assert tid.tolist() == [2, 1, 3] and uid.tolist() == [0, 1, 3]  # the new one: tentative
    np.testing.assert_array_equal(meas, dxy[[2, 0, 1]])
    assert np.isfinite(pred).all()  # existing tracks' rows carry their prediction
    # the scene's speeds learn from the confirmed tracks that took a detection (here at rest)
    assert n_speed == 3 and speed2.tolist() == [0.0, 0.0]


def test_settings_in_frames_and_box_sizes() -> None:
    c10, c30 = TrackerConfig(fps=10), TrackerConfig(fps=30)
    wh = np.array([[40.0, 90.0]])
    r10, v10 = c10.noise(wh)
    r30, v30 = c30.noise(wh)
    np.testing.assert_allclose(r10, (0.1 * wh) ** 2)  # measurement: box sizes, any fps
    np.testing.assert_array_equal(r10, r30)
    np.testing.assert_allclose(v10, (1.5 * wh / 10) ** 2)  # velocity: per second
    np.testing.assert_allclose(v30 * 9, v10)
    q10, m10 = c10.accelerations(wh)
    np.testing.assert_allclose(q10, (1.0 * wh / 100) ** 2)
    np.testing.assert_allclose(m10, (15.0 * wh / 100) ** 2)
    a, b = c10.mode_switching()
    assert a == pytest.approx(1 - np.exp(-1 / 100)) and b == pytest.approx(1 - np.exp(-1 / 10))
    p = c10.life_cycle((640.0, 480.0))
    assert p[lc.P_MAX_MISSES] == 10 and p[lc.P_MIN_MISSES] == 3  # frames, any fps
    assert (p[lc.P_FRAME_W], p[lc.P_FRAME_H]) == (640.0, 480.0)
    from mvtrack.tracking.config import USER_SETTINGS

    assert list(c10.settings()) == list(USER_SETTINGS) and len(USER_SETTINGS) <= 20


def test_presets() -> None:
    p1 = paper1("rls", fps=30)
    assert (p1.predictor, p1.distance, p1.gate, p1.assign) == ("rls", "euclidean", 400.0,
                                                              "nearest")
    assert p1.max_misses == 3 and p1.warmup == 6 and p1.confirm_hits == 1
    assert paper1("kalman-ca", gate_px=10).gate == 100.0
    with pytest.raises(ValueError, match="kalman-ca"):
        paper1("kalman-cv")
    p2 = paper2()
    assert (p2.predictor, p2.distance, p2.gate, p2.assign) == ("kalman-ca", "coupled", None,
                                                              "nearest")
    d = preset("default", fps=10)
    assert d.fps == 10 and d == TrackerConfig(fps=10)
    assert preset("default", distance="euclidean").gate is None  # the new distance's own
    with pytest.raises(ValueError, match="paper3"):
        preset("paper3")


def _tf(frame, ids, states, xy):
    n = len(ids)
    xy = np.asarray(xy, float).reshape(n, 2)
    return TrackFrame(frame, np.array(ids), np.array(states), np.full(n, -1), xy, xy, xy,
                      np.tile([10.0, 6.0], (n, 1)), np.zeros((n, 2)))


def test_track_log_to_mot_rows() -> None:
    log = TrackLog()
    log.append(_tf(0, [2, 1], [C, C], [[50, 50], [20, 30]]))
    log.append(TrackFrame.empty(1))
    log.append(_tf(2, [1, 2, -1], [K, C, T], [[22, 31], [55, 52], [0, 0]]))
    rows = log.to_mot()
    np.testing.assert_array_equal(rows[:, 0], [1, 1, 3, 3])  # 1-based frames
    np.testing.assert_array_equal(rows[:, 1], [1, 2, 1, 2])  # sorted by frame, then id
    np.testing.assert_array_equal(rows[0, 2:6], [15, 27, 10, 6])  # left, top, w, h
    np.testing.assert_array_equal(rows[:, 6], [1, 1, 0.5, 1])  # coasting conf 0.5
    np.testing.assert_array_equal(rows[:, 7:], -1)
    no_coast = log.to_mot(include_coasting=False)
    assert no_coast[:, :2].tolist() == [[1, 1], [1, 2], [3, 2]]
    assert log.n_rows == 5 and len(log) == 3 and log.track_ids.tolist() == [1, 2]
    assert log.columns()["frame"].tolist() == [0, 0, 2, 2, 2]


def test_track_log_writes_results_atomically(tmp_path) -> None:
    from mvtrack.io.mot import read_tracks

    log = TrackLog()
    log.append(_tf(0, [1], [C], [[20, 30]]))
    log.append(_tf(1, [1], [K], [[22, 31]]))
    dest = tmp_path / "out" / "seq.txt"
    log.write_mot(dest)
    table = read_tracks(dest)
    assert table.frame.tolist() == [0, 1] and table.id.tolist() == [1, 1]
    np.testing.assert_allclose(table.tlwh[1], [17, 28, 10, 6])
    assert [p.name for p in dest.parent.iterdir()] == ["seq.txt"]


def test_the_kernels_equal_their_plain_functions() -> None:
    rng = np.random.default_rng(1)
    n = 30
    state = rng.choice([T, C, K, S], n)
    ints, floats = _table(state, rng.integers(0, 9, n), rng.integers(0, 12, n))
    det = np.where(rng.random(n) < 0.6, rng.integers(0, 20, n), -1).astype(np.intp)
    args = (det, np.zeros(n, bool) | (rng.random(n) < 0.1), rng.uniform(0, 500, (n, 2)),
            np.full((n, 2), 40.0), rng.random(n), rng.uniform(0, 40, (n, 2)),
            rng.uniform(-10, 700, (n, 2)), 3, TrackerConfig().life_cycle((640.0, 480.0)))
    i1, f1 = ints.copy(), floats.copy()
    i2, f2 = ints.copy(), floats.copy()
    for a, b in zip(advance(i1, f1, *args), advance.py_func(i2, f2, *args), strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(i1, i2)
    np.testing.assert_array_equal(f1, f2)
