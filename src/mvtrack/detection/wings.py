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

All blobs in one compiled pass (:func:`wing_parts`): each blob's box is scanned once for the
top, bottom and pixel count of its columns, and its parts follow from them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.jit import kernel

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
    boxes, source, area = wing_parts(labels, ids, st, float(tau))
    return boxes, source, area


@kernel
def wing_parts(
    labels: NDArray[np.integer], ids: IntArray, stats: NDArray[np.integer], tau: float,
) -> tuple[FloatArray, IntArray, FloatArray]:
    """:func:`cut_flat_wings` for ``tau > 0``: each blob's box scanned row by row for its
    columns' top :math:`t(c)`, bottom and pixel count; the tall columns
    (:math:`h(c) = b - t(c) + 1 \\ge \\tau \\max h`) grouped into runs, each run a part,
    blob by blob in the order of ``ids``, left to right."""
    n_rows = labels.shape[0]
    total = 0
    for i in range(ids.size):
        total += stats[ids[i], 2]
    boxes = np.empty((total, 4))
    source = np.empty(total, np.intp)
    area = np.empty(total)
    k = 0
    for i in range(ids.size):
        lab = ids[i]
        left, top, width, height = stats[lab, 0], stats[lab, 1], stats[lab, 2], stats[lab, 3]
        col_top = np.full(width, n_rows, np.intp)
        col_bottom = np.zeros(width, np.intp)
        col_count = np.zeros(width, np.intp)
        for r in range(top, top + height):
            for c in range(width):
                if labels[r, left + c] == lab:
                    if col_top[c] == n_rows:
                        col_top[c] = r
                    col_bottom[c] = r
                    col_count[c] += 1
        base = top + height - 1  # the blob's lowest row
        tallest = 0
        for c in range(width):
            if col_count[c] > 0:
                tallest = max(tallest, base - col_top[c] + 1)
        least = tau * tallest
        run = False
        x0 = x1 = y0 = y1 = 0
        pixels = 0.0
        for c in range(width + 1):  # one past the last column: it ends the last part
            if c < width and col_count[c] == 0:  # no pixel (not for a connected blob)
                continue
            if c < width and base - col_top[c] + 1 >= least:  # tall: starts or extends
                if not run:
                    run, x0, y0, y1, pixels = True, c, col_top[c], col_bottom[c], 0.0
                x1 = c
                y0, y1 = min(y0, col_top[c]), max(y1, col_bottom[c])
                pixels += col_count[c]
            elif run:  # a low column (or the box's end) ends the part
                boxes[k, 0], boxes[k, 1] = left + x0 - 0.5, y0 - 0.5
                boxes[k, 2], boxes[k, 3] = x1 - x0 + 1, y1 - y0 + 1
                source[k], area[k] = i, pixels
                k += 1
                run = False
    return boxes[:k], source[:k], area[:k]
