"""Offline relinking (:mod:`mvtrack.tracking.relink`): a walker hidden for longer than a lost
track lives comes back under its ID when the new piece starts, alone, where it was heading."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking import TrackerConfig, track_detections
from mvtrack.tracking.relink import MAX_STD, SPEED_STD, gap_variance
from mvtrack.types import Detections

WH = np.array([[40.0, 100.0]])


def _frames(paths: list[np.ndarray], n: int) -> list[Detections]:
    out = []
    for k in range(n):
        xy = np.array([p[k] for p in paths if np.isfinite(p[k]).all()]).reshape(-1, 2)
        out.append(Detections(k, xy, np.repeat(WH, len(xy), axis=0)))
    return out


def _walker(start, speed, fps: float, seconds: float, hidden: tuple[float, float]) -> np.ndarray:
    """A walker at ``speed`` px/s, undetected from ``hidden[0]`` s for ``hidden[1]`` s."""
    n = round(seconds * fps)
    t = np.arange(n)[:, None] / fps
    p = np.asarray(start, float) + t * np.asarray(speed, float)
    p[round(hidden[0] * fps):round((hidden[0] + hidden[1]) * fps)] = np.nan
    return p


def _ids(log, frames, path) -> set[int]:
    """The IDs of the rows that carry ``path``'s detections."""
    out = set()
    for k, tf in enumerate(log):
        for tid, j in zip(tf.track_id, tf.det_index, strict=True):
            if j >= 0 and np.allclose(frames[k].xy[j], path[k]):
                out.add(int(tid))
    return out


@pytest.mark.parametrize("fps", [5.0, 10.0, 30.0])
def test_a_walker_hidden_for_a_second_keeps_its_id_at_any_frame_rate(fps: float) -> None:
    """Hidden 1 s (5 to 30 frames, longer than max_misses allows a lost track to live at 30
    fps and than lost_std at every rate): one ID offline with relinking, two without; the
    hidden stretch is longer than max_misses, so it is not filled with guessed rows."""
    p = _walker([100.0, 300.0], [40.0, 0.0], fps, 6.0, (2.0, 1.0))
    frames = _frames([p], len(p))
    config = TrackerConfig(fps=fps)
    assert len(_ids(track_detections(frames, config, relink=False), frames, p)) == 2
    log = track_detections(frames, config)
    assert _ids(log, frames, p) == {1} and log.track_ids.tolist() == [1]
    rows = log.to_mot()
    hidden = (rows[:, 0] >= 2.0 * fps + config.max_misses + 1) & (rows[:, 0] < 3.0 * fps)
    assert not hidden.any()


def test_a_start_far_from_where_the_ended_track_was_heading_is_another_object() -> None:
    """The second piece starts 2 box widths behind the first one's extrapolation: a new ID."""
    fps = 10.0
    p = _walker([100.0, 300.0], [40.0, 0.0], fps, 6.0, (2.0, 1.0))
    p[30:] -= [80.0, 0.0]
    frames = _frames([p], len(p))
    assert len(_ids(track_detections(frames, TrackerConfig(fps=fps)), frames, p)) == 2


def test_a_gap_beyond_the_longest_bridged_is_not_relinked() -> None:
    """A walker hidden for longer than the extrapolation's std allows (MAX_STD box sizes)
    comes back as a new track, even exactly where it was heading."""
    fps = 10.0
    longest = np.sqrt(MAX_STD**2 - 2 * TrackerConfig().measurement_noise**2) / SPEED_STD
    p = _walker([100.0, 300.0], [20.0, 0.0], fps, 4.0 + longest + 1.0, (2.0, longest + 0.5))
    frames = _frames([p], len(p))
    assert len(_ids(track_detections(frames, TrackerConfig(fps=fps)), frames, p)) == 2
    q = _walker([100.0, 300.0], [20.0, 0.0], fps, 4.0 + longest, (2.0, longest - 0.3))
    frames = _frames([q], len(q))
    assert len(_ids(track_detections(frames, TrackerConfig(fps=fps)), frames, q)) == 1


def test_two_walkers_side_by_side_hidden_together_are_not_guessed() -> None:
    """Two walkers half a box width apart vanish together and come back: each new piece has
    two endings in its gate, so neither is relinked (a wrong join costs more than the switch);
    one walker alone in the same motion is relinked."""
    fps = 10.0
    a = _walker([100.0, 300.0], [40.0, 0.0], fps, 6.0, (2.0, 1.0))
    b = _walker([100.0, 330.0], [40.0, 0.0], fps, 6.0, (2.0, 1.0))
    b[:, 0] += 200.0  # apart at first (separate tracks), then ...
    b[25:, 0] -= 200.0  # side by side from before they vanish (b reborn beside a)
    b[20:25] = np.nan
    frames = _frames([a, b], len(a))
    log = track_detections(frames, TrackerConfig(fps=fps))
    assert len(_ids(log, frames, a)) == 2
    frames = _frames([a], len(a))
    assert len(_ids(track_detections(frames, TrackerConfig(fps=fps)), frames, a)) == 1


def test_gap_variance_grows_with_the_seconds_missed_not_the_frames() -> None:
    """S(T) = 2 σ_z² + (σ_u T)², in seconds: the same at any frame rate."""
    c = TrackerConfig(measurement_noise=0.1)
    t = np.array([0.0, 0.5, 1.0])
    np.testing.assert_allclose(gap_variance(c, t), 0.02 + (SPEED_STD * t) ** 2)
    assert gap_variance(c.replace(fps=5.0), 1.0) == gap_variance(c.replace(fps=30.0), 1.0)
