"""OpenCV's HOG people detector (Dalal & Triggs' default linear SVM): a detector, and a
verifier of candidate boxes run only where the foreground is.

In OpenCV 5 the HOG descriptor ships with the contrib build
(``opencv-contrib-python-headless``), which mvtrack depends on.

- :class:`HOGDetector` — ``detector(frame, index) -> Detections`` over the whole frame
  (``detectMultiScale``; slow: tens of milliseconds per frame);
- :func:`hog_scores` — the SVM margin of each candidate box: the box is widened to the
  detector's 64×128 window (a person fills about 96 of its 128 rows), resized to it, and
  scored by one descriptor and one dot product, so a verifier costs a fraction of a
  millisecond per box.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.types import Detections, FloatArray

WINDOW = (64, 128)  #: the default people detector's window (width, height)
_BODY = 96 / 128  #: share of the window's height a person fills in the training data


def _hog() -> cv2.HOGDescriptor:
    if not hasattr(cv2, "HOGDescriptor"):  # pragma: no cover - OpenCV 5 without contrib
        raise RuntimeError(
            "cv2.HOGDescriptor is missing: install opencv-contrib-python-headless"
        )
    hog = cv2.HOGDescriptor()
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    return hog


class HOGDetector:
    """Whole-frame HOG people detector (``cv2.HOGDescriptor.detectMultiScale``).

    Parameters
    ----------
    scale : float, default 1.05
        Pyramid step.
    hit_threshold : float, default 0
        SVM margin a window needs.
    win_stride : int, default 8
        Window step, pixels.
    min_area : float, default 0
        Boxes of a smaller area (px²) are dropped. ``mvtrack track`` fills in its blob stage's
        size-dependent ``min_area`` for every front end; a person's HOG box (at least the
        64×128 window) is far larger.
    close_size : int or None
        Accepted for the same reason and unused: HOG has no foreground mask to close.
    """

    name = "hog"

    def __init__(self, scale: float = 1.05, hit_threshold: float = 0.0, win_stride: int = 8,
                 min_area: float = 0.0, close_size: int | None = None):
        if not scale > 1.0:
            raise ValueError(f"scale must be > 1, got {scale}")
        if not (np.isfinite(min_area) and min_area >= 0):
            raise ValueError(f"min_area must be a non-negative number, got {min_area}")
        if not win_stride >= 1:
            raise ValueError(f"win_stride must be at least 1, got {win_stride}")
        self.min_area = float(min_area)
        self.scale = float(scale)
        self.hit_threshold = float(hit_threshold)
        self.win_stride = int(win_stride)
        self._hog = _hog()
        self.frames_seen = 0

    def __call__(self, frame: NDArray[np.uint8], index: int | None = None) -> Detections:
        """People found in ``frame``; the score is the SVM margin."""
        k = self.frames_seen if index is None else int(index)
        self.frames_seen += 1
        if frame.shape[0] < WINDOW[1] or frame.shape[1] < WINDOW[0]:
            # no window fits (the pyramid only shrinks the frame); OpenCV 5.0's
            # detectMultiScale also corrupts memory on such frames (e.g. 100x200 crashes)
            return Detections.empty(k)
        rects, weights = self._hog.detectMultiScale(
            frame,
            hitThreshold=self.hit_threshold,
            winStride=(self.win_stride, self.win_stride),
            scale=self.scale,
        )
        if len(rects) == 0:
            return Detections.empty(k)
        r = np.asarray(rects, np.float64).reshape(-1, 4)
        score = np.asarray(weights, np.float64).reshape(-1)
        keep = r[:, 2] * r[:, 3] >= self.min_area
        return Detections.from_tlwh(k, r[keep], score[keep])


def window_of(tlwh: FloatArray) -> FloatArray:
    """The detector window (tlwh, 1:2) in which the box would fill a person's share."""
    b = np.asarray(tlwh, np.float64).reshape(-1, 4)
    h = np.maximum(b[:, 3], 2.0 * b[:, 2] * _BODY) / _BODY
    w = h * WINDOW[0] / WINDOW[1]
    c = b[:, :2] + b[:, 2:] / 2
    return np.column_stack([c - np.column_stack([w, h]) / 2, w, h])


def hog_scores(
    frame: NDArray[np.uint8], tlwh: FloatArray, hog: cv2.HOGDescriptor | None = None
) -> FloatArray:
    """SVM margin of the default people detector for each box (higher: more person-like).

    Parameters
    ----------
    frame : (H, W, 3) or (H, W) uint8
    tlwh : (M, 4)
        Candidate boxes.
    hog : cv2.HOGDescriptor or None
        A descriptor with the default people detector set (made when None).
    """
    hog = _hog() if hog is None else hog
    boxes = window_of(tlwh)
    if len(boxes) == 0:
        return np.zeros(0)
    svm = np.asarray(cv2.HOGDescriptor_getDefaultPeopleDetector(), np.float64).ravel()
    pad = int(np.ceil(max(boxes[:, 2].max(), boxes[:, 3].max())))
    big = cv2.copyMakeBorder(frame, pad, pad, pad, pad, cv2.BORDER_REPLICATE)
    out = np.empty(len(boxes))
    for i, (x, y, w, h) in enumerate(boxes.tolist()):  # the few candidate boxes of a frame
        x0, y0 = round(x) + pad, round(y) + pad
        crop = big[y0 : y0 + max(round(h), 2), x0 : x0 + max(round(w), 1)]
        win = cv2.resize(crop, WINDOW, interpolation=cv2.INTER_AREA)
        feat = hog.compute(win).astype(np.float64).ravel()
        out[i] = feat @ svm[:-1] + svm[-1]
    return out
