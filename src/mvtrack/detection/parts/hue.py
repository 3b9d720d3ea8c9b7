"""Colour for part segmentation: HSI from BGR, and 2-means of hues on the circle (SPEC §3.3)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]


def bgr_to_hsi(frame: NDArray[np.uint8]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Hue (degrees, [0, 360)), saturation ([0, 1]) and intensity ([0, 255]) of HSI.

    .. math::

        I = \\frac{R+G+B}{3},\\quad S = 1 - \\frac{\\min(R,G,B)}{I},\\quad
        H = \\begin{cases}θ & B ≤ G\\\\ 360° − θ & B > G\\end{cases},\\quad
        θ = \\arccos\\frac{\\tfrac12[(R−G)+(R−B)]}{\\sqrt{(R−G)^2+(R−B)(G−B)}}
    """
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[-1] != 3:
        raise ValueError(f"frame must be an (H, W, 3) BGR image, got shape {frame.shape}")
    b, g, r = (frame[..., c].astype(np.float32) for c in range(3))
    inten = (r + g + b) / 3.0
    mn = np.minimum(np.minimum(r, g), b)
    sat = np.where(inten > 0, 1.0 - mn / np.maximum(inten, 1e-12), 0.0)
    num = 0.5 * ((r - g) + (r - b))
    den = np.sqrt((r - g) ** 2 + (r - b) * (g - b))
    theta = np.degrees(np.arccos(np.clip(num / np.maximum(den, 1e-12), -1.0, 1.0)))
    hue = np.where(b <= g, theta, 360.0 - theta) % 360.0
    return hue.astype(np.float64), sat.astype(np.float64), inten.astype(np.float64)


def hue_diff(a: FloatArray, b: FloatArray) -> FloatArray:
    d = np.abs(np.asarray(a) - np.asarray(b)) % 360.0
    return np.minimum(d, 360.0 - d)


def _circ_mean(hue_deg: FloatArray, weights: FloatArray | None = None) -> float:
    rad = np.radians(hue_deg)
    w = np.ones_like(rad) if weights is None else weights
    return float(np.degrees(np.arctan2((w * np.sin(rad)).sum(), (w * np.cos(rad)).sum())) % 360)


HUE_BINS = 360
_MIDS = (np.arange(HUE_BINS) + 0.5) * (360.0 / HUE_BINS)
_SIN, _COS = np.sin(np.radians(_MIDS)), np.cos(np.radians(_MIDS))


def _hist_mean(counts: FloatArray) -> float:
    return float(np.degrees(np.arctan2(counts @ _SIN, counts @ _COS)) % 360.0)


def kmeans2_hist(counts: FloatArray, iters: int = 20) -> tuple[FloatArray, BoolArray]:
    """2-means on a 360-bin hue histogram: centres (2,) and, per bin, whether it is in the
    second cluster. Each iteration costs O(360)."""
    coarse = counts.reshape(36, -1).sum(axis=1)
    cmids = np.arange(36) * 10.0 + 5.0
    c0 = cmids[np.argmax(coarse)]
    c1 = cmids[np.argmax(coarse * hue_diff(cmids, c0))]
    centres = np.array([c0, c1])
    second = np.zeros(HUE_BINS, dtype=bool)
    for it in range(iters):
        new = hue_diff(_MIDS, centres[1]) < hue_diff(_MIDS, centres[0])
        for k, sel in enumerate((~new, new)):
            w = np.where(sel, counts, 0.0)
            if w.sum() > 0:
                centres[k] = _hist_mean(w)
        if it and np.array_equal(new, second):
            break
        second = new
    return centres, second


def circular_kmeans2(hue_deg: FloatArray, iters: int = 20) -> tuple[FloatArray, BoolArray]:
    """K-means with K = 2 on hue angles (degrees), run on a 1° hue histogram.

    Pixels are quantised to 1° (far below the 20° stop rule), so each iteration costs O(360)
    whatever the number of pixels: k-means on the weighted bin centres, with circular distance
    and circular means. Initialised at the mode of a 10° histogram and the 10° bin that
    maximises count × circular distance to it.

    Returns
    -------
    centres : (2,)
        Hue centres in degrees.
    second : (P,) bool
        True where a pixel belongs to the second centre.
    """
    h = np.asarray(hue_deg, dtype=float) % 360.0
    if h.size < 2:
        raise ValueError("circular_kmeans2 needs at least 2 hue values")
    b = h.astype(np.intp) % HUE_BINS
    centres, second = kmeans2_hist(np.bincount(b, minlength=HUE_BINS).astype(float), iters)
    return centres, second[b]
