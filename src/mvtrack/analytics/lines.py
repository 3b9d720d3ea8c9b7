"""Directional count lines with hysteresis, decided from the filtered track.

A count line is a directed segment ``a → b`` with a band of half-width ``h`` (the hysteresis)
around it. Each row of a track is on the left of the line (``d < -h``), on its right
(``d > h``) or inside the band (:func:`~mvtrack.analytics.geometry.signed_distance`). A
track *crosses* when its side changes from left to right (``forward``) or from right to left
(``backward``), the band rows in between ignored, and the straight step between the last
row on the old side and the first row on the new side cuts the segment itself (not its
extension). So a box that flickers around the line, or a track born or ended inside the
band, is never counted; a track that really goes over and comes back is counted once each
way, in the two directions apart.

Everything runs over all rows at once: the side is forward-filled within each track with a
running maximum of row indices, and a crossing is a row whose side differs from the
last non-band side before it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mvtrack.analytics.geometry import along, as_points, signed_distance
from mvtrack.analytics.tracks import TrackPoints

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

FORWARD, BACKWARD = 1, -1


@dataclass(frozen=True)
class CountLine:
    """A directed count line.

    Attributes
    ----------
    name : str
        Name in the outputs.
    a, b : (2,) float64
        End points, px. ``forward`` is a crossing from the left of ``a → b`` to its right, as
        seen on the screen (image y points down).
    hysteresis : float
        Half-width of the band around the line, px: a track must be farther than this on
        both sides for a crossing.
    labels : (str, str)
        Names of the ``forward`` and ``backward`` directions in the outputs.
    """

    name: str
    a: FloatArray
    b: FloatArray
    hysteresis: float = 4.0
    labels: tuple[str, str] = ("forward", "backward")

    def __post_init__(self) -> None:
        pts = as_points([self.a, self.b], 2, f"line {self.name!r} points")
        if np.hypot(*(pts[1] - pts[0])) < 1e-9:
            raise ValueError(f"line {self.name!r}: its two points coincide")
        if not (np.isfinite(self.hysteresis) and self.hysteresis >= 0):
            raise ValueError(f"line {self.name!r}: hysteresis must be >= 0, got "
                             f"{self.hysteresis}")
        if len(self.labels) != 2 or self.labels[0] == self.labels[1]:
            raise ValueError(f"line {self.name!r}: labels must be two different names")
        object.__setattr__(self, "a", pts[0])
        object.__setattr__(self, "b", pts[1])
        object.__setattr__(self, "labels", (str(self.labels[0]), str(self.labels[1])))

    def label(self, direction: int) -> str:
        """Name of ``FORWARD`` (+1) or ``BACKWARD`` (-1)."""
        return self.labels[0] if direction > 0 else self.labels[1]


@dataclass(frozen=True)
class Crossings:
    """The crossings of one line, in row order of the tracks.

    Attributes
    ----------
    track_id : (C,) int64
    row : (C,) int64
        Row of the :class:`TrackPoints` at which the crossing was decided (first row on the
        new side).
    frame : (C,) float64
        Frame at which the step between the two sides cuts the line (interpolated).
    direction : (C,) int64
        ``FORWARD`` (+1) or ``BACKWARD`` (-1).
    point : (C, 2) float64
        Where the track cut the line, px.
    """

    track_id: IntArray
    row: IntArray
    frame: FloatArray
    direction: IntArray
    point: FloatArray

    def __len__(self) -> int:
        return int(self.track_id.shape[0])


def sides(points: FloatArray, line: CountLine) -> IntArray:
    """Side of each point: -1 left of the band, +1 right of it, 0 inside it."""
    d = signed_distance(points, line.a, line.b)
    return np.where(d > line.hysteresis, 1, np.where(d < -line.hysteresis, -1, 0))


def step_cuts(
    q: FloatArray, p: FloatArray, dq: FloatArray, dp: FloatArray, line: CountLine
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Where the steps ``q → p`` (K, 2), whose ends lie on opposite sides of ``line`` at
    signed distances ``dq``, ``dp``, cut it: the fraction ``u`` of the step, the point, and
    whether it cuts the segment itself (not its extension)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        u = dq / (dq - dp)  # in [0, 1] for ends on opposite sides
    cut = q + u[:, None] * (p - q)
    s = along(cut, line.a, line.b)
    return u, cut, (s >= 0.0) & (s <= 1.0)


def line_crossings(tracks: TrackPoints, line: CountLine, anchor: str = "centre") -> Crossings:
    """Every crossing of ``line`` by ``tracks`` (module docstring).

    Parameters
    ----------
    tracks : TrackPoints
        Rows sorted by track, then frame.
    line : CountLine
        The line.
    anchor : {"centre", "foot"}
        The point of the box that crosses (:meth:`TrackPoints.anchor`).
    """
    p = tracks.anchor(anchor)
    k = len(tracks)
    side = sides(p, line)
    idx = np.arange(k)
    # last row at or before each row with a side (running max restarted per track)
    last = np.maximum.accumulate(np.where(side != 0, idx, -1)) if k else idx
    start_of = tracks.starts[tracks.track_index] if k else idx
    prev = np.empty(k, np.int64)
    prev[:1] = -1
    prev[1:] = last[:-1]
    prev = np.where(prev >= start_of, prev, -1)  # within the same track only
    cand = (side != 0) & (prev >= 0)
    cand[cand] = side[prev[cand]] != side[cand]
    rows = np.flatnonzero(cand)
    q = prev[rows]
    d = signed_distance(p, line.a, line.b)
    u, cut, on = step_cuts(p[q], p[rows], d[q], d[rows], line)  # where the step q → row cuts
    rows, q, u, cut = rows[on], q[on], u[on], cut[on]
    frame = tracks.frame[q] + u * (tracks.frame[rows] - tracks.frame[q])
    return Crossings(tracks.track_id[rows], rows, frame, side[rows].astype(np.int64), cut)
