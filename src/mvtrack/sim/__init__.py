"""Simulated scenes with ground truth: trajectories, detections and rendered video."""
