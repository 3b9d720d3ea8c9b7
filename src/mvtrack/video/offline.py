"""An offline video run (``mvtrack track --offline``): the rows of the online run, revised
once the whole video is tracked.

The online run writes a track from the frame it is confirmed (``confirm_hits`` detections,
the travel of the road-user front end) and each row as the filter had it at that frame. Once
the video has ended, two things are known that were not then:

- **the tentative rows of every track that was confirmed later** (backfill,
  :func:`mvtrack.tracking.log.backfill`). At 3 frames per second a car crosses the view in a
  handful of frames, and its first detection is a large share of its rows;
- **every row's smoothed estimate** from all its track's detections, before and after
  (:func:`mvtrack.tracking.smooth.smooth_tracks`, the Rauch-Tung-Striebel smoother of an
  offline ``track-detections`` run).

The online run itself is unchanged: the tracker outputs its tentative rows too
(``output_tentative``), :meth:`OfflineRows.public` keeps them aside and hands the rest of the
video loop (front end, template rescue, relinking, the front end's travel filter) exactly
the rows and uids it sees online. A tentative row is written if its track was confirmed and then
written online under some ID (after relinking): the ID it gets. Rows the online run never
wrote for a confirmed track (before the road-user front end saw it travel) stay out.

Measured in ``docs/bench/offline-video.md`` (``benchmarks/bench_offline_video.py``): the
US-101 clips' F1 +0.02 to +0.07 in every cell of the frame-rate sweep; KITTI-17 level at 10
and 5 fps, MOTA −0.06 to −0.07 at 3.3 and 2.5 fps (the backfill doubles the rows of short
tracks of clutter), so it is an option.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.tracking.log import TrackLog
from mvtrack.tracking.offline import of_detection
from mvtrack.tracking.smooth import smooth_tracks
from mvtrack.types import Detections, TrackFrame, concat_rows, take_rows

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]


class OfflineRows:
    """The tracker of an offline video run: collects what the run revises, frame by frame.

    It wraps a :class:`~mvtrack.tracking.Tracker` whose ``config.output_tentative`` is set and
    stands in for it in the video loop (every attribute but :meth:`step` and
    :attr:`row_uids` is the tracker's). :meth:`step` returns every row, so that the loop maps
    the rows' detections as for any step; :meth:`public` then keeps the tentative rows aside
    and gives the loop the rows the same tracker gives an online run, with :attr:`row_uids`
    aligned with them: the front end, the template rescue and the relinking see exactly what
    they see online.

    Parameters
    ----------
    tracker : Tracker
        Outputs its tentative rows (``config.output_tentative``); its ``fps`` and noises drive
        the smoother.
    """

    def __init__(self, tracker: Any) -> None:
        if not tracker.config.output_tentative:
            raise ValueError("OfflineRows: the tracker must output its tentative rows")
        self.tracker = tracker
        self.row_uids: IntArray = np.zeros(0, np.int64)
        # (rows, uids, detection sizes) of the tentative rows, per frame
        self._tentative: list[tuple[TrackFrame, IntArray, FloatArray]] = []
        self._sizes: list[FloatArray] = []  # the detection box of each online row
        self._uid_ids: list[IntArray] = []  # (uid, tracker ID) of the public rows
        self._frames = 0

    def __getattr__(self, name: str) -> Any:
        return getattr(self.tracker, name)

    def step(self, dets: Detections, rescue: Any = None) -> TrackFrame:
        """The tracker's step: every row, tentative ones included (pass them to
        :meth:`public`)."""
        return self.tracker.step(dets, rescue=rescue)

    def public(self, tracks: TrackFrame, dets: Detections) -> TrackFrame:
        """Keep the tentative rows (``track_id == -1``) of the last step aside, with their
        uids and their detections' boxes (``dets``, the frame's, which the rows'
        ``det_index`` point into); return the public rows, what the online run sees."""
        uids = self.tracker.row_uids
        tentative = tracks.track_id <= 0
        public = np.flatnonzero(~tentative)
        self.row_uids = uids[public]
        self._uid_ids.append(np.column_stack([self.row_uids, tracks.track_id[public]]))
        late = take_rows(tracks, np.flatnonzero(tentative))
        self._tentative.append((late, uids[tentative], of_detection(late, dets, "wh")))
        return tracks if public.size == len(tracks) else take_rows(tracks, public)

    def add(self, tracks: TrackFrame, dets: Detections) -> None:
        """The rows the online run writes for this frame (shown IDs), and ``dets``, the
        frame's detections (their boxes are the smoother's measured sizes)."""
        self._sizes.append(of_detection(tracks, dets, "wh"))
        self._frames += 1

    def finish(self, log: TrackLog, shown: Any = None) -> TrackLog:
        """The offline rows of the online run's ``log`` (one frame per :meth:`add`).

        Parameters
        ----------
        log : TrackLog
            What the online run wrote, every frame.
        shown : callable, optional
            Tracker IDs to the IDs the run shows (:meth:`Relinker.shown
            <mvtrack.video.relink.Relinker.shown>`); None: the tracker's IDs.

        Returns
        -------
        TrackLog
            The same frames, each with the backfilled rows of its tracks added and every row
            smoothed.
        """
        frames = list(log)
        if len(frames) != self._frames:
            raise ValueError(f"OfflineRows.finish: {len(frames)} frames logged, "
                             f"{self._frames} added")
        pairs = np.concatenate(self._uid_ids[: len(frames)]) if frames else np.zeros((0, 2))
        pairs = pairs.astype(np.int64).reshape(-1, 2)
        top = max([int(pairs[:, 0].max()) if len(pairs) else -1]
                  + [int(u.max()) for _, u, _ in self._tentative if u.size])
        id_of = np.full(top + 1, -1, np.int64)
        id_of[pairs[:, 0]] = pairs[:, 1]  # a track's tracker ID never changes once given
        written = np.unique(np.concatenate([f.track_id for f in frames])) if frames else []
        out: list[TrackFrame] = []
        sizes: list[FloatArray] = []
        for f, wh, (t, uids, twh) in zip(frames, self._sizes, self._tentative, strict=False):
            tid = id_of[uids] if uids.size else uids
            if shown is not None and (tid > 0).any():
                tid = tid.copy()
                tid[tid > 0] = shown(tid[tid > 0])
            keep = np.flatnonzero((tid > 0) & np.isin(tid, written))
            if keep.size:
                late = dataclasses.replace(take_rows(t, keep), track_id=tid[keep])
                f = concat_rows(f, late)
                wh = np.concatenate([wh, twh[keep]])
            out.append(f)
            sizes.append(wh)
        rows = [i for i, f in enumerate(out) if len(f)]
        smoothed = smooth_tracks([out[i] for i in rows], [sizes[i] for i in rows],
                                 self.tracker.config)
        for i, f in zip(rows, smoothed, strict=True):
            out[i] = f
        result = TrackLog()
        for f in out:
            result.append(f)
        return result
