"""A track confirmed where a recently deleted one would be now, of its size, takes its ID
(``TrackerConfig.relink_window``, :mod:`mvtrack.tracking.relink`)."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking import Tracker, TrackerConfig, track_detections
from mvtrack.tracking.relink import empty_gallery, pair_new_tracks
from mvtrack.types import Detections

FPS = 25.0


def _walker(hidden: range, after=lambda x: x, height=(80.0, 80.0), fps: float = FPS,
            seconds: float = 4.0) -> list[Detections]:
    """One person walking right at 50 px/s, 30×80 px, no detection in the frames ``hidden``
    (given at 25 fps); after them the detections are at ``after(x)`` with the second height."""
    out = []
    step = FPS / fps
    for k in range(int(seconds * fps)):
        k25 = k * step
        x = 100.0 + 2.0 * k25
        if int(k25) in hidden:
            out.append(Detections(k, np.zeros((0, 2)), np.zeros((0, 2))))
            continue
        h = height[1] if k25 >= hidden.stop else height[0]
        x = after(x) if k25 >= hidden.stop else x
        out.append(Detections(k, np.array([[x, 200.0]]), np.array([[30.0, h]]),
                              score=np.array([1.0])))
    return out


def _ids(frames: list[Detections], **cfg) -> list[int]:
    tracker = Tracker(TrackerConfig(fps=cfg.pop("fps", FPS), score_high=None, min_score=0.0,
                                    **cfg))
    ids: list[int] = []
    for d in frames:
        ids += tracker.step(d).track_id.tolist()
    return sorted(set(ids))


def test_a_person_hidden_for_a_second_keeps_the_id() -> None:
    frames = _walker(range(30, 55))  # 1 s hidden, longer than max_coast (0.3 s)
    assert _ids(frames) == [1]
    assert _ids(frames, relink_window=None) == [1, 2]  # the tracker alone: a new ID


@pytest.mark.parametrize(("after", "height", "why"), [
    (lambda x: x + 40.0, (80.0, 80.0), "40 px from where the hidden one would be (width 30)"),
    (lambda x: x, (80.0, 140.0), "1.75 times as tall"),
])
def test_another_object_gets_a_new_id(after, height, why) -> None:
    assert _ids(_walker(range(30, 55), after, height)) == [1, 2], why


def test_no_link_after_the_window() -> None:
    frames = _walker(range(30, 90), seconds=6.0)  # 2.4 s hidden
    assert TrackerConfig().relink_window == 3.0
    assert _ids(frames) == [1]
    assert _ids(frames, relink_window=2.0) == [1, 2]
    frames = _walker(range(30, 115), seconds=7.0)  # 3.4 s hidden, beyond the default window
    assert _ids(frames) == [1, 2]


def test_the_same_at_10_and_at_30_fps() -> None:
    for fps in (10.0, 30.0):
        assert _ids(_walker(range(30, 55), fps=fps), fps=fps) == [1], fps


def test_the_nearest_of_two_ended_tracks_is_continued() -> None:
    # two people ended at frame 10, 30 px apart; a new track at frame 20 where the second
    # would be (1 px off) continues the second, not the first (29 px off)
    gallery = (np.array([4, 7]), np.array([10, 10]),
               np.array([[100.0, 50.0, 1.0, 0.0, 30.0, 80.0], [130.0, 50.0, 1.0, 0.0, 30.0, 80.0]]))
    new, old = pair_new_tracks(np.array([[141.0, 50.0]]), np.array([[30.0, 80.0]]),
                               np.array([19]), 20, gallery, reach=1.0, window=50)
    assert new.tolist() == [0] and gallery[0][old].tolist() == [7]
    assert pair_new_tracks(np.array([[141.0, 50.0]]), np.array([[30.0, 80.0]]), np.array([19]),
                           20, empty_gallery(), 1.0, 50)[0].size == 0


def test_offline_rows_never_share_a_frame_under_one_id() -> None:
    # a second box starts a track beside the first while the first still coasts, then
    # goes on where the first would be: the two tracks overlap in time, so the second keeps
    # its own ID and backfill writes no frame twice under one ID
    frames = []
    for k in range(100):
        xy = ([[100.0 + 2 * k, 200.0]] if k < 40 else []) + (
            [[100.0 + 2 * k + 25.0, 200.0]] if k >= 38 else [])
        frames.append(Detections(k, np.array(xy).reshape(-1, 2),
                                 np.array([[30.0, 80.0]] * len(xy)).reshape(-1, 2),
                                 score=np.ones(len(xy))))
    log = track_detections(frames, TrackerConfig(fps=FPS, score_high=None, min_score=0.0))
    pairs = log.to_mot()[:, :2].astype(int)
    assert len({tuple(p) for p in pairs.tolist()}) == len(pairs)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan")])
def test_relink_settings_are_checked(bad) -> None:
    with pytest.raises(ValueError, match="relink_window"):
        TrackerConfig(relink_window=bad)
    with pytest.raises(ValueError, match="relink_reach"):
        TrackerConfig(relink_reach=bad)
