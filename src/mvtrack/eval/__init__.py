"""Evaluation: CLEAR-MOT, identity and HOTA metrics of MOTChallenge results.

- :mod:`~mvtrack.eval.iou` — box IoU, and the overlapping pairs of two whole sequences.
- :mod:`~mvtrack.eval.assignment` — the optimal matchings of those pairs.
- :mod:`~mvtrack.eval.clear` — CLEAR-MOT and identity counts (motmetrics' algorithm).
- :mod:`~mvtrack.eval.hota` — HOTA (TrackEval's algorithm).
- :mod:`~mvtrack.eval.checks` — refusing inputs that cannot belong together.
- :mod:`~mvtrack.eval.metrics` — one sequence: :func:`evaluate`, the ignore flag.
- :mod:`~mvtrack.eval.sequences` — a folder of sequences, combined as the devkit does.

>>> from mvtrack.eval import evaluate
"""

from mvtrack.eval.iou import iou_matrix
from mvtrack.eval.metrics import DEFAULT_IGNORE, IGNORE_MODES, SequenceScores, evaluate

__all__ = ["DEFAULT_IGNORE", "IGNORE_MODES", "SequenceScores", "evaluate", "iou_matrix"]
