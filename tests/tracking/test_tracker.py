"""Exact-identity scenarios of the tracker: crossing, gaps, birth and death, shuffled input,
the same motion at 5, 10 and 30 fps, stopped vehicles, the papers' presets."""

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

#: a pedestrian-sized box (the noise and the gate are in box sizes)
WH = np.array([[40.0, 90.0]])


def _frames(paths: dict[int, np.ndarray], n_frames: int, wh=WH) -> list[Detections]:
    """Detections of targets ``paths[i]`` (n_frames, 2; NaN = absent), rows in target order."""
    out = []
    for k in range(n_frames):
        xy = [p[k] for _, p in sorted(paths.items()) if np.isfinite(p[k]).all()]
        xy = np.array(xy).reshape(-1, 2)
        out.append(Detections(k, xy, np.repeat(wh, len(xy), axis=0)))
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
    "kalman-cv": TrackerConfig(predictor="kalman-cv"),
    "kalman-ca+euclidean+greedy": TrackerConfig(
        predictor="kalman-ca", distance="euclidean", gate=400.0, assign="greedy"
    ),
    "rls+uncoupled+optimal": TrackerConfig(predictor="rls", distance="uncoupled", gate=50.0),
    "coupled+mahalanobis+optimal": TrackerConfig(
        predictor="kalman-coupled", distance="mahalanobis", gate=30.0
    ),
    "iou": TrackerConfig(distance="iou", gate=0.7),
    "paper2 (coupled gate, nearest)": paper2(fps=30.0),
}


@pytest.mark.parametrize("name", list(CONFIGS))
def test_two_crossing_targets_keep_their_ids(name: str) -> None:
    n = 60
    a = _line([100.0, 300.0], [3.0, 0.0], n)  # left to right
    b = _line([100.0, 392.0], [3.0, -3.0], n)  # lower left to upper right, crosses a at k=30
    frames = _frames({0: a, 1: b}, n)
    log = track_detections(frames, CONFIGS[name])
    ida = _id_of_target(log, frames, a)
    idb = _id_of_target(log, frames, b)
    # the same ID follows each target through the crossing, and the two IDs differ
    assert len(set(ida)) == 1 and len(set(idb)) == 1
    assert {ida[-1], idb[-1]} == {1, 2}
    assert log.track_ids.tolist() == [1, 2]


def test_gap_is_bridged_with_the_same_id_and_interpolated() -> None:
    n = 50
    a = _line([50.0, 50.0], [1.5, 0.5], n)
    a[20:24] = np.nan  # four missed frames of a steady walker
    frames = _frames({0: a}, n)
    log = track_detections(frames, TrackerConfig())
    assert log.track_ids.tolist() == [1]
    for k, tf in enumerate(log):
        assert tf.track_id.tolist() == [1]
        if k == 0:  # tentative then, written with the ID it got on confirmation (backfill)
            assert tf.state.tolist() == [TrackState.TENTATIVE]
        elif 20 <= k < 24:  # the frames it bridged, interpolated on the line
            assert tf.state.tolist() == [TrackState.COASTING]
            assert tf.det_index.tolist() == [-1] and np.isnan(tf.measured_xy).all()
            np.testing.assert_allclose(tf.filtered_xy[0], a[19] + (k - 19) * (a[24] - a[19])
                                       / 5, atol=0.3)
        else:
            assert tf.state.tolist() == [TrackState.CONFIRMED]
            np.testing.assert_array_equal(tf.measured_xy[0], a[k])
    # online: the coasting rows are written only while the prediction is certain to within
    # coast_std box sizes; the track lives on and keeps its ID
    tracker, shown = Tracker(), []
    for d in frames:
        shown.append(tracker.step(d).track_id.tolist())
    assert shown[24:] == [[1]] * (n - 24)
    assert 1 <= sum(s == [1] for s in shown[20:24]) < 4


def _frames_alive(path: np.ndarray, config: TrackerConfig) -> int:
    """Frames a track lives on after its last detection (NaN rows of ``path``)."""
    last = int(np.flatnonzero(np.isfinite(path[:, 0]))[-1])
    tracker = Tracker(config)
    for k, d in enumerate(_frames({0: path}, path.shape[0])):
        tracker.step(d)
        if k > last and tracker.n_tracks == 0:
            return k - last - 1
    return path.shape[0]


def test_a_lost_track_ends_when_its_prediction_is_too_uncertain() -> None:
    """A steady walker coasts for as many frames as its prediction stays within lost_std box
    sizes, at most max_misses; a track seen on three frames only, whose velocity is barely
    known, is lost sooner; a larger lost_std keeps both longer."""
    n = 80
    steady = _line([200.0, 100.0], [2.0, 0.5], n)
    steady[40:] = np.nan
    short = np.full((n, 2), np.nan)
    short[37:40] = _line([200.0, 100.0], [2.0, 0.5], 3)
    c = TrackerConfig()
    a, b = _frames_alive(steady, c), _frames_alive(short, c)
    assert 1 <= b < a <= c.max_misses
    assert _frames_alive(short, c.replace(lost_std=1.0)) > b
    assert _frames_alive(steady, c.replace(lost_std=None)) == c.max_misses


def test_birth_confirmation_and_death_at_the_right_frames() -> None:
    n = 40
    a = np.full((n, 2), np.nan)
    a[5:21] = _line([200.0, 100.0], [2.0, 1.0], 16)  # present in frames 5..20
    config = TrackerConfig(confirm_hits=3)
    tracker = Tracker(config)
    out = [tracker.step(d) for d in _frames({0: a}, n)]
    shown = [k for k, tf in enumerate(out) if len(tf)]
    # born at 5, confirmed on its 3rd detection (frame 7): online rows from 7
    assert shown[0] == 7 and all(out[k].state[0] == TrackState.CONFIRMED for k in range(7, 21))
    # offline, its tentative rows 5 and 6 are written once it is confirmed (backfill)
    log = track_detections(_frames({0: a}, n), config)
    assert [k for k, tf in enumerate(log) if len(tf)][:3] == [5, 6, 7]
    assert log[5].state[0] == log[6].state[0] == TrackState.TENTATIVE


def test_a_tentative_track_needs_consecutive_detections_and_their_scores() -> None:
    a = _line([10.0, 10.0], [1.0, 0.0], 12)
    a[1] = a[3] = np.nan  # detections at 0, 2, 4, 5, ...
    log = track_detections(_frames({0: a}, 12), TrackerConfig(confirm_hits=2),
                           backfill_rows=False)
    # the tracks born at 0 and 2 die at their first miss; the one born at 4 is confirmed at 5
    assert log.track_ids.tolist() == [1]
    assert next(k for k, tf in enumerate(log) if len(tf)) == 5
    # detections without a score count 1 each: two confirm; a higher confirm_score waits
    log = track_detections(_frames({0: a}, 12), TrackerConfig(confirm_score=2.5),
                           backfill_rows=False)
    assert next(k for k, tf in enumerate(log) if len(tf)) == 6


def test_tentative_tracks_are_output_with_id_minus_one_when_asked() -> None:
    a = _line([10.0, 10.0], [1.0, 0.0], 5)
    config = TrackerConfig(confirm_hits=3, output_tentative=True)
    tracker = Tracker(config)
    out = [tracker.step(d) for d in _frames({0: a}, 5)]
    assert [tf.track_id.tolist() for tf in out] == [[-1], [-1], [1], [1], [1]]
    log = TrackLog()
    for tf in out:
        log.append(tf)
    assert log.to_mot()[:, 0].tolist() == [3, 4, 5]  # tentative rows are never written


def _random_scene(rng: np.random.Generator, n_targets: int, n_frames: int,
                  scores: bool = False) -> list[Detections]:
    p = rng.uniform(0, 900, (n_targets, 2))
    v = rng.uniform(-3, 3, (n_targets, 2))
    wh0 = rng.uniform(20, 60, (n_targets, 1)) * [1.0, 2.2]
    frames = []
    for k in range(n_frames):
        seen = rng.random(n_targets) > 0.1
        xy = p[seen] + (k * v[seen]) + rng.normal(0, 1.0, (int(seen.sum()), 2))
        wh = wh0[seen] * rng.uniform(0.95, 1.05, (int(seen.sum()), 2))
        nc = rng.poisson(2)
        xy = np.vstack([xy, rng.uniform(0, 900, (nc, 2))])
        wh = np.vstack([wh, rng.uniform(20, 60, (nc, 1)) * [1.0, 2.2]])
        score = rng.uniform(0, 100, len(xy)) if scores else None
        frames.append(Detections(k, xy, wh, score))
    return frames


def test_backfill_changes_nothing_but_the_early_rows() -> None:
    rng = np.random.default_rng(5)
    frames = _random_scene(rng, 15, 30)
    # without interpolation: its gaps' ends may be confirmed by the rows backfill adds;
    # without smoothing, which revises every row
    online = track_detections(frames, TrackerConfig(), backfill_rows=False,
                              interpolate=False, smooth=False).to_mot()
    filled = track_detections(frames, TrackerConfig(), interpolate=False,
                              smooth=False).to_mot()
    online_rows = {tuple(r) for r in online[:, :6]}
    assert online_rows <= {tuple(r) for r in filled[:, :6]}
    first = {int(i): online[online[:, 1] == i, 0].min() for i in np.unique(online[:, 1])}
    extra = [r for r in filled if tuple(r[:6]) not in online_rows]
    assert extra and all(r[0] < first[int(r[1])] for r in extra)


@pytest.mark.parametrize("assign", ["nearest", "greedy", "optimal"])
def test_shuffled_detection_order_gives_identical_tracks(assign: str) -> None:
    rng = np.random.default_rng(7)
    frames = _random_scene(rng, 30, 40, scores=True)
    perms = [rng.permutation(len(d)) for d in frames]
    shuffled = [d.take(p) for d, p in zip(frames, perms, strict=True)]
    config = TrackerConfig(assign=assign)
    a = track_detections(frames, config)
    b = track_detections(shuffled, config)
    assert a.track_ids.size > 20
    for ta, tb, p in zip(a, b, perms, strict=True):
        oa, ob = np.argsort(ta.track_id), np.argsort(tb.track_id)
        np.testing.assert_array_equal(ta.track_id[oa], tb.track_id[ob])
        np.testing.assert_array_equal(ta.state[oa], tb.state[ob])
        np.testing.assert_allclose(ta.filtered_xy[oa], tb.filtered_xy[ob], rtol=1e-12)
        ja, jb = ta.det_index[oa], tb.det_index[ob]  # each input's own row order
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
        assert np.all(np.isin(tf.state[linked], [TrackState.CONFIRMED, TrackState.TENTATIVE]))
        assert np.all(tf.state[~linked] == TrackState.COASTING)
        assert np.isnan(tf.measured_xy[~linked]).all()
        assert len(set(tf.det_index[linked].tolist())) == int(linked.sum())  # exclusive
    assert n_linked > 300


def test_ids_are_consecutive_from_one_in_order_of_confirmation() -> None:
    rng = np.random.default_rng(11)
    log = track_detections(_random_scene(rng, 25, 30), TrackerConfig(), backfill_rows=False)
    ids = log.track_ids
    np.testing.assert_array_equal(ids, np.arange(1, ids.size + 1))
    first_seen = [int(np.flatnonzero(log.columns()["track_id"] == i)[0]) for i in ids]
    assert first_seen == sorted(first_seen)


@pytest.mark.parametrize("fps", [5.0, 10.0, 30.0])
def test_the_same_motion_keeps_the_same_identities_at_5_10_and_30_fps(fps: float) -> None:
    """Two walkers side by side and a third crossing them, 6 s; each is missed for 3 frames
    at some point (0.6 s at 5 fps, 0.1 s at 30 fps): a detector misses frames, not seconds.
    At every frame rate each keeps one ID throughout."""
    n = int(6 * fps)
    t = np.arange(n)[:, None] / fps
    a = np.array([100.0, 300.0]) + t * [60.0, 0.0]  # 1.5 box widths per second
    b = np.array([100.0, 420.0]) + t * [60.0, 0.0]
    c = np.array([500.0, 150.0]) + t * [-40.0, 40.0]  # crosses both
    for p, at in ((a, 2.0), (b, 3.0), (c, 4.0)):
        k = int(at * fps)
        p[k : k + 3] = np.nan
    frames = _frames({0: a, 1: b, 2: c}, n)
    log = track_detections(frames, TrackerConfig(fps=fps))
    for p in (a, b, c):
        ids = _id_of_target(log, frames, p)
        assert len(set(ids[np.isfinite(p).all(axis=1)].tolist())) == 1
    assert log.track_ids.tolist() == [1, 2, 3]


def test_a_new_object_is_found_on_its_second_frame_at_the_scenes_speed() -> None:
    """On a highway at 3 fps a car moves two box lengths a frame, beyond the initial velocity
    prior (1.5 box sizes/s); once the scene's confirmed cars have shown their speed, a new
    car is confirmed on its second detection (the prior learnt from the scene)."""
    fps, wh = 3.0, np.array([[40.0, 20.0]])
    cars = {}
    for i in range(12):  # a car enters every 3 frames, moving 2 box lengths per frame
        p = np.full((60, 2), np.nan)
        p[3 * i : 3 * i + 8] = _line([0.0, 100.0 + 40 * (i % 3)], [20.0 + 2 * (i % 4), 0.0],
                                     8)
        cars[i] = p
    # the first cars are slower (the prior learns from them first)
    for i in range(3):
        cars[i][3 * i : 3 * i + 8] = _line([0.0, 100.0 + 40 * i], [10.0, 0.0], 8)
    frames = _frames(cars, 60, wh)
    tracker = Tracker(TrackerConfig(fps=fps))
    out = [tracker.step(d) for d in frames]
    assert tracker.speed_prior[0] > 1.5**2  # faster than the initial prior, along x
    late = cars[10]
    k0 = int(np.flatnonzero(np.isfinite(late[:, 0]))[0])
    row = next(j for j, z in enumerate(frames[k0 + 1].xy) if np.allclose(z, late[k0 + 1]))
    assert row in out[k0 + 1].det_index.tolist()  # confirmed on its second frame


def test_a_turning_vehicle_keeps_its_id_with_the_imm_and_not_with_one_cv_filter() -> None:
    """A small vehicle turning a corner of radius 40 px at 2.5 px/frame (the intersection of
    experiment X5): the manoeuvring model follows it; the steady filter alone does not."""
    fps, wh = 30.0, np.array([[16.0, 9.0]])
    n = 90
    ang = np.clip((np.arange(n) - 30) * 2.5 / 40.0, 0, np.pi / 2)
    straight = np.arange(n) * 2.5
    x = np.where(np.arange(n) < 30, straight, 75.0 + 40 * np.sin(ang))
    y = np.where(np.arange(n) < 30, 0.0, 40 - 40 * np.cos(ang))
    after = np.arange(n) >= 30 + int(np.ceil(np.pi / 2 * 40 / 2.5))
    y = np.where(after, 40 + (np.arange(n) - (30 + np.pi / 2 * 40 / 2.5)) * 2.5, y)
    x = np.where(after, 115.0, x)
    path = np.stack([x + 50, y + 50], axis=1)
    frames = _frames({0: path}, n, wh)
    imm = track_detections(frames, TrackerConfig(fps=fps))
    assert imm.track_ids.tolist() == [1]
    cv = track_detections(frames, TrackerConfig(fps=fps, predictor="kalman-cv"))
    assert cv.track_ids.size > 1


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

    tracker = Tracker(TrackerConfig(max_misses=2))  # would be lost after 3 misses
    out = [tracker.step(d, rescue=rescue) for d in frames]
    assert all(tf.track_id.tolist() == [1] for tf in out[1:])
    states = [int(tf.state[0]) for tf in out[1:]]
    assert states[22 - 1 : 45 - 1] == [TrackState.STOPPED] * 23
    assert states[45 - 1 :] == [TrackState.CONFIRMED] * (n - 45)
    assert len(calls) == 23 and all(c[0].tolist() == [0] for c in calls)
    assert tracker.row_uids.tolist() == [0]  # the uid the rescue callback saw, row-aligned
    np.testing.assert_array_equal(calls[0][2], WH)
    stopped = out[30]
    assert stopped.det_index.tolist() == [-1]
    np.testing.assert_array_equal(stopped.measured_xy[0], a[20])


@pytest.mark.parametrize("predictor", ["kalman-ca", "rls"])
def test_a_held_vehicle_does_not_leave_with_a_vehicle_passing_within_the_gate(predictor) -> None:
    """Paper 1's system: a 16 × 9 vehicle stops at (140, 100) and fades (held by its
    template from frame 22 on); another drives past 12 px below it at 2 px a frame, inside
    the 20 px circle but outside the held vehicle's box. The held track takes none of its
    detections: it stays held where it stands, and the passing vehicle is tracked apart."""
    n, wh = 60, np.array([[16.0, 9.0]])
    a = _line([100.0, 100.0], [2.0, 0.0], n)
    a[20:] = a[20]
    a[22:] = np.nan  # faded into the background: only the template finds it
    b = _line([100.0, 112.0], [2.0, 0.0], n)
    b[:25] = np.nan  # enters at frame 25, passes (140, 112) at frame 45
    frames = _frames({0: a, 1: b}, n, wh)

    def rescue(uids, xy, wh_):
        return np.ones(len(uids), bool), np.repeat([[140.0, 100.0]], len(uids), axis=0)

    tracker = Tracker(paper1(predictor, fps=30.0))
    out = [tracker.step(d, rescue=rescue) for d in frames]
    first = out[5].track_id[0]
    for k in range(22, n):
        tf = out[k]
        row = np.flatnonzero(tf.track_id == first)
        assert row.size == 1, k
        assert tf.state[row[0]] == TrackState.STOPPED, k
        np.testing.assert_allclose(tf.measured_xy[row[0]], [140.0, 100.0])
    assert all(int(first) not in out[k].track_id[out[k].det_index >= 0] for k in range(22, n))


def test_the_rescue_hook_as_data_equals_the_callback() -> None:
    """``associate`` → template matching on ``Pending.unmatched`` → ``commit`` is ``step``
    with the callback."""
    rng = np.random.default_rng(4)
    frames = _random_scene(rng, 8, 40)

    def answer(uids, xy, wh):
        found = (uids % 2 == 0)
        return found, xy + 1.0

    a, b = Tracker(), Tracker()
    stopped = 0
    for d in frames:
        ta = a.step(d, rescue=answer)
        p = b.associate(d)
        found, xy = answer(p.uids, p.centre[p.unmatched], p.wh)
        tb = b.commit(p, found, xy)
        np.testing.assert_array_equal(ta.track_id, tb.track_id)
        np.testing.assert_array_equal(ta.state, tb.state)
        np.testing.assert_array_equal(ta.filtered_xy, tb.filtered_xy)
        stopped += int((ta.state == TrackState.STOPPED).sum())
    assert stopped >= 5


def test_rescue_is_not_offered_tentative_tracks_and_unfound_tracks_coast() -> None:
    a = _line([10.0, 10.0], [1.0, 0.0], 10)
    a[5:] = np.nan
    seen = []

    def rescue(uids, xy, wh):
        seen.append(uids.tolist())
        return np.zeros(len(uids), bool), np.full((len(uids), 2), np.nan)

    tracker = Tracker(TrackerConfig(coast_std=float("inf")))
    out = [tracker.step(d, rescue=rescue) for d in _frames({0: a}, 10)]
    assert seen[0] == [0] and all(s == [0] for s in seen)
    coasting = [tf for tf in out[5:] if len(tf)]
    assert coasting and all(int(tf.state[0]) == TrackState.COASTING for tf in coasting)


def test_a_track_whose_prediction_leaves_the_image_ends_there() -> None:
    a = _line([560.0, 200.0], [10.0, 0.0], 12)
    a[8:] = np.nan  # last seen at x = 630, predicted past the right edge at 640
    tracker = Tracker(TrackerConfig(), frame_size=(640.0, 480.0))
    for d in _frames({0: a}, 12):
        tracker.step(d)
    assert tracker.n_tracks == 0
    inside = Tracker(TrackerConfig(), frame_size=(2000.0, 480.0))
    for d in _frames({0: a}, 10):
        inside.step(d)
    assert inside.n_tracks == 1


def test_paper1_warmup_gate_centre_is_the_linear_extrapolation() -> None:
    a = _line([50.0, 60.0], [3.0, -1.0], 12)
    a += np.random.default_rng(0).normal(0, 0.3, a.shape)
    log = track_detections(_frames({0: a}, 12), paper1("kalman-ca"))
    assert log.track_ids.tolist() == [1]
    np.testing.assert_array_equal(log[1].predicted_xy[0], a[0])  # y_k after one association
    for k in range(2, 6):  # hits 2..5 < 2M = 6: centre 2 y_{k-1} − y_{k-2}
        np.testing.assert_allclose(log[k].predicted_xy[0], 2 * a[k - 1] - a[k - 2], rtol=1e-12)
    assert not np.allclose(log[7].predicted_xy[0], 2 * a[6] - a[5])  # the filter's own now


def test_paper1_nearest_is_non_exclusive_and_counts_coasting_in_frames() -> None:
    a = _line([100.0, 100.0], [2.0, 0.0], 10)
    b = _line([100.0, 110.0], [2.0, 0.0], 10)
    b[5:] = np.nan  # b disappears; both tracks now take a's detection (paper 1 rule)
    log = track_detections(_frames({0: a, 1: b}, 10, np.array([[12.0, 8.0]])),
                           paper1("kalman-ca"))
    assert log[6].det_index.tolist() == [0, 0]
    for fps in (10.0, 30.0):  # 3 frames without detection at any frame rate (SPEC §1.1)
        c = _line([100.0, 100.0], [2.0, 0.0], 12)
        c[5:] = np.nan
        tracker = Tracker(paper1("kalman-ca", fps=fps))
        out = [tracker.step(d) for d in _frames({0: c}, 12, np.array([[12.0, 8.0]]))]
        assert [len(tf) for tf in out[5:]] == [1, 1, 1, 0, 0, 0, 0]


@pytest.mark.parametrize(
    "changes",
    [
        {"fps": 0.0}, {"fps": float("nan")}, {"gate": -1.0}, {"confirm_hits": 0},
        {"max_misses": -1}, {"max_misses": 1.5}, {"assign": "hungarian"},
        {"measurement_noise": 0.0}, {"accel_noise": -1.0}, {"manoeuvre_noise": float("inf")},
        {"velocity_prior": 0.0}, {"size_noise": 0.0}, {"lost_std": -0.1},
        {"coast_std": -0.1}, {"coast_std": float("nan")}, {"confirm_score": -1.0},
        {"predictor": ""}, {"predictor_params": [1, 2]}, {"distance": "iou", "gate": 100.0},
        {"score_high": 1.5}, {"min_score": -0.1}, {"birth_iou": 0.0}, {"warmup": -1},
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
    a = _line([10.0, 10.0], [1.0, 0.0], 7)
    frames = _frames({0: a}, 7)
    log = track_detections([frames[0], frames[1], frames[2], frames[5], frames[6]],
                           TrackerConfig())
    assert [tf.frame for tf in log] == [0, 1, 2, 3, 4, 5, 6]
    assert [int(tf.state[0]) for tf in log[2:]] == [1, 2, 2, 1, 1]  # 3, 4 interpolated
    with pytest.raises(ValueError, match="frame 1"):
        track_detections([frames[2], frames[1]], TrackerConfig())


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("fps", [5.0, 25.0])
def test_the_compiled_step_equals_the_composition_from_python(seed: int, fps: float) -> None:
    """The default family's two compiled calls (:mod:`mvtrack.tracking.step`) and the same
    kernels composed from Python give the same tracks, bit for bit, on random scenes with
    scores, clutter, misses and stopped vehicles held by a rescue."""
    rng = np.random.default_rng(seed)
    frames = _random_scene(rng, 20, 50, scores=True)

    def rescue(uids, xy, wh):
        return uids % 3 == 0, xy

    a, b = Tracker(TrackerConfig(fps=fps)), Tracker(TrackerConfig(fps=fps), fused=False)
    assert a.fused and not b.fused
    for d in frames:
        ta, tb = a.step(d, rescue), b.step(d, rescue)
        for name in ("track_id", "state", "det_index", "measured_xy", "filtered_xy",
                     "predicted_xy", "wh", "velocity"):
            np.testing.assert_array_equal(getattr(ta, name), getattr(tb, name))
    np.testing.assert_array_equal(a.speed_prior, b.speed_prior)


def test_the_compiled_step_is_given_one_array_layout(monkeypatch) -> None:
    """The step's kernels see C-contiguous arrays whatever the caller's boxes are (here
    column slices of one array), so numba compiles each kernel once, not once per layout: a
    strided ``wh`` would cost a second compilation of the whole step on a first run."""
    import mvtrack.tracking.tracker as tracker_module

    seen: list[bool] = []

    def checked(kernel):  # type: ignore[no-untyped-def]
        def call(*args):  # type: ignore[no-untyped-def]
            seen.extend(a.flags.c_contiguous for a in args if isinstance(a, np.ndarray))
            return kernel(*args)
        return call

    for name in ("predict_assign", "update_commit"):
        monkeypatch.setattr(tracker_module, name, checked(getattr(tracker_module, name)))
    rng = np.random.default_rng(3)
    tracker = Tracker(TrackerConfig(fps=25.0))
    for d in _random_scene(rng, 12, 15, scores=True):
        boxes = np.hstack([d.xy, d.wh])  # (M, 4): the columns below are strided views
        tracker.step(Detections(d.frame, boxes[:, :2], boxes[:, 2:], d.score))
    assert len(seen) > 100 and all(seen)
