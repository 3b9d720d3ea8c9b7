"""The multi-target tracker: predict, gate, assign, update, life cycle.

- :mod:`~mvtrack.tracking.config` — :class:`TrackerConfig` (twenty settings in box sizes,
  seconds and frames); :mod:`~mvtrack.tracking.presets` — the presets :func:`paper1`,
  :func:`paper2`, :func:`default` (:data:`PRESETS`, :func:`preset`).
- :mod:`~mvtrack.tracking.tracker` — :class:`Tracker` (``step(dets, rescue=None) ->
  TrackFrame``: scores, predict, gate, assign, update, life cycle).
- :mod:`~mvtrack.tracking.lifecycle` — births, confirmation, coasting, stopped, loss, IDs.
- :mod:`~mvtrack.tracking.scores` — detection scores on one calibrated scale.
- :mod:`~mvtrack.tracking.offline` — :func:`track_detections`: a detection file, offline
  (backfill, interpolation).
- :mod:`~mvtrack.tracking.table` — the struct-of-arrays :class:`TrackTable`.
- :mod:`~mvtrack.tracking.log` — :class:`TrackLog` (all frames as arrays, MOTChallenge rows).

>>> from mvtrack.tracking import Tracker, TrackerConfig, track_detections
"""

from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.log import TrackLog
from mvtrack.tracking.offline import track_detections
from mvtrack.tracking.presets import PRESETS, default, paper1, paper2, preset
from mvtrack.tracking.table import TrackTable
from mvtrack.tracking.tracker import Tracker

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
