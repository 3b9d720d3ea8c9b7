"""Blobs of a foreground mask: 8-connected labels and each blob's box and area.

:func:`label_blobs` labels with OpenCV's BBDT labeller (16-bit labels unless there are more
than 65535 blobs: less memory traffic, the same labels) over the band of rows that holds
foreground only, and counts the statistics in one compiled pass (:func:`blob_stats`) that
skips the background eight bytes at a time: OpenCV's statistics pass costs more than its
labelling on a road scene (about 0.25 against 0.18 ms on a 640×480 mask), and this one a
third of it.

The band starts on an even row: the labeller numbers the blobs in the order of their first
2×2 block, which rows of background before and after the band do not change (nor the
threads' stripes, which are joined in that order), so the labels are those of the whole
image.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.jit import kernel

Image = NDArray[np.uint8]


def label_blobs(mask: Image) -> tuple[NDArray[np.integer], NDArray[np.int32]]:
    """8-connected labels of ``mask`` (non-zero: foreground) and statistics.

    Returns
    -------
    labels : (H, W) uint16 or int32
        ``cv2.connectedComponents``'s labels (BBDT), 0 the background.
    stats : (N, 5) int32
        Left, top, width, height and area of each label (``cv2.CC_STAT_*`` columns, as
        ``cv2.connectedComponentsWithStats`` gives them); row 0, the background, holds the
        whole image's box and the background's area.
    """
    h, w = mask.shape
    _, y, _, bh = cv2.boundingRect(mask)
    y0, y1 = y - y % 2, y + bh
    if bh == 0:
        return np.zeros((h, w), np.uint16), np.array([[0, 0, w, h, h * w]], np.int32)
    band = mask[y0:y1] if (y0, y1) != (0, h) else mask
    try:
        n, lab = cv2.connectedComponentsWithAlgorithm(band, 8, cv2.CV_16U, cv2.CCL_BBDT)
    except cv2.error:  # more than 65535 blobs (OpenCV checks before overflowing)
        n, lab = cv2.connectedComponentsWithAlgorithm(band, 8, cv2.CV_32S, cv2.CCL_BBDT)
    flat = lab.reshape(-1)
    per = 8 // flat.itemsize  # labels in a 64-bit word
    words = flat[: flat.size // per * per].view(np.uint64)
    stats = np.zeros((n, 5), np.int32)
    blob_stats(flat, words, per, w, y0, stats)
    stats[0] = (0, 0, w, h, h * w - int(stats[1:, 4].sum()))
    if band is mask:
        return lab, stats
    labels = np.zeros((h, w), lab.dtype)
    labels[y0:y1] = lab
    return labels, stats


@kernel
def blob_stats(flat: NDArray[np.integer], words: NDArray[np.uint64], per: int, width: int,
               y0: int, stats: NDArray[np.int32]) -> None:
    """Left, top, width, height and area of labels 1… of the label image ``flat`` (rows of
    ``width``, the first at row ``y0`` of the image) into ``stats`` (zeros); ``words``: the
    same labels ``per`` to a 64-bit word, all-background words skipped."""
    n = stats.shape[0]
    left = np.full(n, width, np.int64)
    right = np.full(n, -1, np.int64)
    top = np.full(n, np.iinfo(np.int64).max, np.int64)
    bottom = np.full(n, -1, np.int64)
    area = np.zeros(n, np.int64)
    for i in range(words.size + 1):
        if i < words.size:
            if words[i] == 0:
                continue
            start, stop = per * i, per * i + per
        else:  # the labels after the last whole word
            start, stop = per * words.size, flat.size
        for j in range(start, stop):
            lab = flat[j]
            if lab == 0:
                continue
            y = j // width
            x = j - y * width
            area[lab] += 1
            if x < left[lab]:
                left[lab] = x
            if x > right[lab]:
                right[lab] = x
            if y < top[lab]:
                top[lab] = y
            bottom[lab] = y
    for lab in range(1, n):
        stats[lab, 0] = left[lab]
        stats[lab, 1] = top[lab] + y0
        stats[lab, 2] = right[lab] - left[lab] + 1
        stats[lab, 3] = bottom[lab] - top[lab] + 1
        stats[lab, 4] = area[lab]
