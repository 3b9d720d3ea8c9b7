"""The names a user may choose, one registry each: detection front ends, predictors,
distances (with their default gates) and assignment rules.

Each registry maps a name to a :class:`Choice` (a one-line summary and, where the owner does
not dispatch by name itself, where the implementation lives). This module imports nothing
heavy (no NumPy, OpenCV or SciPy), so the command line builds its help texts and checks its
options here; the libraries look their implementations up by the same names
(:func:`mvtrack.detection.make_detector`, :func:`mvtrack.filters.predictors.make_predictor`,
:data:`mvtrack.association.DISTANCES`, :func:`mvtrack.association.assign`). A new front end,
predictor, distance or rule is added here, once; a distance's default gate is set here and
nowhere else (:func:`default_gate`).
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Choice:
    """One registered name.

    Attributes
    ----------
    summary : str
        What it is, in a few words (for help texts).
    target : str
        ``"module:attribute"`` of the implementation ("" where the owner dispatches by name).
    """

    summary: str
    target: str = ""


#: the front end used when none is named: one model for any moving road user, cars and
#: people alike (docs/bench/vehicles.md); the paper experiments and ``mvtrack demo`` name
#: paper 1's disturbance map themselves
DEFAULT_DETECTOR = "road-users"

#: detection front ends (:func:`mvtrack.detection.make_detector`)
DETECTORS: dict[str, Choice] = {
    "disturbance-map": Choice(
        "paper 1's disturbance map", "mvtrack.detection.background:DisturbanceMap"
    ),
    "frame-diff": Choice(
        "frame differencing (the baseline paper 1 rejects)",
        "mvtrack.detection.background:FrameDifference",
    ),
    "mog2": Choice("OpenCV's Gaussian mixture model", "mvtrack.detection.background:MOG2"),
    "knn": Choice(
        "OpenCV's k-nearest-neighbours background subtractor",
        "mvtrack.detection.background:KNN",
    ),
    "hog": Choice(
        "OpenCV's HOG people detector over the whole frame (no background model)",
        "mvtrack.detection.hog:HOGDetector",
    ),
    "road-users": Choice(
        "any moving road user: colour background, the scene's kinds and sizes learnt",
        "mvtrack.detection.roadusers:RoadUserDetector",
    ),
    "scene": Choice(
        "per-pixel background, shadows, size prior, blobs split with the tracker",
        "mvtrack.detection.scene:SceneDetector",
    ),
}

#: predictors (:func:`mvtrack.filters.predictors.make_predictor`)
PREDICTORS: dict[str, Choice] = {
    "kalman-ca": Choice(
        "per-axis constant-acceleration Kalman filter (paper 1)",
        "mvtrack.filters.axis_kalman:KalmanCAPredictor",
    ),
    "kalman-cv": Choice(
        "per-axis constant-velocity Kalman filter in closed form",
        "mvtrack.filters.cv:KalmanCVPredictor",
    ),
    "kalman-imm": Choice(
        "steady and manoeuvring constant-velocity Kalman filters mixed (IMM)",
        "mvtrack.filters.imm:KalmanIMMPredictor",
    ),
    "kalman-coupled": Choice(
        "one 2-D Kalman filter per track (full position covariance, paper 2)",
        "mvtrack.filters.coupled_kalman:CoupledKalmanPredictor",
    ),
    "rls": Choice(
        "per-axis RLS adaptive transversal predictor (paper 1)",
        "mvtrack.filters.rls_predictor:RLSPredictor",
    ),
    "structured": Choice(
        "structured Kalman filter over the parts of a body (paper 3)",
        "mvtrack.filters.structured:StructuredPredictor",
    ),
}


@dataclass(frozen=True)
class DistanceChoice(Choice):
    """A registered distance and its default gate.

    Attributes
    ----------
    gate : float
        The gate applied when none is given: pairs whose distance value is ``<= gate`` pass.
    unit : str
        What the gate measures, for help texts.
    box_gate : float or None
        The tracker's gate where none is given, when it differs from ``gate``: a χ² on the
        distance measured in box sizes (``euclidean``,
        :func:`mvtrack.association.gate.tracker_gate`); ``gate`` stays the default of the
        functions that take a gate in the distance's own units.
    """

    gate: float = 0.0
    unit: str = ""
    box_gate: float | None = None


#: χ² quantile of 2 degrees of freedom at 99 %, the gate of the Mahalanobis-type distances
CHI2_2DOF_99 = 9.21

#: association distances (:data:`mvtrack.association.DISTANCES`) and their default gates; the
#: tracker's default is ``mahalanobis`` at 9.21 (99 % of a χ² with 2 degrees of freedom on the
#: filter's innovation covariance, :mod:`mvtrack.association.gate`); the Euclidean 100 px² (a
#: 10 px circle) is paper 1's synthetic experiment's (its real videos use 20 px, ``paper1``);
#: a tracker given no gate measures the Euclidean distance in box sizes and gates it at 9.21
DISTANCES: dict[str, DistanceChoice] = {
    "euclidean": DistanceChoice(
        "squared centre distance (papers 1 and 2)", gate=100.0, unit="px²",
        box_gate=CHI2_2DOF_99,
    ),
    "uncoupled": DistanceChoice(
        "per-axis normalised squared distance, eq. (8) of paper 2", gate=CHI2_2DOF_99, unit="χ²"
    ),
    "coupled": DistanceChoice(
        "x-y coupled region, eq. (10) of paper 2 as corrected", gate=CHI2_2DOF_99, unit="χ²"
    ),
    "coupled-literal": DistanceChoice(
        "x-y coupled region, eq. (10) of paper 2 as printed", gate=CHI2_2DOF_99, unit="χ²"
    ),
    "mahalanobis": DistanceChoice(
        "full-covariance Mahalanobis distance", gate=CHI2_2DOF_99, unit="χ²"
    ),
    "iou": DistanceChoice("box overlap, cost 1 − IoU", gate=0.7, unit="1 − IoU"),
}


def default_gate(name: str) -> float:
    """The default gate of the distance ``name``, from :data:`DISTANCES`.

    Parameters
    ----------
    name : str
        A registered distance.

    Returns
    -------
    float
        Squared pixels for ``euclidean``, a χ² value for the Mahalanobis-type distances, a
        cost 1 − IoU for ``iou``.

    Raises
    ------
    ValueError
        If ``name`` is not a registered distance.
    """
    check("distance", name, DISTANCES)
    return DISTANCES[name].gate


def gate_help() -> str:
    """Help text of the ``--gate`` option, with the tracker's default gate of every distance."""
    by_value: dict[tuple[float, str], list[str]] = {}
    for name, d in DISTANCES.items():
        key = (d.gate, d.unit) if d.box_gate is None else (d.box_gate, "χ² in box sizes")
        by_value.setdefault(key, []).append(name)
    defaults = "; ".join(
        f"{'/'.join(names)} {gate:g} ({unit})" for (gate, unit), names in by_value.items()
    )
    return (
        "Gate on the distance's value (euclidean: px², '20px' for a radius). "
        f"Defaults: {defaults}. Default: the preset's, else the distance's."
    )


#: assignment rules (:func:`mvtrack.association.assign`)
ASSIGN_RULES: dict[str, Choice] = {
    "nearest": Choice("each track its nearest gated detection, non-exclusive (the papers)"),
    "greedy": Choice("exclusive nearest, pairs in increasing cost"),
    "optimal": Choice("global minimum-cost exclusive assignment"),
}


def one_of(registry: Mapping[str, Any], default: str | None = None) -> str:
    """``"a (default), b or c"``: the names of ``registry`` for a help text."""
    names = [f"{n} (default)" if n == default else n for n in registry]
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"


def check(kind: str, name: str, registry: Mapping[str, Any]) -> None:
    """Raise ``ValueError`` naming the choices unless ``name`` is in ``registry``."""
    if name not in registry:
        raise ValueError(f"unknown {kind} {name!r}; choose one of: {', '.join(registry)}")


def load(choice: Choice) -> Any:
    """The implementation a :class:`Choice` names (its module imported now)."""
    module, _, attribute = choice.target.partition(":")
    return getattr(importlib.import_module(module), attribute)
