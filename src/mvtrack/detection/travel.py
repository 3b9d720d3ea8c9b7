r"""Which tracks have travelled: objects enter a fixed camera's view moving; the flicker of
leaves, a ghost left in the background or a reflection stays where it is.

:class:`Travel` follows the rows of a tracker's output frame by frame and keeps, for each track
ID, its *anchor* — where it was born: the prediction of its first row, made from its first
detection before the update (:attr:`~mvtrack.types.TrackFrame.predicted_xy`) — and whether it
has travelled: a track has travelled from the first row whose position :math:`p` (the
measurement, or the filter's position without one) lies ``reach`` box sizes from the anchor
:math:`a` along either axis,

.. math:: |p_x - a_x| \ge \rho\, w \;\vee\; |p_y - a_y| \ge \rho\, h,

and stays so. Distances are in the track's own box sizes (the same test for a car that crosses
the picture and a walker far away); ``reach`` is :math:`\rho`. A track that waits after it
arrived (a car at a red light) has travelled. A track whose first box touches the image's
border has come into the view from outside it: it has travelled from its first row (a car
entering the picture shows only its front, whose box grows more than its centre moves).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.types import TrackFrame

BoolArray = NDArray[np.bool_]


class Travel:
    """Anchors and the travelled flag of every track ID (module docstring).

    Parameters
    ----------
    reach : float, default 0.5
        :math:`\\rho`, box sizes from the anchor (0: every track has travelled at once).
    """

    def __init__(self, reach: float = 0.5) -> None:
        if not (np.isfinite(reach) and reach >= 0):
            raise ValueError(f"reach must be a number >= 0, got {reach}")
        self.reach = float(reach)
        self._anchor = np.full((1, 2), np.nan)  # track ID -> anchor (NaN: not seen)
        self._done = np.zeros(1, bool)  # track ID -> travelled

    def _grow(self, n: int) -> None:
        if n <= self._done.size:
            return
        m = max(n, 2 * self._done.size)
        self._anchor = np.concatenate([self._anchor, np.full((m - len(self._anchor), 2),
                                                             np.nan)])
        self._done = np.concatenate([self._done, np.zeros(m - self._done.size, bool)])

    def update(self, tracks: TrackFrame, size: tuple[int, int] | None = None) -> BoolArray:
        """Follow the rows of ``tracks``; whether each row's track has travelled (rows
        without a public ID, ``track_id <= 0``, have not). With the image's ``size``
        (W, H), a track whose first box touches the image's border came in from outside
        the view: it has travelled."""
        ids = np.asarray(tracks.track_id, np.int64)
        out = np.zeros(ids.size, bool)
        pub = ids > 0
        if not pub.any():
            return out
        tid = ids[pub]
        self._grow(int(tid.max()) + 1)
        new = np.isnan(self._anchor[tid, 0])
        first = tracks.predicted_xy[pub][new]
        self._anchor[tid[new]] = np.where(np.isnan(first), tracks.filtered_xy[pub][new], first)
        pos = np.where(np.isnan(tracks.measured_xy[pub]), tracks.filtered_xy[pub],
                       tracks.measured_xy[pub])
        wh = tracks.wh[pub]
        far = (np.abs(pos - self._anchor[tid]) >= self.reach * wh).any(axis=1)
        self._done[tid[far]] = True
        if size is not None and new.any():  # born at the border: came in from outside
            b = np.column_stack([tracks.filtered_xy[pub][new] - wh[new] / 2, wh[new]])
            edge = (b[:, 0] < 1.5) | (b[:, 1] < 1.5) | (b[:, 0] + b[:, 2] > size[0] - 2.5) | (
                b[:, 1] + b[:, 3] > size[1] - 2.5)
            self._done[tid[new][edge]] = True
        out[pub] = self._done[tid]
        return out

    def travelled(self, ids: NDArray[np.integer]) -> BoolArray:
        """Whether the tracks ``ids`` have travelled (IDs never seen have not)."""
        ids = np.asarray(ids, np.int64)
        inside = (ids > 0) & (ids < self._done.size)
        out = np.zeros(ids.shape, bool)
        out[inside] = self._done[ids[inside]]
        return out
