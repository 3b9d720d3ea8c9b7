"""The interface every detection front end implements: ``detector(frame) -> Detections``."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.blobs import BlobExtractor
from mvtrack.types import Detections


class FrontEnd:
    """Base of the foreground front ends: a foreground mask per frame, then the blob stage.

    Subclasses implement :meth:`foreground` (a ``uint8`` mask, non-zero = moving, or ``None``
    while the model has no reference yet) and :meth:`_reset_model`.

    Parameters
    ----------
    blobs : BlobExtractor
        Morphology, connected components and area filters (:mod:`mvtrack.detection.blobs`).
    warmup : int, default 0
        Frames after a reset whose detections are suppressed while the model still learns
        (the frames still update it).

    Notes
    -----
    Call ``detector(frame)`` once per frame, in order; ``detector(frame, index)`` sets the frame
    index stored in the result (default: frames seen since the last :meth:`reset`).
    """

    name: str = ""

    def __init__(self, blobs: BlobExtractor, warmup: int = 0) -> None:
        if warmup < 0:
            raise ValueError(f"warmup must be ≥ 0 frames, got {warmup}")
        self.blobs = blobs
        self.warmup = int(warmup)
        self.frames_seen = 0
        self.raw_mask: NDArray[np.uint8] | None = None

    @property
    def mask(self) -> NDArray[np.uint8] | None:
        """The cleaned foreground mask of the last frame (a reused buffer), or ``None``."""
        return self.blobs.mask if self.raw_mask is not None else None

    def __call__(self, frame: NDArray[np.uint8], index: int | None = None) -> Detections:
        """Detections in ``frame`` (BGR ``uint8`` (H, W, 3) or grey (H, W))."""
        k = self.frames_seen if index is None else int(index)
        if frame.dtype != np.uint8 or frame.ndim not in (2, 3):
            raise ValueError(
                f"{type(self).__name__}: frame must be a uint8 image, got {frame.dtype} "
                f"{frame.shape}"
            )
        mask = self.foreground(frame)
        self.frames_seen += 1
        self.raw_mask = mask
        if mask is None or self.frames_seen <= self.warmup:
            return Detections.empty(k)
        return self.blobs(mask, k)

    def reset(self) -> None:
        """Forget the background model and the frame counter (e.g. at a scene cut)."""
        self.frames_seen = 0
        self.raw_mask = None
        self.blobs.mask = None
        self._reset_model()

    def foreground(self, frame: NDArray[np.uint8]) -> NDArray[np.uint8] | None:
        """The raw foreground mask of ``frame``; updates the model."""
        raise NotImplementedError

    def _reset_model(self) -> None:
        raise NotImplementedError


def luminance(frame: NDArray[np.uint8], out: NDArray[np.uint8] | None = None) -> NDArray[np.uint8]:
    """Grey level (ITU-R BT.601 luma, as ``cv2.COLOR_BGR2GRAY``) of a BGR frame; grey passes."""
    if frame.ndim == 2:
        return frame
    if frame.shape[2] == 1:
        return frame[:, :, 0]
    if out is None or out.shape != frame.shape[:2]:
        return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY, dst=out)
