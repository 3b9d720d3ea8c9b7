"""Tracker configuration: twenty settings, each in the unit that keeps it true for any scene.

Motion and noise are in **box sizes** and **seconds** (a person 40 px tall far away and one
400 px tall near the camera move and jitter alike relative to their size; a frame rate changes
how far they move per frame, not per second); the life cycle is in **frames** (a detector
misses frames, not seconds) and in **what the filter knows** (how uncertain a prediction is
against the object's size). The table of settings with their units, defaults and reasons is
``docs/settings.md``; the presets are :mod:`mvtrack.tracking.presets`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.registry import ASSIGN_RULES
from mvtrack.tracking import lifecycle as lc
from mvtrack.tracking.scores import check_scale

FloatArray = NDArray[np.float64]

#: weight of a new detection's box size in the exponential average of a track's box
SIZE_SMOOTHING = 0.5

#: mean time an object stays steady and manoeuvres (``kalman-imm``'s switching), seconds
MODE_TIMES = (10.0, 1.0)

#: the settings a user sets (the others are the papers' presets' and offline runs')
USER_SETTINGS = (
    "predictor", "distance", "assign", "gate", "fps", "measurement_noise", "accel_noise",
    "manoeuvre_noise", "velocity_prior", "size_noise", "confirm_hits", "confirm_score",
    "min_misses", "max_misses", "lost_std", "coast_std", "score_scale", "score_high",
    "min_score", "birth_iou",
)


@dataclass(frozen=True)
class TrackerConfig:
    """Everything the :class:`~mvtrack.tracking.Tracker` needs.

    Attributes
    ----------
    predictor : str
        ``kalman-imm`` (default: a steady and a manoeuvring constant-velocity filter, mixed),
        ``kalman-cv``, ``kalman-ca``, ``kalman-coupled``, ``rls`` or ``structured``
        (:func:`mvtrack.filters.predictors.make_predictor`).
    predictor_params : mapping
        The predictor's own keyword arguments in pixels and frames (``r`` px², ``q``,
        ``vel_var``): they replace the noise below, which ``kalman-imm`` and ``kalman-cv``
        scale with each track's box.
    distance : str
        The gate (:mod:`mvtrack.association.gate`): ``mahalanobis`` (default, the filter's
        innovation covariance), ``euclidean``, ``uncoupled``, ``coupled``,
        ``coupled-literal`` or ``iou``.
    distance_params : mapping
        The distance's parameters (``rho``, ``min_speed``, ``use_innovation``).
    assign : str
        ``optimal`` (default: global nearest neighbour), ``greedy`` or ``nearest`` (the
        papers' non-exclusive rule).
    gate : float or None
        Gate on the distance's value (χ² for the Mahalanobis-type ones, px² for
        ``euclidean``, ``1 − IoU`` for ``iou``); None: the distance's default
        (:func:`mvtrack.association.resolve_gate`; 9.21, 99 % of a χ² with 2 degrees of
        freedom, for ``mahalanobis``).
    fps : float
        Frame rate of the input (converts the per-second settings to frames).
    measurement_noise : float
        Std of a detection's centre, in box sizes (along x in widths, along y in heights).
    accel_noise : float
        Std of an object's random acceleration while it moves steadily, box sizes per s².
    manoeuvre_noise : float
        The same while it manoeuvres (turns, brakes, starts), for ``kalman-imm``.
    velocity_prior : float
        Std of a new object's velocity, box sizes per s: how far the first gate of a new track
        opens (its velocity is not known yet).
    size_noise : float or None
        Std of the log ratio of an object's box size from one detection to the next: the size
        term of the gate (:mod:`mvtrack.association.gate`); None: position only.
    confirm_hits : int
        Detections in consecutive frames that confirm a tentative track.
    confirm_score : float
        The sum of their calibrated scores (:mod:`mvtrack.tracking.scores`) also needed.
    min_misses : int
        Frames a confirmed track lives through without detection whatever its uncertainty.
    max_misses : int
        Frames a confirmed track may go without detection at the most.
    lost_std : float or None
        A track without detection is lost once its predicted position is uncertain by more
        than this many box sizes (std along x in widths, along y in heights); None: only
        ``max_misses``.
    coast_std : float or None
        A coasting track's rows are written while its predicted position is certain to within
        this many box sizes; None: never; ``inf``: always.
    score_scale : {"auto", "prob"} or (lo, hi)
        How detection scores are read (:mod:`mvtrack.tracking.scores`).
    score_high : float or None
        Calibrated score from which a detection is matched in the first stage; the others are
        offered to the tracks left over (ByteTrack's two stages). None: every detection high.
    min_score : float
        Calibrated score below which a detection is dropped.
    birth_iou : float or None
        A detection left over starts a track only if its box overlaps no live track's box by
        this IoU or more. None: every one left over starts a track.
    shared_iou : float or None
        A weak box (under ``score_high``) that overlaps another track's predicted box by this
        IoU or more is shared: its centre's std widens to the offset of two such boxes,
        ``(1 − t) / (1 + t)`` box sizes (:mod:`mvtrack.association.shared`). None: off.
    warmup : int
        The papers' presets: paper 1's warm-up gate centre ``2 y_k − y_{k−1}`` until a track
        has this many associations (SPEC §1.1 [R]); 0: off.
    output_tentative : bool
        Offline runs: tentative tracks' rows are output too (``track_id`` −1), so that a track
        can be written from its first detection once it is confirmed.
    """

    predictor: str = "kalman-imm"
    predictor_params: Mapping[str, Any] = field(default_factory=dict)
    distance: str = "mahalanobis"
    distance_params: Mapping[str, Any] = field(default_factory=dict)
    assign: str = "optimal"
    gate: float | None = None
    fps: float = 30.0
    measurement_noise: float = 0.1
    accel_noise: float = 1.0
    manoeuvre_noise: float = 15.0
    velocity_prior: float = 1.5
    size_noise: float | None = 0.25
    confirm_hits: int = 2
    confirm_score: float = 1.0
    min_misses: int = 3
    max_misses: int = 10
    lost_std: float | None = 0.3
    coast_std: float | None = 0.05
    score_scale: str | tuple[float, float] = "auto"
    score_high: float | None = 0.5
    min_score: float = 0.1
    birth_iou: float | None = 0.3
    shared_iou: float | None = 0.4
    warmup: int = 0
    output_tentative: bool = False

    def __post_init__(self) -> None:
        def bad(name: str, why: str) -> ValueError:
            return ValueError(f"TrackerConfig.{name} {why} (got {getattr(self, name)!r})")

        for name in ("predictor", "distance", "assign"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name):
                raise bad(name, "must be a non-empty name")
        if self.assign not in ASSIGN_RULES:
            raise bad("assign", f"must be one of {', '.join(ASSIGN_RULES)}")
        if not _positive(self.fps):
            raise bad("fps", "must be a finite number > 0")
        if self.gate is not None and not _positive(self.gate):
            raise bad("gate", "must be a finite number > 0 or None")
        if self.distance == "iou" and self.gate is not None and self.gate > 1.0:
            raise bad("gate", "is a cost 1 − IoU for distance 'iou' and must be <= 1 "
                      "(gate=None gives its default)")
        for name in ("measurement_noise", "accel_noise", "manoeuvre_noise", "velocity_prior"):
            if not _positive(getattr(self, name)):
                raise bad(name, "must be a finite number of box sizes > 0")
        for name in ("size_noise", "lost_std"):
            v = getattr(self, name)
            if v is not None and not _positive(v):
                raise bad(name, "must be a finite number > 0 or None")
        c = self.coast_std
        if c is not None and not (_number(c) and c >= 0 and not math.isnan(c)):
            raise bad("coast_std", "must be a number >= 0 (inf: always) or None")
        for name in ("confirm_hits", "min_misses", "max_misses", "warmup"):
            v = getattr(self, name)
            low = 1 if name == "confirm_hits" else 0
            if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < low:
                raise bad(name, f"must be a whole number of frames >= {low}")
        if not (_number(self.confirm_score) and 0 <= self.confirm_score < math.inf):
            raise bad("confirm_score", "must be a finite number >= 0")
        try:
            check_scale(self.score_scale)
        except ValueError as exc:
            raise bad("score_scale", str(exc)) from None
        for name in ("score_high", "min_score", "birth_iou", "shared_iou"):
            v = getattr(self, name)
            if v is None and name != "min_score":
                continue
            if not _number(v) or not (0.0 <= v <= 1.0):
                tail = "" if name == "min_score" else " or None"
                raise bad(name, f"must be a number in [0, 1]{tail}")
        if self.birth_iou is not None and self.birth_iou <= 0:
            raise bad("birth_iou", "must be > 0 or None")
        if not isinstance(self.output_tentative, bool):
            raise bad("output_tentative", "must be True or False")
        for name in ("predictor_params", "distance_params"):
            if not isinstance(getattr(self, name), Mapping):
                raise bad(name, "must be a mapping of keyword arguments")

    def replace(self, **changes: Any) -> TrackerConfig:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    # ------------------------------------------------------------------ derived, per frame

    @property
    def scales_noise(self) -> bool:
        """Whether the noise follows each track's box (``kalman-cv`` without ``r``/``q``)."""
        return self.predictor in ("kalman-cv", "kalman-imm") and not (
            {"r", "q", "vel_var"} & set(self.predictor_params)
        )

    def noise(self, wh: FloatArray, speed2: FloatArray | None = None
              ) -> tuple[FloatArray, FloatArray]:
        """The measurement and initial velocity noise of boxes ``wh`` (K, 2) in pixels and
        frames, per axis: ``r = (σ_z wh)²`` px² and ``σ_v² (wh / fps)²`` px²/frame², ``σ_v² =
        speed2`` (per axis, (box sizes/s)²) if given, else ``velocity_prior²``."""
        f = 1.0 / float(self.fps)
        r = (self.measurement_noise * wh) ** 2
        v2 = self.velocity_prior**2 if speed2 is None else speed2
        return r, v2 * (f * wh) ** 2

    def accelerations(self, wh: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The white-acceleration variances of boxes ``wh`` (K, 2), px²/frame⁴ per axis, of
        the steady and the manoeuvring motion: ``(σ_a wh / fps²)²`` and ``(σ_m wh / fps²)²``."""
        f2 = 1.0 / float(self.fps) ** 2
        return (self.accel_noise * f2 * wh) ** 2, (self.manoeuvre_noise * f2 * wh) ** 2

    def mode_switching(self) -> tuple[float, float]:
        """``kalman-imm``'s probabilities per frame of leaving the steady and the manoeuvring
        mode, ``1 − exp(−1 / (fps τ))`` for the mean times τ of :data:`MODE_TIMES`."""
        return tuple(float(1.0 - np.exp(-1.0 / (self.fps * t))) for t in MODE_TIMES)

    def life_cycle(self, frame_size: tuple[float, float] | None = None) -> FloatArray:
        """The parameters of :func:`mvtrack.tracking.lifecycle.advance`."""
        p = np.empty(lc.N_PARAMS)
        p[lc.P_CONFIRM_HITS] = self.confirm_hits
        p[lc.P_CONFIRM_SCORE] = self.confirm_score
        p[lc.P_MAX_MISSES] = int(self.max_misses)
        p[lc.P_LOST_STD] = math.inf if self.lost_std is None else self.lost_std
        p[lc.P_COAST_STD] = -1.0 if self.coast_std is None else self.coast_std
        p[lc.P_SMOOTHING] = SIZE_SMOOTHING
        p[lc.P_TENTATIVE_ROWS] = float(self.output_tentative)
        p[lc.P_FRAME_W], p[lc.P_FRAME_H] = (-1.0, -1.0) if frame_size is None else frame_size
        p[lc.P_BIRTH_IOU] = math.inf if self.birth_iou is None else self.birth_iou
        p[lc.P_FPS] = self.fps
        p[lc.P_MIN_MISSES] = self.min_misses
        return p

    def settings(self) -> dict[str, Any]:
        """The user-facing settings as a dict (for ``summary.json`` and ``config --show``)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name in USER_SETTINGS}


def _number(v: Any) -> bool:
    return isinstance(v, int | float | np.integer | np.floating) and not isinstance(v, bool)


def _positive(v: Any) -> bool:
    return _number(v) and math.isfinite(v) and v > 0
