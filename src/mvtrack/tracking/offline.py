"""Offline tracking of a detection file: :func:`track_detections` runs a fresh
:class:`~mvtrack.tracking.tracker.Tracker` over all frames, then writes a confirmed track
from its first detection (backfill), interpolates the gaps it bridged and drops the short
tracks (:mod:`mvtrack.tracking.log`)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.config import _round as _round_frames
from mvtrack.tracking.log import TrackLog, backfill, drop_short_tracks, interpolate_gaps
from mvtrack.tracking.tracker import RescueFn, Tracker
from mvtrack.types import Detections, TrackFrame

IntArray = NDArray[np.int64]


def track_detections(
    frames: Iterable[Detections],
    config: TrackerConfig | None = None,
    rescue: RescueFn | None = None,
    scores: Any = None,
) -> TrackLog:
    """Run a fresh :class:`Tracker` over ``frames`` (one :class:`Detections` per frame).

    Frames must come in increasing order; a frame index that skips ahead is filled with empty
    frames so that the predictors advance one step per frame. With ``config.backfill`` (and
    without ``output_tentative``) a confirmed track's rows start at its first detection
    (:func:`mvtrack.tracking.log.backfill`); with ``config.interpolate`` the gaps a track
    bridged are written in full, interpolated (:func:`mvtrack.tracking.log.interpolate_gaps`).

    The ``"auto"`` score scale is calibrated on the scores seen so far, as online (the same
    thresholds mean the same in both modes); ``scores`` (for example every score of the file)
    calibrates it on those instead (:meth:`Tracker.prime_scores`). On the MOT15 development
    sequences the run-so-far calibration measured better offline too
    (``docs/bench/mot15-defaults.md``).
    """
    config = TrackerConfig() if config is None else config
    own = isinstance(config, TrackerConfig)
    late = own and config.backfill and not config.output_tentative
    fill = own and config.interpolate
    inner = config.replace(output_tentative=True) if late else config
    if fill:  # every coasting row, to be interpolated or cut to coast_output afterwards
        inner = inner.replace(coast_output=None)
    tracker = Tracker(inner)
    if scores is not None:
        tracker.prime_scores(scores)
    out: list[TrackFrame] = []
    uids: list[IntArray] = []
    last = None
    for dets in frames:
        if last is not None:
            if dets.frame <= last:
                raise ValueError(
                    f"track_detections: frame {dets.frame} does not follow frame {last}"
                )
            for f in range(last + 1, dets.frame):
                out.append(tracker.step(Detections.empty(f), rescue))
                uids.append(tracker.row_uids)
        out.append(tracker.step(dets, rescue))
        uids.append(tracker.row_uids)
        last = dets.frame
    if late:
        out = backfill(out, uids)
    if fill:
        out = interpolate_gaps(out, config.frames().coast_output)
    if own and config.min_track_length is not None:  # whole tracks shorter than this go
        out = drop_short_tracks(out, _round_frames(config.min_track_length * config.fps))
    log = TrackLog()
    for tf in out:
        log.append(tf)
    return log
