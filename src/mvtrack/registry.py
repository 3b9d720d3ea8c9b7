"""The names a user may choose, one registry each: detection front ends and assignment rules.

Each registry maps a name to a :class:`Choice` (a one-line summary and, for the front ends,
where the implementation lives). This module imports nothing heavy (no NumPy, OpenCV or
SciPy), so the command line builds its help texts and checks its options here; the libraries
look their implementations up by the same names (:func:`mvtrack.detection.make_detector`,
:func:`mvtrack.association.assign`). A new front end or rule is added here, once.
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


#: the front end used when none is named: the one that measures best on real video
#: (KITTI-17 from the command line, docs/bench/frontend.md §6); the paper experiments and
#: ``mvtrack demo`` name paper 1's disturbance map themselves
DEFAULT_DETECTOR = "scene"

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
    "scene": Choice(
        "per-pixel background, shadows, size prior, blobs split with the tracker",
        "mvtrack.detection.scene:SceneDetector",
    ),
}

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
