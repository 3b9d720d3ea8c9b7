"""Part features, their distance, the occlusion degree α (eq. (16) of paper 3) and matching."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mvtrack.detection.parts.hue import FloatArray, IntArray, hue_diff


@dataclass(frozen=True)
class PartFeatures:
    """Features of ``L`` regions (SPEC §3.3): one row per region.

    Attributes
    ----------
    area : (L,)
        Pixel count A.
    centroid : (L, 2)
        Centre of the pixels, x, y (continuous coordinates).
    wh : (L, 2)
        Bounding-box width and height.
    hue : (L,)
        Circular mean hue h̄ of the pixels with saturation ≥ 0.15 (NaN if none).
    sigma_i : (L,)
        Standard deviation of the HSI intensity σ_I (texture).
    """

    area: FloatArray
    centroid: FloatArray
    wh: FloatArray
    hue: FloatArray
    sigma_i: FloatArray

    @property
    def aspect(self) -> FloatArray:
        """Bounding-box aspect ratio w / h."""
        return self.wh[:, 0] / np.maximum(self.wh[:, 1], 1e-12)

    @property
    def boxes(self) -> FloatArray:
        """Bounding boxes (L, 4) x0, y0, x1, y1."""
        c = self.centroid
        return np.concatenate([c - self.wh / 2, c + self.wh / 2], axis=1)


def region_features(
    labels: NDArray[np.integer],
    n_labels: int,
    hue: FloatArray,
    sat: FloatArray,
    inten: FloatArray,
    min_saturation: float = 0.15,
) -> PartFeatures:
    """Features of regions 1 … ``n_labels`` of a label image, all at once (bincount).

    Regions with no pixel get area 0 and NaN elsewhere. The box of a region is that of its
    pixels; its centre for :attr:`PartFeatures.boxes` is the pixel centroid.
    """
    lab2 = np.asarray(labels)
    if lab2.size != hue.size:
        raise ValueError(f"labels and hue differ in size: {lab2.size} vs {hue.size}")
    L = n_labels + 1
    pix = np.flatnonzero((lab2.ravel() > 0) & (lab2.ravel() < L))  # labelled pixels only
    lab = lab2.ravel()[pix].astype(np.intp)
    vv, uu = np.divmod(pix, lab2.shape[1])
    inten_p = inten.ravel()[pix]
    area = np.bincount(lab, minlength=L).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = np.bincount(lab, weights=uu, minlength=L) / area + 0.5
        cy = np.bincount(lab, weights=vv, minlength=L) / area + 0.5
        s1 = np.bincount(lab, weights=inten_p, minlength=L)
        s2 = np.bincount(lab, weights=inten_p**2, minlength=L)
        sig = np.sqrt(np.maximum(s2 / area - (s1 / area) ** 2, 0.0))
    chroma = (sat.ravel()[pix] >= min_saturation).astype(float)
    rad = np.radians(hue.ravel()[pix])
    hs = np.bincount(lab, weights=chroma * np.sin(rad), minlength=L)
    hc = np.bincount(lab, weights=chroma * np.cos(rad), minlength=L)
    nchroma = np.bincount(lab, weights=chroma, minlength=L)
    hbar = np.where(nchroma > 0, np.degrees(np.arctan2(hs, hc)) % 360.0, np.nan)
    # bounding boxes: extreme pixel coordinates per label
    wh = np.full((L, 2), np.nan)
    if pix.size:
        big = np.iinfo(np.int64).max
        x0, y0 = np.full(L, big), np.full(L, big)
        x1, y1 = np.full(L, -1), np.full(L, -1)
        np.minimum.at(x0, lab, uu)
        np.minimum.at(y0, lab, vv)
        np.maximum.at(x1, lab, uu)
        np.maximum.at(y1, lab, vv)
        seen = area > 0
        wh[seen] = np.stack([x1 - x0 + 1, y1 - y0 + 1], axis=1)[seen]
    return PartFeatures(
        area=area[1:],
        centroid=np.stack([cx, cy], axis=1)[1:],
        wh=wh[1:],
        hue=hbar[1:],
        sigma_i=sig[1:],
    )


def feature_distance(prev: PartFeatures, cur: PartFeatures) -> FloatArray:
    """|ΔF| between every previous and every current region (L_prev, L_cur) (SPEC §3.3).

    .. math::

        |ΔF| = \\frac{|Δ\\bar h|}{20°} + \\frac{|ΔA|}{0.1\\,A(k-1)}
             + \\frac{|Δ(w/h)|}{0.2} + \\frac{|Δσ_I|}{10}

    NaN where either region is empty.
    """
    dh = hue_diff(prev.hue[:, None], cur.hue[None, :]) / 20.0
    with np.errstate(invalid="ignore", divide="ignore"):
        da = np.abs(prev.area[:, None] - cur.area[None, :]) / (0.1 * prev.area[:, None])
    dr = np.abs(prev.aspect[:, None] - cur.aspect[None, :]) / 0.2
    ds = np.abs(prev.sigma_i[:, None] - cur.sigma_i[None, :]) / 10.0
    out = dh + da + dr + ds
    empty = (prev.area[:, None] == 0) | (cur.area[None, :] == 0)
    return np.where(empty, np.nan, out)


def occlusion_degree(dF: FloatArray) -> FloatArray:
    """α = 1 − exp(−|ΔF|), eq. (16) of paper 3; NaN (no match) gives α = 1 (E3.8)."""
    dF = np.asarray(dF, dtype=float)
    return np.where(np.isfinite(dF), 1.0 - np.exp(-np.abs(np.nan_to_num(dF))), 1.0)  # eq. (16)


def match_parts(
    prev: PartFeatures,
    cur: PartFeatures,
    min_px: int = 5,
    max_hue_diff: float = 45.0,
) -> tuple[IntArray, FloatArray]:
    """Match previous parts to current regions by least |ΔF| (exclusive, Hungarian).

    Candidates with fewer than ``min_px`` pixels or a hue more than ``max_hue_diff`` degrees
    away are not allowed (an achromatic region, NaN hue, only matches an achromatic part).

    Returns
    -------
    idx : (L_prev,)
        Index of the matched current region, −1 if none.
    alpha : (L_prev,)
        Occlusion degree of eq. (16); 1 where unmatched (SPEC §3.3).
    """
    n_prev, n_cur = prev.area.size, cur.area.size
    idx = np.full(n_prev, -1, dtype=np.intp)
    alpha = np.ones(n_prev)
    if n_prev == 0 or n_cur == 0:
        return idx, alpha
    dF = feature_distance(prev, cur)
    hd = hue_diff(prev.hue[:, None], cur.hue[None, :])
    both_grey = np.isnan(prev.hue)[:, None] & np.isnan(cur.hue)[None, :]
    hue_ok = np.where(np.isnan(hd), both_grey, hd <= max_hue_diff)
    ok = np.isfinite(dF) & (cur.area[None, :] >= min_px) & (prev.area[:, None] > 0) & hue_ok
    if not ok.any():
        return idx, alpha
    big = 1e6
    cost = np.where(ok, np.nan_to_num(dF), big)
    r, c = linear_sum_assignment(cost)
    good = ok[r, c]
    idx[r[good]] = c[good]
    alpha[r[good]] = occlusion_degree(dF[r[good], c[good]])
    return idx, alpha
