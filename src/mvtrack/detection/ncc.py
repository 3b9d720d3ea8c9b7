"""Normalised cross-correlation of a stored appearance, over its object's pixels only.

:class:`Template` is one stored appearance (a grey patch, its object mask, the box centre
inside it) with the terms of :func:`masked_ncc` computed once, cut from a frame by
:func:`cut_template`; the search over a window is :func:`masked_ncc` (with a mask) or OpenCV's
``TM_CCOEFF_NORMED`` (without), inside a circular gate by :func:`search_gate`, which
:meth:`mvtrack.detection.template.TemplateBank.rescue` runs for each missed track.
"""

from __future__ import annotations

import math

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


def grey_region(frame: Image, x0: int, y0: int, x1: int, y1: int, smooth: float, pad: int) -> Image:
    """Grey levels of ``frame[y0:y1, x0:x1]``, smoothed by a Gaussian of ``smooth`` px.

    The blur is computed on the region widened by ``pad`` px (3σ), so the borders see their
    real neighbours; ``pad = 0`` leaves the region unsmoothed.
    """
    if pad == 0:
        return np.ascontiguousarray(grey(frame[y0:y1, x0:x1]))
    height, width = frame.shape[:2]
    a, b = max(x0 - pad, 0), max(y0 - pad, 0)
    c, d = min(x1 + pad, width), min(y1 + pad, height)
    g = cv2.GaussianBlur(grey(frame[b:d, a:c]), (0, 0), smooth)
    return np.ascontiguousarray(g[y0 - b : y1 - b, x0 - a : x1 - a])


def cut_template(
    frame: Image,
    mask: Image | None,
    box: NDArray[np.float64],
    tick: int,
    *,
    min_size: int,
    min_pixels: int,
    min_std: float,
    smooth: float,
    pad: int,
) -> Template | None:
    """The grey patch of ``frame`` under ``box`` ``(x, y, w, h)``, or None if unusable.

    The box is clipped to the image; a patch narrower or lower than ``min_size``, with fewer
    than ``min_pixels`` object pixels in ``mask`` (non-zero = object; None: the whole box), or
    whose grey levels vary by less than ``min_std`` (standard deviation) is not kept.
    ``smooth`` and ``pad`` as in :func:`grey_region`.
    """
    height, width = frame.shape[:2]
    x, y, w, h = box
    left = math.floor(x - (w - 1) / 2 + 0.5)
    top = math.floor(y - (h - 1) / 2 + 0.5)
    x0, y0 = max(left, 0), max(top, 0)
    x1 = min(left + max(round(w), 1), width)
    y1 = min(top + max(round(h), 1), height)
    if x1 - x0 < min_size or y1 - y0 < min_size:
        return None
    patch = grey_region(frame, x0, y0, x1, y1, smooth, pad)
    on = None
    if mask is not None:
        on = cv2.compare(mask[y0:y1, x0:x1], 0, cv2.CMP_GT)  # 255 on the object
        if cv2.countNonZero(on) < min_pixels:
            return None
    mean, spread = (v[0, 0] for v in cv2.meanStdDev(patch, mask=on))
    if spread < min_std:
        return None
    return Template(patch, on, (x - x0, y - y0), tick, float(mean))


def search_gate(
    frame: Image, t: Template, px: float, py: float, r: float, smooth: float, pad: int
) -> tuple[float, float, float] | None:
    r"""Best NCC of template ``t`` over the placements whose box centre is within ``r`` of
    ``(px, py)``.

    The NCC (``cv2.TM_CCOEFF_NORMED``, or :func:`masked_ncc` for a masked template) is
    evaluated on the window of ``frame`` around the gate (grey, smoothed as in
    :func:`grey_region`, clipped to the image), then maximised inside the circle.

    Returns
    -------
    (best, x, y) or None
        The best NCC and the box centre of its placement; None when the template placed on
        ``(px, py)`` sticks out of the image (an object leaving the picture has not stopped),
        or when the gate holds only flat placements.
    """
    height, width = frame.shape[:2]
    ph, pw = t.patch.shape
    ox, oy = t.offset
    # top-left of the template when its box centre sits on the prediction
    tx, ty = round(px - ox), round(py - oy)
    if tx < 0 or ty < 0 or tx + pw > width or ty + ph > height:
        return None  # predicted partly outside the image: leaving, not stopped
    ri = math.floor(r)
    r2 = r * r
    x0, y0 = max(tx - ri, 0), max(ty - ri, 0)
    x1, y1 = min(tx + ri + pw, width), min(ty + ri + ph, height)
    window = grey_region(frame, x0, y0, x1, y1, smooth, pad)
    if t.mask is None:
        ncc = cv2.matchTemplate(window, t.patch, cv2.TM_CCOEFF_NORMED)
    else:  # NCC over the object's pixels only
        ncc = masked_ncc(window, t.tz, t.mf, t.var_t, t.n)
    cv2.patchNaNs(ncc, -2.0)  # flat placements: no correlation
    # centre of placement (row i, col c) is (x0 + c + ox, y0 + i + oy); circular gate
    key = (*ncc.shape, x0 + ox - px, y0 + oy - py, r2)
    if t.gate is not None and t.gate[0] == key:
        inside = t.gate[1]
    else:
        cx = np.arange(ncc.shape[1]) + key[2]
        cy = np.arange(ncc.shape[0]) + key[3]
        inside = cv2.compare(np.add.outer(cy * cy, cx * cx), r2, cv2.CMP_LE)
        t.gate = (key, inside)
    _, best, _, (c, i) = cv2.minMaxLoc(ncc, inside)
    if c < 0 or best < -1.0:  # nothing inside the gate, or only flat placements
        return None
    return best, x0 + c + ox, y0 + i + oy
