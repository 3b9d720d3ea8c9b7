"""Data association: distances and gates (papers 1 and 2), and assignment rules.

- :mod:`~mvtrack.association.distances` — :class:`TrackView` and the distances by name
  (:data:`DISTANCES`: ``euclidean``, ``uncoupled``, ``coupled``, ``coupled-literal``,
  ``mahalanobis``, ``iou``; names, help and default gates in :data:`mvtrack.registry.DISTANCES`)
  and :func:`resolve_gate`, the one place a missing gate becomes the distance's default.
- :mod:`~mvtrack.association.view` — :class:`TrackView`, what association knows of the tracks;
  :mod:`~mvtrack.association.radius` — each distance's radius bound for spatial gating.
- :mod:`~mvtrack.association.gating` — :func:`candidate_pairs`: spatially pre-gated pairs
  (the one spatial index, :func:`~mvtrack.association.gating.spatial_pairs`).
- :mod:`~mvtrack.association.discs` — gating and the tiered optimal assignment for
  disc-shaped gates (Euclidean, isotropic Mahalanobis): the tracker's default path.
- :mod:`~mvtrack.association.assign` — :func:`assign` with rules ``nearest``, ``greedy``,
  ``optimal``.
- :mod:`~mvtrack.association.explain` — :func:`explain`: why a detection was not associated.
"""

from mvtrack.association.assign import ASSIGN_RULES, Assignment, assign
from mvtrack.association.distances import (
    DISTANCES,
    Distance,
    TrackView,
    default_gate,
    distance_matrix,
    gate_radius,
    get_distance,
    pair_distance,
    resolve_gate,
)
from mvtrack.association.explain import Explanation, explain
from mvtrack.association.gating import candidate_pairs

__all__ = [
    "ASSIGN_RULES",
    "DISTANCES",
    "Assignment",
    "Distance",
    "Explanation",
    "TrackView",
    "assign",
    "candidate_pairs",
    "default_gate",
    "distance_matrix",
    "explain",
    "gate_radius",
    "get_distance",
    "pair_distance",
    "resolve_gate",
]
