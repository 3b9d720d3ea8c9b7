"""Score-aware association and birth: exact-identity scenarios and invariances."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtrack.tracking import Tracker, TrackerConfig, TrackLog, track_detections
from mvtrack.types import Detections

WH = (30.0, 80.0)


def _frames(targets: list[tuple[np.ndarray, np.ndarray]], n: int) -> list[Detections]:
    """Detections of ``targets`` = [(xy (n, 2) with NaN rows = absent, score (n,))]."""
    out = []
    for k in range(n):
        xy = [p[k] for p, _ in targets if np.isfinite(p[k]).all()]
        sc = [s[k] for p, s in targets if np.isfinite(p[k]).all()]
        xy = np.array(xy, float).reshape(-1, 2)
        out.append(Detections(k, xy, np.tile(WH, (len(xy), 1)), np.array(sc, float)))
    return out


def _run(frames: list[Detections], config: TrackerConfig) -> TrackLog:
    tracker, log = Tracker(config), TrackLog()
    for d in frames:
        log.append(tracker.step(d))
    return log


def _ids_at(log: TrackLog, frames: list[Detections], xy: np.ndarray) -> list[int]:
    """Per frame, the ID of the row that used the detection at ``xy[k]`` (0: none)."""
    ids = []
    for k, tf in enumerate(log):
        hit = [int(t) for t, j in zip(tf.track_id, tf.det_index, strict=True)
               if j >= 0 and np.allclose(frames[k].xy[j], xy[k])]
        ids.append(hit[0] if hit else 0)
    return ids


def _walker(n: int, start=(100.0, 200.0), v=(3.0, 0.0)) -> np.ndarray:
    return np.asarray(start) + np.arange(n)[:, None] * np.asarray(v)


CFG = TrackerConfig(fps=30.0, score_scale="prob", score_high=0.5)


def test_a_low_score_box_never_starts_a_track():
    n = 20
    person = _walker(n)
    clutter = np.tile([400.0, 300.0], (n, 1))  # a static box, low score every frame
    frames = _frames([(person, np.full(n, 0.9)), (clutter, np.full(n, 0.3))], n)
    log = _run(frames, CFG)
    assert set(log.track_ids.tolist()) == {1}
    assert _ids_at(log, frames, clutter) == [0] * n
    # the same boxes without the score split do start a track on the clutter
    assert set(_run(frames, CFG.replace(score_high=None)).track_ids.tolist()) == {1, 2}


def test_an_isolated_low_box_starts_a_track_only_a_high_box_confirms():
    n = 12
    person = _walker(n)
    score = np.full(n, 0.9)
    score[:4] = 0.3  # weak for the first four frames, then strong
    frames = _frames([(person, score)], n)
    # the default: each weak box starts a tentative track, which the next weak box cannot
    # confirm (tentative tracks take high boxes only); the first strong box (frame 4)
    # confirms the one born on frame 3, so the person has an ID from frame 4 on
    ids = _ids_at(_run(frames, CFG), frames, person)
    assert ids == [0] * 4 + [1] * (n - 4)
    # offline, the confirmed track is written from its first (weak) box on
    off = track_detections(frames, CFG)
    assert _ids_at(off, frames, person) == [0] * 3 + [1] * (n - 3)
    # ByteTrack's rule (low_birth_iou=None): born on frame 4, confirmed on frame 5
    strict = _run(frames, CFG.replace(low_birth_iou=None))
    assert _ids_at(strict, frames, person) == [0] * 5 + [1] * (n - 5)
    # a weak box beside a strong one on a frame with no track yet starts nothing
    dup = np.where(np.arange(n)[:, None] < 4, person + np.array([6.0, 4.0]), np.nan)  # IoU 0.62
    both = _frames([(person, np.full(n, 0.9)), (dup, np.full(n, 0.3))], n)
    log = _run(both, CFG)
    assert set(log.track_ids.tolist()) == {1}
    assert _ids_at(log, both, person)[1:] == [1] * (n - 1)


def test_low_tentative_lets_low_boxes_alone_make_a_track():
    n = 20
    clutter = np.tile([400.0, 300.0], (n, 1))  # a static, isolated box, low every frame
    frames = _frames([(_walker(n), np.full(n, 0.9)), (clutter, np.full(n, 0.3))], n)
    log = _run(frames, CFG.replace(low_tentative=True))
    assert set(log.track_ids.tolist()) == {1, 2}
    assert _ids_at(log, frames, clutter) == [0] + [2] * (n - 1)  # born on 0, confirmed on 1
    assert _ids_at(_run(frames, CFG), frames, clutter) == [0] * n  # the default: never


def test_a_track_lives_on_low_score_boxes_through_a_partial_occlusion():
    n = 40
    person = _walker(n)
    score = np.full(n, 0.9)
    score[10:30] = 0.2  # 20 frames (0.67 s, longer than max_coast) of a weak, occluded box
    frames = _frames([(person, score)], n)
    ids = _ids_at(_run(frames, CFG), frames, person)
    assert ids[1:] == [1] * (n - 1)  # confirmed on frame 1, one ID throughout
    # with the weak boxes dropped instead, the track ends and the person comes back as new
    # (and relinking, when on, hands the old ID to the new track)
    dropped = _run(frames, CFG.replace(min_score=0.5, relink_window=None))
    assert set(_ids_at(dropped, frames, person)[31:]) == {2}  # born at 30, confirmed at 31
    relinked = _run(frames, CFG.replace(min_score=0.5))
    assert set(_ids_at(relinked, frames, person)[31:]) == {1}


def test_a_duplicate_box_beside_a_tracked_person_starts_nothing():
    n = 20
    person = _walker(n)
    dup = person + np.array([6.0, 4.0])  # a second box on the same person (IoU 0.62)
    present = np.full((n, 2), np.nan)
    present[5:] = dup[5:]
    # a weak duplicate: matched by nobody, starts nothing
    frames = _frames([(person, np.full(n, 0.9)), (present, np.full(n, 0.4))], n)
    log = _run(frames, CFG)
    assert set(log.track_ids.tolist()) == {1}
    # a strong duplicate: suppressed by the overlap test (nms_iou)
    frames = _frames([(person, np.full(n, 0.9)), (present, np.full(n, 0.8))], n)
    assert set(_run(frames, CFG).track_ids.tolist()) == {1, 2}
    log = _run(frames, CFG.replace(nms_iou=0.5))
    assert set(log.track_ids.tolist()) == {1}
    assert _ids_at(log, frames, person)[1:] == [1] * (n - 1)


def _scene(fps: float, seconds: float = 4.0) -> tuple[list[Detections], list[np.ndarray]]:
    """Three people crossing at 90 px/s (the same motion at any frame rate); person 1 is
    missed for 0.2 s and weak (score 0.2) for 0.6 s; a clutter box flickers."""
    n = round(seconds * fps)
    t = np.arange(n) / fps
    paths = [np.stack([100 + 90 * t, 200 + 0 * t], 1), np.stack([460 - 90 * t, 230 + 0 * t], 1),
             np.stack([280 + 0 * t, 60 + 90 * t], 1)]
    scores = [np.full(n, 0.9) for _ in paths]
    paths[0][(t >= 1.0) & (t < 1.2)] = np.nan
    scores[0][(t >= 2.0) & (t < 2.6)] = 0.2
    clutter = np.full((n, 2), np.nan)
    clutter[::3] = [600.0, 400.0]
    targets = [*zip(paths, scores, strict=True), (clutter, np.full(n, 0.1))]
    return _frames(targets, n), paths


def test_the_same_motion_at_10_and_30_fps_keeps_the_same_identities():
    result = {}
    for fps in (10.0, 30.0):
        frames, paths = _scene(fps)
        log = _run(frames, TrackerConfig(fps=fps, score_scale="prob", score_high=0.5))
        per = []
        for p in paths:
            ids = [i for i in _ids_at(log, frames, p) if i]
            per.append(sorted(set(ids)))
        result[fps] = per
    # one ID per person, never shared, and the same at both frame rates
    assert result[10.0] == result[30.0]
    assert all(len(ids) == 1 for ids in result[10.0])
    assert len({ids[0] for ids in result[10.0]}) == 3


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_permuting_a_frames_detections_changes_no_identity(seed):
    frames, paths = _scene(25.0)
    rng = np.random.default_rng(seed)
    shuffled = []
    for d in frames:
        o = rng.permutation(len(d))
        shuffled.append(Detections(d.frame, d.xy[o], d.wh[o], d.score[o]))
    cfg = TrackerConfig(fps=25.0, score_high=0.3)  # the automatic (rank) calibration
    a, b = _run(frames, cfg), _run(shuffled, cfg)
    for p in paths:
        assert _ids_at(a, frames, p) == _ids_at(b, shuffled, p)


@settings(max_examples=15, deadline=None)
@given(a=st.floats(0.01, 100.0), b=st.floats(-50.0, 50.0), power=st.sampled_from([1, 3]))
def test_a_monotone_rescaling_of_the_scores_changes_no_identity(a, b, power):
    frames, _ = _scene(25.0)
    scaled = [Detections(d.frame, d.xy, d.wh, a * d.score**power + b) for d in frames]
    cfg = TrackerConfig(fps=25.0, score_high=0.3)
    for run in (_run, lambda f, c: track_detections(f, c)):
        x, y = run(frames, cfg), run(scaled, cfg)
        np.testing.assert_array_equal(x.columns()["track_id"], y.columns()["track_id"])
        np.testing.assert_array_equal(x.columns()["det_index"], y.columns()["det_index"])
