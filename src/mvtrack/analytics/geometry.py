"""Plane geometry over arrays of points: directed segments and polygons.

Image coordinates: x to the right, y down, in pixels. The *side* of a point ``p`` with respect
to the directed segment ``a → b`` is the signed distance

.. math::  d(p) = \\frac{(b - a) \\times (p - a)}{\\lVert b - a \\rVert},
           \\qquad u \\times v = u_x v_y - u_y v_x,

positive on the right of ``a → b`` as seen on the screen (with y down, facing along ``+x``,
``+y`` is on the right).
"""

from __future__ import annotations

import numpy as np
from matplotlib.path import Path as _MplPath
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def as_points(value: ArrayLike, n: int | None = None, what: str = "points") -> FloatArray:
    """``value`` as a finite ``(N, 2)`` float array (exactly ``n`` rows if given)."""
    pts = np.asarray(value, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"{what} must be a list of [x, y] pairs, got shape {pts.shape}")
    if n is not None and pts.shape[0] != n:
        raise ValueError(f"{what} must have {n} points, got {pts.shape[0]}")
    if not np.isfinite(pts).all():
        raise ValueError(f"{what} must be finite numbers")
    return pts


def signed_distance(points: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Signed distance (px) of ``points`` (K, 2) from the line through ``a → b``; > 0 on its
    right (module docstring)."""
    d = np.asarray(b, float) - np.asarray(a, float)
    rel = points - np.asarray(a, float)
    return (d[0] * rel[:, 1] - d[1] * rel[:, 0]) / np.hypot(d[0], d[1])


def along(points: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Position of the projection of ``points`` on ``a → b``: 0 at ``a``, 1 at ``b``."""
    d = np.asarray(b, float) - np.asarray(a, float)
    return ((points - np.asarray(a, float)) @ d) / float(d @ d)


def polygon_area(vertices: FloatArray) -> float:
    """Signed area of a polygon (shoelace formula); the sign is the vertex order's."""
    x, y = vertices[:, 0], vertices[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def polygon_centroid(vertices: FloatArray) -> FloatArray:
    """Centroid of a simple polygon (of its area, not of its vertices)."""
    x, y = vertices[:, 0], vertices[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    a = cross.sum() / 2.0
    if abs(a) < 1e-12:
        return vertices.mean(axis=0)
    return np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * a)


def inside_polygon(points: FloatArray, vertices: FloatArray) -> BoolArray:
    """Which of ``points`` (K, 2) lie inside the polygon ``vertices`` (V, 2), V ≥ 3.

    Even-odd rule (matplotlib's compiled point-in-path test); points exactly on an edge may
    fall either way.
    """
    if points.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    ok = np.isfinite(points).all(axis=1)
    out = np.zeros(points.shape[0], dtype=bool)
    out[ok] = _MplPath(vertices).contains_points(points[ok])
    return out
