"""Parts of a moving region: the hue tree of 2-means splits, refinement and adjacency."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.parts.hue import (
    HUE_BINS,
    BoolArray,
    FloatArray,
    IntArray,
    hue_diff,
    kmeans2_hist,
)


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
    pix_bin = hue.ravel()[idx].astype(np.intp) % HUE_BINS
    counts = np.bincount(pix_bin, minlength=HUE_BINS).astype(float)
    leaves: list[tuple[BoolArray, float]] = []
    stack: list[tuple[BoolArray, int]] = [(counts > 0, 0)]
    while stack:
        node, depth = stack.pop()
        c = np.where(node, counts, 0.0)
        occupied = np.flatnonzero(c)
        # all hues within a 20° arc: any two centres are < 20° apart, so it is a leaf
        # circular span of the occupied bins = 360° − the widest empty gap
        gaps = np.diff(occupied, append=occupied[0] + HUE_BINS) if occupied.size else [HUE_BINS]
        narrow = (HUE_BINS - np.max(gaps) + 1) * (360.0 / HUE_BINS) < p.min_hue_sep
        if c.sum() < p.min_node_px or depth >= p.max_depth or narrow:
            leaves.append((node, 0.0))
            continue
        centres, second = kmeans2_hist(c)
        second &= node
        first = node & ~second
        if hue_diff(centres[0], centres[1]) < p.min_hue_sep or not (
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
