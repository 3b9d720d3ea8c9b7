"""Exact-identity scenarios of the tracker: crossing, gaps, birth and death, shuffled input."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking import (
    Tracker,
    TrackerConfig,
    TrackLog,
    paper1,
    paper2,
    track_detections,
)
from mvtrack.types import Detections, TrackState

WH = np.array([[20.0, 15.0]])


def _frames(paths: dict[int, np.ndarray], n_frames: int, skip=None) -> list[Detections]:
    """Detections of targets ``paths[i]`` (n_frames, 2; NaN = absent), rows in target order."""
    out = []
    for k in range(n_frames):
        xy = [p[k] for i, p in sorted(paths.items()) if np.isfinite(p[k]).all()]
        if skip is not None:
            xy = [z for i, z in enumerate(xy) if (k, i) not in skip]
        xy = np.array(xy).reshape(-1, 2)
        out.append(Detections(k, xy, np.repeat(WH, len(xy), axis=0)))
    return out


def _line(start, velocity, n) -> np.ndarray:
    return np.asarray(start, float) + np.arange(n)[:, None] * np.asarray(velocity, float)


def _id_of_target(log: TrackLog, frames: list[Detections], target_xy: np.ndarray) -> np.ndarray:
    """Per frame, the ID of the row whose detection is the target's (0 when none)."""
    ids = np.zeros(len(frames), dtype=np.int64)
    for k, tf in enumerate(log):
        for tid, j in zip(tf.track_id, tf.det_index, strict=True):
            if j >= 0 and np.allclose(frames[k].xy[j], target_xy[k]):
                ids[k] = tid
    return ids


CONFIGS = {
    "default": TrackerConfig(),
    "kalman-ca+euclidean+greedy": TrackerConfig(
        predictor="kalman-ca", distance="euclidean", gate=400.0, assign="greedy"
    ),
    "rls+uncoupled+optimal": TrackerConfig(predictor="rls", distance="uncoupled", gate=50.0),
    "coupled+mahalanobis+optimal": TrackerConfig(
        predictor="kalman-coupled", distance="mahalanobis", gate=30.0
    ),
    "paper2 (coupled gate, nearest)": paper2(fps=30.0),
}


@pytest.mark.parametrize("name", list(CONFIGS))
def test_two_crossing_targets_keep_their_ids(name: str) -> None:
    n = 60
    a = _line([100.0, 300.0], [4.0, 0.0], n)  # left to right
    b = _line([100.0, 422.0], [4.0, -4.0], n)  # lower left to upper right, crosses a at k≈30
    frames = _frames({0: a, 1: b}, n)
    log = track_detections(frames, CONFIGS[name])
    ida = _id_of_target(log, frames, a)
    idb = _id_of_target(log, frames, b)
    confirmed = slice(CONFIGS[name].confirm_hits - 1, n)
    # the same ID follows each target through the crossing, and the two IDs differ
    assert len(set(ida[confirmed])) == 1 and len(set(idb[confirmed])) == 1
    assert ida[-1] != idb[-1] and {ida[-1], idb[-1]} == {1, 2}
    assert log.track_ids.tolist() == [1, 2]


def test_gap_is_bridged_by_coasting_with_the_same_id() -> None:
    n = 50
    a = _line([50.0, 50.0], [3.0, 1.0], n)
    a[20:26] = np.nan  # six missed frames (0.2 s at 30 fps; max_coast is 1 s)
    frames = _frames({0: a}, n)
    log = track_detections(
        frames, TrackerConfig(confirm_hits=3, max_coast=1.0, coast_output=None)
    )
    assert log.track_ids.tolist() == [1]
    for k, tf in enumerate(log):
        assert tf.track_id.tolist() == [1]
        if k < 2:  # tentative then, written with the ID it got on confirmation (backfill)
            assert tf.state.tolist() == [TrackState.TENTATIVE]
            assert tf.det_index.tolist() == [0]
            continue
        if 20 <= k < 26:
            assert tf.state.tolist() == [TrackState.COASTING]
            assert tf.det_index.tolist() == [-1]
            assert np.isnan(tf.measured_xy).all()
            # the predicted box is output: it continues the motion
            np.testing.assert_allclose(tf.filtered_xy[0], [50 + 3 * k, 50 + k], atol=0.5)
        else:
            assert tf.state.tolist() == [TrackState.CONFIRMED]
            assert tf.det_index.tolist() == [0]
            np.testing.assert_array_equal(tf.measured_xy[0], a[k])


def test_birth_and_death_at_the_right_frames() -> None:
    n = 60
    a = np.full((n, 2), np.nan)
    a[5:31] = _line([200.0, 100.0], [2.0, 2.0], 26)  # present in frames 5..30
    # coasts 6 frames at 30 fps, every coasting row output
    config = TrackerConfig(confirm_hits=3, max_coast=0.2, coast_output=None)
    log = track_detections(_frames({0: a}, n), config)
    shown = [k for k, tf in enumerate(log) if len(tf)]
    # born at 5, confirmed on its 3rd hit (frame 7), coasts 31..36, deleted at 37; its
    # tentative rows 5 and 6 are written once it is confirmed (backfill)
    assert shown == list(range(5, 37))
    states = {k: int(log[k].state[0]) for k in shown}
    assert states[5] == states[6] == TrackState.TENTATIVE
    assert all(states[k] == TrackState.CONFIRMED for k in range(7, 31))
    assert all(states[k] == TrackState.COASTING for k in range(31, 37))


def test_tentative_tracks_are_output_with_id_minus_one_when_asked() -> None:
    a = _line([10.0, 10.0], [1.0, 0.0], 5)
    config = TrackerConfig(confirm_hits=3, output_tentative=True, min_track_length=None)
    log = track_detections(_frames({0: a}, 5), config)
    assert [tf.track_id.tolist() for tf in log] == [[-1], [-1], [1], [1], [1]]
    assert [int(tf.state[0]) for tf in log] == [0, 0, 1, 1, 1]
    assert log.to_mot()[:, 0].tolist() == [3, 4, 5]  # tentative rows are never written


def test_confirmation_needs_hits_within_the_window() -> None:
    a = _line([10.0, 10.0], [1.0, 0.0], 12)
    a[1] = a[3] = np.nan  # hits at 0, 2, 4, 5, ...
    strict_config = TrackerConfig(confirm_hits=3, backfill=False, min_track_length=None)
    strict = track_detections(_frames({0: a}, 12), strict_config)
    # consecutive hits required: the track born at 0 dies at its first miss, and so on
    assert strict.track_ids.tolist() == [1]
    assert next(k for k, tf in enumerate(strict) if len(tf)) == 6
    lenient_config = strict_config.replace(confirm_window=5 / 30, tentative_max_coast=1 / 30)
    lenient = track_detections(_frames({0: a}, 12), lenient_config)
    assert next(k for k, tf in enumerate(lenient) if len(tf)) == 4
    # with backfill the confirmed track is written from its birth (4, resp. 0); the strict
    # run's tracks born at 0 and 2 were never confirmed and leave no rows
    for config, born in ((strict_config, 4), (lenient_config, 0)):
        filled = track_detections(_frames({0: a}, 12), config.replace(backfill=True))
        assert filled.track_ids.tolist() == [1]
        assert [k for k, tf in enumerate(filled) if len(tf)] == list(range(born, 12))


def test_backfill_changes_nothing_but_the_early_rows() -> None:
    rng = np.random.default_rng(5)
    frames = _random_scene(rng, 15, 30)
    online = track_detections(frames, TrackerConfig(backfill=False)).to_mot()
    filled = track_detections(frames, TrackerConfig()).to_mot()
    # every online row is there unchanged; the extra rows precede their track's first
    # online row
    key = [tuple(r) for r in filled[:, :6]]
    assert {tuple(r) for r in online[:, :6]} <= set(key)
    first = {int(i): online[online[:, 1] == i, 0].min() for i in np.unique(online[:, 1])}
    extra = [r for r in filled if tuple(r[:6]) not in {tuple(o) for o in online[:, :6]}]
    assert extra and all(r[0] < first[int(r[1])] for r in extra)


def _random_scene(rng: np.random.Generator, n_targets: int, n_frames: int):
    p = rng.uniform(0, 600, (n_targets, 2))
    v = rng.uniform(-3, 3, (n_targets, 2))
    frames = []
    for k in range(n_frames):
        seen = rng.random(n_targets) > 0.1
        xy = p[seen] + (k * v[seen]) + rng.normal(0, 1.0, (int(seen.sum()), 2))
        clutter = rng.uniform(0, 600, (rng.poisson(2), 2))
        xy = np.vstack([xy, clutter])
        wh = np.tile([20.0, 15.0], (len(xy), 1)) + rng.normal(0, 0.5, (len(xy), 2))
        frames.append(Detections(k, xy, wh))
    return frames


@pytest.mark.parametrize("assign", ["nearest", "greedy", "optimal"])
def test_shuffled_detection_order_gives_identical_tracks(assign: str) -> None:
    rng = np.random.default_rng(7)
    frames = _random_scene(rng, 30, 40)
    perms = [rng.permutation(len(d)) for d in frames]
    shuffled = [d.take(p) for d, p in zip(frames, perms, strict=True)]
    config = TrackerConfig(assign=assign, predictor_params={"r": 1.0})
    a = track_detections(frames, config)
    b = track_detections(shuffled, config)
    assert a.track_ids.size > 20
    for ta, tb, p in zip(a, b, perms, strict=True):
        oa, ob = np.argsort(ta.track_id), np.argsort(tb.track_id)
        np.testing.assert_array_equal(ta.track_id[oa], tb.track_id[ob])
        np.testing.assert_array_equal(ta.state[oa], tb.state[ob])
        np.testing.assert_array_equal(ta.filtered_xy[oa], tb.filtered_xy[ob])
        # det_index refers to each input's own row order
        ja, jb = ta.det_index[oa], tb.det_index[ob]
        np.testing.assert_array_equal(ja, np.where(jb >= 0, p[jb], -1))


def test_rows_link_to_the_detection_they_used() -> None:
    rng = np.random.default_rng(3)
    frames = _random_scene(rng, 15, 30)
    log = track_detections(frames, TrackerConfig())
    n_linked = 0
    for tf, dets in zip(log, frames, strict=True):
        linked = tf.det_index >= 0
        n_linked += int(linked.sum())
        np.testing.assert_array_equal(tf.measured_xy[linked], dets.xy[tf.det_index[linked]])
        # rows with a detection: confirmed, or tentative then (backfilled)
        assert np.all(np.isin(tf.state[linked], [TrackState.CONFIRMED, TrackState.TENTATIVE]))
        assert np.all(tf.state[~linked] == TrackState.COASTING)
        assert np.isnan(tf.measured_xy[~linked]).all()
        # one detection per track under exclusive assignment
        assert len(set(tf.det_index[linked].tolist())) == int(linked.sum())
    assert n_linked > 300


def test_ids_are_consecutive_from_one() -> None:
    rng = np.random.default_rng(11)
    log = track_detections(_random_scene(rng, 25, 30), TrackerConfig())
    ids = log.track_ids
    np.testing.assert_array_equal(ids, np.arange(1, ids.size + 1))
    # IDs appear in order of confirmation
    first_seen = [int(np.flatnonzero(log.columns()["track_id"] == i)[0]) for i in ids]
    assert first_seen == sorted(first_seen)


@pytest.mark.parametrize("fps", [10.0, 30.0])
def test_physical_units_give_the_same_behaviour_at_10_and_30_fps(fps: float) -> None:
    seconds = 4.0
    n = int(seconds * fps)
    t = np.arange(n) / fps
    a = np.stack([100 + 60 * t, 200 + 30 * t], axis=1)  # 60 px/s, 30 px/s
    gone_short = (t >= 1.0) & (t < 1.4)  # a 0.4 s gap: bridged (max_coast 0.5 s)
    gone_long = (t >= 2.5) & (t < 3.2)  # a 0.7 s gap: the track is lost
    a[gone_short | gone_long] = np.nan
    config = TrackerConfig(
        fps=fps, max_coast=0.5, confirm_hits=2, init_velocity_std=120.0, accel_std=30.0,
        distance="euclidean", gate=15.0**2, coast_output=None,
        relink_window=None,  # the life cycle alone (relinking: test_tracker_relink.py)
    )
    log = track_detections(_frames({0: a}, n), config)
    c = log.columns()
    ids_by_time = {}
    for k, tf in enumerate(log):
        ids_by_time[round(t[k], 2)] = tf.track_id.tolist()
    assert log.track_ids.tolist() == [1, 2]
    assert ids_by_time[1.2] == [1]  # coasting through the short gap
    assert ids_by_time[1.5] == [1]
    # coasts 0.5 s after its last detection at t = 2.5 - 1/fps, then is deleted
    assert ids_by_time[2.9] == [1] and ids_by_time[3.0] == []
    assert ids_by_time[3.5] == [2]
    t_coast = t[c["frame"][c["state"] == TrackState.COASTING]]
    last_coast_of_1 = t_coast[t_coast < 3.2].max()
    assert last_coast_of_1 == pytest.approx(2.5 - 1 / fps + 0.5, abs=1e-9)


def test_rescue_holds_a_stopped_track_and_a_detection_confirms_it_again() -> None:
    n = 60
    a = _line([100.0, 100.0], [2.0, 0.0], n)
    a[20:] = a[20]  # the vehicle stops at frame 20 ...
    detected = np.ones(n, bool)
    detected[22:45] = False  # ... fades into the background, then moves on
    a[45:] = a[20] + np.arange(1, n - 44)[:, None] * [2.0, 0.0]
    frames = _frames({0: np.where(detected[:, None], a, np.nan)}, n)
    calls = []

    def rescue(uids, xy, wh):
        calls.append((uids.copy(), xy.copy(), wh.copy()))
        return np.ones(len(uids), bool), np.repeat(a[20][None], len(uids), axis=0)

    tracker = Tracker(TrackerConfig(max_coast=0.1))  # would be deleted after 3 misses
    out = [tracker.step(d, rescue=rescue) for d in frames]
    assert all(tf.track_id.tolist() == [1] for tf in out[2:])
    states = [int(tf.state[0]) for tf in out[2:]]
    assert states[22 - 2 : 45 - 2] == [TrackState.STOPPED] * 23
    assert states[45 - 2 :] == [TrackState.CONFIRMED] * (n - 45)
    assert len(calls) == 23 and all(c[0].tolist() == [0] for c in calls)
    assert tracker.row_uids.tolist() == [0]  # the uid the rescue callback saw, row-aligned
    np.testing.assert_array_equal(calls[0][2], WH)
    stopped = out[30]
    assert stopped.det_index.tolist() == [-1]
    np.testing.assert_array_equal(stopped.measured_xy[0], a[20])


def test_rescue_is_not_offered_tentative_tracks_and_unfound_tracks_coast() -> None:
    a = _line([10.0, 10.0], [1.0, 0.0], 10)
    a[5:] = np.nan
    seen = []

    def rescue(uids, xy, wh):
        seen.append(uids.tolist())
        return np.zeros(len(uids), bool), np.full((len(uids), 2), np.nan)

    tracker = Tracker(TrackerConfig(coast_output=None))
    out = [tracker.step(d, rescue=rescue) for d in _frames({0: a}, 10)]
    assert seen == [[0]] * 5
    assert [int(tf.state[0]) for tf in out[5:]] == [TrackState.COASTING] * 5


def test_paper1_warmup_gate_centre_is_the_linear_extrapolation() -> None:
    a = _line([50.0, 60.0], [3.0, -1.0], 12)
    a += np.random.default_rng(0).normal(0, 0.3, a.shape)
    log = track_detections(_frames({0: a}, 12), paper1("kalman-ca"))
    assert log.track_ids.tolist() == [1]
    np.testing.assert_array_equal(log[1].predicted_xy[0], a[0])  # y_k after one association
    for k in range(2, 6):  # hits 2..5 < 2M = 6: centre 2 y_{k-1} − y_{k-2}
        np.testing.assert_allclose(log[k].predicted_xy[0], 2 * a[k - 1] - a[k - 2], rtol=1e-12)
    assert not np.allclose(log[7].predicted_xy[0], 2 * a[6] - a[5])  # the filter's own now


def test_paper1_nearest_is_non_exclusive() -> None:
    a = _line([100.0, 100.0], [2.0, 0.0], 10)
    b = _line([100.0, 110.0], [2.0, 0.0], 10)
    b[5:] = np.nan  # b disappears; both tracks now take a's detection (paper 1 rule)
    log = track_detections(_frames({0: a, 1: b}, 10), paper1("kalman-ca"))
    assert log[6].det_index.tolist() == [0, 0]


@pytest.mark.parametrize(
    "changes",
    [
        {"fps": 0.0}, {"fps": float("nan")}, {"gate": -1.0}, {"confirm_hits": 0},
        {"max_coast": -0.1}, {"assign": "hungarian"}, {"size_smoothing": 0.0},
        {"confirm_window": 0.0}, {"init_velocity_std": -5.0}, {"warmup_hits": 1},
        {"predictor": ""}, {"predictor_params": [1, 2]}, {"distance": "iou", "gate": 100.0},
        {"recover_speed": 0.0}, {"second_gate": -2.0}, {"recover_window": 0.0},
        {"size_ref": 0.0}, {"coast_output": -0.1}, {"coast_output": float("inf")},
        {"size_weight": 1.0}, {"size_weight": -0.1},
    ],
)
def test_bad_config_values_raise_value_error(changes: dict) -> None:
    with pytest.raises(ValueError, match=next(iter(changes))):
        TrackerConfig(**changes)


@pytest.mark.parametrize(
    "changes, word",
    [({"predictor": "kalman-xx"}, "kalman-xx"), ({"distance": "manhattan"}, "manhattan"),
     ({"predictor_params": {"r": -1.0}}, "r")],
)
def test_unknown_names_raise_value_error(changes: dict, word: str) -> None:
    with pytest.raises(ValueError, match=word):
        Tracker(TrackerConfig(**changes))


def test_track_detections_fills_skipped_frames_and_rejects_disorder() -> None:
    a = _line([10.0, 10.0], [1.0, 0.0], 6)
    frames = _frames({0: a}, 6)
    config = TrackerConfig(min_track_length=None)  # a 6-frame track
    log = track_detections([frames[0], frames[1], frames[2], frames[5]], config)
    assert [tf.frame for tf in log] == [0, 1, 2, 3, 4, 5]
    assert [int(tf.state[0]) for tf in log[2:]] == [1, 2, 2, 1]
    with pytest.raises(ValueError, match="frame 1"):
        track_detections([frames[2], frames[1]], TrackerConfig())


def test_coasting_rows_are_output_only_for_coast_output_but_the_track_lives_on() -> None:
    a = _line([100.0, 100.0], [2.0, 0.0], 20)
    a[8:14] = np.nan  # a 6-frame gap, shorter than max_coast = 0.3 s = 9 frames at 30 fps
    config = TrackerConfig(fps=30.0, max_coast=0.3, coast_output=2 / 30, interpolate=False)
    log = track_detections(_frames({0: a}, 20), config)
    ids = [tf.track_id.tolist() for tf in log]
    states = [tf.state.tolist() for tf in log]
    assert ids[8:10] == [[1], [1]] and states[8:10] == [[TrackState.COASTING]] * 2
    assert ids[10:14] == [[]] * 4  # still alive, no longer output
    assert ids[14:] == [[1]] * 6 and states[14] == [TrackState.CONFIRMED]  # same ID after
    every = track_detections(_frames({0: a}, 20), config.replace(coast_output=None))
    assert [tf.track_id.tolist() for tf in every][8:14] == [[1]] * 6


def test_interpolation_writes_a_bridged_gap_on_the_line_and_cuts_the_tail() -> None:
    a = _line([100.0, 100.0], [2.0, 1.0], 30)
    a[8:14] = np.nan  # bridged: the track is associated again at frame 14
    a[22:] = np.nan  # the target leaves: the track coasts 9 frames and is deleted
    config = TrackerConfig(fps=30.0, max_coast=0.3, coast_output=2 / 30)
    log = track_detections(_frames({0: a}, 30), config)
    plain = track_detections(_frames({0: a}, 30), config.replace(interpolate=False))
    # every row of the gap is written, on the straight line between the filtered positions
    # of frames 7 and 14; the rows with a measurement are those of the run without it
    assert [tf.track_id.tolist() for tf in log][8:14] == [[1]] * 6
    assert all(int(log[k].state[0]) == TrackState.COASTING for k in range(8, 14))
    x7, x14 = log[7].filtered_xy[0], log[14].filtered_xy[0]
    for k in range(8, 14):
        t = (k - 7) / 7
        np.testing.assert_allclose(log[k].filtered_xy[0], (1 - t) * x7 + t * x14)
        np.testing.assert_allclose(log[k].velocity[0], (x14 - x7) / 7)
    for k in [*range(8), *range(14, 22)]:
        np.testing.assert_array_equal(log[k].filtered_xy, plain[k].filtered_xy)
    # after the last detection only coast_output (2 frames) is written, as without it
    assert [len(tf) for tf in log][22:] == [1, 1] + [0] * 6
    assert [len(tf) for tf in plain][22:] == [1, 1] + [0] * 6


def _jump_frames(wh: np.ndarray, jump: np.ndarray) -> list[Detections]:
    """A still target at (200, 200) for 6 frames, then one detection displaced by ``jump``."""
    out = [Detections(k, [[200.0, 200.0]], wh[None]) for k in range(6)]
    out.append(Detections(6, [[200.0 + jump[0], 200.0 + jump[1]]], wh[None]))
    return out


@pytest.mark.parametrize(
    "wh, jump, size_ref, kept",
    [
        # a 120 x 40 px box stretches the 10 px gate to 30 px along x, not along y
        ((120.0, 40.0), (25.0, 0.0), 40.0, True),
        ((120.0, 40.0), (0.0, 25.0), 40.0, False),
        ((40.0, 120.0), (0.0, 25.0), 40.0, True),
        ((120.0, 40.0), (25.0, 0.0), None, False),  # no scaling: 10 px in both
        ((30.0, 30.0), (12.0, 0.0), 40.0, False),  # boxes below size_ref: unscaled
        ((30.0, 30.0), (8.0, 0.0), 40.0, True),
    ],
)
def test_euclidean_gate_stretches_with_the_box_per_axis(wh, jump, size_ref, kept) -> None:
    config = TrackerConfig(
        size_ref=size_ref, second_gate=None, recover_speed=None, min_track_length=None
    )
    log = track_detections(_jump_frames(np.array(wh), np.array(jump)), config)
    last = log[6]
    assert (last.track_id.tolist() == [1] and last.det_index.tolist() == [0]) == kept


def test_measurement_noise_scales_with_the_larger_box_factor() -> None:
    wh = np.array([160.0, 80.0])  # f_x = 4, f_y = 2 at size_ref 40: r = 2² · 4² px²
    frames = _jump_frames(wh, np.array([0.0, 0.0]))
    scaled = Tracker(TrackerConfig(size_ref=40.0, measurement_std=2.0))
    plain = Tracker(TrackerConfig(size_ref=None, measurement_std=2.0 * 4.0))
    for d in frames:
        a, b = scaled.step(d), plain.step(d)
    np.testing.assert_allclose(scaled.pstate.P, plain.pstate.P, rtol=1e-12)
    np.testing.assert_allclose(a.filtered_xy, b.filtered_xy, rtol=1e-12)


@pytest.mark.parametrize("weight, small_takes", [(0.0, 0), (0.5, 1)])
def test_size_term_gives_the_small_box_to_the_small_track(weight, small_takes) -> None:
    # a small (20 px) and a large (44 px) box stand 8 px apart; then two detections appear
    # between them: by position alone the small track's nearest is the large box (16 vs
    # 20.25 px²), with the size term it is the small one
    still = [
        Detections(k, [[100.0, 100.0], [108.0, 100.0]], [[20.0, 20.0], [44.0, 44.0]])
        for k in range(5)
    ]
    last = Detections(5, [[104.0, 100.0], [104.5, 100.0]], [[44.0, 44.0], [20.0, 20.0]])
    config = TrackerConfig(
        size_weight=weight, second_gate=None, recover_speed=None, size_gate=None,
        min_track_length=None,
    )
    log = track_detections([*still, last], config)
    out = log[5]
    by_id = dict(zip(out.track_id.tolist(), out.det_index.tolist(), strict=True))
    assert sorted(by_id) == [1, 2]  # track 1 is the small box (born first: lower x)
    assert by_id[1] == small_takes and by_id[2] == 1 - small_takes


def test_size_gate_keeps_a_box_of_another_size_from_a_track() -> None:
    # a 100 × 200 px person walks right; from frame 12 on only a 40 × 90 px box is detected
    # 3 px from its path (someone else, farther away): with the size gate a new track starts.
    # The box is inside the first gate and the recovery radius: every stage must refuse it.
    n = 20
    xy = _line([300.0, 200.0], [2.0, 0.0], n)
    frames = []
    for k in range(n):
        small = k >= 12
        p = xy[k] + (3.0 if small else 0.0, 0.0)
        wh = [[40.0, 90.0]] if small else [[100.0, 200.0]]
        frames.append(Detections(k, p[None], np.array(wh)))
    config = TrackerConfig(fps=25.0, size_gate=None)
    assert track_detections(frames, config).track_ids.tolist() == [1]
    assert TrackerConfig().size_gate == 1.5  # on by default
    gated = track_detections(frames, config.replace(size_gate=2.0))
    assert gated.track_ids.tolist() == [1, 2]
    assert gated[n - 1].track_id.tolist() == [2]
    np.testing.assert_allclose(gated[n - 1].wh, [[40.0, 90.0]])
    # a ratio of 2 or less still passes: the same run with a 60 × 120 px box keeps one ID
    for tf in frames[12:]:
        tf.wh[:] = [60.0, 120.0]
    assert track_detections(frames, config.replace(size_gate=2.0)).track_ids.tolist() == [1]


def test_size_gate_is_loose_on_the_width_a_stride_changes() -> None:
    # a walker seen from the side: the box is 40 or 62 px wide by turns (legs together, legs
    # apart; 62 / 40 > 1.5), always 150 px high: one track, with the default gate of 1.5;
    # gating the width at 1.5 too would refuse every other box
    n = 30
    xy = _line([300.0, 200.0], [3.0, 0.0], n)
    frames = [Detections(k, xy[k][None], np.array([[62.0 if k % 2 else 40.0, 150.0]]))
              for k in range(n)]
    log = track_detections(frames, TrackerConfig(fps=25.0))
    assert log.track_ids.tolist() == [1]
    assert all(tf.det_index.tolist() == [0] for tf in log[2:])


def _lower_body_frames(n, hidden):
    """A 60 × 150 px person walking right at 2 px/frame, detected whole except on the frames
    ``hidden``, where only the lower body is: a 50 × 90 px box on the same bottom edge."""
    xy = _line([300.0, 200.0], [2.0, 0.0], n)
    frames = []
    for k in range(n):
        if k in hidden:
            c, wh = xy[k] + (1.0, 30.0), [[50.0, 90.0]]  # bottom edge 275, as the person's
        else:
            c, wh = xy[k], [[60.0, 150.0]]
        frames.append(Detections(k, c[None], np.array(wh)))
    return xy, frames


def test_a_partial_view_below_an_occluder_keeps_the_track_and_its_box() -> None:
    # the lower body alone for 15 frames (0.6 s, longer than a track coasts): the size gate
    # (150 / 90 > 1.5) lets it through as a partial view; the track measures the foot point
    # and keeps its own box, so its rows stay on the whole person
    n, hidden = 40, range(12, 27)
    xy, frames = _lower_body_frames(n, hidden)
    config = TrackerConfig(fps=25.0)
    assert config.partial_tolerance == 0.15  # on by default
    log = track_detections(frames, config)
    assert log.track_ids.tolist() == [1]
    for k in hidden:
        tf = log[k]
        assert tf.track_id.tolist() == [1] and tf.det_index.tolist() == [0]
        np.testing.assert_allclose(tf.wh, [[60.0, 150.0]])
        # measured: the centre of the track's box standing on the detection's bottom edge
        np.testing.assert_allclose(tf.measured_xy[0], xy[k] + (1.0, 0.0))
        assert np.abs(tf.filtered_xy[0] - xy[k]).max() < 2.0  # the whole person's centre
    # without the rule the gate refuses the lower body: the track is lost, the lower body
    # starts a track of its own
    alone = track_detections(frames, config.replace(partial_tolerance=None))
    assert len(alone.track_ids) > 1
    assert alone[20].wh.tolist() == [[50.0, 90.0]]


def test_a_smaller_box_higher_up_is_not_a_partial_view() -> None:
    # the same small box with its bottom edge 40 px above the person's (someone farther
    # away on the ground plane) is refused as before
    n, hidden = 40, range(12, 27)
    _, frames = _lower_body_frames(n, hidden)
    for k in hidden:
        frames[k].xy[0, 1] -= 40.0
    log = track_detections(frames, TrackerConfig(fps=25.0))
    assert len(log.track_ids) > 1
    assert 1 not in log[20].track_id.tolist()


def test_partial_tolerance_must_be_a_fraction() -> None:
    for bad in (-0.1, 1.0, float("nan")):
        with pytest.raises(ValueError, match="partial_tolerance"):
            TrackerConfig(partial_tolerance=bad)
    assert TrackerConfig(partial_tolerance=None).partial_tolerance is None


def test_size_gate_must_be_a_ratio_above_one() -> None:
    with pytest.raises(ValueError, match="size_gate"):
        TrackerConfig(size_gate=1.0)
    assert TrackerConfig(size_gate=None).size_gate is None


@pytest.mark.parametrize("margin", [4.0, None])
def test_a_standing_track_is_not_carried_off_by_a_vehicle_passing_within_its_gate(margin):
    """Paper 1's non-exclusive nearest rule: a vehicle stands (held by template matching)
    while another passes 16 px from it, inside the 20 px gate. With ``stopped_margin`` the
    standing track keeps to the place it stands (the passer is beyond half a box + 4 px, 14 px,
    and its box ends 6 px from it) and
    stays STOPPED; without it the standing track takes the passer's detection."""
    n = 40
    stand = np.tile([100.0, 100.0], (n, 1))
    seen = np.full(n, np.nan)[:, None] * np.ones(2)
    seen[:10] = stand[:10]  # detected, then faded into the background
    passer = np.full((n, 2), np.nan)
    passer[20:30] = [116.0, 100.0] + np.arange(10)[:, None] * [0.0, 0.5]  # 16 px away, slow
    frames = _frames({0: seen, 1: passer}, n)

    def rescue(uids, xy, wh):
        return np.ones(len(uids), bool), np.repeat(stand[:1], len(uids), axis=0)

    config = paper1("kalman-ca", fps=30.0).replace(stopped_margin=margin)
    tracker = Tracker(config)
    out = [tracker.step(d, rescue=rescue) for d in frames]
    first = out[20]  # the passer's first frame
    row = first.track_id.tolist().index(1)
    if margin is None:
        assert first.det_index[row] >= 0  # the standing track took the passer
        assert np.hypot(*(first.filtered_xy[row] - stand[0])) > 5
    else:
        assert first.det_index[row] == -1 and first.state[row] == TrackState.STOPPED
        for tf in out[20:30]:  # held where it stands all through the passing
            r = tf.track_id.tolist().index(1)
            assert tf.state[r] == TrackState.STOPPED
            np.testing.assert_allclose(tf.measured_xy[r], stand[0])
        assert 2 in out[20].track_id.tolist()  # the passer has a track of its own


def test_a_standing_track_takes_a_blob_that_holds_the_place_it_stands():
    """A queue that drives on merges into one wide blob whose centre lies between the
    vehicles: the standing track may take it (the blob's box holds where it stands)."""
    stand = np.array([100.0, 100.0])
    tracker = Tracker(paper1("kalman-ca", fps=30.0))
    for k in range(8):
        tracker.step(Detections(k, stand[None], WH.copy()) if k < 5 else
                     Detections.empty(k), rescue=lambda u, xy, wh: (
                         np.ones(len(u), bool), np.repeat(stand[None], len(u), axis=0)))
    assert tracker.tracks.state.tolist() == [int(TrackState.STOPPED)]
    merged = Detections(8, np.array([[118.0, 100.0]]), np.array([[44.0, 10.0]]))  # centre 18 px off
    tf = tracker.step(merged)
    assert tf.det_index.tolist() == [0] and tf.track_id.tolist() == [1]
