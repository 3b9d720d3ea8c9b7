"""A 10⁶-frame soak of streaming: memory stays flat and the files stay valid.

The tracker's own memory is bounded by the tracks alive; what grew with the frames was the
run's record of them (the track log, about 2 KB per frame with rows, the blob flags, the
summary's inputs), which :class:`~mvtrack.video.stream.StreamingOutput` now owns. A full
video loop costs tens of microseconds per frame (decode, detect, ``Tracker.step``), far too
slow for 10⁶ frames in the suite, so the soak drives that layer directly with the frames a
tracker would give: one track every 200 frames, output in 20 frames of which one coasts. The
full loop with streaming is checked on short videos in ``tests/video/test_stream.py``.
"""

from __future__ import annotations

import itertools

import numpy as np
import psutil
import pytest

from mvtrack.io.mot import read_mot
from mvtrack.types import TrackFrame, TrackState
from mvtrack.video.stream import StreamingOutput

FRAMES = 1_000_000
PERIOD, ALIVE = 200, 20  # a new track every PERIOD frames, output in ALIVE of them
GROWTH_MB = 8.0


def _rss_mb() -> float:
    return psutil.Process().memory_info().rss / 2**20


@pytest.mark.slow
def test_a_million_streamed_frames_keep_memory_flat_and_the_files_valid(tmp_path) -> None:
    one = lambda v, dt=np.float64: np.array([v], dtype=dt)  # noqa: E731
    xy, wh, no_flags = np.array([[50.0, 60.0]]), np.array([[10.0, 20.0]]), np.zeros(0, np.int8)
    flags = np.zeros(1, np.int8)
    ticks = itertools.count()
    out = StreamingOutput(tmp_path, 5000.0, gap=9, clock=ticks.__next__)  # every ~5000 frames
    rss = {}
    for k in range(FRAMES):
        phase = k % PERIOD
        if phase < ALIVE:
            coasting = phase == ALIVE // 2
            tf = TrackFrame(
                k, one(1 + k // PERIOD, np.int64),
                one(int(TrackState.COASTING if coasting else TrackState.CONFIRMED), np.int64),
                one(-1 if coasting else 0, np.int64), xy, xy + phase, xy, wh, xy * 0,
            )
            out.add(tf, no_flags if coasting else flags)
        else:
            out.add(TrackFrame.empty(k), no_flags)
        if k + 1 in (FRAMES // 10, FRAMES):
            rss[k + 1] = _rss_mb()
    out.close()
    growth = rss[FRAMES] - rss[FRAMES // 10]
    print(f"RSS {rss[FRAMES // 10]:.1f} MB at frame 10^5, {rss[FRAMES]:.1f} MB at 10^6")
    assert growth < GROWTH_MB, rss
    n_tracks = FRAMES // PERIOD
    table = read_mot(tmp_path / "results.txt", "results")
    assert len(table) == n_tracks * (ALIVE - 1)  # coasting rows are not written
    assert table.frame.max() == FRAMES - PERIOD + ALIVE - 1 and np.unique(table.id).size == n_tracks
    states = (tmp_path / "states.csv").read_text().splitlines()
    assert len(states) == 1 + n_tracks * ALIVE
    assert out.stats.n_tracks == n_tracks and out.stats.lengths() == {"median": 20.0, "max": 20}
    assert out.flushes > 150 and len(out.log) == FRAMES and out.log.n_rows == 0
