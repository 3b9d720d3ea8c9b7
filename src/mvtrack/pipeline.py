"""Frames in, tracks out: the video pipeline of paper 1 (SPEC §1.1, Fig. 1).

.. code-block:: text

    frames ─▶ detector (disturbance map, §1.1 step 2) ─▶ Detections
           ─▶ tracker.step(dets, rescue)  (prediction §1.1 step 4, association step 5)
           ─▶ TrackFrame per frame ─▶ results, annotated video, plots

Stopped vehicles fade into the disturbance-map background (§1.1 step 3); a *rescuer*
(template matching, :class:`StoppedVehicleRescuer` around
:class:`~mvtrack.detection.template.TemplateRescuer`) is consulted by the tracker for confirmed
tracks that got no detection and holds them in state STOPPED.

:func:`run_frames` is the loop and knows only small interfaces (a detector is a callable
``frame -> Detections``, a tracker has ``step(dets, rescue=None) -> TrackFrame``), so the tests
drive it with toy parts. It shows a tqdm progress bar on stderr when stderr is a terminal,
stops cleanly on Ctrl-C (``KeyboardInterrupt`` inside the loop ends it with
``interrupted=True``; what was tracked so far is returned) and treats a source that fails
mid-way the same (``error`` holds the message). :func:`build_detector`, :func:`build_tracker`
and :func:`build_rescuer` make the real parts from :class:`~mvtrack.config.RunSettings`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from mvtrack.config import RunSettings
from mvtrack.errors import InputError
from mvtrack.types import Detections, TrackFrame

Image = NDArray[np.uint8]
RescueFn = Callable[..., Any]
FloatArray = NDArray[np.float64]


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
    """

    tracks: list[TrackFrame] = field(default_factory=list)
    n_frames: int = 0
    n_detections: int = 0
    seconds: float = 0.0
    interrupted: bool = False
    error: str | None = None

    @property
    def ended_early(self) -> bool:
        """True when Ctrl-C or a failing source cut the run short."""
        return self.interrupted or self.error is not None

    @property
    def fps(self) -> float:
        """Frames per second of the whole loop."""
        return self.n_frames / self.seconds if self.seconds > 0 else float("nan")


def _with_frame(dets: Detections, k: int) -> Detections:
    return dets if dets.frame == k else dataclasses.replace(dets, frame=k)


def progress_bar(total: int | None, desc: str, enabled: bool | None = None) -> Any:
    """A tqdm bar on stderr, shown only when stderr is a terminal (or ``enabled``)."""
    from tqdm import tqdm

    show = sys.stderr.isatty() if enabled is None else enabled
    return tqdm(total=total, desc=desc, unit="frame", file=sys.stderr, disable=not show,
                leave=False, dynamic_ncols=True)


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

    Returns
    -------
    PipelineResult
        Never raises on Ctrl-C or on a source error after the first frame: the run ends
        early and says so.
    """
    if max_frames is not None and max_frames < 1:
        raise ValueError(f"max_frames must be at least 1, got {max_frames}")
    if max_frames is not None:
        total = max_frames if total is None else min(total, max_frames)
    result = PipelineResult()
    bar = progress_bar(total, desc, progress)
    t0 = time.perf_counter()
    iterator: Iterator[Image] = iter(frames)
    k = 0
    try:
        while max_frames is None or k < max_frames:
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
            rescue = rescuer.callback(image, dets) if rescuer is not None else None
            tracks = tracker.step(dets, rescue=rescue)
            if rescuer is not None:
                rescuer.observe(image, dets, tracks)
            result.tracks.append(tracks)
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


# --------------------------------------------------------------------------- building parts


#: the image size the papers' pixel parameters refer to (SPEC §1.4: 320×240)
REFERENCE_SIZE = (320, 240)


def resolve_settings(settings: RunSettings, size: tuple[int, int]) -> RunSettings:
    """Fill in the size-dependent defaults the user left open, for a ``size`` (W, H) video.

    With ``s² = W·H / (320·240)`` (the papers' 320×240, SPEC §1.4):

    - blob stage: ``min_area = 40 s²`` px and a 7×7 closing (``close_size = 7``), which merges
      fragments a few pixels apart — two-tone vehicles and clothes otherwise split into
      several blobs, the "segmentation splits vehicles by colour" of paper 1 (SPEC §1.5).
      The closing is not scaled with the image: a larger one merges people walking side by
      side in 768×576 video. SPEC §1.1 [R] (opening only, area ≥ 20 px) is
      ``close_size = 0, min_area = 20``;
    - the default tracker preset: measurement noise ``measurement_std = 2 s`` px, i.e.
      ``r = 4 s²`` px² (SPEC §2.1 [R] gives 4 px² at 320×240, the preset's own value there;
      blob centroids jitter with the blob's size).

    - the default preset's pixel distances (its Euclidean gate, ``second_gate``,
      ``recover_margin``) scaled by ``s`` (the gate, in px², by ``s²``). ``recover_speed``
      stays: scaled, it let tracks hop 70 px per frame on 768×576 video at 10 fps. Its
      ``size_ref`` is scaled by ``s`` too (boxes larger than that stretch the gates).

    - no size gate (``size_gate = None``): blobs merge and split, so the size of a blob's box
      says little about which object it is.

    The tracker values are only scaled up: images smaller than 320×240 keep them.

    Values present in ``settings`` are kept; the paper presets are not touched.
    """
    w, h = size
    s2 = (w * h) / (REFERENCE_SIZE[0] * REFERENCE_SIZE[1])
    det = dict(settings.detector_params)
    det.setdefault("min_area", float(round(40.0 * s2)))
    det.setdefault("close_size", 7)
    tracker = dict(settings.tracker)
    if tracker.get("preset", "default") == "default":
        # blobs merge and split (two vehicles in one blob, a person in two): a blob's box
        # size is no evidence of identity, unlike a detector's box
        tracker.setdefault("size_gate", None)
        up = max(s2, 1.0)  # smaller images keep the 320×240 values
        if not {"predictor_params", "measurement_std"} & set(tracker):
            tracker["measurement_std"] = round(2.0 * up**0.5, 3)  # r = 4 s² px²
        tracker.update(_scaled_pixel_fields(tracker, up))
    return dataclasses.replace(settings, detector_params=det, tracker=tracker)


def _scaled_pixel_fields(tracker: dict[str, Any], s2: float) -> dict[str, Any]:
    """Pixel-valued defaults of ``TrackerConfig`` scaled to an image ``s²`` times 320×240."""
    from mvtrack.tracking import TrackerConfig

    defaults = {f.name: f.default for f in dataclasses.fields(TrackerConfig)}
    # size_ref (the box size above which the gates stretch with the box) scales too, so a
    # blob s times the reference box is treated as the reference box at 320×240
    power = {"second_gate": 0.5, "recover_margin": 0.5, "size_ref": 0.5}
    if tracker.get("distance", defaults.get("distance")) == "euclidean":
        power["gate"] = 1.0  # px², scales with the area
    out = {}
    for name, p in power.items():
        value = defaults.get(name)
        if name in tracker or not isinstance(value, (int, float)) or s2 == 1.0:
            continue
        out[name] = round(float(value) * s2**p, 3)
    return out


def build_detector(settings: RunSettings) -> Callable[[Image], Detections]:
    """The detection front end named in ``settings`` with its parameters.

    Raises
    ------
    ValueError
        Unknown front end or parameter (one line, from :func:`mvtrack.detection.make_detector`).
    """
    from mvtrack.detection import make_detector

    return make_detector(settings.detector, **settings.detector_params)


def build_tracker_config(settings: RunSettings, fps: float) -> Any:
    """The :class:`~mvtrack.tracking.TrackerConfig` of ``settings`` at frame rate ``fps``.

    ``settings.tracker["preset"]`` (default ``"default"``) is built for ``fps``; keys the preset
    function takes as arguments (e.g. ``paper1(predictor=...)``, which then picks the
    predictor's own parameters) are passed to it, the others replace fields of the result.
    Changing the distance without a gate resets the gate to the new distance's default (a gate
    is in the distance's units: px² for ``euclidean``, χ² for the others).

    Raises
    ------
    InputError
        Unknown preset or field, or a bad value (one line).
    """
    import inspect

    from mvtrack.tracking import PRESETS, TrackerConfig

    params = dict(settings.tracker)
    name = params.pop("preset", "default")
    if name not in PRESETS:
        raise InputError(f"unknown tracker preset {name!r}; choose one of: {', '.join(PRESETS)}")
    known = {f.name for f in dataclasses.fields(TrackerConfig)}
    for key in params:
        if key not in known:
            raise InputError(
                f"unknown tracker setting {key!r} (known: {', '.join(sorted(known))})"
            )
    if "distance" in params and "gate" not in params:
        params["gate"] = None  # a gate is in the distance's units: use the new one's default
    build = PRESETS[name]
    takes = set(inspect.signature(build).parameters) - {"fps"}
    args = {k: params.pop(k) for k in list(params) if k in takes}
    try:
        config = build(fps=fps, **args)
        return config.replace(**params) if params else config
    except (TypeError, ValueError) as exc:
        raise InputError(f"tracker settings: {exc}") from None


def build_tracker(settings: RunSettings, fps: float) -> Any:
    """A fresh :class:`~mvtrack.tracking.Tracker` for ``settings`` (validates predictor etc.)."""
    from mvtrack.tracking import Tracker

    config = build_tracker_config(settings, fps)
    try:
        return Tracker(config)
    except (TypeError, ValueError) as exc:
        raise InputError(f"tracker settings: {exc}") from None


def build_rescuer(settings: RunSettings, tracker: Any, detector: Any = None) -> Rescuer:
    """Template matching for stopped vehicles (paper 1 §1.1 step 3) attached to ``tracker``.

    A :class:`~mvtrack.detection.template.TemplateBank` with ``settings.template_params``
    (NCC ≥ 0.8 inside the gate radius, SPEC §1.1 [R]; the bank owns the check that a track
    has driven somewhere before it is searched: ``min_travel`` box lengths, ``min_travel_px``,
    ``min_hits``) in its :class:`~mvtrack.detection.template.TemplateRescuer`, given the
    ``detector`` (its foreground mask restricts the templates to the objects' own pixels),
    guarded by :class:`StoppedVehicleRescuer` (``max_shift``).

    With a detector and no ``min_pixels`` in the settings, a template needs half the
    detector's ``min_area`` in object pixels (20 px at 320×240, 115 px at 768×576 with the
    size-dependent defaults): the bank's fixed 50 px dropped the templates of two-tone vehicles
    whose blob covers only one tone (two of the ten waiting vehicles of five ``intersection``
    runs lost their track).
    """
    from mvtrack.detection.template import TemplateBank, TemplateRescuer

    params = dict(settings.template_params)
    min_area = getattr(getattr(detector, "blobs", None), "min_area", None)
    if min_area and "min_pixels" not in params:
        params["min_pixels"] = max(round(0.5 * min_area), 1)
    max_shift = params.pop("max_shift", StoppedVehicleRescuer.MAX_SHIFT)
    try:
        bank = TemplateBank(**params)
        guard = StoppedVehicleRescuer(None, tracker, max_shift)
    except TypeError as exc:
        raise InputError(f"template settings: {exc}") from None
    # matches farther than max_shift are refused: the NCC need not look beyond it
    guard.inner = TemplateRescuer(bank, tracker, detector=detector, max_radius=guard.max_shift)
    return guard


class StoppedVehicleRescuer:
    """Template matching restricted to what a stopped vehicle looks like.

    Paper 1 uses template matching for one case: a vehicle that *stopped* and faded into the
    disturbance-map background (SPEC §1.1 step 3). A bare NCC search also "finds" other things,
    and a track held that way never ends:

    - a track that never moved (a ghost blob where a parked vehicle left, a pole flickering
      under camera jitter) has a template of static scenery, which matches forever — the
      template bank searches only tracks that have driven somewhere
      (:class:`~mvtrack.detection.template.TemplateBank`, ``min_travel``);
    - a duplicate track (two blobs of one two-tone vehicle) whose detection went to its twin
      follows the moving vehicle by template, frame after frame.

    So the search is centred on the track's last measured position, a match is accepted only
    if it lies within ``max_shift`` px of it (a stopped vehicle stands where it was last seen),
    and no detection of this frame covers the match (a detected object has not faded). All
    checks are array operations over the missed tracks.

    Parameters
    ----------
    inner : TemplateRescuer
        The NCC search (:mod:`mvtrack.detection.template`).
    tracker : mvtrack.tracking.Tracker
        Its ``tracks`` table gives each uid's last measurement.
    max_shift : float
        Largest distance (px) between the match and the last measured position.
    """

    #: default ``max_shift`` in px
    MAX_SHIFT = 4.0

    def __init__(self, inner: Any, tracker: Any, max_shift: float = MAX_SHIFT) -> None:
        if not max_shift > 0:
            raise InputError(f"template settings: max_shift must be > 0, got {max_shift}")
        self.inner = inner
        self.tracker = tracker
        self.max_shift = float(max_shift)

    def callback(self, image: Image, dets: Detections) -> RescueFn:
        """``rescue(uids, predicted_xy, wh) -> (found, xy)`` for this frame."""
        tab = self.tracker.tracks

        def rescue(uids: Any, predicted_xy: Any, wh: Any) -> tuple[Any, Any]:
            search = self.inner.callback(image)  # only on frames with missed tracks
            uids = np.asarray(uids, np.int64).reshape(-1)
            # a stopped vehicle stands where it was last measured: search around that place,
            # not around the prediction, which keeps drifting with the last velocity estimate
            order = np.argsort(tab.uid)
            at = order[np.searchsorted(tab.uid[order], uids)]
            last = tab.last_xy[at]
            f_sub, xy_sub = search(uids, last, wh)
            found = np.array(f_sub, bool)
            xy = np.array(xy_sub, np.float64)
            if not found.any():
                return found, xy
            # the match must sit where the vehicle was last measured (it stands still)
            d = xy - last
            found &= np.hypot(d[:, 0], d[:, 1]) <= self.max_shift
            # and no detection may cover it (a detected object has not faded)
            if len(dets) and found.any():
                lo, hi = dets.xy - dets.wh / 2, dets.xy + dets.wh / 2
                inside = ((xy[:, None, :] >= lo[None]) & (xy[:, None, :] <= hi[None])).all(2)
                found &= ~inside.any(axis=1)
            xy[~found] = np.nan
            return found, xy

        return rescue

    def observe(self, image: Image, dets: Detections, tracks: TrackFrame) -> None:
        """Feed the template bank."""
        self.inner.observe(image, dets, tracks)


# --------------------------------------------------------------------------- gate overlay


def next_gates(
    tracker: Any, next_k: int
) -> tuple[NDArray[np.int64], FloatArray, FloatArray, FloatArray]:
    """The gates that the next frame's detections must fall in, for the confirmed tracks.

    The tracker's current predictor state is advanced one frame (a pure function of the
    state; the tracker is not changed) and turned into the region of the configured distance
    (:func:`mvtrack.viz.annotate.gate_shapes`). Under paper 1's warm-up the gate centre is
    ``2 y_k − y_{k−1}`` (SPEC §1.1 [R]) as in the tracker.

    Parameters
    ----------
    tracker : mvtrack.tracking.Tracker
        The tracker after its step for frame ``next_k − 1``.
    next_k : int
        The tracker's step number of the next frame (frames are counted from 0).

    Returns
    -------
    track_id : (K,) int64
        Public IDs of the tracks (tentative tracks are left out).
    center : (K, 2)
        Gate centres.
    shape : (K, 2, 2)
        Shape matrices ``C`` of ``(z − c)ᵀ C⁻¹ (z − c) ≤ r²``.
    r2 : (K,)
        Gate thresholds.
    """
    from mvtrack.association.distances import get_distance
    from mvtrack.viz.annotate import gate_shapes

    tab = tracker.tracks
    keep = np.asarray(tab.track_id) > 0
    if not keep.any():
        z = np.zeros(0)
        return z.astype(np.int64), z.reshape(0, 2), z.reshape(0, 2, 2), z
    from mvtrack import _batch

    pred = tracker.predictor
    ps = pred.predict(_batch.take(tracker.pstate, keep))
    xy = pred.position(ps)
    config = tracker.config
    fp = config.frames()
    if fp.warmup_hits:
        warm = tab.hits[keep] < fp.warmup_hits
        last, prev = tab.last_xy[keep], tab.prev_xy[keep]
        span = np.maximum(tab.last_k[keep] - tab.prev_k[keep], 1)[:, None]
        gap = (next_k - tab.last_k[keep])[:, None]
        centre = last + (last - prev) * (gap / span)  # 2 y_k − y_{k−1}, SPEC §1.1 [R]
        xy = np.where(warm[:, None], centre, xy)
    dist = get_distance(config.distance)
    gate = dist.gate if config.gate is None else float(config.gate)
    params = {k: v for k, v in dict(getattr(config, "distance_params", {})).items()
              if k in ("rho", "min_speed", "use_innovation")}
    center, shape, r2 = gate_shapes(
        config.distance, xy, pred.position_cov(ps), pred.innovation_cov(ps), pred.velocity(ps),
        gate, **params,
    )
    return np.asarray(tab.track_id)[keep], center, shape, r2


def second_gates(tracker: Any, next_k: int) -> tuple[FloatArray, FloatArray] | None:
    """The second association stage's circles for the next frame, or None without one.

    Tracks the first stage leaves unmatched may take a leftover detection within
    ``config.second_gate`` px of the same gate centre (gated global nearest neighbour, see
    :class:`~mvtrack.tracking.Tracker`). Returns the centres (K, 2) and radii² (K,) for the
    confirmed tracks, in the order of :func:`next_gates`. (The recovery stage, around the last
    measurement of established tracks, is not drawn.)
    """
    radius = getattr(tracker.config, "second_gate", None)
    if radius is None:
        return None
    _, center, _, _ = next_gates(tracker, next_k)
    return center, np.full(center.shape[0], float(radius) ** 2)


# --------------------------------------------------------------------------- whole runs


@dataclass
class RunOutput:
    """A finished run: the loop's result, the files written and the summary."""

    result: PipelineResult
    log: Any  # mvtrack.tracking.TrackLog
    summary: dict[str, Any]
    paths: dict[str, Path]


def _track_lengths(log: Any) -> NDArray[np.int64]:
    ids = log.columns()["track_id"]
    ids = ids[ids > 0]
    return np.unique(ids, return_counts=True)[1] if ids.size else np.zeros(0, dtype=np.int64)


def track_to_folder(
    frames: Iterable[Image],
    *,
    fps: float,
    size: tuple[int, int],
    settings: RunSettings,
    out: str | os.PathLike[str],
    max_frames: int | None = None,
    total: int | None = None,
    source: str = "",
    progress: bool | None = None,
    parts: tuple[Any, Any] | None = None,
    source_error: Callable[[], str | None] | None = None,
    snapshot: int | None = None,
) -> RunOutput:
    """Track ``frames`` and write everything into the folder ``out``.

    Files (each written atomically; a failure leaves no partial file):

    - ``results.txt`` — MOTChallenge results (frame, id, left, top, w, h, conf, -1, -1, -1)
      of the rows with a measurement (confirmed, or stopped and held by template matching);
      coasting predictions are drawn in the video but not written;
    - ``tracks.mp4`` — the annotated video (unless ``settings.video`` is False): boxes in
      their state colour, IDs, trails and the predicted gates (ellipse or circle);
    - ``trajectories.png`` — every track's path over the first frame;
    - ``summary.json`` — frames, tracks, states histogram, speed, settings, ``ended_early``;
    - ``frameNNNNN.png`` — one annotated frame, if ``snapshot`` is given.

    Ctrl-C during the loop ends it early; the files are still written for the frames
    processed (``summary["interrupted"]``).

    Parameters
    ----------
    frames : iterable of (H, W, 3) uint8
        The video.
    fps : float
        Frame rate of the video (converts the tracker's time-based parameters).
    size : (W, H)
        Frame size.
    settings : RunSettings
        Detector, tracker and output settings.
    out : path
        Output folder (created).
    max_frames : int, optional
        Stop after this many frames.
    total : int, optional
        Expected number of frames, for the progress bar.
    source : str
        Name of the video, for the summary.
    progress : bool, optional
        Force the progress bar on or off.
    parts : (detector, tracker), optional
        Ready-made parts instead of building them from ``settings``.
    source_error : callable, optional
        Asked after the loop why the source ended early (e.g. ``lambda: src.error`` of a
        :class:`~mvtrack.io.video.FrameSource`); its answer goes to ``result.error``.
    snapshot : int, optional
        Also save the annotated frame with this index as ``frameNNNNN.png`` (lossless), with or
        without the video.
    """
    import cv2

    from mvtrack.io.atomic import atomic_path, write_json
    from mvtrack.tracking import TrackLog
    from mvtrack.viz.annotate import TrailBuffer, annotate_frame
    from mvtrack.viz.plots import TrackRows, save_figure, trajectory_figure

    if parts is None:
        settings = resolve_settings(settings, size)
        detector, tracker = build_detector(settings), build_tracker(settings, fps)
    else:
        detector, tracker = parts
    rescuer = build_rescuer(settings, tracker, detector) if settings.templates else None
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths: dict[str, Path] = {}
    log = TrackLog()
    background: list[Image] = []
    config = tracker.config
    label = f"{config.predictor} | {config.distance} | {config.assign}"

    with contextlib.ExitStack() as stack:
        writer = None
        if settings.video:
            dest = out / "tracks.mp4"
            tmp = stack.enter_context(atomic_path(dest))
            writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
            if not writer.isOpened():
                raise OSError(f"cannot write video {dest} (OpenCV has no MPEG-4 encoder)")
            stack.callback(writer.release)  # runs before atomic_path renames the file
            paths["video"] = dest
        trails = TrailBuffer(settings.trail)

        def on_frame(k: int, image: Image, dets: Detections, tracks: TrackFrame) -> None:
            log.append(tracks)
            if k == 0:
                background.append(image.copy())
            shot = snapshot is not None and k == snapshot
            if writer is None and snapshot is None:
                return
            trails.push(tracks)
            if writer is None and not shot:
                return
            gates: dict[str, Any] = {}
            if settings.gates:
                _, center, shape, r2 = next_gates(tracker, k + 1)
                gates = {"gate_center": center, "gate_cov": shape, "gate_r2": r2}
                outer = second_gates(tracker, k + 1)
                if outer is not None:
                    gates["outer_r2"] = outer[1]
            text = [f"frame {k}  tracks {len(tracks)}", label]
            img = annotate_frame(image, tracks, trails=trails, text=text, **gates)
            if writer is not None:
                writer.write(img)
            if shot:
                dest = out / f"frame{k:05d}.png"
                with atomic_path(dest) as tmp_png:
                    if not cv2.imwrite(str(tmp_png), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
                        raise OSError(f"cannot write {dest}")
                paths["snapshot"] = dest

        result = run_frames(
            frames, detector, tracker, rescuer=rescuer, max_frames=max_frames,
            on_frame=on_frame, total=total, progress=progress,
        )
        if result.error is None and source_error is not None and not result.interrupted:
            result.error = source_error()

    paths["results"] = out / "results.txt"
    log.write_mot(paths["results"], include_coasting=False)
    rows = TrackRows.from_frames(log)
    lengths = _track_lengths(log)
    name = Path(source).name if source else "video"
    fig = trajectory_figure(
        rows, size, background[0] if background else None,
        title=f"{name}: {len(lengths)} tracks ({label})",
    )
    paths["trajectories"] = out / "trajectories.png"
    save_figure(fig, paths["trajectories"])
    summary = {
        "source": source,
        "frames": result.n_frames,
        "video_fps": fps,
        "size": list(size),
        "tracks": len(lengths),
        "track_length_frames": {
            "median": float(np.median(lengths)) if lengths.size else 0.0,
            "max": int(lengths.max()) if lengths.size else 0,
        },
        "detections": result.n_detections,
        "states": rows.state_histogram(),
        "fps": round(result.fps, 2) if result.n_frames else None,
        "seconds": round(result.seconds, 3),
        "ended_early": result.ended_early,
        "interrupted": result.interrupted,
        "error": result.error,
        "settings": settings.as_dict(),
        "tracker": _config_dict(config),
        "files": {k: v.name for k, v in paths.items()},
    }
    paths["summary"] = out / "summary.json"
    summary["files"]["summary"] = "summary.json"
    write_json(paths["summary"], summary)
    return RunOutput(result, log, summary, paths)


def _config_dict(config: Any) -> dict[str, Any]:
    out = {}
    for f in dataclasses.fields(config):
        value = getattr(config, f.name)
        out[f.name] = dict(value) if isinstance(value, Mapping) else value
    return out


def track_video(
    video: str | int,
    out: str | os.PathLike[str],
    settings: RunSettings,
    *,
    fps: float | None = None,
    max_frames: int | None = None,
    progress: bool | None = None,
    snapshot: int | None = None,
) -> RunOutput:
    """Open ``video``, build its parts for its size and frame rate, and :func:`track_to_folder`.

    What ``mvtrack track`` and each job of ``mvtrack batch`` run. Everything that can be wrong
    with the source or the settings fails before any file is written.

    Parameters
    ----------
    video : str or int
        Video file, image folder, camera index or stream URL (see
        :func:`mvtrack.io.video.open_source`).
    out : path
        Output folder.
    settings : RunSettings
        Settings as the user gave them; the size-dependent defaults are filled in here
        (:func:`resolve_settings`).
    fps : float, optional
        Frame rate to assume instead of the source's.
    max_frames, progress, snapshot
        As in :func:`track_to_folder`.

    Raises
    ------
    InputError
        Missing, unreadable or empty source; bad settings.
    """
    from mvtrack.io.video import open_source

    src = open_source(video, fps=fps)
    with src:
        resolved = resolve_settings(settings, src.size)
        parts = (build_detector(resolved), build_tracker(resolved, src.fps))
        return track_to_folder(
            (frame for _, frame in src), fps=src.fps, size=src.size, settings=resolved,
            out=out, max_frames=max_frames, total=src.frame_count, source=str(video),
            progress=progress, parts=parts, source_error=lambda: src.error, snapshot=snapshot,
        )
