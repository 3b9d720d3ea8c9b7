"""Detection front ends: disturbance map, frame differencing, MOG2, KNN, templates, parts."""

from mvtrack.detection.background import KNN, MOG2, DisturbanceMap, FrameDifference
from mvtrack.detection.base import FrontEnd
from mvtrack.detection.blobs import BlobExtractor, blobs_from_mask
from mvtrack.detection.frontends import DETECTORS, make_detector
from mvtrack.detection.template import TemplateBank

__all__ = [
    "DETECTORS",
    "KNN",
    "MOG2",
    "BlobExtractor",
    "DisturbanceMap",
    "FrameDifference",
    "FrontEnd",
    "TemplateBank",
    "blobs_from_mask",
    "make_detector",
]
