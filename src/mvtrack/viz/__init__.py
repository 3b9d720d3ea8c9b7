"""Drawings: annotated video frames and plots."""
