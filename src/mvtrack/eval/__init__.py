"""Evaluation: MOTA, IDF1 (motmetrics) and HOTA (TrackEval)."""
