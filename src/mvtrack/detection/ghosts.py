"""Ghosts: foreground blobs where the background holds an object that has since left.

Such a blob's outline has strong edges in the background and none in the frame
(:func:`ghost_blobs`); :class:`~mvtrack.detection.adaptive.GaussianBackground` resets its
pixels to the frame at once.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

Image = NDArray[np.uint8]


def ghost_blobs(
    labels: NDArray[np.int32],
    n: int,
    frame_grey: Image,
    mean_grey: Image,
    ratio: float = 2.0,
) -> NDArray[np.bool_]:
    """Which of the ``n - 1`` labelled blobs are ghosts (True), from the edges on their outline.

    A real object's outline is an edge of the frame; a ghost's (the place an object of the
    background has left) is an edge of the background and not of the frame. With ``E_I`` and
    ``E_B`` the Sobel gradient magnitudes of the frame and the background, a blob is a ghost
    when ``Σ E_B > ratio · Σ E_I`` over its outline (its pixels with a neighbour outside it).

    Parameters
    ----------
    labels : (H, W) int32
        Labels of ``cv2.connectedComponents`` (0 = background).
    n : int
        Number of labels, the background included.
    frame_grey, mean_grey : (H, W) uint8
        Grey frame and grey background.
    ratio : float
        Edge ratio above which a blob is a ghost.

    Returns
    -------
    (n - 1,) bool
        One flag per blob, labels 1 … n - 1.
    """
    if n <= 1:
        return np.zeros(0, bool)
    inside = (labels > 0).astype(np.uint8)
    outline = inside - cv2.erode(inside, None)
    lab = labels[outline > 0]
    ei = _edges(frame_grey)[outline > 0]
    eb = _edges(mean_grey)[outline > 0]
    si = np.bincount(lab, ei, minlength=n)[1:]
    sb = np.bincount(lab, eb, minlength=n)[1:]
    return sb > ratio * si


def ghost_pixels(
    mask: Image, frame_grey: Image, background_grey: Image, ratio: float = 2.0
) -> NDArray[np.bool_] | None:
    """The pixels of the ghost blobs of a foreground ``mask`` (:func:`ghost_blobs` over its
    8-connected components), or ``None`` when it has none."""
    n, labels = cv2.connectedComponents(mask, connectivity=8)
    if n <= 1:
        return None
    ghost = ghost_blobs(labels, n, frame_grey, background_grey, ratio)
    if not ghost.any():
        return None
    return np.concatenate([[False], ghost])[labels]


def _edges(grey: Image) -> NDArray[np.float32]:
    gx = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    return cv2.magnitude(gx, gy)
