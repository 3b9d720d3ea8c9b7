"""Zones: which tracks are inside a polygon, their visits (enter, leave, dwell) and the
occupancy per frame.

A *visit* is a run of a track's rows inside the zone; two runs of the same track separated
by at most ``gap`` frames outside (a box flickering over the zone's edge) are one visit.
Dwell is ``(last - first + 1) / fps`` of the visit's frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mvtrack.analytics.geometry import as_points, inside_polygon, polygon_area, polygon_centroid
from mvtrack.analytics.tracks import TrackPoints

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Zone:
    """A polygonal zone (px), at least 3 vertices, non-zero area."""

    name: str
    polygon: FloatArray

    def __post_init__(self) -> None:
        pts = as_points(self.polygon, None, f"zone {self.name!r} polygon")
        if pts.shape[0] < 3:
            raise ValueError(f"zone {self.name!r}: a polygon needs at least 3 points, got "
                             f"{pts.shape[0]}")
        if abs(polygon_area(pts)) < 1e-9:
            raise ValueError(f"zone {self.name!r}: the polygon has no area")
        object.__setattr__(self, "polygon", pts)

    @property
    def centroid(self) -> FloatArray:
        return polygon_centroid(self.polygon)

    def contains(self, points: FloatArray) -> NDArray[np.bool_]:
        """(K,) which points are inside."""
        return inside_polygon(points, self.polygon)


@dataclass(frozen=True)
class Visits:
    """The visits of one zone, sorted by track then time.

    Attributes
    ----------
    track_id : (V,) int64
    first, last : (V,) int64
        First and last frame inside.
    first_row, last_row : (V,) int64
        The corresponding rows of the :class:`TrackPoints`.
    """

    track_id: IntArray
    first: IntArray
    last: IntArray
    first_row: IntArray
    last_row: IntArray

    def __len__(self) -> int:
        return int(self.track_id.shape[0])

    def dwell(self, fps: float) -> FloatArray:
        """(V,) seconds inside."""
        return (self.last - self.first + 1) / float(fps)


def zone_visits(inside: NDArray[np.bool_], tracks: TrackPoints, gap: int = 0) -> Visits:
    """Visits from the rows ``inside`` (K,) a zone (module docstring).

    A visit starts at an inside row whose previous inside row of the same track is more than
    ``gap + 1`` frames before it (or does not exist).
    """
    rows = np.flatnonzero(inside)
    if rows.size == 0:
        z = np.zeros(0, np.int64)
        return Visits(z, z, z, z, z)
    tid, fr = tracks.track_id[rows], tracks.frame[rows]
    new = np.ones(rows.size, dtype=bool)
    new[1:] = (tid[1:] != tid[:-1]) | (fr[1:] - fr[:-1] > gap + 1)
    begin = np.flatnonzero(new)
    end = np.append(begin[1:], rows.size) - 1
    return Visits(tid[begin], fr[begin], fr[end], rows[begin], rows[end])


def occupancy(inside: NDArray[np.bool_], tracks: TrackPoints, n_frames: int) -> IntArray:
    """(n_frames,) number of tracks inside the zone in each frame."""
    fr = tracks.frame[inside]
    fr = fr[(fr >= 0) & (fr < n_frames)]
    return np.bincount(fr, minlength=n_frames).astype(np.int64)
