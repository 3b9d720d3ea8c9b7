"""Any detector, same tracker: adapters between mvtrack's :class:`~mvtrack.types.Detections`
and the detectors users already run.

- :func:`from_supervision` / :func:`to_supervision` — ``supervision.Detections`` (xyxy,
  confidence, class_id; tracker IDs added on the way out when given);
- :func:`from_ultralytics` — one ``ultralytics`` result (``result.boxes.xyxy``, ``.conf``,
  ``.cls``, as tensors or arrays);
- :class:`CallableDetector` — any callable ``frame -> boxes`` (an ``(M, 4)`` xyxy array, an
  ``(M, 5)`` array with scores, a pair ``(xyxy, scores)``, a ``supervision.Detections``, an
  ultralytics result or list of results, or :class:`Detections`) as a front end with the
  ``detector(frame, index) -> Detections`` interface, optionally keeping only some classes
  and scores.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.types import Detections, FloatArray


def _array(x: Any) -> NDArray[Any]:
    """A NumPy array from an array, a list or a tensor (``.cpu().numpy()`` when it has it)."""
    if hasattr(x, "detach"):
        x = x.detach()
    if hasattr(x, "cpu"):
        x = x.cpu()
    if hasattr(x, "numpy"):
        x = x.numpy()
    return np.asarray(x)


def from_xyxy(frame: int, xyxy: Any, score: Any = None) -> Detections:
    """:class:`Detections` from corner boxes ``(x1, y1, x2, y2)`` and optional scores."""
    b = _array(xyxy).astype(np.float64).reshape(-1, 4)
    if not np.isfinite(b).all():
        raise ValueError("detector boxes must be finite numbers")
    if (b[:, 2:] < b[:, :2]).any():
        raise ValueError("detector boxes must have x2 >= x1 and y2 >= y1")
    s = None if score is None else _array(score).astype(np.float64).reshape(-1)
    return Detections(frame, (b[:, :2] + b[:, 2:]) / 2, b[:, 2:] - b[:, :2], s)


def from_supervision(det: Any, frame: int) -> Detections:
    """:class:`Detections` of ``frame`` from a ``supervision.Detections``.

    The confidence is used as the score (1 when supervision has none).
    """
    return from_xyxy(frame, det.xyxy, det.confidence)


def to_supervision(
    dets: Detections, class_id: Any = None, tracker_id: Any = None
) -> Any:
    """A ``supervision.Detections`` with the boxes (xyxy) and scores of ``dets``.

    Parameters
    ----------
    dets : Detections
    class_id : (M,) int or None
        Classes to attach (supervision's annotators colour by them).
    tracker_id : (M,) int or None
        Track IDs to attach (e.g. from a :class:`~mvtrack.types.TrackFrame`).
    """
    import supervision as sv

    return sv.Detections(
        xyxy=dets.xyxy.astype(np.float32),
        confidence=dets.score.astype(np.float32),
        class_id=None if class_id is None else _array(class_id).astype(int),
        tracker_id=None if tracker_id is None else _array(tracker_id).astype(int),
    )


def from_ultralytics(
    result: Any, frame: int, classes: Iterable[int] | None = None
) -> Detections:
    """:class:`Detections` from one ultralytics result (``result.boxes``), optionally only
    the given class indices (e.g. ``[0]``, COCO's person)."""
    boxes = result.boxes
    xyxy = _array(boxes.xyxy).astype(np.float64).reshape(-1, 4)
    conf = _array(boxes.conf).astype(np.float64).reshape(-1)
    if classes is not None:
        cls = _array(boxes.cls).astype(np.int64).reshape(-1)
        keep = np.isin(cls, np.fromiter(classes, np.int64))
        xyxy, conf = xyxy[keep], conf[keep]
    return from_xyxy(frame, xyxy, conf)


def _convert(out: Any, frame: int, classes: Iterable[int] | None) -> Detections:
    if isinstance(out, Detections):
        return Detections(frame, out.xy, out.wh, out.score, out.area)
    if hasattr(out, "xyxy") and hasattr(out, "confidence"):  # supervision
        if classes is not None and out.class_id is not None:
            out = out[np.isin(out.class_id, list(classes))]
        return from_supervision(out, frame)
    if isinstance(out, (list, tuple)) and out and hasattr(out[0], "boxes"):
        out = out[0]  # ultralytics returns one result per image
    if hasattr(out, "boxes"):
        return from_ultralytics(out, frame, classes)
    if isinstance(out, tuple) and len(out) == 2:
        return from_xyxy(frame, out[0], out[1])
    arr = _array(out).astype(np.float64)
    if arr.size == 0:
        return Detections.empty(frame)
    if arr.ndim != 2 or arr.shape[1] not in (4, 5):
        raise ValueError(f"detector output must be (M, 4) or (M, 5) boxes, got {arr.shape}")
    return from_xyxy(frame, arr[:, :4], arr[:, 4] if arr.shape[1] == 5 else None)


class CallableDetector:
    """Any callable ``frame -> boxes`` as a front end (module docstring).

    Parameters
    ----------
    fn : callable
        The detector; called with the frame.
    min_score : float, default -inf
        Boxes scoring below are dropped.
    classes : iterable of int or None
        Keep only these classes (supervision and ultralytics outputs).
    """

    name = "callable"

    def __init__(
        self,
        fn: Callable[[Any], Any],
        min_score: float = -np.inf,
        classes: Iterable[int] | None = None,
    ) -> None:
        if not callable(fn):
            raise TypeError(f"detector must be callable, got {type(fn).__name__}")
        self.fn = fn
        self.min_score = float(min_score)
        self.classes = None if classes is None else tuple(int(c) for c in classes)
        self.frames_seen = 0

    def __call__(self, frame: Any, index: int | None = None) -> Detections:
        """Detections of ``frame``."""
        k = self.frames_seen if index is None else int(index)
        self.frames_seen += 1
        dets = _convert(self.fn(frame), k, self.classes)
        if np.isfinite(self.min_score):
            dets = dets.take(dets.score >= self.min_score)
        return dets


def tlwh_to_xyxy(tlwh: FloatArray) -> FloatArray:
    """Boxes ``(left, top, w, h)`` → ``(x1, y1, x2, y2)``."""
    b = np.asarray(tlwh, np.float64).reshape(-1, 4)
    return np.column_stack([b[:, :2], b[:, :2] + b[:, 2:]])
