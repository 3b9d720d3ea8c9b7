"""The moving region of an object from two consecutive frames, and the detection zone."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mvtrack.detection.parts.hue import BoolArray, FloatArray


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
