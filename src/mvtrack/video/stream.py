"""Streaming output of a video run (``mvtrack track --flush SECONDS``).

A video run tracks online: the rows :meth:`Tracker.step` returns for frame ``k`` are never
changed by a later frame (backfill, interpolation and the dropping of short tracks belong to
the offline run, :mod:`mvtrack.tracking.offline`). Every frame is therefore final as soon as
it is tracked, and :class:`StreamingOutput` appends it to the output folder at the next flush:

- ``results.txt`` gets the frames' MOTChallenge rows, ``states.csv`` their state rows
  (:func:`mvtrack.analytics.outputs.states_table`), each batch as whole lines in one write,
  then ``fsync`` (:class:`mvtrack.io.stream.LineAppender`): both files are valid at every
  moment, and at the end of the run they are byte for byte those of a run without streaming;
- the track log (:class:`mvtrack.tracking.TrackLog`), the detections' blob flags and the
  template scores of the held rows then release the frames written, so memory stays flat on
  an endless stream;
- the summary's figures (tracks, their lengths, the states histogram) are kept as running
  counts (:class:`TrackStats`): the same numbers as without streaming, in memory that grows
  with the tracks alive and the distinct track lengths, not with the frames;
- ``trajectories.png`` draws the tracks of the last :data:`TRAJECTORY_FRAMES` frames only
  (:class:`RecentRows`), where a run without streaming draws every frame.

A flush runs with SIGINT and SIGTERM held back (:func:`signals_held`): a Ctrl-C arriving
while a batch is formatted or written takes effect right after it, so what was streamed is
whole and the rest is written at the end of the run, as without streaming.
"""

from __future__ import annotations

import contextlib
import math
import signal
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.io.mot import format_rows
from mvtrack.io.stream import LineAppender
from mvtrack.tracking.log import TrackLog
from mvtrack.types import TrackFrame, TrackState
from mvtrack.video.loop import NO_SCORES, HeldScores

IntArray = NDArray[np.int64]

#: Frames drawn in ``trajectories.png`` by a streaming run (the last ones): 5 min at 30 fps.
TRAJECTORY_FRAMES = 9000


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Inside the block SIGINT and SIGTERM are only recorded; on leaving it the first one is
    raised again, so that its own handler runs (main thread only; elsewhere nothing changes).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []

    def record(signum: int, frame: FrameType | None) -> None:
        got.append(signum)

    old = {s: signal.signal(s, record) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
        if got:
            signal.raise_signal(got[0])


class TrackStats:
    """The summary's track figures as running counts: tracks, their lengths, states.

    A track's length is its number of output rows with a public ID (coasting rows included),
    as :func:`mvtrack.video.run.track_to_folder` counts it. A track not output for more than
    ``gap`` frames has ended (a live track is output at least once every ``max_misses + 1``
    frames, the tracker deletes it after that), and its length moves into a histogram of
    lengths: memory grows with the tracks alive and the distinct lengths only.

    Parameters
    ----------
    gap : int or None
        Frames of absence after which a track has ended (the tracker's
        :attr:`~mvtrack.tracking.TrackerConfig.max_misses`); ``None``: never (every track
        kept).
    """

    def __init__(self, gap: int | None) -> None:
        self.gap = gap
        self._ids = np.zeros(0, dtype=np.int64)  # tracks that may still be output
        self._count = np.zeros(0, dtype=np.int64)
        self._last = np.zeros(0, dtype=np.int64)
        self._hist = np.zeros(1, dtype=np.int64)  # ended tracks per length
        self.states = np.zeros(len(TrackState), dtype=np.int64)  #: rows per state

    def add(self, frame: IntArray, track_id: IntArray, state: IntArray, now: int) -> None:
        """Count the rows ``(frame, track_id, state)`` of the frames up to ``now``."""
        self.states += np.bincount(state, minlength=len(TrackState))[: len(TrackState)]
        pub = track_id > 0
        ids = np.concatenate([self._ids, track_id[pub]])
        count = np.concatenate([self._count, np.ones(int(pub.sum()), dtype=np.int64)])
        last = np.concatenate([self._last, frame[pub]])
        uniq, inv = np.unique(ids, return_inverse=True)
        total = np.bincount(inv, weights=count, minlength=uniq.size).astype(np.int64)
        latest = np.full(uniq.size, np.iinfo(np.int64).min)
        np.maximum.at(latest, inv, last)
        ended = (now - latest > self.gap) if self.gap is not None else np.zeros(uniq.size, bool)
        if ended.any():
            self._hist = _add_counts(self._hist, total[ended])
        live = ~ended
        self._ids, self._count, self._last = uniq[live], total[live], latest[live]

    @property
    def n_tracks(self) -> int:
        """Tracks output so far."""
        return int(self._hist.sum()) + int(self._ids.size)

    def lengths(self) -> dict[str, float | int]:
        """``{"median": ..., "max": ...}`` of the track lengths in frames (as ``np.median``)."""
        hist = _add_counts(self._hist, self._count)
        n = int(hist.sum())
        if n == 0:
            return {"median": 0.0, "max": 0}
        cum = np.cumsum(hist)
        lo, hi = np.searchsorted(cum, [(n - 1) // 2, n // 2], side="right")
        return {"median": float((lo + hi) / 2), "max": int(np.flatnonzero(hist)[-1])}

    def state_histogram(self) -> dict[str, int]:
        """Rows per life-cycle state name (as :meth:`TrackRows.state_histogram`)."""
        return {s.name.lower(): int(self.states[s]) for s in TrackState
                if s != TrackState.DELETED}


def _add_counts(hist: IntArray, lengths: IntArray) -> IntArray:
    """``hist`` (counts per length) with one more count at each of ``lengths``."""
    size = max(hist.size, int(lengths.max()) + 1 if lengths.size else 0)
    out = np.zeros(size, dtype=np.int64)
    out[: hist.size] = hist
    out += np.bincount(lengths, minlength=size)
    return out


class RecentRows:
    """The output rows of the last ``frames`` frames, for the trajectory figure."""

    def __init__(self, frames: int = TRAJECTORY_FRAMES) -> None:
        self.frames = frames
        self._cols: dict[str, NDArray] | None = None

    def add(self, cols: dict[str, NDArray], now: int) -> None:
        """Add rows (``frame``, ``track_id``, ``state``, ``filtered_xy``, ``wh``) and forget
        those before ``now - frames + 1``."""
        names = ("frame", "track_id", "state", "filtered_xy", "wh")
        new = {k: cols[k] for k in names}
        if self._cols is not None:
            new = {k: np.concatenate([self._cols[k], new[k]]) for k in names}
        keep = new["frame"] > now - self.frames
        self._cols = {k: v[keep] for k, v in new.items()}

    def track_rows(self) -> Any:
        """The rows as :class:`mvtrack.viz.plots.TrackRows`."""
        from mvtrack.viz.plots import TrackRows

        c = self._cols
        if c is None:
            return TrackRows.from_frames([])
        return TrackRows(c["frame"], c["track_id"], c["state"], c["filtered_xy"], c["wh"])


class _FrameItems:
    """Per-frame items (blob flags, template scores) of frames ``first .. first + len(items)
    - 1``, indexed by frame number (what :func:`~mvtrack.analytics.outputs.states_table`
    looks them up by)."""

    def __init__(self, first: int, items: list[Any]) -> None:
        self.first, self.items = first, items

    def __len__(self) -> int:
        return self.first + len(self.items)

    def __getitem__(self, f: int) -> Any:
        return self.items[f - self.first]


class StreamingOutput:
    """``results.txt`` and ``states.csv`` of a video run, appended every ``interval`` seconds.

    Parameters
    ----------
    out : path
        Output folder (it must exist); both files are created at once, empty (``states.csv``
        with its header), so a folder that cannot take them fails before the run starts.
    interval : float
        Seconds between two flushes (> 0).
    gap : int or None
        Frames of absence after which a track has ended (:class:`TrackStats`).
    history : int
        Frames kept for the trajectory figure (:class:`RecentRows`).
    clock : callable
        Seconds, monotonic (a test may pass its own).
    coasting : bool
        Also write the rows of coasting tracks to ``results.txt`` (``--coasting``).

    Raises
    ------
    ValueError
        ``interval`` not a finite number > 0.
    OSError
        A file cannot be created or appended to.
    """

    def __init__(
        self, out: str | Path, interval: float, *, gap: int | None = None,
        history: int = TRAJECTORY_FRAMES, clock: Callable[[], float] = time.monotonic,
        fps: float = 30.0, coasting: bool = False,
    ) -> None:
        from mvtrack.analytics.outputs import states_table, table_csv

        if not (isinstance(interval, (int, float)) and math.isfinite(interval) and interval > 0):
            raise ValueError(f"--flush must be a number of seconds > 0, got {interval}")
        out = Path(out)
        self.interval = float(interval)
        self.fps = float(fps)
        self.coasting = bool(coasting)
        self.results = LineAppender(out / "results.txt")
        self.states = LineAppender(out / "states.csv",
                                   header=table_csv(states_table(TrackLog())))
        self.log = TrackLog()  #: the frames tracked since the last flush
        self.stats = TrackStats(gap)
        self.recent = RecentRows(history)
        self.flushes = 0  #: flushes that wrote rows
        self._flags: list[NDArray[np.int8]] = []
        self._scores: list[HeldScores] = []
        self._clock = clock
        self._due = clock() + self.interval

    @property
    def paths(self) -> dict[str, Path]:
        """``{"results": ..., "states": ...}``."""
        return {"results": self.results.path, "states": self.states.path}

    def add(
        self, tracks: TrackFrame, flags: NDArray[np.int8], scores: HeldScores = NO_SCORES
    ) -> None:
        """One more frame (its rows, its detections' blob flags and the template scores of
        its held rows, :func:`~mvtrack.video.loop.scores_of`); flush when due."""
        self.log.append(tracks)
        self._flags.append(flags)
        self._scores.append(scores)
        if self._clock() >= self._due:
            self.flush()

    def flush(self) -> None:
        """Append the frames tracked since the last flush to both files and forget them."""
        from mvtrack.analytics.outputs import states_table, table_csv

        with signals_held():
            self._due = self._clock() + self.interval
            held = len(self.log) - self.log.released  # frames tracked since the last flush
            if held == 0:
                return
            now = self.log[-1].frame
            first = now - held + 1
            cols = self.log.columns()
            self.stats.add(cols["frame"], cols["track_id"], cols["state"], now)
            self.recent.add(cols, now)
            results = format_rows(self.log.to_mot(include_coasting=self.coasting), "results")
            table = states_table(self.log, _FrameItems(first, self._flags),
                                 _FrameItems(first, self._scores), fps=self.fps)
            states = table_csv(table).split("\n", 1)[1] if len(table["frame"]) else ""
            self.results.append(results)
            self.states.append(states)
            self.log.release()
            self._flags = []
            self._scores = []
            self.flushes += 1

    def close(self) -> None:
        """Write what is left and close both files."""
        try:
            self.flush()
        finally:
            self.results.close()
            self.states.close()
