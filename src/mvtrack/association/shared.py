"""Boxes shared by two tracks: a weak detection over another track's predicted box.

In a group a detector's weak box often lies over two objects at once: half on the one it was
assigned to, half on the one beside. Its centre then says little about either, and a track
updated with it at the usual measurement noise is pulled between the two, box and velocity.
The tracker weighs such a box less (the measurement-origin uncertainty that JPDA weighs, here
for the one box a track took): a detection is **shared** when it is weak (class ``LOW`` of
:func:`mvtrack.association.assign.associate`, under ``score_high``) and overlaps the
predicted box of a track other than its own by IoU ≥ ``t`` (``TrackerConfig.shared_iou``,
0.4); its centre's std is then at least :func:`shared_std` box sizes.

The std is the distance between the two objects the box may be on. Two boxes of one size
offset by ``d`` box sizes along an axis overlap by

.. math:: \\mathrm{IoU} = \\frac{1 - d}{1 + d}, \\qquad d = \\frac{1 - t}{1 + t},

so at the threshold ``t`` = 0.4 the other object's centre is up to ``d`` = 0.43 box sizes
away. A threshold of 1 or more turns the rule off (no box is shared). Strong boxes keep
``measurement_noise``: the detector is sure of them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.assign import LOW
from mvtrack.association.pairs import overlap_pairs
from mvtrack.jit import kernel

FloatArray = NDArray[np.float64]

__all__ = ["OFF", "measurement_var", "shared", "shared_std"]

#: the threshold that turns the rule off (``TrackerConfig.shared_iou`` None)
OFF = 1.0


@kernel
def shared_std(t: float) -> float:
    """A shared box's centre std in box sizes, ``d = (1 − t) / (1 + t)``: the offset of two
    boxes of one size that overlap by IoU ``t`` (0 for ``t ≥ 1``)."""
    return max(0.0, (1.0 - t) / (1.0 + t))


@kernel
def shared(det_index: NDArray[np.intp], centre: FloatArray, wh: FloatArray,
           dxy: FloatArray, dwh: FloatArray, dclass: NDArray[np.int8], t: float
           ) -> NDArray[np.bool_]:
    """Whether each track's detection is shared.

    ``det_index`` (N,): each track's detection (−1: none); ``centre``, ``wh`` (N, 2): the
    tracks' predicted centres and boxes; ``dxy``, ``dwh``, ``dclass`` (M, ...): the
    detections' centres, boxes and classes. Track ``i`` with detection ``j`` is shared when
    ``dclass[j]`` is ``LOW`` and ``IoU(b_o, b_j) ≥ t`` for some track ``o ≠ i``. The
    overlapping pairs come from :func:`mvtrack.association.pairs.overlap_pairs` (a grid of
    cells in a large frame), so the work grows with the pairs, not with ``N²``.
    """
    n, m = det_index.shape[0], dxy.shape[0]
    out = np.zeros(n, np.bool_)
    if t >= OFF or n < 2:
        return out
    dsel = np.zeros(m, np.bool_)
    for i in range(n):
        j = det_index[i]
        if j >= 0 and dclass[j] == LOW:
            dsel[j] = True
    if not dsel.any():
        return out
    ti, dj, _ = overlap_pairs(centre, wh, np.ones(n, np.bool_), dxy, dwh, dsel, 1.0 - t, 0.0)
    count = np.zeros(m, np.intp)  # tracks whose predicted box overlaps detection j by ≥ t
    first = np.full(m, -1, np.intp)  # the first of them
    for e in range(ti.size):
        if count[dj[e]] == 0:
            first[dj[e]] = ti[e]
        count[dj[e]] += 1
    for i in range(n):
        j = det_index[i]
        if j >= 0 and dsel[j]:
            out[i] = count[j] >= 2 or (count[j] == 1 and first[j] != i)
    return out


@kernel
def measurement_var(rz: float, wh: FloatArray, is_shared: NDArray[np.bool_], t: float
                    ) -> FloatArray:
    """Each track's measurement variance per axis, px²: ``r = (σ wh)²`` with ``σ = rz`` box
    sizes, or ``max(rz, shared_std(t))`` for a shared box: the ``R`` of the update,
    eqs. (3)–(5) of paper 1."""
    n = wh.shape[0]
    wide = max(rz, shared_std(t))
    r = np.empty((n, 2))
    for i in range(n):
        s = wide if is_shared[i] else rz
        for ax in range(2):
            v = s * wh[i, ax]
            r[i, ax] = v * v  # R = (σ wh)²
    return r
