"""Planar paths of straight lines and circular arcs, walked by arc length."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from mvtrack.sim.scene import FloatArray


# ---------------------------------------------------------------------- paths
@dataclass(frozen=True)
class Path2D:
    """A planar path of straight lines and circular arcs, walked by arc length.

    Segments are ``("line", p0, p1)`` or ``("arc", centre, r, a0, sweep)`` with the point
    ``centre + r (cos a, sin a)``, ``a = a0 + sweep·u`` for ``u ∈ [0, 1]``. Beyond either end
    the path continues straight along its end heading.
    """

    segments: tuple[tuple[Any, ...], ...]

    @property
    def lengths(self) -> FloatArray:
        """Length of each segment."""
        out = []
        for seg in self.segments:
            if seg[0] == "line":
                out.append(float(np.hypot(*np.subtract(seg[2], seg[1]))))
            else:
                out.append(abs(seg[2] * seg[4]))
        return np.array(out)

    @property
    def length(self) -> float:
        """Total length."""
        return float(self.lengths.sum())

    def at(self, s: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Positions ``(..., 2)`` and headings at arc lengths ``s`` (vectorised)."""
        s = np.asarray(s, dtype=np.float64)
        lengths = self.lengths
        starts = np.concatenate([[0.0], np.cumsum(lengths)])
        seg = np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(lengths) - 1)
        xy = np.zeros((*s.shape, 2))
        hd = np.zeros(s.shape)
        for i, sg in enumerate(self.segments):  # a few segments, vectorised over s
            m = seg == i
            if not m.any():
                continue
            d = s[m] - starts[i]  # may be < 0 before the first or > L after the last
            if sg[0] == "line":
                p0, p1 = np.asarray(sg[1], float), np.asarray(sg[2], float)
                u = (p1 - p0) / max(lengths[i], 1e-12)
                xy[m] = p0 + d[:, None] * u
                hd[m] = np.arctan2(u[1], u[0])
            else:
                c, r, a0, sweep = np.asarray(sg[1], float), sg[2], sg[3], sg[4]
                sign = np.sign(sweep)
                dc = np.clip(d, 0.0, lengths[i])
                a = a0 + sign * dc / r
                h = a + sign * np.pi / 2
                extra = d - dc  # straight continuation past either end of an arc
                xy[m] = c + r * np.stack([np.cos(a), np.sin(a)], -1) + extra[:, None] * np.stack(
                    [np.cos(h), np.sin(h)], -1
                )
                hd[m] = h
        return xy, np.arctan2(np.sin(hd), np.cos(hd))


def rotation(theta: float) -> FloatArray:
    """The 2×2 rotation by ``theta`` (radians)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def local_path(segments: list[tuple[Any, ...]], theta: float, centre: Any) -> Path2D:
    """A :class:`Path2D` from ``segments`` given in a local frame (travel along +x), turned
    by ``theta`` and moved to ``centre``: an approach of an intersection."""
    rot, c = rotation(theta), np.asarray(centre, np.float64)
    out: list[tuple[Any, ...]] = []
    for sg in segments:
        if sg[0] == "line":
            out.append(("line", tuple(c + rot @ sg[1]), tuple(c + rot @ sg[2])))
        else:
            out.append(("arc", tuple(c + rot @ np.asarray(sg[1])), sg[2], sg[3] + theta, sg[4]))
    return Path2D(tuple(out))


def place(
    path: Path2D, s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Centres (NaN off the path) and headings for arc lengths ``s``."""
    xy, hd = path.at(s)
    off = (s < 0) | (s > path.length)
    xy[off] = np.nan
    return xy, hd
