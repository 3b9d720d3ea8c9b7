"""The scene front end beside a tracker: predicted boxes fed back, the size prior taught.

:class:`TrackFeedback` is what a :class:`~mvtrack.detection.scene_frontend.SceneFrontEnd`
takes from the tracker frame by frame: the confirmed tracks' predicted boxes for the next
frame (:func:`predicted_boxes`), and the boxes of isolated (:func:`isolated`), moving,
confirmed tracks of plain blobs, which teach its size prior. :func:`detect_with_tracker` runs
the two together over a clip (online), :func:`two_pass` twice (offline).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.scene_frontend import SceneFrontEnd
from mvtrack.detection.splitmerge import PLAIN, _overlap
from mvtrack.types import Detections, TrackFrame, TrackState

Image = NDArray[np.uint8]
FloatArray = NDArray[np.float64]


def predicted_boxes(tf: TrackFrame) -> FloatArray:
    """Next frame's boxes of the confirmed tracks of ``tf`` (filtered + velocity), tlwh."""
    live = (tf.track_id > 0) & (tf.state != int(TrackState.DELETED))
    xy = tf.filtered_xy[live] + tf.velocity[live]
    wh = tf.wh[live]
    return np.column_stack([xy - wh / 2, wh])


def isolated(tlwh: FloatArray, margin: float = 0.1) -> NDArray[np.bool_]:
    """Boxes that overlap no other box, each widened by ``margin`` of its size."""
    b = np.asarray(tlwh, np.float64).reshape(-1, 4)
    if len(b) == 0:
        return np.zeros(0, bool)
    g = b.copy()
    g[:, :2] -= margin * b[:, 2:]
    g[:, 2:] *= 1 + 2 * margin
    inter = _overlap(g, g)
    np.fill_diagonal(inter, 0.0)
    return ~(inter > 0).any(axis=1)


class TrackFeedback:
    """What a :class:`SceneFrontEnd` takes from the tracker beside it, frame by frame.

    :meth:`observe` after each ``tracker.step``: the detections of the confirmed, isolated
    tracks that came from plain blobs, move at least ``min_speed`` pixels per frame and have
    been measured in the last ``min_run`` frames in a row teach the size prior (leaves and
    flags that flicker in place are not objects); :attr:`predicted` holds the confirmed
    tracks' boxes for the next frame.
    """

    def __init__(
        self, frontend: SceneFrontEnd, *, learn: bool = True, min_speed: float = 1.0,
        min_run: int = 5,
    ) -> None:
        self.frontend = frontend
        self.learn = bool(learn)
        self.min_speed = float(min_speed)
        self.min_run = int(min_run)
        self.predicted: FloatArray | None = None
        self._run = np.zeros(1, np.int64)  # consecutive measured frames, by public track ID

    def observe(self, dets: Detections, flags: NDArray[np.int8], tf: TrackFrame) -> None:
        """Learn from frame ``tf`` (whose detections were ``dets`` with ``flags``)."""
        if self.learn and len(tf):
            speed = np.hypot(tf.velocity[:, 0], tf.velocity[:, 1])
            ids = tf.track_id
            run = self._run
            if ids.max() >= len(run):
                run = np.concatenate([run, np.zeros(2 * int(ids.max()) + 1 - len(run), np.int64)])
                self._run = run
            measured = (ids > 0) & (tf.det_index >= 0)
            prev = run[np.maximum(ids, 0)]
            run[:] = 0
            run[ids[measured]] = prev[measured] + 1
            hit = measured & (speed >= self.min_speed) & (run[np.maximum(ids, 0)] >= self.min_run)
            rows = tf.det_index[hit]
            boxes = dets.tlwh[rows] if len(rows) else np.zeros((0, 4))
            alone = isolated(dets.tlwh)[rows] if len(rows) else np.zeros(0, bool)
            good = alone & (flags[rows] == PLAIN) if len(rows) else alone
            if good.any():
                self.frontend.learn(boxes[good])
        self.predicted = predicted_boxes(tf)


def detect_with_tracker(
    frames: Iterable[Image],
    frontend: SceneFrontEnd,
    tracker: Any,
    *,
    learn: bool = True,
    min_speed: float = 1.0,
    min_run: int = 5,
    on_frame: Callable[[int, Image, Detections, TrackFrame], None] | None = None,
) -> list[Detections]:
    """Run ``frontend`` with ``tracker`` (a :class:`~mvtrack.tracking.Tracker`) over ``frames``.

    Each frame gets the confirmed tracks' predicted boxes; afterwards :class:`TrackFeedback`
    teaches the size prior (``learn``, ``min_speed``, ``min_run`` as there). Returns the
    detections of every frame (feed them to :func:`~mvtrack.tracking.track_detections` for
    an offline run with backfill and interpolation).
    """
    out: list[Detections] = []
    feedback = TrackFeedback(frontend, learn=learn, min_speed=min_speed, min_run=min_run)
    for k, frame in enumerate(frames):
        dets = frontend(frame, k, predicted=feedback.predicted)
        tf = tracker.step(dets)
        feedback.observe(dets, frontend.flags, tf)
        if on_frame is not None:
            on_frame(k, frame, dets, tf)
        out.append(dets)
    return out


def two_pass(
    frames: Sequence[Image],
    make_frontend: Callable[[], SceneFrontEnd],
    make_tracker: Callable[[], Any],
) -> tuple[list[Detections], SceneFrontEnd]:
    """Offline: bootstrap on the clip's median, learn the prior in a first pass, detect again.

    The second pass starts from the same median background and keeps the prior learnt in the
    first, so that blobs of the first frames are already split by size.
    """
    fe = make_frontend()
    fe.bootstrap(frames)
    detect_with_tracker(frames, fe, make_tracker())
    prior = fe.prior
    fe2 = make_frontend()
    fe2.prior = prior
    fe2.bootstrap(frames)
    return detect_with_tracker(frames, fe2, make_tracker()), fe2
