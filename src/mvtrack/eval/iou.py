"""Intersection over union of axis-aligned boxes, all pairs at once."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from mvtrack.types import FloatArray


def iou_matrix(a_tlwh: ArrayLike, b_tlwh: ArrayLike) -> FloatArray:
    """IoU of every box in ``a`` with every box in ``b``.

    .. math:: \\mathrm{IoU}(a, b) = \\frac{|a \\cap b|}{|a| + |b| - |a \\cap b|}

    Parameters
    ----------
    a_tlwh : (N, 4) array
        Boxes ``(left, top, width, height)``.
    b_tlwh : (M, 4) array
        Boxes ``(left, top, width, height)``.

    Returns
    -------
    (N, M) float64
        IoU in [0, 1]; 0 where the boxes do not overlap or both have zero area.
    """
    a = np.asarray(a_tlwh, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b_tlwh, dtype=np.float64).reshape(-1, 4)
    a_lo, a_hi = a[:, None, :2], a[:, None, :2] + a[:, None, 2:]
    b_lo, b_hi = b[None, :, :2], b[None, :, :2] + b[None, :, 2:]
    inter = np.clip(np.minimum(a_hi, b_hi) - np.maximum(a_lo, b_lo), 0.0, None).prod(axis=2)
    union = a[:, None, 2:].prod(axis=2) + b[None, :, 2:].prod(axis=2) - inter
    out = np.zeros_like(inter)
    np.divide(inter, union, out=out, where=(inter > 0) & (union > 0))
    return out
