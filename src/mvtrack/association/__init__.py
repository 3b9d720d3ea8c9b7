"""Data association: the gate, the distances of papers 1 and 2, and the assignment rules.

- :mod:`~mvtrack.association.gate` — :class:`Gate`: per frame, each track's centre and
  region (the filter's innovation covariance by default, or a distance of the papers) and a
  size term; the candidate pairs and their costs, and the regions to draw.
- :mod:`~mvtrack.association.distances` — the distances by name (:data:`DISTANCES`:
  ``euclidean``, ``uncoupled``, ``coupled``, ``coupled-literal``, ``mahalanobis``, ``iou``;
  names, help and default gates in :data:`mvtrack.registry.DISTANCES`) and
  :func:`resolve_gate`, the one place a missing gate becomes the distance's default;
  :mod:`~mvtrack.association.view` — :class:`TrackView`, what association knows of the tracks.
- :mod:`~mvtrack.association.assign` — the tracker's association of a frame
  (:func:`~mvtrack.association.assign.associate`, compiled) and :func:`assign` with the rules
  ``nearest``, ``greedy``, ``optimal``.
- :mod:`~mvtrack.association.explain` — :func:`explain`: why a detection was not associated.
"""

from mvtrack.association.assign import ASSIGN_RULES, Assignment, assign
from mvtrack.association.distances import (
    DISTANCES,
    Distance,
    TrackView,
    default_gate,
    distance_matrix,
    get_distance,
    pair_distance,
    resolve_gate,
)
from mvtrack.association.explain import Explanation, explain
from mvtrack.association.gate import Gate, GateRegions

__all__ = [
    "ASSIGN_RULES",
    "DISTANCES",
    "Assignment",
    "Distance",
    "Explanation",
    "Gate",
    "GateRegions",
    "TrackView",
    "assign",
    "default_gate",
    "distance_matrix",
    "explain",
    "get_distance",
    "pair_distance",
    "resolve_gate",
]
