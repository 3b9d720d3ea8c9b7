"""Offline runs leave out the tracks whose detections score low among the tracks' own
(:func:`mvtrack.tracking.offline.drop_weak`)."""

from __future__ import annotations

import numpy as np

from mvtrack.tracking import TrackerConfig, track_detections
from mvtrack.tracking.offline import MIN_MEAN_SCORE
from mvtrack.types import Detections

WH = np.array([40.0, 100.0])


def _scene(scores_of: dict[int, float], n: int = 30) -> list[Detections]:
    """Four walkers 200 px apart, each detected every frame with its own score; walker 3
    moves the other way (its own track, never confused with the others)."""
    out = []
    for k in range(n):
        xy = np.array([[100.0 + 200 * i + (3.0 if i != 3 else -3.0) * k, 300.0]
                       for i in range(4)])
        score = np.array([scores_of[i] for i in range(4)])
        out.append(Detections(k, xy, np.tile(WH, (4, 1)), score))
    return out


def _ids_near(log, x0: float) -> set[int]:
    rows = log.to_mot()
    centre = rows[:, 2] + rows[:, 4] / 2
    first = rows[:, 0] == rows[:, 0].min()
    return set(rows[first & (np.abs(centre - x0) < 20), 1].astype(int).tolist())


def test_a_track_of_the_weakest_boxes_is_left_out_offline_and_kept_online() -> None:
    """Three walkers detected with strong scores and one with the weakest of the run: the
    weak one's track is left out of the offline results (its mean rank 1/4 < 0.275), kept
    with ``drop_weak_tracks=False``; the strong ones are kept either way."""
    frames = _scene({0: 50.0, 1: 60.0, 2: 70.0, 3: 5.0})
    config = TrackerConfig(fps=10.0, score_high=None, min_score=0.0)
    log = track_detections(frames, config)
    assert log.track_ids.size == 3 and not _ids_near(log, 700.0)
    assert all(_ids_near(log, 100.0 + 200 * i) for i in range(3))
    every = track_detections(frames, config, drop_weak_tracks=False)
    assert every.track_ids.size == 4 and _ids_near(every, 700.0)
    assert 0.25 < MIN_MEAN_SCORE  # the weak walker's mean rank is 1/4


def test_ranks_not_scores_decide_and_equal_scores_keep_every_track() -> None:
    """Any increasing rescaling of the scores leaves the same tracks; a run whose scores
    are all equal (a detector without scores) keeps every track."""
    config = TrackerConfig(fps=10.0, score_high=None, min_score=0.0)
    a = track_detections(_scene({0: 50.0, 1: 60.0, 2: 70.0, 3: 5.0}), config).to_mot()
    b = track_detections(_scene({0: np.exp(5.0), 1: np.exp(6.0), 2: np.exp(7.0),
                                 3: np.exp(0.5)}), config).to_mot()
    np.testing.assert_array_equal(a, b)
    same = track_detections(_scene({0: 1.0, 1: 1.0, 2: 1.0, 3: 1.0}), config)
    assert same.track_ids.size == 4
