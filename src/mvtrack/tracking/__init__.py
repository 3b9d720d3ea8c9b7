"""The multi-target tracker: predict, gate, assign, update, life cycle.

- :mod:`~mvtrack.tracking.config` — :class:`TrackerConfig` (physical units, converted with
  ``fps``); :mod:`~mvtrack.tracking.presets` — the presets :func:`paper1`, :func:`paper2`,
  :func:`default` (:data:`PRESETS`, :func:`preset`).
- :mod:`~mvtrack.tracking.tracker` — :class:`Tracker` (``step(dets, rescue=None) ->
  TrackFrame``: predict, associate, update, life cycle, births).
- :mod:`~mvtrack.tracking.offline` — :func:`track_detections`: a detection file, offline
  (backfill, interpolation, short tracks dropped).
- :mod:`~mvtrack.tracking.table` — the struct-of-arrays :class:`TrackTable` and its row
  operations.
- :mod:`~mvtrack.tracking.stages` — :class:`~mvtrack.tracking.stages.Associator`: the
  association stages of a frame (first stage, second gate, recovery, low-score stage, size
  term), composed from :mod:`mvtrack.association`.
- :mod:`~mvtrack.tracking.lifecycle` — the state machine as pure functions over arrays.
- :mod:`~mvtrack.tracking.log` — :class:`TrackLog` (all frames as arrays, MOTChallenge rows).

>>> from mvtrack.tracking import Tracker, TrackerConfig, track_detections
"""

from mvtrack.tracking.config import Frames, TrackerConfig
from mvtrack.tracking.log import TrackLog
from mvtrack.tracking.offline import track_detections
from mvtrack.tracking.presets import PRESETS, default, paper1, paper2, preset
from mvtrack.tracking.table import TrackTable
from mvtrack.tracking.tracker import Tracker

__all__ = [
    "PRESETS",
    "Frames",
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
