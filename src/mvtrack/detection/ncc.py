"""Normalised cross-correlation of a stored appearance, over its object's pixels only.

:class:`Template` is one stored appearance (a grey patch, its object mask, the box centre
inside it) with the terms of :func:`masked_ncc` computed once; the search over a window is
:func:`masked_ncc` (with a mask) or OpenCV's ``TM_CCOEFF_NORMED`` (without), in
:meth:`mvtrack.detection.template.TemplateBank.rescue`.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

Image = NDArray[np.uint8]


def grey(img: Image) -> Image:
    """The image in grey levels (unchanged if it is grey already)."""
    return img if img.ndim == 2 else cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)


class Template:
    """One stored appearance: grey patch, its object mask (or None), the box centre inside it,
    the observation tick; for a masked template also the terms of :func:`masked_ncc`."""

    __slots__ = ("gate", "mask", "mf", "n", "offset", "patch", "tick", "tz", "var_t")

    def __init__(
        self,
        patch: Image,
        mask: Image | None,
        offset: tuple[float, float],
        tick: int,
        mean: float | None = None,
    ) -> None:
        self.patch = patch
        self.mask = mask
        self.offset = offset
        self.tick = tick
        # the gate mask of the last search and its key (placements' shape, offset of the
        # first placement's centre from the search centre): a stopped vehicle is searched
        # around the same place frame after frame, so the mask is usually reused
        self.gate: tuple[tuple[int, int, float, float, float], Image] | None = None
        if mask is not None:
            self.mf = (mask > 0).astype(np.float32)
            self.n = float(cv2.countNonZero(mask))
            if mean is None:
                mean = cv2.mean(patch, mask)[0]
            self.tz = patch.astype(np.float32)
            self.tz -= mean
            self.tz *= self.mf  # T − T̄ on the mask, 0 off it
            self.var_t = float(cv2.norm(self.tz, cv2.NORM_L2SQR))


def masked_ncc(
    window: Image,
    tz: NDArray[np.float32],
    mf: NDArray[np.float32],
    var_t: float,
    n: float | None = None,
) -> NDArray[np.float32]:
    r"""NCC of a template over its mask pixels ``M`` only, at every placement in ``window``.

    .. math::

        \mathrm{NCC}(u) = \frac{\sum_M (T - \bar T)(I_u - \bar I_u)}
            {\sqrt{\sum_M (T - \bar T)^2 \; \sum_M (I_u - \bar I_u)^2}},
        \quad \sum_M (T - \bar T)(I_u - \bar I_u) = \sum_M (T - \bar T) I_u,
        \quad \sum_M (I_u - \bar I_u)^2 = \sum_M I_u^2 - \tfrac{1}{n}\big(\sum_M I_u\big)^2,

    with means over the ``n`` mask pixels: three plain correlations (``cv2.TM_CCORR``; the
    two with the mask in one call, over the window stacked on its square), the same values as
    ``cv2.matchTemplate(..., TM_CCOEFF_NORMED, mask=M)`` (to ~1e-5) at a third to two thirds
    of its cost. ``tz`` is :math:`(T - \bar T)` on the mask and 0 off it, ``mf``
    the mask as 0/1 floats, ``var_t`` :math:`\sum_M (T - \bar T)^2`, ``n`` the number of mask
    pixels (counted if not given). Flat placements give NaN.

    On the small windows of a gate search the fixed cost of each call dominates, so the
    arithmetic is done in place on the correlation outputs (a few element-wise operations).
    """
    if n is None:
        n = float(mf.sum())
    h = window.shape[0]
    both = np.empty((2 * h, window.shape[1]), np.float32)  # [I ; I²], one correlation for both
    w = both[:h]
    np.subtract(window, cv2.mean(window)[0], out=w, casting="unsafe")  # smaller sums below
    np.multiply(w, w, out=both[h:])
    num = cv2.matchTemplate(w, tz, cv2.TM_CCORR)  # Σ_M (T − T̄) I_u
    sums = cv2.matchTemplate(both, mf, cv2.TM_CCORR)  # rows straddling the seam are unused
    s1, var_i = sums[: h - mf.shape[0] + 1], sums[h:]  # Σ_M I_u, Σ_M I_u²
    var_i -= s1 * s1 * (1.0 / n)  # Σ_M (I_u − Ī_u)²
    flat = var_i <= 1e-6 * n
    np.maximum(var_i, 1e-6 * n, out=var_i)
    var_i *= var_t
    num /= np.sqrt(var_i, out=var_i)
    num[flat] = np.nan
    return num
