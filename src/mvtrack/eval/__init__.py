"""Evaluation: MOTA, IDF1 (motmetrics) and HOTA (TrackEval).

>>> from mvtrack.eval import evaluate
"""

from mvtrack.eval.iou import iou_matrix
from mvtrack.eval.metrics import evaluate

__all__ = ["evaluate", "iou_matrix"]
