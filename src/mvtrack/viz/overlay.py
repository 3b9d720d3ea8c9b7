"""The analytics drawn on the annotated video while it is written: count lines with their
running counts, zones with the tracks inside, approaches, and each box's speed.

:class:`LiveAnalytics` sees the tracker's rows frame by frame, as a live display would, and
keeps its state in arrays indexed by track ID (no per-track objects):

- **counts** follow the rule of :func:`~mvtrack.analytics.lines.line_crossings` row by row:
  a track crosses when its side of the line's band changes and the step between its last row
  on the old side and its first row on the new side cuts the segment. Only the rows that
  ``results.txt`` holds are used (public IDs, not coasting), and a crossing of a track with
  fewer than ``min_frames`` rows so far is held back until the track has them, so a track too
  short to be counted never shows as a count and, at the last frame, every line shows the
  totals of ``counts.csv`` (up to the rounding of the boxes in ``results.txt``);
- **zones** show the tracks inside in this frame;
- **speeds** are the filter's velocity on the ground plane, km/h (the point's Jacobian of the
  calibration times the velocity in px/frame), "stopped" under ``stop_max``; ``speeds.csv``
  fits a centred window afterwards, which a live display cannot, so a label may differ from
  the file's row by the filter's noise.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.analytics.geometry import signed_distance
from mvtrack.analytics.lines import sides, step_cuts
from mvtrack.types import TrackFrame, TrackState
from mvtrack.viz.scene import draw_scene, draw_speeds

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_COASTING = int(TrackState.COASTING)


class LiveAnalytics:
    """Running counts, occupancy and speeds of an
    :class:`~mvtrack.analytics.settings.AnalyticsSettings`, updated by :meth:`push` and drawn
    by :meth:`draw` (module docstring).

    Parameters
    ----------
    settings : AnalyticsSettings
        Lines, zones, approaches, anchor, ``min_frames``, calibration and speed settings.
    fps : float
        Frame rate (px/frame → m/s).
    """

    def __init__(self, settings: Any, fps: float) -> None:
        self.settings = settings
        self.fps = float(fps)
        n_lines = len(settings.lines)
        #: crossings shown so far, (lines, 2): forward, backward
        self.total = np.zeros((n_lines, 2), np.int64)
        self._rows = np.zeros(0, np.int64)  # rows seen, by track ID
        self._side = np.zeros((0, n_lines), np.int8)  # last side off the band (0: none yet)
        self._last = np.zeros((0, n_lines, 2))  # the point of that row
        self._held = np.zeros((0, n_lines, 2), np.int64)  # crossings of too-short tracks
        self._now: tuple[FloatArray, FloatArray, NDArray[np.bool_]] = (
            np.zeros((0, 2)), np.zeros(0), np.zeros(0, bool))
        self._occupancy = {z.name: 0 for z in settings.zones}

    def _grow(self, top: int) -> None:
        n = self._rows.shape[0]
        if top < n:
            return
        m = max(2 * n, top + 1, 64)

        def pad(a: NDArray[Any]) -> NDArray[Any]:
            out = np.zeros((m, *a.shape[1:]), a.dtype)
            out[:n] = a
            return out

        self._rows, self._side = pad(self._rows), pad(self._side)
        self._last, self._held = pad(self._last), pad(self._held)

    def counts(self) -> dict[str, tuple[int, int]]:
        """Each line's ``(forward, backward)`` crossings shown so far, by name."""
        return {ln.name: (int(t[0]), int(t[1]))
                for ln, t in zip(self.settings.lines, self.total, strict=True)}

    def push(self, tracks: TrackFrame) -> None:
        """Take one frame's tracker rows."""
        s = self.settings
        keep = (tracks.track_id > 0) & (tracks.state != _COASTING)
        keep &= np.isfinite(tracks.filtered_xy).all(axis=1)
        ids = tracks.track_id[keep].astype(np.int64)
        xy, wh = tracks.filtered_xy[keep], tracks.wh[keep]
        if ids.size:
            self._grow(int(ids.max()))
        self._rows[ids] += 1
        foot = xy + np.column_stack([np.zeros(ids.size), wh[:, 1] / 2])  # bottom centre
        p = foot if s.anchor == "foot" else xy
        ready = self._rows[ids] >= s.min_frames
        for j, line in enumerate(s.lines):  # a handful of lines, each over all rows
            d = signed_distance(p, line.a, line.b)
            side = sides(p, line).astype(np.int8)
            prev, q = self._side[ids, j], self._last[ids, j]
            cross = (side != 0) & (prev != 0) & (side != prev)
            if cross.any():
                cross &= step_cuts(q, p, signed_distance(q, line.a, line.b), d, line)[2]
                col = (side < 0).astype(np.int64)  # 0: forward (to the right), 1: backward
                now = cross & ready
                np.add.at(self.total[j], col[now], 1)
                later = cross & ~ready
                np.add.at(self._held[:, j], (ids[later], col[later]), 1)
            off = side != 0
            self._side[ids[off], j] = side[off]
            self._last[ids[off], j] = p[off]
        # tracks that have just reached min_frames rows: their held crossings count now
        just = ids[self._rows[ids] == s.min_frames]
        if just.size:
            self.total += self._held[just].sum(axis=0)
            self._held[just] = 0
        self._occupancy = {z.name: int(np.count_nonzero(z.contains(p))) for z in s.zones}
        self._now = (foot,
                     *self._speeds(p, tracks.velocity[keep]))

    def _speeds(self, p: FloatArray, v: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
        """km/h of the filter's velocity ``v`` (px/frame) at the image points ``p``, and
        which read as stopped; NaN outside the calibrated region or without a calibration."""
        cal = self.settings.calibration
        if cal is None or p.shape[0] == 0:
            return np.full(p.shape[0], np.nan), np.zeros(p.shape[0], bool)
        g = (cal.jacobian(p) @ v[:, :, None])[:, :, 0]  # m/frame on the ground
        kmh = np.hypot(g[:, 0], g[:, 1]) * self.fps * 3.6
        kmh[~cal.calibrated(p)] = np.nan
        return kmh, kmh < self.settings.speed.stop_max

    def draw(self, image: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """Draw the scene, the counts and occupancy so far and this frame's speeds on
        ``image`` (BGR, in place; returned)."""
        draw_scene(image, self.settings, self.counts(), self._occupancy)
        xy, kmh, stopped = self._now
        if xy.shape[0]:
            draw_speeds(image, xy, kmh, stopped)
        return image
