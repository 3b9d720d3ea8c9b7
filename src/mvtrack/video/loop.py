"""The frame loop: frames in, detections and tracks out, with a progress bar.

.. code-block:: text

    frames ─▶ detector (disturbance map, §1.1 step 2) ─▶ Detections
           ─▶ tracker.step(dets, rescue)  (prediction §1.1 step 4, association step 5)
           ─▶ TrackFrame per frame ─▶ on_frame (log, annotated video)

:func:`run_frames` knows only small interfaces (a detector is a callable
``frame -> Detections``, a tracker has ``step(dets, rescue=None) -> TrackFrame``, a rescuer
gives the ``rescue`` argument and observes the result), so the tests drive it with toy parts.
A detector may also take part in the tracking (the scene front end,
:class:`~mvtrack.detection.scene.SceneDetector`): if it has ``prepare(frames) -> frames`` the
loop reads the video through it (a background bootstrap from the first frames); if it has
``observe(dets, tracks)`` the loop calls it after each ``tracker.step`` (predicted boxes for
the next frame, the size prior taught by the tracks); its ``flags`` after each call (plain /
merged / split of each box) are kept in :attr:`PipelineResult.flags`. A rescuer's
``held_scores`` after each frame (the NCC score of each row held by template matching) are
kept in :attr:`PipelineResult.scores`. A rescuer with ``fragments(image, dets) -> (M,) bool``
names the detections that belong to vehicles it holds (the pieces of a vehicle that stands):
the tracker's step and the rescuer's callback do without them (:func:`step_without`), and
everything else sees the frame's detections as the front end gave them.
It shows a tqdm progress bar on stderr when stderr is a terminal, stops cleanly on Ctrl-C
(``KeyboardInterrupt`` inside the loop ends it with ``interrupted=True``; what was tracked so
far is returned) and treats a source that fails mid-way the same (``error`` holds the message).

A SIGINT or SIGTERM that arrives while a frame is processed takes effect when the frame is done
(:func:`frame_boundary_signals`): the handler that was installed for it (Python's Ctrl-C, the
command line's SIGTERM) is called then, not in the middle of the tracker's compiled kernels,
which turn an exception raised by a handler inside them into a ``SystemError``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from mvtrack.types import Detections, TrackFrame

Image = NDArray[np.uint8]
RescueFn = Callable[..., Any]


class HeldScores(NamedTuple):
    """The rows of one frame held by template matching and the NCC score of each match.

    Attributes
    ----------
    track_id : (K,) int64
        Public IDs of the rows in state ``STOPPED``.
    score : (K,) float64
        The NCC of the match that held each of them.
    """

    track_id: NDArray[np.int64]
    score: NDArray[np.float64]


#: a frame without rows held by template matching
NO_SCORES = HeldScores(np.zeros(0, np.int64), np.zeros(0, np.float64))


class Detector(Protocol):
    """A detection front end: one frame in, its detections out."""

    def __call__(self, frame: Image) -> Detections: ...


class StepTracker(Protocol):
    """The tracker interface the pipeline uses."""

    def step(self, dets: Detections, rescue: RescueFn | None = None) -> TrackFrame: ...


class Rescuer(Protocol):
    """Finds confirmed tracks that lost their detection (stopped vehicles)."""

    def callback(self, image: Image, dets: Detections) -> RescueFn | None:
        """The ``rescue`` argument of ``tracker.step`` for this frame and its detections."""
        ...

    def observe(self, image: Image, dets: Detections, tracks: TrackFrame) -> None:
        """Learn from this frame's result (e.g. store the appearance of detected tracks)."""
        ...


@dataclass
class PipelineResult:
    """What a run produced.

    Attributes
    ----------
    tracks : list of TrackFrame
        The tracker's output, one per processed frame.
    n_frames : int
        Frames processed (detected and tracked).
    n_detections : int
        Detections over all frames.
    seconds : float
        Wall time of the loop (decode, detect, track, and ``on_frame`` work).
    interrupted : bool
        Stopped by Ctrl-C.
    error : str or None
        The source failed mid-way with this message; the frames before it are kept.
    flags : list of (M,) int8
        Per frame, the blob flag of each detection
        (:data:`~mvtrack.detection.splitmerge.PLAIN`, ``MERGED`` or ``SPLIT``); all plain
        for a detector that has no ``flags``.
    scores : list of HeldScores
        Per frame, the public ID of each row held by template matching and the NCC score of
        its match (:func:`scores_of`; none in a run without a rescuer).
    """

    tracks: list[TrackFrame] = field(default_factory=list)
    n_frames: int = 0
    n_detections: int = 0
    seconds: float = 0.0
    interrupted: bool = False
    error: str | None = None
    flags: list[NDArray[np.int8]] = field(default_factory=list)
    scores: list[HeldScores] = field(default_factory=list)

    @property
    def ended_early(self) -> bool:
        """True when Ctrl-C or a failing source cut the run short."""
        return self.interrupted or self.error is not None

    @property
    def processing_speed(self) -> float:
        """Frames processed per second of wall time by the whole loop (not the frame rate)."""
        return self.n_frames / self.seconds if self.seconds > 0 else float("nan")


def _with_frame(dets: Detections, k: int) -> Detections:
    return dets if dets.frame == k else dataclasses.replace(dets, frame=k)


def flags_of(detector: Any, n: int) -> NDArray[np.int8]:
    """The blob flag of each of the ``n`` detections the detector just gave (all plain when
    it has no ``flags``)."""
    flags = getattr(detector, "flags", None)
    if flags is None or len(flags) != n:
        return np.zeros(n, np.int8)  # PLAIN
    return np.array(flags, np.int8)


def scores_of(rescuer: Any) -> HeldScores:
    """The rows the rescuer held in the frame it just observed, with their NCC scores (none
    for a rescuer that has no ``held_scores``, or no rescuer)."""
    held = getattr(rescuer, "held_scores", None)
    return NO_SCORES if held is None else HeldScores(*held)


def shown_scores(rescuer: Any, relink: Any = None) -> HeldScores:
    """:func:`scores_of` with the IDs the relinker shows (``relink`` None: as they are)."""
    held = scores_of(rescuer)
    if relink is not None and held.track_id.size:
        held = HeldScores(relink.shown(held.track_id), held.score)
    return held


def step_without(tracker: StepTracker, rescuer: Rescuer, image: Image, dets: Detections,
                 drop: NDArray[np.bool_]) -> TrackFrame:
    """The rescuer's callback and ``tracker.step`` on the detections not in ``drop``; the
    rows' ``det_index`` point into ``dets`` (all of them) again, so that the detector, the
    rescuer and the writers see the frame's detections as the front end gave them, and no
    track uses a dropped one."""
    if not drop.any():
        return tracker.step(dets, rescue=rescuer.callback(image, dets))
    keep = np.flatnonzero(~drop)
    kept = dets.take(keep)
    tracks = tracker.step(kept, rescue=rescuer.callback(image, kept))
    det = tracks.det_index.copy()
    used = det >= 0
    det[used] = keep[det[used]]
    return dataclasses.replace(tracks, det_index=det)


def progress_bar(total: int | None, desc: str, enabled: bool | None = None) -> Any:
    """A tqdm bar on stderr, shown only when stderr is a terminal (or ``enabled``)."""
    from tqdm import tqdm

    show = sys.stderr.isatty() if enabled is None else enabled
    return tqdm(total=total, desc=desc, unit="frame", file=sys.stderr, disable=not show,
                leave=False, dynamic_ncols=True)


@contextlib.contextmanager
def frame_boundary_signals() -> Iterator[Callable[[], None]]:
    """Inside the block, SIGINT and SIGTERM wait for the caller's next check.

    Yields ``check()``: it calls the handler that was installed for the first signal that
    arrived since the last check (Python's ``default_int_handler`` raises
    ``KeyboardInterrupt``; ``mvtrack``'s command line raises its ``Terminated`` on SIGTERM)
    and does nothing when none arrived. A signal whose handler is not a Python function (the
    default SIGTERM, which ends the process; an ignored one) is left alone, and so is every
    signal outside the main thread, where Python runs no handlers. A signal left unchecked
    when the block ends is handled as it ends.
    """
    pending: list[int] = []
    old: dict[int, Callable[..., Any]] = {}

    def check() -> None:
        if pending:
            signum = pending[0]
            pending.clear()
            old[signum](signum, None)

    if threading.current_thread() is not threading.main_thread():
        yield check
        return

    def record(signum: int, frame: Any) -> None:
        pending.append(signum)

    for s in (signal.SIGINT, signal.SIGTERM):
        handler = signal.getsignal(s)
        if callable(handler):
            old[s] = handler
            signal.signal(s, record)
    try:
        yield check
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
        check()


def run_frames(
    frames: Iterable[Image],
    detector: Callable[[Image], Detections],
    tracker: StepTracker,
    *,
    rescuer: Rescuer | None = None,
    max_frames: int | None = None,
    on_frame: Callable[[int, Image, Detections, TrackFrame], None] | None = None,
    total: int | None = None,
    progress: bool | None = None,
    desc: str = "tracking",
    keep: bool = True,
    relink: Any = None,
    offline: Any = None,
) -> PipelineResult:
    """Detect and track every frame of ``frames``.

    Parameters
    ----------
    frames : iterable of (H, W, 3) uint8
        The video, frame by frame (index k = 0, 1, ...).
    detector : callable
        ``frame -> Detections`` (its ``frame`` field is set to k here).
    tracker : StepTracker
        Receives ``step(dets, rescue)`` once per frame.
    rescuer : Rescuer, optional
        Template matching for stopped vehicles; its callback is passed as ``rescue``.
    max_frames : int, optional
        Stop after this many frames.
    on_frame : callable, optional
        ``on_frame(k, image, dets, tracks)`` after each frame (e.g. write the annotated video).
    total : int, optional
        Expected number of frames, for the progress bar.
    progress : bool, optional
        Force the progress bar on or off (default: on when stderr is a terminal).
    desc : str
        Label of the progress bar.
    keep : bool
        Keep every frame's tracks, flags and scores in the result (``False``: a streaming
        run, whose ``on_frame`` writes them, keeps memory flat; ``tracks``, ``flags`` and
        ``scores`` stay empty).
    relink : Relinker, optional
        Gives a new track the ID of one that ended where it reappears
        (:class:`mvtrack.video.relink.Relinker`); called after the detector and the rescuer
        have seen the tracker's own IDs, so everything kept, drawn and written carries the
        shown IDs.
    offline : OfflineRows, optional
        The ``tracker`` of an offline run (:class:`mvtrack.video.offline.OfflineRows`): the
        tentative rows of each step are kept aside; everything after sees the public rows.

    Returns
    -------
    PipelineResult
        Never raises on Ctrl-C or on a source error after the first frame: the run ends
        early and says so. A signal during a frame ends the run after that frame
        (:func:`frame_boundary_signals`): the frame is kept whole.
    """
    if max_frames is not None and max_frames < 1:
        raise ValueError(f"max_frames must be at least 1, got {max_frames}")
    if max_frames is not None:
        total = max_frames if total is None else min(total, max_frames)
    result = PipelineResult()
    bar = progress_bar(total, desc, progress)
    t0 = time.perf_counter()
    prepare = getattr(detector, "prepare", None)
    iterator: Iterator[Image] = iter(prepare(frames) if prepare is not None else frames)
    observe = getattr(detector, "observe", None)
    shown = getattr(detector, "shown", None)
    fragments = getattr(rescuer, "fragments", None)
    k = 0
    try:
        with frame_boundary_signals() as check_signals:
            while max_frames is None or k < max_frames:
                check_signals()  # a signal during the last frame ends the run here
                try:
                    image = next(iterator)
                except StopIteration:
                    break
                except (ValueError, OSError) as exc:  # the source dropped mid-way
                    if k == 0:
                        raise
                    result.error = str(exc)
                    break
                dets = _with_frame(detector(image), k)
                if fragments is None:
                    rescue = rescuer.callback(image, dets) if rescuer is not None else None
                    tracks = tracker.step(dets, rescue=rescue)
                else:  # pieces of stopped vehicles left out: their templates hold them
                    tracks = step_without(tracker, rescuer, image, dets,
                                          fragments(image, dets))
                if offline is not None:
                    tracks = offline.public(tracks, dets)
                if observe is not None:
                    observe(dets, tracks)
                if keep:
                    result.flags.append(flags_of(detector, len(dets)))
                if rescuer is not None:
                    rescuer.observe(image, dets, tracks)
                if relink is not None:
                    live = getattr(getattr(tracker, "tracks", None), "track_id", None)
                    tracks = relink(image, tracks, live)
                if shown is not None:
                    tracks = shown(tracks)
                if keep:
                    result.tracks.append(tracks)
                    result.scores.append(shown_scores(rescuer, relink))
                result.n_frames = k + 1
                result.n_detections += len(dets)
                if on_frame is not None:
                    on_frame(k, image, dets, tracks)
                bar.update(1)
                k += 1
    except KeyboardInterrupt:
        result.interrupted = True
    finally:
        bar.close()
        close = getattr(iterator, "close", None)
        if close is not None:
            close()
    result.seconds = time.perf_counter() - t0
    return result
