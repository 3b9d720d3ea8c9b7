"""Simulated scenes with ground truth: trajectories, detections and rendered video.

* :mod:`mvtrack.sim.scenes` — :class:`~mvtrack.sim.scenes.Scene` (ground truth as a struct of
  arrays) and the builders ``x4_nine_vehicles``, ``x5_intersection``, ``x7_crossing``,
  ``x8_splitting_group``, ``crowd`` and ``build(name, ...)``.
* :mod:`mvtrack.sim.detections` — ``detections_from_scene`` / ``detections_with_truth``:
  noisy detections with misses and clutter, one :class:`~mvtrack.types.Detections` per frame.
* :mod:`mvtrack.sim.render` — ``render_frames``, ``render_background``, ``write_video``:
  synthetic traffic video (BGR uint8 frames, MP4).
"""
