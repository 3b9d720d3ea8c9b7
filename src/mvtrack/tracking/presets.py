"""Named tracker configurations: the systems of papers 1 and 2 and the modern default."""

from __future__ import annotations

import inspect
from typing import Any

from mvtrack.tracking.config import Frames, TrackerConfig

__all__ = ["PRESETS", "default", "paper1", "paper2", "preset"]


#: what both paper presets share: R = 4 px² (SPEC §2.1 [R]), the predictors' own priors, no
#: recovery stage, no scaling with the box size or size gate, every detection used whatever
#: its score (the papers' detections have none), paper 1's warm-up gate centre
#: until 2M = 6 associations
_PAPER_COMMON: dict[str, Any] = {
    "size_ref": None,
    "coast_output": None,
    "size_weight": 0.0,
    "measurement_std": 2.0,
    "init_velocity_std": None,
    "accel_std": None,
    "recover_speed": None,
    "second_gate": None,
    "size_gate": None,
    "score_high": None,
    "min_score": 0.0,
    "min_track_length": None,
    "relink_window": None,
    "warmup": True,
    "warmup_hits": 6,
}


def paper1(predictor: str = "kalman-ca", fps: float = 30.0, gate_px: float = 20.0) -> TrackerConfig:
    """Paper 1's system (SPEC §1.1): per-axis CA Kalman or RLS, 20 px circle, nearest.

    Non-exclusive nearest detection inside a circle of ``gate_px`` (20 px; 10 px in the
    synthetic experiment), unused detections start tracks at once (every started track is
    counted, so ``confirm_hits = 1``), a track ends after 3 consecutive frames without a
    detection (it coasts meanwhile), and the warm-up gate centre ``2 y_k − y_{k−1}`` is used
    until a track has 2M = 6 associations. R = 4 px² and, for the CA filter, q = 0.05
    (SPEC §2.1 [R]; paper 1's own 5 and 0.5 are in metres for its 1-D simulation, E1.7).
    """
    if predictor not in ("kalman-ca", "rls"):
        raise ValueError(f"paper1: predictor must be 'kalman-ca' or 'rls' (got {predictor!r})")
    params = {"q": 0.05} if predictor == "kalman-ca" else {}
    return TrackerConfig(
        predictor=predictor,
        predictor_params=params,
        distance="euclidean",
        gate=float(gate_px) ** 2,
        assign="nearest",
        fps=fps,
        confirm_hits=1,
        max_coast=Frames(3),  # SPEC §1.1: 3 frames without a detection
        # ours, not paper 1's: a track held by template matching takes only detections at the
        # place it stands, so a vehicle passing within the gate does not carry a standing
        # vehicle's track off (X5)
        stopped_margin=4.0,
        **_PAPER_COMMON,
    )


def paper2(distance: str = "coupled", fps: float = 15.0) -> TrackerConfig:
    """Paper 2's system (SPEC §2.1): independent per-axis KFs, coupled region, nearest.

    Per-axis constant-acceleration KF with R = 4 px² and q = 0.05 (SPEC §2.1 [R]), the
    corrected coupled gate (SPEC §2.3, χ² 9.21 by default), non-exclusive nearest, new targets
    from unassociated measurements, warm-up as paper 1. The real video of paper 2 is 15 fps.
    """
    return TrackerConfig(
        predictor="kalman-ca",
        predictor_params={"q": 0.05},
        distance=distance,
        gate=None,
        assign="nearest",
        fps=fps,
        confirm_hits=1,
        max_coast=Frames(3),  # SPEC §1.1: 3 frames without a detection
        **_PAPER_COMMON,
    )


def default(fps: float = 30.0) -> TrackerConfig:
    """The modern default, ``TrackerConfig(fps=fps)`` (chosen on the crowd benchmark,
    docs/bench/tracker.md, and on real boxes, docs/bench/tud.md): closed-form per-axis
    constant-velocity KF (σ_z = 2 px, σ_a = 200 px/s², velocity prior 150 px/s); association
    in stages, each the gated global nearest neighbour (``optimal``): a 10 px Euclidean gate,
    then 20 px for the tracks and detections left over, then the recovery stage (250 px/s
    from the last measurement) for established targets that turned or bounced. σ_z, the
    gates and the recovery margin hold for boxes up to 50 px and stretch per axis with larger
    boxes (``size_ref``). Confirmation on 2 consecutive hits; a track coasts up to 0.3 s but
    its coasting rows are output only for the first 0.08 s (``coast_output``). A track and a
    detection whose box heights differ by more than a factor 1.5 (widths 1.5²) are never paired
    (``size_gate``; off in the video pipeline). Detection scores are ranked among the
    run's (``score_scale="auto"``): the lowest 20 % are dropped (``min_score``), those below
    the median only extend established tracks (``score_high``) or, overlapping no track and no
    stronger box, start one that a stronger box must confirm (``low_birth_iou``); chosen by
    leave-one-sequence-out
    on the MOT15 public detections (docs/bench/mot15-defaults.md). Detections without a score
    (blobs, simulations) are all high. Offline runs
    (:func:`~mvtrack.tracking.track_detections`) write a confirmed track from its first
    detection on (``backfill``) and the gaps it bridged in full, interpolated
    (``interpolate``), and leave out tracks shorter than 0.3 s (``min_track_length``; 0.6 s
    measured a little better on MOT15 but drops true short tracks of TUD-Campus)."""
    return TrackerConfig(fps=fps)


#: Named presets for the command line and experiments.
PRESETS = {"paper1": paper1, "paper2": paper2, "default": default}


def preset(name: str, **overrides: Any) -> TrackerConfig:
    """The preset ``name`` (``default``, ``paper1``, ``paper2``) with fields overridden.

    Overrides the preset function takes (``fps``, on which its frame-based paper values
    depend, and ``predictor`` for ``paper1``) are passed to it; the others replace fields of
    its result. Changing ``distance`` to another one without a ``gate`` uses the new
    distance's default; naming the preset's own distance changes nothing.
    """
    try:
        build = PRESETS[name]
    except KeyError:
        raise ValueError(
            f"unknown tracker preset {name!r}; choose one of: {', '.join(PRESETS)}"
        ) from None
    # arguments the preset itself takes (fps, paper 1's predictor) go to it, the rest replace
    # fields of its result
    takes = inspect.signature(build).parameters
    own = {k: overrides.pop(k) for k in list(overrides) if k in takes}
    config = build(**own)
    if overrides.get("distance", config.distance) != config.distance and "gate" not in overrides:
        overrides["gate"] = None  # a new distance: its own default gate
    return config.replace(**overrides) if overrides else config
