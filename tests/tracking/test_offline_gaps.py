"""Offline runs over long stretches without detections: the tracker steps empty frames only
while a track is alive and jumps the rest; the log stores only frames with rows. The results
must equal those of stepping every frame."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.io.mot import MotTable, read_detections, write_detections
from mvtrack.tracking import TrackerConfig, TrackLog, track_detections
from mvtrack.tracking.offline import frames_with_detections
from mvtrack.types import Detections, TrackFrame


def _bursts(rng: np.random.Generator) -> list[Detections]:
    """Three bursts of two moving targets separated by gaps of 200 and 5000 empty frames,
    with a few missed detections inside the bursts (so tracks coast and are interpolated)."""
    frames: list[Detections] = []
    starts = (0, 260, 5300)
    last = starts[-1] + 60
    for k in range(last):
        burst = [s for s in starts if s <= k < s + 60]
        if not burst or rng.random() < 0.1:
            frames.append(Detections.empty(k))
            continue
        t = k - burst[0]
        xy = np.array([[50.0 + 3 * t, 80.0], [400.0 - 2 * t, 300.0 + t]])
        xy += rng.normal(0, 0.5, xy.shape)
        frames.append(Detections.from_tlwh(
            k, np.column_stack([xy - [10, 20], np.full((2, 2), [20.0, 40.0])]),
            np.array([0.9, 0.8]),
        ))
    return frames


def _stepped_every_frame(frames: list[Detections], config: TrackerConfig,
                         **kw: bool) -> np.ndarray:
    """What the offline run gave before gaps were jumped: every frame stepped (a dense list
    has no gap to jump)."""
    return track_detections(frames, config, **kw).to_mot()


@pytest.mark.parametrize("config,kw", [
    (TrackerConfig(fps=30.0), {}),
    (TrackerConfig(fps=30.0), {"backfill_rows": False, "interpolate": False}),
    (TrackerConfig(fps=30.0, max_misses=60, lost_std=None, coast_std=float("inf")), {}),
])
def test_jumping_gaps_gives_the_results_of_stepping_every_frame(config, kw, tmp_path) -> None:
    path = tmp_path / "det.txt"
    write_detections(path, _bursts(np.random.default_rng(3)))
    read = read_detections(path)
    frames = list(read)  # every frame, the empty ones included
    dense = _stepped_every_frame(frames, config, **kw)
    sparse_input = list(frames_with_detections(read))
    assert len(sparse_input) < len(frames) // 2  # the gaps are not visited
    log = track_detections(iter(sparse_input), config, **kw)
    assert len(dense) > 100
    np.testing.assert_array_equal(log.to_mot(), dense)
    assert len(log) == len(read) == len(frames)
    # every frame can still be indexed, with its own frame number
    full = track_detections(frames, config, **kw)
    for k in (0, 1, 59, 60, 200, 259, 2000, 5299, 5300, len(frames) - 1, -1):
        a, b = log[k], full[k]
        assert a.frame == b.frame
        np.testing.assert_array_equal(a.track_id, b.track_id)
        np.testing.assert_array_equal(a.filtered_xy, b.filtered_xy)
    assert [f.frame for f in log] == [f.frame for f in full]


def test_a_detection_file_starting_late_is_logged_from_frame_zero(tmp_path) -> None:
    rows = np.array([[5, -1, 10, 10, 20, 40, 0.9], [6, -1, 12, 10, 20, 40, 0.9],
                     [7, -1, 14, 10, 20, 40, 0.9]], dtype=float)
    path = tmp_path / "det.txt"
    path.write_text("".join(",".join(f"{v:g}" for v in r) + "\n" for r in rows))
    read = read_detections(path)
    log = track_detections(frames_with_detections(read), TrackerConfig())
    dense = track_detections(list(read), TrackerConfig())
    assert len(log) == len(dense) == 7
    assert [f.frame for f in log] == list(range(7))
    np.testing.assert_array_equal(log.to_mot(), dense.to_mot())
    assert MotTable.from_rows(log.to_mot()).frame.min() == 4  # backfilled from frame 5 (1-based)


def test_track_log_stores_only_frames_with_rows_and_releases_them() -> None:
    log = TrackLog()
    row = TrackFrame(0, np.array([1]), np.array([1]), np.array([0]), np.zeros((1, 2)),
                     np.ones((1, 2)), np.zeros((1, 2)), np.ones((1, 2)), np.zeros((1, 2)))
    log.append(row)
    for k in range(1, 5):
        log.append(TrackFrame.empty(k))
    log.skip(10)
    assert len(log) == 15 and log.n_rows == 1
    assert len(log._frames) == 1  # empty frames in step are implied, not stored
    assert log[14].frame == 14 and len(log[14]) == 0 and log[-15] is row
    assert [f.frame for f in log[3:15:5]] == [3, 8, 13] and log[:1] == [row]
    out = log.release()
    assert out == [row] and len(log) == 15 and log.n_rows == 0 and log.released == 15
    with pytest.raises(IndexError, match="released"):
        log[0]
    log.append(TrackFrame.empty(15))
    assert [f.frame for f in log] == [15] and log.to_mot().shape == (0, 10)
    with pytest.raises(ValueError, match="append the first frame"):
        TrackLog().skip(3)
