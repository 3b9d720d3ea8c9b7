"""Tracker configuration in physical units (the presets are :mod:`mvtrack.tracking.presets`).

Every life-cycle parameter that depends on the frame rate is given in seconds or pixels per
second, and :meth:`TrackerConfig.frames` converts it with ``fps``; the same configuration
therefore behaves the same at 10 and at 30 fps (up to rounding to whole frames).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from mvtrack.registry import ASSIGN_RULES
from mvtrack.tracking.scores import check_scale


class Frames(int):
    """A duration counted in frames, for the rules that the papers state in frames (paper 1:
    "a track ends after 3 frames without a detection"): ``max_coast=Frames(3)`` is 3 frames at
    any frame rate, where a number is seconds."""

    def __repr__(self) -> str:
        return f"Frames({int(self)})"

    def __str__(self) -> str:
        return f"{int(self)} frames"


def in_frames(value: float, fps: float) -> int:
    """A duration in frames: :class:`Frames` as given, seconds × ``fps`` rounded."""
    return int(value) if isinstance(value, Frames) else _round(value * fps)


@dataclass(frozen=True)
class FrameParams:
    """The life-cycle parameters of a :class:`TrackerConfig` converted to frames."""

    confirm_hits: int  #: associations needed to confirm a track
    confirm_window: int  #: frames (from birth) within which the hits must come
    max_misses: int  #: consecutive frames a confirmed track may coast; deleted on the next
    tentative_max_misses: int  #: consecutive misses a tentative track survives
    warmup_hits: int  #: associations during which the paper-1 gate centre is used (0 = off)
    r: float | None  #: measurement variance, px²
    init_velocity_std: float | None  #: prior std of the velocity of a new track, px/frame
    accel_std: float | None  #: white-acceleration std, px/frame² (None = predictor default)
    recover_speed: float | None  #: recovery radius growth, px/frame (None = no recovery)
    recover_window: int  #: frames since the last measurement within which recovery is tried
    coast_output: int | None  #: consecutive misses up to which coasting rows are output


@dataclass(frozen=True)
class TrackerConfig:
    """Everything the :class:`~mvtrack.tracking.Tracker` needs, in physical units.

    Attributes
    ----------
    predictor : str
        Predictor name for :func:`mvtrack.filters.predictors.make_predictor`
        (``kalman-ca``, ``kalman-cv``, ``kalman-coupled``, ``rls``).
    predictor_params : mapping
        Extra keyword arguments of the predictor, in frame units (e.g. ``r`` in px²).
    distance : str
        Association distance by name (``euclidean``, ``uncoupled``, ``coupled``,
        ``coupled-literal``, ``mahalanobis``, ``iou``).
    distance_params : mapping
        Extra keyword arguments of the distance (e.g. ``rho`` for ``coupled``).
    assign : str
        Assignment rule: ``nearest`` (non-exclusive, the papers), ``greedy`` (exclusive
        nearest) or ``optimal`` (global, per cluster of the gate graph).
    assign_params : mapping
        Extra keyword arguments of :func:`mvtrack.association.assign` (e.g.
        ``unmatched_cost`` for ``optimal``).
    gate : float or None
        Gate on the distance's squared value (px² for ``euclidean``, χ² for Mahalanobis-type
        distances, 1 − IoU for ``iou``); ``None`` (the default) uses the distance's default
        gate, :data:`mvtrack.registry.DISTANCES` (100 px², a 10 px circle, for the default
        ``euclidean``), resolved by :func:`mvtrack.association.resolve_gate`.
    fps : float
        Frame rate of the input, used to convert the time-based parameters below.
    confirm_hits : int
        A tentative track is confirmed (and gets a public ID) on its ``confirm_hits``-th
        association, if that comes within ``confirm_window`` seconds of its birth.
    confirm_window : float or None
        Seconds; ``None`` means ``confirm_hits`` frames (consecutive hits required).
    max_coast : float or Frames
        Seconds (or :class:`Frames`) a confirmed track may coast (no detection) before it is
        deleted.
    tentative_max_coast : float
        Seconds a tentative track may go without detection before it is deleted (0: the first
        miss deletes it).
    measurement_std : float or None
        Std of the detection centres in pixels; the predictors' ``r = measurement_std²``
        (None: the predictor's default). ``predictor_params["r"]`` wins over it.
    init_velocity_std : float or None
        Prior std of a new track's velocity, px/s; the predictors' ``vel_var =
        (init_velocity_std / fps)²`` (None: the predictor's default).
    accel_std : float or None
        White-acceleration std of the constant-velocity models (``kalman-cv``,
        ``kalman-coupled``), px/s²; converted to ``q = (accel_std / fps²)²`` in px²/frame⁴
        (None: the predictor's default). ``kalman-ca`` and ``rls`` take their own ``q`` /
        parameters through ``predictor_params``.
    second_gate : float or None
        Pixels. A second association stage: tracks left unmatched by the first (the
        configured distance and gate) may take a detection left unassigned within this
        Euclidean radius of their prediction (gated global nearest neighbour); ``None``
        disables it. A tight first gate plus a wide second one keeps the assignment
        problems small in dense scenes and still follows manoeuvring targets.
    recover_speed : float or None
        Px/s. Second association stage for confirmed tracks that found no detection inside
        their gate: such a track may take an unassigned detection within
        ``recover_speed × (time since its last measurement) + recover_margin`` of its *last
        measurement* (not of the prediction), so a target that turned sharply (or bounced) is
        re-acquired with its ID instead of being born again; its predictor restarts at that
        detection (zero velocity, the ``init_velocity_std`` prior). ``None`` disables it.
    recover_margin : float
        Pixels added to the recovery radius (measurement noise).
    stopped_margin : float or None
        Pixels. A track held by template matching in the previous frame (``STOPPED``: a
        standing vehicle that faded into the background) takes a detection only within half
        its box's longer side plus this margin of where it stands (its last measurement), not
        anywhere in its gate: a vehicle passing close by does not carry it off, while the
        vehicle's own blob (its fragments, or its body when it drives on) stays within reach.
        Not in paper 1; ``None`` (the default) disables it. The ``paper1`` preset sets 4 px: its
        non-exclusive nearest rule lets a passing vehicle take a standing vehicle's track
        (X5); with the default's exclusive assignment it costs IDs on the stop-and-go queue,
        where a vehicle that drives on leaves a ghost at the place it stood.
    recover_window : float
        Seconds since the last measurement after which a track can no longer be recovered
        (so clutter far away cannot keep a lost track alive).
    recover_min_hits : int
        Associations a track needs before it can be recovered (established tracks only).
    warmup : bool
        Paper 1's warm-up (SPEC §1.1 [R]): until a track has ``warmup_hits`` associations its
        gate centre is ``2 y_k − y_{k−1}`` (``y_k`` after one association), whatever the
        predictor says.
    warmup_hits : int
        ``2M = 6`` in paper 1.
    output_tentative : bool
        Also output tentative tracks (with ``track_id == -1``).
    size_smoothing : float
        Weight in (0, 1] of a new measured box size in the exponential average of ``wh``
        (1 = use the last measured size).
    size_ref : float or None
        Pixels. The pixel values above that describe the *detections* — ``measurement_std``,
        the Euclidean ``gate``, ``second_gate`` and ``recover_margin`` — hold for boxes up to
        ``size_ref`` wide and high; a track whose (smoothed) box is larger has them stretched
        with it, by ``f_x = max(1, w / size_ref)`` along x and ``f_y = max(1, h / size_ref)``
        along y: the Euclidean gates become ellipses ``Δx²/f_x² + Δy²/f_y² <= gate``, the
        measurement variance ``r max(f_x, f_y)²`` and the recovery margin ``max(f_x, f_y)``
        times its value. A detector whose error grows with the box (5 % of a 180 px tall
        person is 9 px) then meets a gate and a noise model of the same relative size, as
        the box-height-proportional noise of DeepSORT; the one isotropic variance per track
        follows the larger factor so that it covers the noisier axis (a person's height).
        The motion parameters (``accel_std``, ``init_velocity_std``, ``recover_speed``) are
        not scaled. The noise is scaled only with the closed-form ``kalman-cv``, the gates
        only for ``euclidean`` (and ``mahalanobis`` through the scaled noise). ``None``
        disables the scaling.
    size_weight : float
        In [0, 1). With the ``euclidean`` distance, the assignment cost of a gated pair is
        ``Δxᵀ F⁻² Δx + size_weight · min(Δwᵀ F⁻² Δw, gate)``: the squared position
        difference plus the weighted squared difference of the box sizes (``Δw`` = detection
        w, h − the track's smoothed w, h; ``F = diag(f_x, f_y)`` the size factors of
        ``size_ref``), capped at the gate. The gate itself stays on the position; the size
        term only ranks competing pairs, as the box overlap does for IoU association (two
        people side by side at different depths differ in height). Below 1, a gated pair
        always costs less than leaving its track and detection unmatched. 0 disables it.
    coast_output : float or None
        Seconds. Rows of a coasting track are output only for its first ``coast_output``
        seconds without a detection; it stays alive (and can be associated again) for
        ``max_coast``. A short gap is usually a missed detection of a target still there,
        a long one more often a target that has left; ``None`` outputs every coasting row.
    size_gate : float or None
        A ratio > 1. With the ``euclidean`` distance (every association stage, recovery
        included), a track and a detection whose box heights differ by more than this factor
        (``h_d > ρ h_t`` or ``h_t > ρ h_d``; ``wh`` of the track the smoothed one), or widths
        by more than its square, are never paired, however close: a box twice or half the
        size is another object (a person nearer or farther away, or a different one), the
        consistency that the overlap enforces in IoU association. The width, which changes
        with a walker's stride or a vehicle's turn, is gated more loosely
        (:func:`mvtrack.association.discs.size_apart`). ``None`` disables it.
        Default 1.5, for a detector's boxes: the leave-one-sequence-out choice on the MOT15
        development sequences among the gates that leave the noisy-ground-truth benchmark as
        it was (1.4 costs it; ``docs/bench/mot15-defaults.md``), where a
        track that may not jump to a box of another scale is also one the relinking can join
        up; the video pipeline turns it off for the disturbance map's blobs, which merge and
        split (:func:`mvtrack.video.resolve_settings`).
    partial_tolerance : float or None
        A fraction of the track's box height. The size gate still pairs a track with a
        detection box smaller than its own when the box stands where the track stands: its
        bottom edge within this fraction of the track's height of the track's, and inside the
        track's box along x (widened by the same fraction) — the visible part of a partly
        hidden person, e.g. a detector firing on the legs below an occluder
        (:func:`mvtrack.association.discs.partial_views`). Such a detection measures the foot
        point only: the track is updated at ``(x_d, y_d + h_d/2 − h_t/2)``, the centre of its
        own box standing on the detection's bottom edge, and keeps its box size. ``None``: the
        size gate refuses every such box. Default 0.15, chosen by leave-one-sequence-out on
        the MOT15 development sequences (``docs/bench/mot15-defaults.md``).
    min_track_length : float or None
        Seconds. Offline runs only (:func:`~mvtrack.tracking.track_detections`): a track with
        fewer output rows than this many seconds of frames is left out whole
        (:func:`mvtrack.tracking.log.drop_short_tracks`). ``None`` keeps every track.
    score_scale : {"auto", "prob"} or (lo, hi)
        How detection scores are read (:mod:`mvtrack.tracking.scores`): ``"auto"`` ranks each
        score among those of the run so far (offline: of the whole file), so thresholds work
        on any detector's scale; ``"prob"`` takes them as probabilities; ``(lo, hi)`` maps
        ``lo … hi`` linearly onto 0 … 1. ``score_high`` and ``min_score`` are on this
        calibrated scale.
    score_high : float or None
        Calibrated score in [0, 1] from which a detection is *high*: only high detections are
        matched in the first stages and start tracks; the others (*low*) are offered only to
        the established tracks left unmatched, in a last stage with the first stage's
        distance and gate, so a track lives on through a partial occlusion without clutter
        starting tracks (the association of ByteTrack). ``None``: every detection is high.
    min_score : float
        Calibrated score in [0, 1] below which a detection is dropped before association.
    nms_iou : float or None
        Within a frame, a detection that overlaps a higher-scored one by at least this IoU is
        dropped before association (duplicate suppression); ``None`` disables it.
    low_birth_iou : float or None
        A low detection (``score_high``) left unassigned by every stage that overlaps no live
        track's predicted box, no high detection and no better-scored such low detection by
        this IoU or more starts a *tentative* track too. A tentative track is matched only in
        the high stages, so it is confirmed (and output) only if a high detection joins it in
        the next frame: a low box alone still never makes a track, while a person detected
        weakly on one frame and well on the next is tracked from the weak box on. The second
        boxes on an already-detected person and clutter beside people, which the low half of a
        detector's boxes mostly is, overlap a track or a high box and start nothing. ``None``
        (ByteTrack's rule): only high detections start tracks. Default 0.1, chosen by
        leave-one-sequence-out on the MOT15 development sequences
        (``docs/bench/mot15-defaults.md``).
    low_tentative : bool
        The low-score stage also serves tentative tracks, so a track born from an isolated
        low box (``low_birth_iou``) can be confirmed by a second low box: a person whom the
        detector scores low on consecutive frames is tracked, but so is a persistent low-score
        false detection that overlaps nothing, which ByteTrack's rule (and the default,
        ``False``) never lets make a track. Measured beside the default in
        ``docs/bench/mot15-defaults.md``.
    frame_size : (float, float) or None
        Width and height of the image, pixels. A track that got no detection and whose
        prediction has left the image (``x ∉ [0, W)`` or ``y ∉ [0, H)``) ends at once: the
        object has left the view, and a track that coasts on past the edge would take the next
        object that enters there (X5: a vehicle leaving eastward and one entering westward at
        the same edge). ``None`` (the default, a tracker that does not know the image) keeps the
        coasting rule alone; the video pipeline sets it for the ``default`` preset
        (:func:`mvtrack.video.resolve_settings`).
    relink_window : float or None
        Seconds. A track confirmed within this time after a confirmed track was deleted, where
        that track's last measurement and velocity put it now (within ``relink_reach`` times
        the shorter side of the two boxes) and of a similar height, takes its public ID
        (:mod:`mvtrack.tracking.relink`): a person lost for longer than ``max_coast`` keeps the
        identity. ``None`` disables it; the paper presets and the video pipeline do (the video
        loop relinks with appearance as well, :mod:`mvtrack.video.relink`). Default 3 s and
        ``relink_reach`` 1, chosen by leave-one-sequence-out on the MOT15 development sequences
        among the settings that leave the noisy-ground-truth benchmark as it was
        (``docs/bench/mot15-defaults.md``).
    relink_reach : float
        The radius of that test in units of the shorter box side (two people side by side are
        about one body width apart).
    backfill : bool
        Offline runs only (:func:`~mvtrack.tracking.track_detections`): once a track is
        confirmed, the rows of its tentative frames — from its first detection on — are
        written too, with its public ID; tracks never confirmed leave no rows. An online
        :meth:`Tracker.step` cannot change frames it has already returned and ignores it.
    """

    predictor: str = "kalman-cv"
    predictor_params: Mapping[str, Any] = field(default_factory=dict)
    distance: str = "euclidean"
    distance_params: Mapping[str, Any] = field(default_factory=dict)
    assign: str = "optimal"
    assign_params: Mapping[str, Any] = field(default_factory=dict)
    gate: float | None = None
    fps: float = 30.0
    confirm_hits: int = 2
    confirm_window: float | None = None
    max_coast: float = 0.3
    tentative_max_coast: float = 0.0
    measurement_std: float | None = 2.0
    init_velocity_std: float | None = 150.0
    accel_std: float | None = 200.0
    second_gate: float | None = 20.0
    recover_speed: float | None = 250.0
    recover_margin: float = 6.0
    recover_window: float = 0.3
    recover_min_hits: int = 5
    stopped_margin: float | None = None
    warmup: bool = False
    warmup_hits: int = 6
    output_tentative: bool = False
    size_smoothing: float = 0.5
    size_ref: float | None = 50.0
    coast_output: float | None = 0.08
    size_weight: float = 0.5
    size_gate: float | None = 1.5
    partial_tolerance: float | None = 0.15
    backfill: bool = True
    interpolate: bool = True
    min_track_length: float | None = 0.3
    score_scale: str | tuple[float, float] = "auto"
    score_high: float | None = 0.5
    min_score: float = 0.2
    nms_iou: float | None = None
    low_birth_iou: float | None = 0.1
    low_tentative: bool = False
    frame_size: tuple[float, float] | None = None
    relink_window: float | None = 3.0
    relink_reach: float = 1.0

    def __post_init__(self) -> None:
        def bad(name: str, why: str) -> ValueError:
            return ValueError(f"TrackerConfig.{name} {why} (got {getattr(self, name)!r})")

        for name in ("predictor", "distance", "assign"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name):
                raise bad(name, "must be a non-empty name")
        if self.assign not in ASSIGN_RULES:
            raise bad("assign", f"must be one of {', '.join(ASSIGN_RULES)}")
        if not _finite_positive(self.fps):
            raise bad("fps", "must be a finite number > 0")
        if self.gate is not None and not _finite_positive(self.gate):
            raise bad("gate", "must be a finite number > 0 or None")
        if self.distance == "iou" and self.gate is not None and self.gate > 1.0:
            raise bad("gate", "is a cost 1 − IoU for distance 'iou' and must be <= 1 "
                      "(gate=None gives its default)")
        if not isinstance(self.confirm_hits, int) or self.confirm_hits < 1:
            raise bad("confirm_hits", "must be an integer >= 1")
        if self.confirm_window is not None and not _finite_positive(self.confirm_window):
            raise bad("confirm_window", "must be a finite number of seconds > 0 or None")
        if self.coast_output is not None and not (
            isinstance(self.coast_output, (int, float)) and math.isfinite(self.coast_output)
            and self.coast_output >= 0
        ):
            raise bad("coast_output", "must be a finite number of seconds >= 0 or None")
        g = self.size_gate
        if g is not None and not (
            isinstance(g, (int, float)) and math.isfinite(g) and g > 1.0
        ):
            raise bad("size_gate", "must be a finite ratio > 1 or None")
        p = self.partial_tolerance
        if p is not None and not (
            isinstance(p, (int, float)) and math.isfinite(p) and 0.0 <= p < 1.0
        ):
            raise bad("partial_tolerance", "must be a fraction in [0, 1) or None")
        for name in ("backfill", "interpolate", "low_tentative"):
            if not isinstance(getattr(self, name), bool):
                raise bad(name, "must be True or False")
        w = self.size_weight
        if not isinstance(w, (int, float)) or not (0.0 <= w < 1.0):
            raise bad("size_weight", "must be a number in [0, 1)")
        for name in ("max_coast", "tentative_max_coast"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise bad(name, "must be a finite number of seconds (or Frames) >= 0")
        m = self.recover_margin
        if not isinstance(m, (int, float)) or not math.isfinite(m) or m < 0:
            raise bad("recover_margin", "must be a finite number of pixels >= 0")
        m = self.stopped_margin
        if m is not None and (not isinstance(m, (int, float)) or not math.isfinite(m) or m < 0):
            raise bad("stopped_margin", "must be a finite number of pixels >= 0 or None")
        if not isinstance(self.recover_min_hits, int) or self.recover_min_hits < 1:
            raise bad("recover_min_hits", "must be an integer >= 1")
        if not _finite_positive(self.recover_window):
            raise bad("recover_window", "must be a finite number of seconds > 0")
        for name in (
            "measurement_std", "init_velocity_std", "accel_std", "recover_speed", "second_gate",
            "size_ref",
        ):
            value = getattr(self, name)
            if value is not None and not _finite_positive(value):
                raise bad(name, "must be a finite number > 0 or None")
        if not isinstance(self.warmup_hits, int) or self.warmup_hits < 2:
            raise bad("warmup_hits", "must be an integer >= 2")
        s = self.size_smoothing
        if not isinstance(s, (int, float)) or not (0.0 < s <= 1.0):
            raise bad("size_smoothing", "must be in (0, 1]")
        try:
            check_scale(self.score_scale)
        except ValueError as exc:
            raise bad("score_scale", str(exc)) from None
        mtl = self.min_track_length
        if mtl is not None and not (
            isinstance(mtl, (int, float)) and math.isfinite(mtl) and mtl >= 0
        ):
            raise bad("min_track_length", "must be a finite number of seconds >= 0 or None")
        for name in ("score_high", "min_score", "nms_iou", "low_birth_iou"):
            v = getattr(self, name)
            if v is None and name != "min_score":
                continue
            if not isinstance(v, (int, float)) or not (0.0 <= v <= 1.0):
                tail = "" if name == "min_score" else " or None"
                raise bad(name, f"must be a number in [0, 1]{tail}")
        for name in ("nms_iou", "low_birth_iou"):
            v = getattr(self, name)
            if v is not None and v <= 0:
                raise bad(name, "must be > 0 or None")
        rw = self.relink_window
        if rw is not None and not _finite_positive(rw):
            raise bad("relink_window", "must be a finite number of seconds > 0 or None")
        if not _finite_positive(self.relink_reach):
            raise bad("relink_reach", "must be a finite number > 0")
        fs = self.frame_size
        if fs is not None:
            if not (isinstance(fs, (tuple, list)) and len(fs) == 2
                    and all(_finite_positive(v) for v in fs)):
                raise bad("frame_size", "must be (width, height) in pixels, both > 0, or None")
            object.__setattr__(self, "frame_size", (float(fs[0]), float(fs[1])))
        for name in ("predictor_params", "distance_params", "assign_params"):
            if not isinstance(getattr(self, name), Mapping):
                raise bad(name, "must be a mapping of keyword arguments")

    def frames(self) -> FrameParams:
        """The life-cycle parameters converted to frames with ``fps``."""
        fps = float(self.fps)
        window = (
            self.confirm_hits
            if self.confirm_window is None
            else max(self.confirm_hits, _round(self.confirm_window * fps))
        )
        return FrameParams(
            confirm_hits=self.confirm_hits,
            confirm_window=window,
            max_misses=in_frames(self.max_coast, fps),
            tentative_max_misses=_round(self.tentative_max_coast * fps),
            warmup_hits=self.warmup_hits if self.warmup else 0,
            r=None if self.measurement_std is None else self.measurement_std**2,
            init_velocity_std=(
                None if self.init_velocity_std is None else self.init_velocity_std / fps
            ),
            accel_std=None if self.accel_std is None else self.accel_std / fps**2,
            recover_speed=None if self.recover_speed is None else self.recover_speed / fps,
            recover_window=max(1, _round(self.recover_window * fps)),
            coast_output=None if self.coast_output is None else _round(self.coast_output * fps),
        )

    def replace(self, **changes: Any) -> TrackerConfig:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)


def _finite_positive(value: Any) -> bool:
    return isinstance(value, (int, float)) and math.isfinite(value) and value > 0


def _round(x: float) -> int:
    # Round half up, with a small tolerance so that 0.1 s × 30 fps gives 3, not 2.
    return math.floor(x + 0.5 + 1e-9)
