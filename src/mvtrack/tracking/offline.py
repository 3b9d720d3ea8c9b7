"""Offline tracking of a detection file: :func:`track_detections` runs a fresh
:class:`~mvtrack.tracking.tracker.Tracker` over all frames, then leaves out the tracks made of
the detector's weakest boxes (:func:`drop_weak`), writes a confirmed track from its first
detection (backfill), continues under its ID a track that ended and came back
where it was heading (:mod:`mvtrack.tracking.relink`), interpolates the gaps it bridged
(:mod:`mvtrack.tracking.log`) and smooths each track over all its detections
(:mod:`mvtrack.tracking.smooth`).

These revise rows after the frame that produced them (a track's first rows get its ID only once
it is confirmed, a gap only once it is bridged or the track ends), so the offline run writes its
results when the whole file is tracked; it does not stream."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.log import ROW_FIELDS, TrackLog, backfill, interpolate_gaps
from mvtrack.tracking.relink import relink as relink_tracks
from mvtrack.tracking.scores import ScoreCalibration
from mvtrack.tracking.smooth import smooth_tracks
from mvtrack.tracking.tracker import RescueFn, Tracker
from mvtrack.types import Detections, TrackFrame

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]

#: a track whose detections' mean rank among the scores of every detection the tracks took
#: is below this is left out of an offline run's results (:func:`drop_weak`); chosen by
#: leave-one-out over the frame-rate sweep (``docs/bench/framerate.md``)
MIN_MEAN_SCORE = 0.275


def track_detections(
    frames: Iterable[Detections],
    config: TrackerConfig | None = None,
    rescue: RescueFn | None = None,
    scores: Any = None,
    *,
    backfill_rows: bool = True,
    interpolate: bool = True,
    relink: bool = True,
    drop_weak_tracks: bool = True,
    smooth: bool = True,
) -> TrackLog:
    """Run a fresh :class:`Tracker` over ``frames`` (one :class:`Detections` per frame).

    Frames must come in increasing order; a frame index that skips ahead is filled with empty
    frames so that the predictors advance one step per frame, for as long as a track is
    alive; the rest of a gap in which no track is left is jumped in one go (an empty frame
    then changes nothing), and only frames with rows are kept, so a long empty stretch costs
    neither time nor memory (:func:`frames_with_detections` gives a detection file's frames
    that way). The log covers every frame from the first given to the last. With
    ``backfill_rows`` (and without ``config.output_tentative``) a confirmed track's rows start
    at its first detection (:func:`mvtrack.tracking.log.backfill`); with ``interpolate`` the
    gaps a track bridged are written in full, interpolated
    (:func:`mvtrack.tracking.log.interpolate_gaps`); with ``relink`` a track that starts,
    alone, where an ended one was heading takes the ended one's ID
    (:func:`mvtrack.tracking.relink.relink`; gaps longer than ``config.max_misses`` frames,
    which only relinking makes, are not interpolated); with ``drop_weak_tracks`` the tracks
    whose detections score low on average are left out (:func:`drop_weak`); with ``smooth``
    every row's position, velocity and box are the track's smoothed estimate from all its
    detections (:func:`mvtrack.tracking.smooth.smooth_tracks`), the last step.

    The ``"auto"`` score scale is calibrated on the scores seen so far, as online (the same
    thresholds mean the same in both modes); ``scores`` (for example every score of the file)
    calibrates it on those instead (:meth:`Tracker.prime_scores`).
    """
    config = TrackerConfig() if config is None else config
    late = backfill_rows and not config.output_tentative
    inner = config.replace(output_tentative=True) if late else config
    tracker = Tracker(inner)
    if scores is not None:
        tracker.prime_scores(scores)
    out: list[TrackFrame] = []  # the frames with rows only
    uids: list[IntArray] = []
    seen: dict[int, Detections] = {}  # the detections of the frames with rows
    first = last = None

    def step(d: Detections) -> None:
        tf = tracker.step(d, rescue)
        if len(tf):
            out.append(tf)
            uids.append(tracker.row_uids)
            seen[d.frame] = d

    for dets in frames:
        if last is None:
            first = dets.frame
        else:
            if dets.frame <= last:
                raise ValueError(
                    f"track_detections: frame {dets.frame} does not follow frame {last}"
                )
            f = last + 1
            # Empty frames while a track lives (it coasts, or is deleted); once none is
            # left an empty frame changes nothing (the tracker compares its step numbers
            # only with each other), so the rest of the gap is jumped.
            while f < dets.frame and tracker.n_tracks:
                step(Detections.empty(f))
                f += 1
        step(dets)
        last = dets.frame
    if drop_weak_tracks and out:
        raw = np.concatenate([_of_detection(f, seen, "score") for f in out])
        out, uids = drop_weak(out, uids, raw)
    if late:
        out = backfill(out, uids)
    if relink:
        out = relink_tracks(out, config)
    if interpolate:
        # a gap longer than max_misses was relinked, not coasted: its rows are not guessed
        out = interpolate_gaps(out, max_gap=config.max_misses + 1)
    if smooth and out:
        out = smooth_tracks(out, [_of_detection(f, seen, "wh") for f in out], config)
    log = TrackLog()
    if first is None:
        return log
    upto = first  # every frame from the first to the last given; the empty ones implied
    for tf in out:
        if upto == first and tf.frame > first:
            log.append(TrackFrame.empty(first))
            upto += 1
        log.skip(tf.frame - upto)
        log.append(tf)
        upto = tf.frame + 1
    if upto == first:
        log.append(TrackFrame.empty(first))
        upto += 1
    log.skip(last + 1 - upto)
    return log


def _of_detection(tf: TrackFrame, seen: dict[int, Detections], field: str) -> FloatArray:
    """:func:`of_detection` with ``seen`` holding the detections of the frames the rows
    came from."""
    return of_detection(tf, seen[tf.frame] if (tf.det_index >= 0).any() else None, field)


def of_detection(tf: TrackFrame, dets: Detections | None, field: str) -> FloatArray:
    """``field`` (``"score"``, ``"wh"``) of each row's detection in ``tf``, NaN for a row
    without one; ``dets`` are the detections of the frame (None when no row has one)."""
    has = tf.det_index >= 0
    if dets is None or not has.any():
        return np.full((len(tf), 2) if field == "wh" else len(tf), np.nan)
    values = getattr(dets, field)
    out = np.full((len(tf), *values.shape[1:]), np.nan)
    out[has] = values[tf.det_index[has]]
    return out


def frames_with_detections(frames: Sequence[Detections]) -> Iterator[Detections]:
    """The first frame of ``frames`` and then only those that hold detections.

    What :func:`track_detections` needs to track ``frames``: the empty frames in between are
    implied by the frame numbers, and a :class:`~mvtrack.io.mot.DetectionFrames` (a file
    read by :func:`~mvtrack.io.mot.read_detections`) is visited through its index, so a file
    whose last frame is 10⁶ costs its rows, not a million frames. The log of the run covers
    every frame from the first to the last that holds detections.
    """
    if len(frames) == 0:
        return
    yield frames[0]
    index = getattr(frames, "index", None)
    if index is not None and hasattr(index, "groups"):
        for f, _ in index.groups():
            if f > 0:
                yield frames[f]
        return
    for f in range(1, len(frames)):
        d = frames[f]
        if len(d):
            yield d


def drop_weak(frames: list[TrackFrame], uids: list[IntArray], score: FloatArray,
              least: float | None = None) -> tuple[list[TrackFrame], list[IntArray]]:
    """Leave out the rows of every track whose detections score low among the tracks' own.

    Each detection a track took (tentative tracks' included) is ranked among all of them,
    ``c_j = #{s_i ≤ s_j} / n`` over the ``n`` detections taken (the ``"auto"`` calibration of
    :mod:`mvtrack.tracking.scores`, on the boxes the tracker used), and a track is kept when
    the mean rank of its detections, ``c̄ = (1 / m) Σ c_j``, is at least ``least``
    (:data:`MIN_MEAN_SCORE`). A detector's weakest boxes are its false alarms and its badly
    placed boxes: a track made mostly of them is, offline, more likely one of those than an
    object (the online tracker must decide at confirmation; offline the whole track is
    known). Ranks, not scores: any detector's scale, and a scene with few false alarms,
    where the weakest boxes taken are still people, loses few tracks. A run whose scores are
    all equal (no scores) keeps every track.

    Parameters
    ----------
    frames, uids : list of TrackFrame, list of (K,) int64
        A run's rows with the tracker's internal uid of each (:attr:`Tracker.row_uids`).
    score : (R,) float
        The raw score of each row's detection, NaN for a row without one, over the rows of
        ``frames`` in order.
    least : float or None
        ``c̄`` below which a track is left out; None: :data:`MIN_MEAN_SCORE`.

    Returns
    -------
    frames, uids
        The rows kept (frames left without a row dropped) and their uids.
    """
    least = MIN_MEAN_SCORE if least is None else least
    u = np.concatenate(uids)
    has = ~np.isnan(score)
    ranks = ScoreCalibration("auto")
    ranks.prime(score[has])
    rank = ranks(score[has])  # c_j
    size = int(u.max()) + 1 if u.size else 0
    total = np.bincount(u[has], weights=rank, minlength=size)
    count = np.bincount(u[has], minlength=size)
    strong = total >= least * count  # c̄ >= least (a track without a detection is kept)
    out, out_u = [], []
    for tf, uid in zip(frames, uids, strict=True):
        keep = strong[uid]
        if keep.all():
            out.append(tf)
            out_u.append(uid)
        elif keep.any():
            out.append(TrackFrame(tf.frame, *(getattr(tf, n)[keep] for n in ROW_FIELDS)))
            out_u.append(uid[keep])
    return out, out_u
