"""Accumulate the tracker's per-frame output and turn it into MOTChallenge rows."""

from __future__ import annotations

import bisect
import os
from collections.abc import Iterator
from typing import overload

import numpy as np
from numpy.typing import NDArray

from mvtrack.types import TrackFrame, TrackState

#: MOTChallenge ``conf`` column per state: rows with a measurement 1, coasting rows 0.5.
_CONF = np.array([1.0, 1.0, 0.5, 1.0, 0.0])

#: the array fields of :class:`~mvtrack.types.TrackFrame`, in its order
ROW_FIELDS = (
    "track_id", "state", "det_index", "measured_xy", "filtered_xy", "predicted_xy", "wh",
    "velocity",
)


def concat_rows(frames: list[TrackFrame]) -> dict[str, NDArray]:
    """The rows of ``frames`` concatenated: ``frame`` (K,) and one array per field (new
    arrays, never views of the frames')."""
    frames = frames or [TrackFrame.empty(0)]
    cols = {
        "frame": np.repeat(
            np.array([f.frame for f in frames], dtype=np.int64), [len(f) for f in frames]
        )
    }
    for name in ROW_FIELDS:
        cols[name] = np.concatenate([getattr(f, name) for f in frames])
    return cols


def split_rows(
    frames: list[TrackFrame], cols: dict[str, NDArray], keep: NDArray[np.bool_]
) -> list[TrackFrame]:
    """One :class:`TrackFrame` per frame of ``frames`` holding the rows of ``cols`` (aligned
    with the concatenated rows of ``frames``) that ``keep`` selects."""
    bounds = np.concatenate([[0], np.cumsum([len(f) for f in frames])])
    out = []
    for i, f in enumerate(frames):
        k = bounds[i] + np.flatnonzero(keep[bounds[i] : bounds[i + 1]])
        out.append(TrackFrame(f.frame, *(cols[name][k] for name in ROW_FIELDS)))
    return out


class TrackLog:
    """All :class:`~mvtrack.types.TrackFrame` s of a run, kept as arrays.

    Frames are appended as they come; :meth:`columns` concatenates them once (cached) into
    one array per field with a leading ``frame`` column, so a log of a million rows costs
    a handful of arrays, not a million objects.

    Only frames with rows are stored: an empty frame whose number follows the previous one's
    costs nothing, and :meth:`skip` adds a whole gap of them at once (the offline run jumps
    over the frames in which no track is alive). Indexing and iterating still see every frame,
    ``log[i]`` being the ``i``-th frame appended (an empty :class:`TrackFrame` for the frames
    not stored).

    A streaming run hands the stored frames to its writer with :meth:`release`; the log then
    keeps counting frames (``len``) but holds only those appended since, so its memory stays
    flat on an endless stream. Released frames can no longer be indexed.
    """

    def __init__(self) -> None:
        self._frames: list[TrackFrame] = []  # the frames stored (with rows, or out of step)
        self._pos: list[int] = []  # index of each stored frame among all frames appended
        self._n = 0  # frames appended or skipped
        self._first = 0  # frame number of the first frame appended
        self._released = 0  # frames before this index were handed out by release()
        self._cache: dict[str, NDArray] | None = None

    def append(self, tf: TrackFrame) -> None:
        """Add one frame's rows."""
        if self._n == 0:
            self._first = tf.frame
        if len(tf) or tf.frame != self._first + self._n:  # an empty frame in step: implied
            self._frames.append(tf)
            self._pos.append(self._n)
            self._cache = None
        self._n += 1

    def skip(self, count: int) -> None:
        """Add ``count`` empty frames after the last one (numbered on from it), storing none."""
        if count < 0:
            raise ValueError(f"TrackLog.skip: count must be >= 0, got {count}")
        if count and self._n == 0:
            raise ValueError("TrackLog.skip: append the first frame before skipping")
        self._n += count

    def release(self) -> list[TrackFrame]:
        """Hand out the stored frames (those with rows) and forget them.

        ``len`` still counts every frame appended; indexing a released frame raises
        ``IndexError``; :meth:`columns` and :meth:`to_mot` cover the frames appended since.
        """
        out = self._frames
        self._frames, self._pos = [], []
        self._released = self._n
        self._cache = None
        return out

    @property
    def released(self) -> int:
        """Frames handed out by :meth:`release` (the first index still held)."""
        return self._released

    def __len__(self) -> int:
        """Number of frames appended (empty and released ones included)."""
        return self._n

    def _empty(self, i: int) -> TrackFrame:
        return TrackFrame.empty(self._first + i)

    def __iter__(self) -> Iterator[TrackFrame]:
        j = 0
        for i in range(self._released, self._n):
            if j < len(self._pos) and self._pos[j] == i:
                yield self._frames[j]
                j += 1
            else:
                yield self._empty(i)

    @overload
    def __getitem__(self, i: int) -> TrackFrame: ...
    @overload
    def __getitem__(self, i: slice) -> list[TrackFrame]: ...
    def __getitem__(self, i: int | slice) -> TrackFrame | list[TrackFrame]:
        n = self._n
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(n))]
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError(f"TrackLog index {i} out of range ({n} frames)")
        if i < self._released:
            raise IndexError(f"TrackLog frame {i} was released (written by a streaming run)")
        j = bisect.bisect_left(self._pos, i)
        if j < len(self._pos) and self._pos[j] == i:
            return self._frames[j]
        return self._empty(i)

    def frames_with_rows(self) -> list[TrackFrame]:
        """The frames held that have rows, in order (a new list)."""
        return [f for f in self._frames if len(f)]

    @property
    def n_rows(self) -> int:
        """Total number of output rows over the frames held."""
        return sum(len(f) for f in self._frames)

    def columns(self) -> dict[str, NDArray]:
        """All rows as arrays: ``frame`` (K,) plus every array field of ``TrackFrame``."""
        if self._cache is None:
            self._cache = concat_rows(self._frames)
        return self._cache

    @property
    def track_ids(self) -> NDArray[np.int64]:
        """Distinct public IDs seen (sorted)."""
        ids = self.columns()["track_id"]
        return np.unique(ids[ids > 0])

    def to_mot(self, include_coasting: bool = True) -> NDArray[np.float64]:
        """MOTChallenge result rows ``(frame, id, left, top, w, h, conf, -1, -1, -1)``.

        ``frame`` is 1-based (our frame index + 1); boxes are centred on the filtered position.
        Tentative rows (``track_id == -1``) are never written. ``conf`` is 1 for rows with a
        measurement (detection or template match) and 0.5 for coasting rows; with
        ``include_coasting=False`` coasting rows are left out. Rows are sorted by frame, then ID.
        """
        c = self.columns()
        keep = c["track_id"] > 0
        if not include_coasting:
            keep &= c["state"] != int(TrackState.COASTING)
        xy, wh = c["filtered_xy"][keep], c["wh"][keep]
        out = np.empty((int(keep.sum()), 10))
        out[:, 0] = c["frame"][keep] + 1
        out[:, 1] = c["track_id"][keep]
        out[:, 2:4] = xy - wh / 2
        out[:, 4:6] = wh
        out[:, 6] = _CONF[c["state"][keep]]
        out[:, 7:] = -1.0
        order = np.lexsort((out[:, 1], out[:, 0]))
        return out[order]

    def write_mot(self, dest: str | os.PathLike[str], include_coasting: bool = True) -> None:
        """Write :meth:`to_mot` to ``dest`` atomically (:func:`mvtrack.io.mot.write_results`)."""
        from mvtrack.io.mot import write_results

        write_results(dest, self.to_mot(include_coasting))


def backfill(frames: list[TrackFrame], uids: list[NDArray[np.int64]]) -> list[TrackFrame]:
    """Give the tentative rows of every track that was confirmed later its public ID.

    Parameters
    ----------
    frames : list of TrackFrame
        A run's output with tentative rows included (``track_id == -1``).
    uids : list of (K,) int64
        The tracker's internal uid of every row of ``frames`` (:attr:`Tracker.row_uids`),
        aligned with them.

    Returns
    -------
    list of TrackFrame
        The same frames in which the rows of tracks confirmed at some point carry that
        track's public ID from its first row on (their ``state`` stays ``TENTATIVE``), and the
        rows of tracks never confirmed are left out.
    """
    all_uids = np.concatenate(uids) if uids else np.zeros(0, dtype=np.int64)
    all_tids = (
        np.concatenate([f.track_id for f in frames]) if frames else np.zeros(0, dtype=np.int64)
    )
    public = all_tids > 0
    tid_of = np.full(int(all_uids.max()) + 1 if all_uids.size else 0, -1, dtype=np.int64)
    tid_of[all_uids[public]] = all_tids[public]  # a track's ID never changes once given
    out = []
    for f, u in zip(frames, uids, strict=True):
        if not np.count_nonzero(f.track_id <= 0):
            out.append(f)
            continue
        tid = tid_of[u]
        keep = (tid > 0).nonzero()[0]
        out.append(TrackFrame(f.frame, tid[keep], *(getattr(f, n)[keep] for n in ROW_FIELDS[1:])))
    return out


#: frames within which each end of a gap must have another measurement of its track, on
#: the side away from the gap, for the gap to be interpolated (:func:`interpolate_gaps`);
#: chosen by leave-one-out over the frame-rate sweep's sequences (``docs/bench/framerate.md``)
END_REACH = 2


def interpolate_gaps(frames: list[TrackFrame], max_gap: int | None = None) -> list[TrackFrame]:
    """Fill the gaps of every track by linear interpolation between its measured rows.

    Offline post-processing (the linear interpolation of ByteTrack's and other offline
    MOTChallenge trackers). A row is *anchored* when it carries a measurement (a detection,
    or a template match in the ``STOPPED`` state). A gap is filled between two anchored rows
    ``a`` and ``b`` of the same track when each end is confirmed by another measurement of the
    track on its outer side, at most :data:`END_REACH` frames before ``k_a`` and after
    ``k_b``. A lone measurement at either end may be a false alarm or another object the
    track took for a frame; interpolated towards it, the gap's rows lie on nobody. Every
    frame ``k`` of a filled gap gets a row — the coasting row the tracker wrote, or a new
    one — re-estimated from its ends, with ``t = (k - k_a) / (k_b - k_a)``:

    ``x_k = (1 - t) x_a + t x_b``,  ``wh_k = (1 - t) wh_a + t wh_b``,
    ``v_k = (x_b - x_a) / (k_b - k_a)``

    (``x`` the filtered position), in state ``COASTING`` without measurement. Rows after a
    track's last anchored row are kept as the tracker wrote them.

    Parameters
    ----------
    frames : list of TrackFrame
        A run's output, in increasing frame order.
    max_gap : int or None
        Gaps of more frames (``k_b − k_a``) are left unfilled; None: no limit.

    Returns
    -------
    list of TrackFrame
        Every frame that holds a row, in order; within a frame the rows of ``frames`` first,
        then the new rows by track ID.
    """
    if not frames:
        return []
    c = concat_rows(frames)
    tid, frame_of = c["track_id"], c["frame"]
    # rows without a public ID (tentative tracks) are left as they are
    anchored = (c["det_index"] >= 0) | (c["state"] == int(TrackState.STOPPED)) | (tid <= 0)
    rows = np.flatnonzero(anchored & (tid > 0))
    rows = rows[np.lexsort((frame_of[rows], tid[rows]))]  # by track, then frame
    a, b = rows[:-1], rows[1:]
    same = tid[a] == tid[b]
    dk = frame_of[b] - frame_of[a]
    # each end confirmed by another measurement of its track at most END_REACH frames away
    # on its outer side: before the gap's first row, after its last
    near = same & (dk <= END_REACH)
    before = np.concatenate([[False], near])  # row i has a measurement just before it
    after = np.concatenate([near, [False]])  # ... and just after it
    gap = same & (dk > 1) & before[:-1] & after[1:]
    if max_gap is not None:
        gap &= dk <= max_gap
    a, b = a[gap], b[gap]
    if a.size == 0:
        return list(frames)
    span = frame_of[b] - frame_of[a]
    n_new = span - 1
    src_a = np.repeat(a, n_new)
    src_b = np.repeat(b, n_new)
    step = np.arange(n_new.sum()) - np.repeat(np.cumsum(n_new) - n_new, n_new) + 1
    k = frame_of[src_a] + step
    t = (step / np.repeat(span, n_new))[:, None]
    xy, wh = c["filtered_xy"], c["wh"]
    new = {
        "frame": k, "track_id": tid[src_a],
        "state": np.full(k.size, int(TrackState.COASTING), np.int64),
        "det_index": np.full(k.size, -1, np.int64),
        "measured_xy": np.full((k.size, 2), np.nan),
        "filtered_xy": (1.0 - t) * xy[src_a] + t * xy[src_b],
        "predicted_xy": np.full((k.size, 2), np.nan),
        "wh": (1.0 - t) * wh[src_a] + t * wh[src_b],
        "velocity": np.repeat((xy[b] - xy[a]) / span[:, None], n_new, axis=0),
    }
    # the tracker's own rows in the gaps are replaced by the new ones
    width = int(tid.max()) + 1
    old = ~np.isin(frame_of * width + tid, k * width + new["track_id"])
    order_new = np.lexsort((new["track_id"], k))
    allc = {name: np.concatenate([c[name][old], new[name][order_new]])
            for name in ("frame", *ROW_FIELDS)}
    first = np.concatenate([np.zeros(int(old.sum()), np.int64), np.ones(k.size, np.int64)])
    order = np.lexsort((np.arange(first.size), first, allc["frame"]))
    fr = allc["frame"][order]
    cuts = np.flatnonzero(np.diff(fr)) + 1
    out = []
    for idx in np.split(order, cuts):
        out.append(TrackFrame(int(allc["frame"][idx[0]]), *(allc[n][idx] for n in ROW_FIELDS)))
    return out
