"""Any blob front end beside the tracker: a blob that several confirmed tracks predict into is
divided among them, fragments inside one predicted box are merged.

Vehicles in a queue that starts again are close enough for their blobs to merge into one; the
exclusive assignment then gives that blob to one of their tracks, which is carried off with
it, and the others lose their vehicle (the stop-and-go scene, ``mvtrack.sim.queue``). The
scene front end divides such blobs for people (:mod:`mvtrack.detection.scene`); this wrapper
applies the same two steps of :func:`~mvtrack.detection.splitmerge.split_merge` (merge the
fragments inside one predicted box; divide a blob's foreground among the predicted boxes it
holds) to any :class:`~mvtrack.detection.base.FrontEnd` (the disturbance map, MOG2, KNN), with
no size prior: only the tracker's own predicted boxes decide.

The video loop calls :meth:`TrackSplit.observe` after each tracker step (as it does for the
scene front end), which keeps the confirmed tracks' boxes predicted for the next frame.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.claims import shared_blob
from mvtrack.detection.feedback import predicted_boxes
from mvtrack.detection.splitmerge import PLAIN, split_merge
from mvtrack.types import Detections, TrackFrame

Image = NDArray[np.uint8]


class TrackSplit:
    """``inner`` (a blob front end) with its blobs split and merged by the tracker's
    predicted boxes (module docstring).

    Parameters
    ----------
    inner : FrontEnd
        The front end; its cleaned ``mask`` of the last frame gives the pixels to divide.
    inside, cover : float
        :func:`~mvtrack.detection.splitmerge.split_merge`'s share of a fragment inside its
        predicted box (merge) and of a predicted box inside a blob (claim).
    merge : bool
        Also merge the fragments inside one predicted box (``False``: blobs are only
        divided). Merging holds a walking group's blobs together in its predicted box as the
        group splits up (X8), so the pipeline's disturbance map only divides.
    """

    def __init__(self, inner: Any, *, inside: float = 0.6, cover: float = 0.5,
                 merge: bool = True) -> None:
        self.inner = inner
        self.name = getattr(inner, "name", "")
        self.inside = float(inside)
        self.cover = float(cover)
        self.merge = bool(merge)
        self.predicted = np.zeros((0, 4))
        self.flags = np.zeros(0, np.int8)

    def __getattr__(self, attr: str) -> Any:  # mask, blobs, reset, ... of the front end
        return getattr(self.__dict__["inner"], attr)

    def __call__(self, frame: Image, index: int | None = None) -> Detections:
        """The front end's detections of ``frame``, split and merged by the predicted boxes."""
        dets = self.inner(frame, index)
        mask = getattr(self.inner, "mask", None)
        if mask is None or len(dets) == 0 or len(self.predicted) == 0 or (
            not self.merge and not self._shared(dets)
        ):
            self.flags = np.full(len(dets), PLAIN, np.int8)
            return dets
        boxes, flags = split_merge(dets.tlwh, mask, self.predicted, None, inside=self.inside,
                                   cover=self.cover, merge=self.merge)
        self.flags = flags
        if len(boxes) == len(dets) and not flags.any():
            return dets  # nothing split or merged: the blobs as they were (their areas kept)
        return Detections.from_tlwh(dets.frame, boxes)

    def _shared(self, dets: Detections) -> bool:
        """Whether a blob is claimed by two or more predicted boxes (without merging,
        :func:`~mvtrack.detection.splitmerge.split_merge` changes nothing otherwise): its own
        test, on the boxes it would use, in one compiled call
        (:func:`~mvtrack.detection.claims.shared_blob`)."""
        pred = np.ascontiguousarray(self.predicted, np.float64).reshape(-1, 4)
        return bool(shared_blob(dets.xy, dets.wh, pred, self.cover))

    def observe(self, dets: Detections, tracks: TrackFrame) -> None:
        """Keep the confirmed tracks' boxes predicted for the next frame (and hand the
        tracks to the front end's own ``observe``, if it has one)."""
        self.predicted = predicted_boxes(tracks)
        inner = getattr(self.inner, "observe", None)
        if inner is not None:
            inner(dets, tracks, self.predicted)
