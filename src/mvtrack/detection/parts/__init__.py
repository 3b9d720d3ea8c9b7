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

One step a module: :mod:`~mvtrack.detection.parts.hue` (HSI, hue 2-means),
:mod:`~mvtrack.detection.parts.region` (moving region, detection zone),
:mod:`~mvtrack.detection.parts.segment` (the hue tree, adjacency) and
:mod:`~mvtrack.detection.parts.match` (features, α, matching).
"""

from __future__ import annotations

from mvtrack.detection.parts.hue import bgr_to_hsi, circular_kmeans2
from mvtrack.detection.parts.match import (
    PartFeatures,
    feature_distance,
    match_parts,
    occlusion_degree,
    region_features,
)
from mvtrack.detection.parts.region import DetectionZone, moving_box, moving_region
from mvtrack.detection.parts.segment import SegmentParams, adjacency, segment_parts

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
