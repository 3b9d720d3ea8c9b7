"""TrackEval's HOTA metric class (the only metric mvtrack takes from TrackEval)."""

from .hota import HOTA

__all__ = ["HOTA"]
