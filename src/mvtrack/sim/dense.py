"""Build a :class:`~mvtrack.sim.scene.Scene` from dense per-frame arrays of objects.

The scenes of the analytics (:mod:`mvtrack.sim.queue`, :mod:`mvtrack.sim.speed`) compute
their objects as ``(F, N, ...)`` arrays (NaN where an object is absent); this turns them
into the scene's rows, keeping the rows whose box touches the image.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.sim.scene import Scene

FloatArray = NDArray[np.float64]


def inside_fraction(xy: FloatArray, wh: FloatArray, size: tuple[int, int]) -> FloatArray:
    """Fraction of each box ``(…, 2)`` centre / size that lies inside the image."""
    lo, hi = xy - wh / 2, xy + wh / 2
    img = np.array(size, dtype=np.float64)
    inside = np.clip(np.minimum(hi, img) - np.maximum(lo, 0.0), 0.0, None).prod(axis=-1)
    return np.clip(inside / np.maximum(wh.prod(axis=-1), 1e-12), 0.0, 1.0)


def scene_from_dense(
    name: str, fps: float, size: tuple[int, int], xy: FloatArray, wh: FloatArray,
    heading: FloatArray, *, category: list[str], kind: list[str], body: FloatArray,
    rotates: NDArray[np.bool_], color: NDArray[np.uint8], color2: NDArray[np.uint8],
    meta: dict[str, Any], per_row: dict[str, FloatArray] | None = None,
) -> Scene:
    """A scene from ``(F, N, 2)`` centres and boxes and ``(F, N)`` headings.

    ``per_row`` holds further ``(F, N, ...)`` arrays (e.g. the true speed); they are cut to
    the scene's rows, in its order, and stored in ``meta`` under their names.
    """
    present = np.isfinite(xy).all(axis=-1)
    xy0 = np.where(present[..., None], xy, 0.0)
    wh0 = np.where(present[..., None], wh, 1.0)
    vis = inside_fraction(xy0, wh0, size)
    keep = present & (vis > 0)
    f_idx, o_idx = np.nonzero(keep)  # row-major: sorted by frame, then object
    meta = dict(meta)
    for key, arr in (per_row or {}).items():
        meta[key] = np.asarray(arr)[keep]
    return Scene(
        name=name, fps=float(fps), size=(int(size[0]), int(size[1])), n_frames=xy.shape[0],
        frame=f_idx.astype(np.int64), id=o_idx.astype(np.int64) + 1, xy=xy0[keep],
        wh=wh0[keep], heading=np.asarray(heading, float)[keep], visibility=vis[keep],
        category=np.asarray(category, dtype=str), kind=np.asarray(kind, dtype=str),
        body=np.asarray(body, float), rotates=np.asarray(rotates, bool),
        color=np.asarray(color, np.uint8), color2=np.asarray(color2, np.uint8), meta=meta,
    )
