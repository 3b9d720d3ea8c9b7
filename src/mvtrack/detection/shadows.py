r"""Shadows and changes of exposure on a background model, and per-pixel channel reductions.

A cast shadow, or the camera's gain, scales the light a surface sends and keeps its colour or
its texture (Cucchiara et al.'s test, here in normalised chromaticity, and a texture test for
shadows lit by the blue sky): :func:`shadow_mask` finds such pixels among the foreground of
:class:`~mvtrack.detection.adaptive.GaussianBackground`, which then leaves them out.
:func:`channel_max` and :func:`channel_sum` reduce the three channels of a float image per
pixel, as the background model's tests need.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

Image = NDArray[np.uint8]


def shadow_mask(
    frame: NDArray[np.float32],
    mean: NDArray[np.float32],
    candidates: Image,
    ratio: tuple[float, float] = (0.1, 1.3),
    chroma: float = 0.02,
    texture: float = 0.8,
    min_texture: float = 3.0,
    radius: int = 2,
    out: Image | None = None,
) -> Image:
    r"""Pixels of ``candidates`` that are shadows (or a change of exposure) on ``mean`` (0/255).

    A cast shadow, or the camera's gain, scales the light a surface sends and keeps its
    colour or its texture. With brightness :math:`L = b + g + r`, chromaticity
    :math:`\chi = (b, g, r) / L` and :math:`\rho` the normalised cross-correlation of the grey
    frame and background over a :math:`(2 r + 1)^2` window, a candidate is a shadow when

    .. math::

        r_{lo} \le L_I / L_\mu \le r_{hi} \;\wedge\;
        \big(\|\chi_I - \chi_\mu\|_1 < \tau_c \;\vee\;
        (\rho > \tau_\rho \wedge s_\mu > s_{\min})\big),

    :math:`s_\mu` the background's local standard deviation (the texture test needs texture).
    The chromaticity test is Cucchiara et al.'s; on sunlit scenes a shadow lit by the blue
    sky changes colour and only the texture test finds it (on KITTI-17's bricks: 21 % of the
    dark shadow pixels, against 11 % of the people's pixels lost; measured in
    ``benchmarks/bench_kitti.py``'s research notes, docs/bench/kitti.md).

    Parameters
    ----------
    frame, mean : (H, W, 3) float32
        The frame and the background mean (BGR).
    candidates : (H, W) uint8
        Pixels to test (non-zero); others are never shadow.
    ratio : (float, float)
        :math:`[r_{lo}, r_{hi}]`, the brightness ratios a shadow or a change of gain may have.
    chroma : float
        :math:`\tau_c`, L1 distance of the chromaticities.
    texture : float
        :math:`\tau_\rho`; above 1 disables the texture test.
    min_texture : float
        :math:`s_{\min}`, grey levels.
    radius : int
        Half-side of the correlation window.
    """
    lo, hi = ratio
    if out is None or out.shape != candidates.shape:
        out = np.empty(candidates.shape, np.uint8)
    out.fill(0)
    x, y, w, h = cv2.boundingRect(candidates)  # the tests run on the candidates' rectangle
    if w == 0 or h == 0:
        return out
    pad = radius if texture <= 1.0 else 0
    x0, y0 = max(x - pad, 0), max(y - pad, 0)
    x1, y1 = min(x + w + pad, candidates.shape[1]), min(y + h + pad, candidates.shape[0])
    fr, mu = frame[y0:y1, x0:x1], mean[y0:y1, x0:x1]
    li = channel_sum(fr) + 1.0
    lm = channel_sum(mu) + 1.0
    r = li / lm
    dchi = channel_sum(cv2.absdiff(fr / li[..., None], mu / lm[..., None]))
    same = dchi < chroma
    if texture <= 1.0:
        rho, s_mu = _correlation(li, lm, radius)
        same |= (rho > texture) & (s_mu > 3.0 * min_texture)  # L sums 3 channels
    shadow = (r >= lo) & (r <= hi) & same & (candidates[y0:y1, x0:x1] > 0)
    np.multiply(shadow, np.uint8(255), out=out[y0:y1, x0:x1], casting="unsafe")
    return out


def channel_max(img: NDArray[np.float32]) -> NDArray[np.float32]:
    """Largest of the three channels per pixel (elementwise: a NumPy reduction over a last
    axis of length 3 is several times slower)."""
    b, g, r = cv2.split(img)
    return cv2.max(cv2.max(b, g), r)


def channel_sum(img: NDArray[np.float32]) -> NDArray[np.float32]:
    """Sum of the three channels per pixel."""
    b, g, r = cv2.split(img)
    return cv2.add(cv2.add(b, g), r)


def _correlation(
    a: NDArray[np.float32], b: NDArray[np.float32], radius: int
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """Windowed normalised cross-correlation of ``a`` and ``b``, and the local std of ``b``."""
    k = (2 * radius + 1, 2 * radius + 1)
    ea, eb = cv2.blur(a, k), cv2.blur(b, k)
    cov = cv2.blur(a * b, k) - ea * eb
    va = np.maximum(cv2.blur(a * a, k) - ea * ea, 0.0)
    vb = np.maximum(cv2.blur(b * b, k) - eb * eb, 0.0)
    return cov / np.sqrt(va * vb + 1e-3), np.sqrt(vb)
