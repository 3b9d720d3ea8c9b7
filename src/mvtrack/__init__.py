"""mvtrack: multi-object tracking in fixed-camera video.

Data flows one way: frames -> :mod:`mvtrack.detection` -> :class:`~mvtrack.types.Detections`
-> :class:`mvtrack.tracking.Tracker` (predict with :mod:`mvtrack.filters`, gate and assign with
:mod:`mvtrack.association`, update, life cycle) -> :class:`~mvtrack.types.TrackFrame` rows ->
:mod:`mvtrack.io` writers, :mod:`mvtrack.eval` metrics and :mod:`mvtrack.viz` drawings.
"""

from mvtrack.types import Detections, TrackFrame, TrackState

__all__ = ["Detections", "TrackFrame", "TrackState", "__version__"]
__version__ = "0.1.0"
