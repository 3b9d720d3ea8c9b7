"""Named tracker configurations: the systems of papers 1 and 2 and the default."""

from __future__ import annotations

import inspect
from typing import Any

from mvtrack.tracking.config import TrackerConfig

__all__ = ["PRESETS", "default", "paper1", "paper2", "preset"]


#: what both paper presets share: fixed noise in pixels (R = 4 px², SPEC §2.1 [R]), no size
#: term, every detection used whatever its score (the papers' detections have none), a track
#: started by one detection and ended after 3 frames without one (it coasts meanwhile, and
#: its coasting rows are written), paper 1's warm-up gate centre until 2M = 6 associations
_PAPER_COMMON: dict[str, Any] = {
    "size_noise": None,
    "confirm_hits": 1,
    "confirm_score": 0.0,
    "max_misses": 3,  # SPEC §1.1: 3 frames without a detection
    "lost_std": None,
    "coast_std": float("inf"),
    "score_high": None,
    "min_score": 0.0,
    "birth_iou": None,
    "warmup": 6,
}


def paper1(predictor: str = "kalman-ca", fps: float = 30.0, gate_px: float = 20.0) -> TrackerConfig:
    """Paper 1's system (SPEC §1.1): per-axis CA Kalman or RLS, 20 px circle, nearest.

    Non-exclusive nearest detection inside a circle of ``gate_px`` (20 px; 10 px in the
    synthetic experiment), unused detections start tracks at once (every started track is
    counted), a track ends after 3 consecutive frames without a detection (it coasts
    meanwhile), and the warm-up gate centre ``2 y_k − y_{k−1}`` is used until a track has
    2M = 6 associations. R = 4 px² and, for the CA filter, q = 0.05 (SPEC §2.1 [R]; paper 1's
    own 5 and 0.5 are in metres for its 1-D simulation, E1.7).
    """
    if predictor not in ("kalman-ca", "rls"):
        raise ValueError(f"paper1: predictor must be 'kalman-ca' or 'rls' (got {predictor!r})")
    params = {"q": 0.05, "r": 4.0} if predictor == "kalman-ca" else {"r": 4.0}
    return TrackerConfig(
        predictor=predictor,
        predictor_params=params,
        distance="euclidean",
        gate=float(gate_px) ** 2,
        assign="nearest",
        fps=fps,
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
        predictor_params={"q": 0.05, "r": 4.0},
        distance=distance,
        gate=None,
        assign="nearest",
        fps=fps,
        **_PAPER_COMMON,
    )


def default(fps: float = 30.0) -> TrackerConfig:
    """The default, ``TrackerConfig(fps=fps)``, the same for every command, scene, object
    and frame rate (``docs/settings.md``): the per-axis constant-velocity Kalman filter with
    its noise in box sizes, the gate of its innovation covariance and box size, the global
    nearest neighbour in two stages by detection score, a life cycle in frames and in the
    filter's uncertainty."""
    return TrackerConfig(fps=fps)


#: Named presets for the command line and experiments.
PRESETS = {"paper1": paper1, "paper2": paper2, "default": default}


def preset(name: str, **overrides: Any) -> TrackerConfig:
    """The preset ``name`` (``default``, ``paper1``, ``paper2``) with fields overridden.

    Overrides the preset function takes (``fps``, and ``predictor`` for ``paper1``) are passed
    to it; the others replace fields of its result. Changing ``distance`` to another one
    without a ``gate`` uses the new distance's default; naming the preset's own distance
    changes nothing.
    """
    try:
        build = PRESETS[name]
    except KeyError:
        raise ValueError(
            f"unknown tracker preset {name!r}; choose one of: {', '.join(PRESETS)}"
        ) from None
    takes = inspect.signature(build).parameters
    own = {k: overrides.pop(k) for k in list(overrides) if k in takes}
    config = build(**own)
    if overrides.get("distance", config.distance) != config.distance and "gate" not in overrides:
        overrides["gate"] = None  # a new distance: its own default gate
    return config.replace(**overrides) if overrides else config
