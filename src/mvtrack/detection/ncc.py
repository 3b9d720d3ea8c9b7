"""Normalised cross-correlation of a stored appearance, over its object's pixels only.

:class:`Template` is one stored appearance (a grey patch, its object mask, the box centre
inside it) with the terms of :func:`gate_ncc` computed once, cut from a frame by
:func:`cut_template`; the search over a window is :func:`gate_ncc` (with a mask: one compiled
pass over the placements inside the gate) or OpenCV's ``TM_CCOEFF_NORMED`` (without), inside
a circular gate by :func:`search_gate`, which
:meth:`mvtrack.detection.template.TemplateBank.rescue` runs for each missed track.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.jit import kernel

Image = NDArray[np.uint8]


def grey(img: Image) -> Image:
    """The image in grey levels (unchanged if it is grey already)."""
    return img if img.ndim == 2 else cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)


class Template:
    """One stored appearance: grey patch, its object mask (or None), the box centre inside it,
    the observation tick; for a masked template also the terms of :func:`gate_ncc`: the mask's
    pixels (``rows``, ``cols``), :math:`T - \\bar T` at them (``tz``) and
    :math:`\\sum_M (T - \\bar T)^2` (``var_t``)."""

    __slots__ = ("cols", "gate", "mask", "offset", "patch", "rows", "tick", "tz", "var_t")

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
            rows, cols = np.nonzero(mask)
            self.rows, self.cols = rows.astype(np.intp), cols.astype(np.intp)
            if mean is None:
                mean = cv2.mean(patch, mask)[0]
            self.tz = patch[rows, cols].astype(np.float64) - mean  # T − T̄ on the mask
            self.var_t = float(np.dot(self.tz, self.tz))


@kernel
def gate_ncc(
    window: Image, rows: NDArray[np.intp], cols: NDArray[np.intp], tz: NDArray[np.float64],
    var_t: float, dx0: float, dy0: float, r2: float, out: NDArray[np.float64],
) -> tuple[float, int, int]:
    r"""NCC of a template over its mask pixels ``M`` only, at the placements of ``window``
    inside a circular gate; the best of them.

    .. math::

        \mathrm{NCC}(u) = \frac{\sum_M (T - \bar T)(I_u - \bar I_u)}
            {\sqrt{\sum_M (T - \bar T)^2 \; \sum_M (I_u - \bar I_u)^2}},
        \quad \sum_M (T - \bar T)(I_u - \bar I_u) = \sum_M (T - \bar T) I_u,
        \quad \sum_M (I_u - \bar I_u)^2 = \sum_M I_u^2 - \tfrac{1}{n}\big(\sum_M I_u\big)^2,

    with means over the ``n`` mask pixels (``rows``, ``cols`` in the template; ``tz`` is
    :math:`T - \bar T` at them, ``var_t`` :math:`\sum_M (T - \bar T)^2`): OpenCV's
    ``matchTemplate(..., TM_CCOEFF_NORMED, mask=M)``, in double precision, the window's grey
    levels taken relative to their mean. Placement ``(i, c)`` (the template's top-left corner
    at row ``i``, column ``c`` of the window) lies in the gate when
    :math:`(c + dx_0)^2 + (i + dy_0)^2 \le r^2` (its offset from the gate's centre); ``out``
    (``window`` less the template, plus one, in each direction) gets the NCC there, −2 where
    the window is flat under the mask, −inf outside the gate.

    Returns
    -------
    (best, i, c)
        The largest value of ``out`` and its first placement in row order; ``c = -1`` when no
        placement lies in the gate.
    """
    h_out, w_out = out.shape
    n = rows.size
    mean = 0.0
    for y in range(window.shape[0]):
        for x in range(window.shape[1]):
            mean += window[y, x]
    mean /= window.shape[0] * window.shape[1]
    flat = 1e-6 * n
    best, bi, bc = -np.inf, -1, -1
    for i in range(h_out):
        cy = i + dy0
        for c in range(w_out):
            cx = c + dx0
            if cx * cx + cy * cy > r2:
                out[i, c] = -np.inf
                continue
            num = 0.0
            s1 = 0.0
            s2 = 0.0
            for k in range(n):
                v = window[i + rows[k], c + cols[k]] - mean
                num += tz[k] * v
                s1 += v
                s2 += v * v
            var_i = s2 - s1 * s1 / n
            value = -2.0 if var_i <= flat else num / math.sqrt(var_i * var_t)
            out[i, c] = value
            if value > best:
                best, bi, bc = value, i, c
    return best, bi, bc


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

    The NCC (``cv2.TM_CCOEFF_NORMED``, or :func:`gate_ncc` for a masked template) is
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
    if t.mask is not None:  # NCC over the object's pixels only, in the gate
        out = np.empty((window.shape[0] - ph + 1, window.shape[1] - pw + 1))
        best, i, c = gate_ncc(window, t.rows, t.cols, t.tz, t.var_t, x0 + ox - px,
                              y0 + oy - py, r * r, out)
        if c < 0 or best < -1.0:  # nothing inside the gate, or only flat placements
            return None
        return best, x0 + c + ox, y0 + i + oy
    ncc = cv2.matchTemplate(window, t.patch, cv2.TM_CCOEFF_NORMED)
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
