r"""Flat wings at the base of a blob cut off: cast shadows on the ground, and the joins of
objects standing side by side.

An object's cast shadow on sunlit ground, when it is much darker than the ground, is found as
foreground by any photometric test (a hard shadow at a fifth of the ground's brightness, lit
by the blue sky, keeps neither the ground's colour nor, through the camera's noise and
compression, its texture). It lies on the ground: in the picture it is a flat wing at the
object's base, and it joins objects that walk or stand side by side into one blob.

With :math:`b` the blob's lowest row and :math:`t(c)` the top of its pixels in column
:math:`c`, the column's *height above the base* is :math:`h(c) = b - t(c) + 1` (the blob's
upper envelope, measured from its base). A column is *tall* when

.. math:: h(c) \ge \tau \max_{c'} h(c')

(``tau``); the blob's parts are its maximal runs of tall columns, each boxed over its own
columns and pixels. A flat wing at either end is cut off; a flat run between two tall parts
(a shadow or a thin bridge of pixels at ground level) separates them. Arms, bags and the
gaps between legs do not make a column low: its top is the object's top. Nothing here is
about a kind of object: a car seen from above or from the side has columns of nearly equal
height, and keeps its box.

All blobs at once: the foreground pixels are grouped by (blob, column) of the blobs' boxes
(no sort: each group's place is known from the blob's box), the heights, parts and boxes follow
from reductions over the groups (no loop over blobs).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


def cut_flat_wings(
    labels: NDArray[np.integer], ids: NDArray[np.integer], stats: NDArray[np.integer],
    tau: float,
) -> tuple[FloatArray, IntArray, FloatArray]:
    """The parts of the blobs ``ids`` with their flat wings cut off (module docstring).

    Parameters
    ----------
    labels : (H, W) int
        Label image (``cv2.connectedComponentsWithStats``, 8-connected).
    ids : (M,) int
        The labels of the blobs to look at (others are ignored).
    stats : (N, 5) int
        The labeller's statistics of every label (left, top, width, height, area).
    tau : float
        Least height of a tall column, as a share of the blob's tallest (0: nothing cut).

    Returns
    -------
    boxes : (K, 4) float
        The parts' boxes ``(left, top, width, height)``, pixel ``(col, row)`` covering
        ``[col - 0.5, col + 0.5)``; a blob without a low column gives its own box.
    source : (K,) int
        Index into ``ids`` of each part's blob.
    area : (K,) float
        Foreground pixels of each part (its columns' pixels of its blob).
    """
    ids = np.asarray(ids, np.intp).reshape(-1)
    st = np.asarray(stats)
    if ids.size == 0:
        return np.zeros((0, 4)), np.zeros(0, np.intp), np.zeros(0)
    if tau <= 0:
        s = st[ids].astype(np.float64)
        boxes = np.column_stack([s[:, 0] - 0.5, s[:, 1] - 0.5, s[:, 2], s[:, 3]])
        return boxes, np.arange(ids.size), s[:, 4]
    h, w = labels.shape
    index = np.full(len(st), -1, np.intp)  # label -> index into ids
    index[ids] = np.arange(ids.size)
    r0 = int(st[ids, 1].min())  # the rows of the blobs asked for
    band = labels[r0 : int((st[ids, 1] + st[ids, 3]).max())].reshape(-1)
    pix = np.flatnonzero(band != 0)  # row by row (a boolean image is scanned fastest)
    blob = index[band[pix]]
    inside = blob >= 0
    pix, blob = pix[inside], blob[inside]
    row, col = np.divmod(pix, w)
    row += r0
    # one group per (blob, column) of the blob's box, blob by blob, columns left to right;
    # a blob's columns are contiguous (it is connected), an empty one is dropped anyway
    left, width = st[ids, 0].astype(np.intp), st[ids, 2].astype(np.intp)
    offset = np.cumsum(width) - width
    key = offset[blob] + col - left[blob]
    n_groups = int(width.sum())
    count = np.bincount(key, minlength=n_groups)
    top = np.full(n_groups, h, np.intp)
    np.minimum.at(top, key, row)
    bottom = np.zeros(n_groups, np.intp)
    np.maximum.at(bottom, key, row)
    present = np.flatnonzero(count)
    gblob = np.repeat(np.arange(ids.size), width)[present]
    gcol = (np.arange(n_groups) - np.repeat(offset - left, width))[present]
    top, bottom = top[present], bottom[present]
    count = count[present].astype(np.float64)
    base = st[ids, 1] + st[ids, 3] - 1  # each blob's lowest row
    height = base[gblob] - top + 1  # h(c)
    bstart = np.flatnonzero(np.r_[True, gblob[1:] != gblob[:-1]])
    tallest = np.maximum.reduceat(height, bstart)
    tall = height >= tau * np.repeat(tallest, np.diff(np.r_[bstart, gblob.size]))
    # parts: runs of tall columns within a blob (a blob's columns are contiguous)
    g = np.flatnonzero(tall)
    new = np.r_[True, (gblob[g][1:] != gblob[g][:-1]) | (np.diff(g) > 1)]
    start = np.flatnonzero(new)
    x0 = gcol[g][start]
    x1 = np.maximum.reduceat(gcol[g], start)
    y0 = np.minimum.reduceat(top[g], start)
    y1 = np.maximum.reduceat(bottom[g], start)
    area = np.add.reduceat(count[g], start)
    boxes = np.column_stack([x0 - 0.5, y0 - 0.5, x1 - x0 + 1, y1 - y0 + 1]).astype(np.float64)
    return boxes, gblob[g][start].astype(np.intp), area
