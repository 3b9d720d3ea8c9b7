"""Whether a blob is claimed by two predicted boxes, in one compiled pass.

:class:`~mvtrack.detection.tracksplit.TrackSplit` without merging changes a frame's blobs only
when one of them holds most of two tracks' predicted boxes; every frame it asks
:func:`shared_blob`, which does in one call what
:func:`~mvtrack.detection.splitmerge.usable_predictions` (without a size prior) and
:func:`~mvtrack.detection.splitmerge.blob_claims` do in a dozen array steps, with the same
arithmetic (:func:`~mvtrack.detection.splitmerge.overlap_areas` for the intersections).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.splitmerge import SAME, distinct_boxes, overlap_areas
from mvtrack.jit import kernel

FloatArray = NDArray[np.float64]

@kernel
def usable_boxes(predicted: FloatArray) -> FloatArray:
    """:func:`~mvtrack.detection.splitmerge.usable_predictions` without a size prior: the
    finite boxes (tlwh, C-contiguous) of positive size, without duplicates
    (:func:`~mvtrack.detection.splitmerge.distinct_boxes`)."""
    n = predicted.shape[0]
    ok = np.zeros(n, np.bool_)
    m = 0
    for j in range(n):
        good = predicted[j, 2] > 0.0 and predicted[j, 3] > 0.0
        for c in range(4):
            if not np.isfinite(predicted[j, c]):
                good = False
        ok[j] = good
        m += good
    pred = np.empty((m, 4))
    i = 0
    for j in range(n):
        if ok[j]:
            pred[i] = predicted[j]
            i += 1
    return distinct_boxes(pred, SAME)


@kernel
def shared_blob(xy: FloatArray, wh: FloatArray, predicted: FloatArray, cover: float) -> bool:
    """Whether a blob (centres ``xy``, sizes ``wh``) is the home of two or more of the usable
    ``predicted`` boxes (tlwh; :func:`usable_boxes`) that it covers by ``cover`` of their
    area: each box's home is the blob holding most of it (the first of equal shares).
    False with fewer than two usable boxes or no blob."""
    pred = usable_boxes(predicted)
    n, m = pred.shape[0], xy.shape[0]
    if n < 2 or m == 0:
        return False
    blobs = np.empty((m, 4))
    for i in range(m):
        blobs[i, 0] = xy[i, 0] - wh[i, 0] / 2
        blobs[i, 1] = xy[i, 1] - wh[i, 1] / 2
        blobs[i, 2] = wh[i, 0]
        blobs[i, 3] = wh[i, 1]
    inter = np.empty((m, n))
    overlap_areas(blobs, pred, inter)
    count = np.zeros(m, np.int64)
    for j in range(n):
        area = max(pred[j, 2] * pred[j, 3], 1e-9)
        home, best = 0, inter[0, j] / area
        if best == best:  # argmax: the first largest, or the first NaN
            for i in range(1, m):
                s = inter[i, j] / area
                if s != s:
                    home, best = i, s
                    break
                if s > best:
                    home, best = i, s
        if best >= cover:
            count[home] += 1
            if count[home] >= 2:
                return True
    return False
