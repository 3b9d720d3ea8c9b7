r"""A newly confirmed track that starts where a recently ended one would be now takes its ID.

The tracker's part of relinking, by motion and size only (a detection file has no pixels; the
video loop adds appearance, :mod:`mvtrack.video.relink`). A confirmed track that is deleted
enters a gallery with its last measured position ``x``, frame ``k_e``, filter velocity ``v``
and box ``(w, h)``. A track confirmed at frame ``k`` at position ``z`` with box ``(w', h')``,
born after the ended track's last output row, may continue it when

.. math::

    k - k_e \le W, \qquad \|z - (x + v (k - k_e))\| \le \rho \min(w, w', h, h'), \qquad
    \max(h, h') / \min(h, h') \le 1.6,

and one assignment minimising :math:`\|z - \hat x\|` over the pairs that pass pairs the new
tracks with the ended ones; a paired new track gets the ended track's public ID instead of a
new one (its rows carry no ID before its confirmation, so nothing is rewritten). The radius
follows the boxes' shorter side: two people side by side are about one body width apart.
``W`` is ``TrackerConfig.relink_window`` (3 s), ``ρ`` ``relink_reach`` (1).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: largest ratio of the two box heights of a pair
SIZE_RATIO = 1.6

#: gallery columns of the float block: x, y, vx, vy, w, h
GALLERY_FLOATS = 6


def empty_gallery() -> tuple[IntArray, IntArray, FloatArray]:
    """No ended track: public IDs, last measured frames, ``(x, y, vx, vy, w, h)`` rows."""
    return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, GALLERY_FLOATS))


def pair_new_tracks(
    z: FloatArray, wh: FloatArray, born: IntArray, k: int,
    gallery: tuple[IntArray, IntArray, FloatArray], reach: float, window: int, shown: int = 0,
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Rows of the new tracks (positions ``z`` (N, 2), boxes ``wh`` (N, 2), birth frames
    ``born`` (N,)) paired with rows of the gallery (module docstring); returns
    ``(new_rows, gallery_rows)``. A new track born within ``shown`` frames of the ended one's
    last measurement (while its coasting rows are written) is not paired."""
    _, kg, fg = gallery
    gap = (k - kg)[None, :].astype(np.float64)  # (1, G) frames
    pred = fg[None, :, 0:2] + fg[None, :, 2:4] * gap[..., None]
    dist = np.linalg.norm(z[:, None, :] - pred, axis=2)
    side = np.minimum(wh.min(axis=1)[:, None], fg[None, :, 4:6].min(axis=2))
    h, hg = wh[:, 1][:, None], fg[None, :, 5]
    ratio = np.maximum(h, hg) / np.maximum(np.minimum(h, hg), 1e-9)
    after = born[:, None] > (kg + shown)[None, :]
    ok = after & (gap <= window) & (dist <= reach * side) & (ratio <= SIZE_RATIO)
    if not ok.any():
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    r, c = linear_sum_assignment(np.where(ok, dist, 1e9))
    keep = ok[r, c]
    return r[keep], c[keep]
