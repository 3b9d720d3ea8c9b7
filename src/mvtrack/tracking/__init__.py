"""The multi-target tracker: predict, gate, assign, update, life cycle.

- :mod:`~mvtrack.tracking.config` — :class:`TrackerConfig` (physical units, converted with
  ``fps``) and the presets :func:`paper1`, :func:`paper2`, :func:`default` (:data:`PRESETS`,
  :func:`preset`).
- :mod:`~mvtrack.tracking.tracker` — :class:`Tracker` (``step(dets, rescue=None) ->
  TrackFrame``), its struct-of-arrays :class:`TrackTable`, and :func:`track_detections`.
- :mod:`~mvtrack.tracking.lifecycle` — the state machine as pure functions over arrays.
- :mod:`~mvtrack.tracking.log` — :class:`TrackLog` (all frames as arrays, MOTChallenge rows).
- :mod:`~mvtrack.tracking.fastkf`, :mod:`~mvtrack.tracking.associate` — the closed-form
  ``kalman-cv`` and the disc-gate association used on the hot path.

>>> from mvtrack.tracking import Tracker, TrackerConfig, track_detections
"""

from mvtrack.tracking.config import PRESETS, TrackerConfig, default, paper1, paper2, preset
from mvtrack.tracking.log import TrackLog
from mvtrack.tracking.tracker import Tracker, TrackTable, track_detections

__all__ = [
    "PRESETS",
    "TrackLog",
    "TrackTable",
    "Tracker",
    "TrackerConfig",
    "default",
    "paper1",
    "paper2",
    "preset",
    "track_detections",
]
