"""Part segmentation and matching of paper 3 (SPEC §3.1, §3.3).

Pipeline for one object:

1. **Moving region** (:func:`moving_region`): difference of two consecutive frames, noise removal
   (morphological opening), closing and hole filling.
2. **Segmentation** (:func:`segment_parts`): top-down along a binary tree; each node splits its
   pixels in two by K-means (K = 2) on the hue of HSI (:func:`bgr_to_hsi`), ignoring pixels with
   saturation < 0.15; a node stops splitting when its two hue centres are < 20° apart or it holds
   < 50 px. The leaves are the parts.
3. **Refinement**: connected pieces under 30 px or 2 % of the region's chromatic pixels are
   dropped.
4. **Adjacency** (:func:`adjacency`): two parts are adjacent when they share ≥ 3 boundary pixels.
5. **Matching** (:func:`match_parts`): parts of consecutive frames are matched by colour, texture
   and shape features (:func:`region_features`, :func:`feature_distance`); the least |ΔF| wins
   and gives the occlusion degree α = 1 − exp(−|ΔF|) (eq. (16) of paper 3,
   :func:`occlusion_degree`).

A :class:`DetectionZone` is the rectangle (e.g. near a door) where new objects are picked up.

Coordinates are continuous image coordinates: pixel (u, v) covers [u, u+1) × [v, v+1), so a
region's centroid is the mean of its pixel indices plus ½.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy import ndimage
from scipy.optimize import linear_sum_assignment

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

__all__ = [
    "DetectionZone",
    "PartFeatures",
    "SegmentParams",
    "adjacency",
    "bgr_to_hsi",
    "circular_kmeans2",
    "feature_distance",
    "match_parts",
    "moving_box",
    "moving_region",
    "occlusion_degree",
    "region_features",
    "segment_parts",
]


# --------------------------------------------------------------------------- colour


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


def _hue_diff(a: FloatArray, b: FloatArray) -> FloatArray:
    d = np.abs(np.asarray(a) - np.asarray(b)) % 360.0
    return np.minimum(d, 360.0 - d)


def _circ_mean(hue_deg: FloatArray, weights: FloatArray | None = None) -> float:
    rad = np.radians(hue_deg)
    w = np.ones_like(rad) if weights is None else weights
    return float(np.degrees(np.arctan2((w * np.sin(rad)).sum(), (w * np.cos(rad)).sum())) % 360)


_BINS = 360
_MIDS = (np.arange(_BINS) + 0.5) * (360.0 / _BINS)
_SIN, _COS = np.sin(np.radians(_MIDS)), np.cos(np.radians(_MIDS))


def _hist_mean(counts: FloatArray) -> float:
    return float(np.degrees(np.arctan2(counts @ _SIN, counts @ _COS)) % 360.0)


def _kmeans2_hist(counts: FloatArray, iters: int = 20) -> tuple[FloatArray, BoolArray]:
    """2-means on a 360-bin hue histogram: centres (2,) and, per bin, whether it is in the
    second cluster. Each iteration costs O(360)."""
    coarse = counts.reshape(36, -1).sum(axis=1)
    cmids = np.arange(36) * 10.0 + 5.0
    c0 = cmids[np.argmax(coarse)]
    c1 = cmids[np.argmax(coarse * _hue_diff(cmids, c0))]
    centres = np.array([c0, c1])
    second = np.zeros(_BINS, dtype=bool)
    for it in range(iters):
        new = _hue_diff(_MIDS, centres[1]) < _hue_diff(_MIDS, centres[0])
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
    b = h.astype(np.intp) % _BINS
    centres, second = _kmeans2_hist(np.bincount(b, minlength=_BINS).astype(float), iters)
    return centres, second[b]


# --------------------------------------------------------------------------- moving region


def moving_region(
    prev: NDArray[np.uint8],
    cur: NDArray[np.uint8],
    threshold: float = 20.0,
    close_size: int = 15,
    min_area: int = 20,
) -> BoolArray:
    """Moving region from two consecutive frames (SPEC §3.1 step 2).

    max over B, G, R of |I(k) − I(k−1)| > ``threshold``; noise removal drops connected pieces
    under ``min_area`` px (an opening would also erase the thin strips a uniformly coloured
    object leaves in a frame difference); a closing by a ``close_size`` square joins the
    strips; holes are filled.
    """
    if prev.shape != cur.shape:
        raise ValueError(f"prev and cur differ in shape: {prev.shape} vs {cur.shape}")
    if not threshold >= 0:
        raise ValueError(f"threshold must be >= 0, got {threshold}")
    absdiff = cv2.absdiff(prev, cur)
    if absdiff.ndim == 3:  # largest change over the colour channels: a hue change counts too
        absdiff = absdiff.max(axis=2)
    diff = (absdiff > threshold).astype(np.uint8)
    _, comp, stats, _ = cv2.connectedComponentsWithStats(diff, connectivity=8)
    keep = stats[:, cv2.CC_STAT_AREA] >= min_area
    keep[0] = False
    diff = keep[comp].astype(np.uint8)
    if close_size > 1:
        k = np.ones((close_size, close_size), np.uint8)
        diff = cv2.morphologyEx(diff, cv2.MORPH_CLOSE, k)
    return ndimage.binary_fill_holes(diff.astype(bool))


def moving_box(
    prev: NDArray[np.uint8],
    cur: NDArray[np.uint8],
    zone: DetectionZone | None = None,
    min_pixels: int = 50,
    **params: float,
) -> FloatArray | None:
    """MER ``x0, y0, x1, y1`` of the moving region inside ``zone`` (the whole frame if None),
    or None when fewer than ``min_pixels`` pixels move: how a new object is picked up."""
    region = moving_region(prev, cur, **params)  # type: ignore[arg-type]
    if zone is not None:
        H, W = region.shape
        inside = np.zeros_like(region)
        x0, y0 = max(int(zone.x0), 0), max(int(zone.y0), 0)
        inside[y0 : min(int(np.ceil(zone.y1)), H), x0 : min(int(np.ceil(zone.x1)), W)] = True
        region &= inside
    ys, xs = np.nonzero(region)
    if ys.size < min_pixels:
        return None
    return np.array([xs.min(), ys.min(), xs.max() + 1, ys.max() + 1], dtype=float)


@dataclass(frozen=True)
class DetectionZone:
    """Rectangle ``x0, y0, x1, y1`` where new objects are picked up (Fig. 5 of paper 3)."""

    x0: float
    y0: float
    x1: float
    y1: float

    def __post_init__(self) -> None:
        if not (self.x1 > self.x0 and self.y1 > self.y0):
            raise ValueError(f"detection zone must have x1 > x0 and y1 > y0, got {self}")

    def contains(self, xy: FloatArray) -> BoolArray:
        """Which points (M, 2) lie inside the zone."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        return (
            (xy[:, 0] >= self.x0)
            & (xy[:, 0] <= self.x1)
            & (xy[:, 1] >= self.y0)
            & (xy[:, 1] <= self.y1)
        )


# --------------------------------------------------------------------------- segmentation


@dataclass(frozen=True)
class SegmentParams:
    """Segmentation parameters (SPEC §3.3 defaults)."""

    min_saturation: float = 0.15
    min_hue_sep: float = 20.0
    min_node_px: int = 50
    min_part_px: int = 30
    min_part_frac: float = 0.02
    max_depth: int = 4
    min_shared: int = 3
    gap: int = 2


def segment_parts(
    hue: FloatArray,
    sat: FloatArray,
    mask: BoolArray,
    params: SegmentParams | None = None,
) -> tuple[NDArray[np.int32], FloatArray]:
    """Hierarchical top-down hue segmentation of one moving region (SPEC §3.1 steps 3–4).

    Parameters
    ----------
    hue, sat : (H, W)
        HSI hue (degrees) and saturation of the image (or of a crop around the region).
    mask : (H, W) bool
        The moving region.
    params : SegmentParams

    Returns
    -------
    labels : (H, W) int32
        0 outside parts, 1 … P for the parts (ordered top to bottom by centroid).
    hues : (P,)
        Hue centre of each part (degrees).
    """
    p = params or SegmentParams()
    mask = np.asarray(mask, dtype=bool)
    if hue.shape != mask.shape or sat.shape != mask.shape:
        raise ValueError(
            f"hue, sat and mask differ in shape: {hue.shape}, {sat.shape}, {mask.shape}"
        )
    labels = np.zeros(mask.shape, dtype=np.int32)
    chroma = mask & (sat >= p.min_saturation)
    idx = np.flatnonzero(chroma)
    if idx.size < p.min_part_px:
        return labels, np.zeros(0)
    # the tree splits by hue only, so it partitions the hue circle: run it on the 1° histogram
    # of the region (a handful of nodes, O(360) each) and label pixels through their hue bin
    pix_bin = hue.ravel()[idx].astype(np.intp) % _BINS
    counts = np.bincount(pix_bin, minlength=_BINS).astype(float)
    leaves: list[tuple[BoolArray, float]] = []
    stack: list[tuple[BoolArray, int]] = [(counts > 0, 0)]
    while stack:
        node, depth = stack.pop()
        c = np.where(node, counts, 0.0)
        occupied = np.flatnonzero(c)
        # all hues within a 20° arc: any two centres are < 20° apart, so it is a leaf
        # circular span of the occupied bins = 360° − the widest empty gap
        gaps = np.diff(occupied, append=occupied[0] + _BINS) if occupied.size else [_BINS]
        narrow = (_BINS - np.max(gaps) + 1) * (360.0 / _BINS) < p.min_hue_sep
        if c.sum() < p.min_node_px or depth >= p.max_depth or narrow:
            leaves.append((node, 0.0))
            continue
        centres, second = _kmeans2_hist(c)
        second &= node
        first = node & ~second
        if _hue_diff(centres[0], centres[1]) < p.min_hue_sep or not (
            counts[second].sum() and counts[first].sum()
        ):
            leaves.append((node, 0.0))
            continue
        stack.append((first, depth + 1))
        stack.append((second, depth + 1))
    # refinement: keep connected pieces of each leaf that are large enough
    # "2 % of the region": of the region's chromatic pixels, the ones that are segmented
    min_px = max(p.min_part_px, p.min_part_frac * idx.size)
    flat = labels.ravel()
    n_found = 0
    leaf_img = np.zeros(mask.shape, dtype=np.uint8)
    for node, _ in leaves:  # a few leaves; each a C call over the crop
        leaf_img[:] = 0
        leaf_img.ravel()[idx[node[pix_bin]]] = 1
        _, comp, stats, _ = cv2.connectedComponentsWithStats(leaf_img, connectivity=8)
        big = stats[:, cv2.CC_STAT_AREA] >= min_px
        big[0] = False  # component 0 is the background of leaf_img
        if not big.any():
            continue
        n_found += 1
        flat[big[comp.ravel()]] = n_found
    if not n_found:
        return labels, np.zeros(0)
    # hue of each part: circular mean of its pixels; order parts top to bottom
    pix = np.flatnonzero(flat)
    lab = flat[pix]
    rad = np.radians(hue.ravel()[pix])
    hues = (
        np.degrees(
            np.arctan2(
                np.bincount(lab, np.sin(rad), n_found + 1),
                np.bincount(lab, np.cos(rad), n_found + 1),
            )
        )[1:]
        % 360.0
    )
    cnt = np.bincount(lab, minlength=n_found + 1)[1:]
    ymean = np.bincount(lab, weights=pix // mask.shape[1], minlength=n_found + 1)[1:] / cnt
    order = np.argsort(ymean, kind="stable")
    remap = np.zeros(n_found + 1, dtype=np.int32)
    remap[order + 1] = np.arange(1, n_found + 1)
    return remap[labels], hues[order]


def adjacency(labels: NDArray[np.int32], min_shared: int = 3, gap: int = 2) -> IntArray:
    """Adjacent part pairs (E, 2), i < j (1-based labels), by shared boundary pixels.

    A pixel of part a is on its boundary with part b when a pixel of b lies at horizontal or
    vertical distance ≤ ``gap`` (``gap`` > 1 bridges thin unlabelled seams, e.g. achromatic
    pixels between two parts). Parts a and b are adjacent when both have ≥ ``min_shared``
    such boundary pixels (SPEC §3.3: ≥ 3).
    """
    lab = np.asarray(labels)
    H, W = lab.shape
    flat_idx = np.arange(H * W).reshape(H, W)
    rows = []
    for d in range(1, gap + 1):
        for a, b, ia, ib in (
            (lab[:, :-d], lab[:, d:], flat_idx[:, :-d], flat_idx[:, d:]),
            (lab[:-d, :], lab[d:, :], flat_idx[:-d, :], flat_idx[d:, :]),
        ):
            sel = (a > 0) & (b > 0) & (a != b)
            pa, pb, qa, qb = a[sel], b[sel], ia[sel], ib[sel]
            lo, hi = np.minimum(pa, pb), np.maximum(pa, pb)
            # (pair, which end, pixel): each boundary pixel once per pair and side
            rows.append(np.stack([lo, hi, (pa > pb).astype(int), qa], axis=1))
            rows.append(np.stack([lo, hi, (pb > pa).astype(int), qb], axis=1))
    allr = np.concatenate(rows) if rows else np.zeros((0, 4), int)
    if allr.size == 0:
        return np.zeros((0, 2), dtype=np.intp)
    uniq = np.unique(allr, axis=0)  # distinct boundary pixels
    keys, counts = np.unique(uniq[:, :3], axis=0, return_counts=True)
    pairs, side_counts = keys[:, :2], counts
    # both sides of a pair must have enough boundary pixels
    pu, inv = np.unique(pairs, axis=0, return_inverse=True)
    least = np.full(len(pu), np.iinfo(np.int64).max)
    np.minimum.at(least, inv.ravel(), side_counts)
    n_sides = np.bincount(inv.ravel(), minlength=len(pu))
    return pu[(n_sides == 2) & (least >= min_shared)].astype(np.intp)


# --------------------------------------------------------------------------- features, α


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
    dh = _hue_diff(prev.hue[:, None], cur.hue[None, :]) / 20.0
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
    hd = _hue_diff(prev.hue[:, None], cur.hue[None, :])
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
