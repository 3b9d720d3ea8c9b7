"""Detection front ends by name: ``make_detector("disturbance-map", threshold=30)``."""

from __future__ import annotations

import inspect
from typing import Any

from mvtrack import registry
from mvtrack.detection.base import FrontEnd
from mvtrack.detection.blobs import BlobExtractor

#: Front-end names accepted by :func:`make_detector` (:data:`mvtrack.registry.DETECTORS`), and
#: their classes.
DETECTORS: dict[str, type[Any]] = {
    name: registry.load(choice) for name, choice in registry.DETECTORS.items()
}


def make_detector(name: str, **params: Any) -> Any:
    """A detection front end by name, with its parameters as keywords.

    Parameters
    ----------
    name : str
        ``"disturbance-map"`` (paper 1, the default of the pipeline), ``"frame-diff"`` (the
        baseline paper 1 rejects), ``"mog2"`` (OpenCV's mixture model), ``"knn"`` (OpenCV's
        k-nearest-neighbours subtractor) or ``"hog"`` (OpenCV's HOG people detector over the
        whole frame; no background model).
    **params
        ``track_split=True`` (background-model front ends): blobs split and merged by the
        tracker's predicted boxes (:class:`~mvtrack.detection.tracksplit.TrackSplit`;
        ``track_merge=False``: only split). The
        others are constructor parameters of the class (see :class:`DisturbanceMap`,
        :class:`FrameDifference`, :class:`MOG2`, :class:`KNN`,
        :class:`~mvtrack.detection.hog.HOGDetector`);
        names use underscores (``min_area``). The blob stage's parameters
        (:class:`BlobExtractor`) apply to the background-model front ends only.

    Raises
    ------
    ValueError
        Unknown name (the message lists the known ones), or a parameter the front end does not
        have.
    """
    registry.check("detector", name, DETECTORS)
    cls = DETECTORS[name]
    split = params.pop("track_split", False)
    merge = params.pop("track_merge", True)
    if not isinstance(split, bool):
        raise ValueError(f"detector {name!r}: track_split must be true or false, got {split!r}")
    if not isinstance(merge, bool):
        raise ValueError(f"detector {name!r}: track_merge must be true or false, got {merge!r}")
    if split and not issubclass(cls, FrontEnd):
        raise ValueError(f"detector {name!r}: track_split needs a background-model front end")
    known = {
        p.name for p in inspect.signature(cls).parameters.values() if p.kind != p.VAR_KEYWORD
    }
    if issubclass(cls, FrontEnd):
        known |= set(inspect.signature(BlobExtractor).parameters)
    unknown = sorted(set(params) - known)
    if unknown:
        raise ValueError(
            f"detector {name!r}: unknown parameter {', '.join(map(repr, unknown))} "
            f"(known: {', '.join(sorted(known))})"
        )
    try:
        det = cls(**params)
    except (TypeError, ValueError) as exc:  # a bad value: say which front end it was given to
        raise ValueError(f"detector {name!r}: {exc}") from None
    if split:
        from mvtrack.detection.tracksplit import TrackSplit

        return TrackSplit(det, merge=merge)
    return det
