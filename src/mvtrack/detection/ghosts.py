"""Ghosts: foreground blobs where the background holds an object that has since left.

Such a blob's outline has strong edges in the background and none in the frame
(:func:`ghost_blobs`); :class:`~mvtrack.detection.adaptive.GaussianBackground` resets its
pixels to the frame at once. :func:`reset_ghosts` does the test and the reset of the disturbance
map in one compiled pass over the labels (:func:`ghost_reset`), the Sobel gradients taken at the
outline pixels only.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.jit import kernel

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


def reset_ghosts(
    mask: Image, frame_grey: Image, background: NDArray[np.float32], ratio: float = 2.0
) -> bool:
    """Reset the ghost blobs of a foreground ``mask`` to the frame, in place: the pixels of
    :func:`ghost_pixels` ``(mask, frame_grey, cv2.convertScaleAbs(background))`` take the
    frame's grey level in ``background`` and leave ``mask`` (0). Whether there were any.

    Parameters
    ----------
    mask : (H, W) uint8
        Foreground, non-zero on the blobs; their ghost pixels are set to 0.
    frame_grey : (H, W) uint8
        The grey frame.
    background : (H, W) float32
        The running-average background (grey levels in [0, 255]); its ghost pixels are set
        to the frame's.
    ratio : float
        Edge ratio above which a blob is a ghost (:func:`ghost_blobs`).
    """
    n, labels = cv2.connectedComponents(mask, connectivity=8)
    if n <= 1:
        return False
    return bool(ghost_reset(np.ascontiguousarray(labels, np.int32), int(n),
                            np.ascontiguousarray(frame_grey), background, mask, float(ratio)))


@kernel
def _reflect(i: int, n: int) -> int:
    """Index ``i`` of an axis of length ``n`` with OpenCV's ``BORDER_REFLECT_101``."""
    if n == 1:
        return 0
    if i < 0:
        return -i
    if i >= n:
        return 2 * n - 2 - i
    return i


@kernel
def ghost_reset(
    labels: NDArray[np.int32], n: int, grey: Image, background: NDArray[np.float32],
    mask: Image, ratio: float,
) -> bool:
    r"""The ghost test of :func:`ghost_blobs` and the reset of :func:`reset_ghosts` in one
    pass over the image: for each labelled pixel with a neighbour (of the 8, inside the
    image) outside every blob, the 3×3 Sobel gradient magnitudes
    :math:`\sqrt{g_x^2 + g_y^2}` (float32, ``BORDER_REFLECT_101``) of ``grey`` and of the
    background rounded to grey levels (``cv2.convertScaleAbs``) are summed per label in row
    order (as ``np.bincount``); a label is a ghost when ``Σ E_B > ratio · Σ E_I``, and its
    pixels get ``background = grey`` and ``mask = 0``. Returns whether any label is a
    ghost."""
    h, w = labels.shape
    si = np.zeros(n)
    sb = np.zeros(n)
    for y in range(h):
        for x in range(w):
            lab = labels[y, x]
            if lab <= 0:
                continue
            outline = False
            for yy in range(max(y - 1, 0), min(y + 2, h)):
                for xx in range(max(x - 1, 0), min(x + 2, w)):
                    if labels[yy, xx] == 0:
                        outline = True
            if not outline:
                continue
            gxi = 0.0
            gyi = 0.0
            gxb = 0.0
            gyb = 0.0
            for dy in range(-1, 2):
                yy = _reflect(y + dy, h)
                for dx in range(-1, 2):
                    if dx == 0 and dy == 0:
                        continue
                    xx = _reflect(x + dx, w)
                    wx = dx * (2 - abs(dy))  # Sobel: [-1 0 1] across, [1 2 1] along
                    wy = dy * (2 - abs(dx))
                    vi = float(grey[yy, xx])
                    vb = min(float(np.rint(abs(background[yy, xx]))), 255.0)
                    gxi += wx * vi
                    gyi += wy * vi
                    gxb += wx * vb
                    gyb += wy * vb
            # integers below 2**24: float32 holds the squares' sums exactly
            si[lab] += float(np.sqrt(np.float32(gxi * gxi + gyi * gyi)))
            sb[lab] += float(np.sqrt(np.float32(gxb * gxb + gyb * gyb)))
    ghost = np.zeros(n, np.bool_)
    found = False
    for lab in range(1, n):
        if sb[lab] > ratio * si[lab]:
            ghost[lab] = True
            found = True
    if not found:
        return False
    for y in range(h):
        for x in range(w):
            if ghost[labels[y, x]]:
                background[y, x] = grey[y, x]
                mask[y, x] = 0
    return True
