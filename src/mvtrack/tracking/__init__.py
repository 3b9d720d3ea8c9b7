"""The multi-target tracker: predict, gate, assign, update, life cycle.

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
