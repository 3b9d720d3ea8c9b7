"""The life cycle as pure functions, the physical-unit conversion, and the track log."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking import TrackerConfig, TrackLog, paper1, paper2, preset
from mvtrack.tracking.lifecycle import birth_order, count_hits, hand_out_ids, next_state
from mvtrack.tracking.table import AGE, HITS, MISSES, STATE, TID, UID
from mvtrack.types import TrackFrame, TrackState

T, C, K, S = (int(s) for s in (TrackState.TENTATIVE, TrackState.CONFIRMED,
                               TrackState.COASTING, TrackState.STOPPED))


def _ints(state, hits, misses, age):
    n = len(state)
    a = np.zeros((n, 8), dtype=np.int64)
    a[:, UID] = np.arange(n)
    a[:, TID] = np.where(np.array(state) == T, -1, np.arange(1, n + 1))
    a[:, STATE], a[:, HITS], a[:, MISSES], a[:, AGE] = state, hits, misses, age
    return a


def test_frames_conversion_is_physical() -> None:
    c10 = TrackerConfig(fps=10, max_coast=0.5, confirm_hits=3, confirm_window=0.6,
                        init_velocity_std=100.0, accel_std=200.0, recover_speed=300.0)
    c30 = c10.replace(fps=30)
    f10, f30 = c10.frames(), c30.frames()
    assert (f10.max_misses, f30.max_misses) == (5, 15)
    assert (f10.confirm_window, f30.confirm_window) == (6, 18)
    assert f10.init_velocity_std == pytest.approx(10.0) and f30.init_velocity_std == pytest.approx(
        100 / 30)
    assert f10.accel_std == pytest.approx(2.0) and f30.accel_std == pytest.approx(200 / 900)
    assert f10.recover_speed == pytest.approx(30.0) and f30.recover_speed == pytest.approx(10.0)
    # 0.1 s at 30 fps is 3 frames despite 0.1 * 30 = 3.0000000000000004
    assert TrackerConfig(fps=30, max_coast=0.1).frames().max_misses == 3


def test_counters_advance_in_place() -> None:
    a = _ints([C, C, T], [5, 2, 1], [0, 3, 0], [9, 8, 1])
    matched = np.array([True, False, False])
    count_hits(a, matched, np.array([0]))
    assert a[:, HITS].tolist() == [6, 2, 1]
    assert a[:, MISSES].tolist() == [0, 4, 1]
    assert a[:, AGE].tolist() == [10, 9, 2]


def test_state_transitions() -> None:
    fp = TrackerConfig(fps=30, confirm_hits=3, max_coast=2 / 30).frames()
    # rows: tentative confirmed now, tentative still short, tentative missed, confirmed hit,
    # confirmed missed (coasting, 2 misses: kept), coasting too long (3 misses: deleted),
    # stopped, coasting that gets a detection again
    state = [T, T, T, C, C, K, K, K]
    hits = [3, 2, 2, 9, 9, 9, 9, 9]
    misses = [0, 0, 1, 0, 2, 3, 0, 0]
    age = [3, 2, 2, 20, 20, 20, 20, 20]
    matched = np.array([1, 1, 0, 1, 0, 0, 0, 1], bool)
    rescued = np.array([0, 0, 0, 0, 0, 0, 1, 0], bool)
    new, delete, conf = next_state(_ints(state, hits, misses, age), matched, rescued, fp)
    assert new.tolist() == [C, T, T, C, K, K, S, C]
    assert delete.tolist() == [False, False, True, False, False, True, False, False]
    assert conf.tolist() == [True] + [False] * 7


def test_confirmation_window_ends_a_slow_tentative_track() -> None:
    fp = TrackerConfig(fps=30, confirm_hits=3, confirm_window=4 / 30,
                       tentative_max_coast=1 / 30).frames()
    a = _ints([T, T, T], [2, 3, 2], [0, 0, 1], [4, 4, 3])
    state, delete, conf = next_state(a, np.array([1, 1, 0], bool), None, fp)
    assert state.tolist() == [T, C, T]
    assert conf.tolist() == [False, True, False]
    assert delete.tolist() == [True, False, False]  # window over / confirmed / one miss is ok


def test_ids_are_handed_out_consecutively_in_row_order() -> None:
    a = _ints([T, C, T, T], [3, 5, 3, 1], [0, 0, 0, 0], [3, 9, 3, 1])
    a[1, TID] = 1
    nxt = hand_out_ids(a, np.array([True, False, True, False]), 2)
    assert a[:, TID].tolist() == [2, 1, 3, -1] and nxt == 4


def test_birth_order_does_not_depend_on_row_order() -> None:
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 100, (12, 2))
    perm = rng.permutation(12)
    np.testing.assert_array_equal(xy[birth_order(xy)], xy[perm][birth_order(xy[perm])])


def test_presets() -> None:
    p1 = paper1("rls", fps=30)
    assert (p1.predictor, p1.distance, p1.gate, p1.assign) == ("rls", "euclidean", 400.0,
                                                              "nearest")
    assert p1.frames().max_misses == 3 and p1.warmup and p1.confirm_hits == 1
    assert paper1("kalman-ca", gate_px=10).gate == 100.0
    with pytest.raises(ValueError, match="kalman-ca"):
        paper1("kalman-cv")
    p2 = paper2()
    assert (p2.predictor, p2.distance, p2.gate, p2.assign) == ("kalman-ca", "coupled", None,
                                                              "nearest")
    d = preset("default", fps=10)
    assert d.fps == 10 and d == TrackerConfig(fps=10)
    # changing the distance of a preset falls back to that distance's own gate
    assert preset("default", distance="mahalanobis").gate is None
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


def test_paper_presets_count_their_coasting_in_frames_at_any_frame_rate() -> None:
    """Paper 1's "3 frames without a detection" is 3 frames at every frame rate, including
    those where 3 / fps × fps does not come back as exactly 3; seconds still convert."""
    from mvtrack.tracking import Frames, preset

    for fps in (7.0, 10.0, 15.0, 29.97, 30.0, 59.94, 1e-3):
        for name in ("paper1", "paper2"):
            assert preset(name, fps=fps).frames().max_misses == 3
    assert TrackerConfig(fps=10, max_coast=Frames(5)).frames().max_misses == 5
    assert TrackerConfig(fps=10, max_coast=0.5).frames().max_misses == 5
    assert str(Frames(3)) == "3 frames" and repr(Frames(3)) == "Frames(3)"


def _edge_run(frame_size) -> list[list[int]]:
    """Vehicle A drives right out of a 100 px wide image (last seen at x = 98, frame 19);
    from frame 21 vehicle B enters at the same edge, 6 px lower, driving left."""
    from mvtrack.tracking import Tracker
    from mvtrack.types import Detections

    tracker = Tracker(TrackerConfig(fps=30.0, frame_size=frame_size))
    ids = []
    for k in range(30):
        xy = ([[3.0 + 5 * k, 50.0]] if k < 20 else []) + (
            [[97.0 - 5 * (k - 21), 56.0]] if k >= 21 else [])
        d = Detections(k, np.array(xy).reshape(-1, 2), np.tile([10.0, 6.0], (len(xy), 1)))
        ids.append(tracker.step(d).track_id.tolist())
    return ids


def test_a_track_whose_prediction_leaves_the_image_ends_there() -> None:
    ids = _edge_run((100.0, 100.0))
    assert ids[19] == [1] and ids[20] == [] and ids[21] == []  # predicted at 103: gone
    assert all(i == [2] for i in ids[22:])  # B is a new object
    # without the image's size A coasts on past the edge and its recovery takes B
    assert all(i == [1] for i in _edge_run(None)[20:])


@pytest.mark.parametrize("bad", [(0, 10), (10,), "640x480", (10, float("inf"))])
def test_frame_size_must_be_two_positive_numbers(bad) -> None:
    with pytest.raises(ValueError, match="frame_size"):
        TrackerConfig(frame_size=bad)
    assert TrackerConfig(frame_size=[640, 480]).frame_size == (640.0, 480.0)
