"""Simulated scenes with ground truth: trajectories, detections and rendered video.

* :mod:`mvtrack.sim.scene` — :class:`~mvtrack.sim.scene.Scene` (ground truth as a struct of
  arrays); :mod:`mvtrack.sim.paths` — the paths vehicles follow.
* :mod:`mvtrack.sim.scenes` — the scenes by name, ``build(name, ...)``; one module a family:
  :mod:`~mvtrack.sim.nine_vehicles` (``x4_nine_vehicles``), :mod:`~mvtrack.sim.intersection`
  (``x5_intersection``), :mod:`~mvtrack.sim.crossing` (``x7_crossing``),
  :mod:`~mvtrack.sim.splitting_group` (``x8_splitting_group``), :mod:`~mvtrack.sim.crowd`
  (``crowd``).
* :mod:`mvtrack.sim.detections` — ``detections_from_scene`` / ``detections_with_truth``:
  noisy detections with misses and clutter, one :class:`~mvtrack.types.Detections` per frame.
* :mod:`mvtrack.sim.render` — ``render_frames``, ``write_video``: synthetic traffic video (BGR
  uint8 frames, MP4); the look of each scene in :mod:`~mvtrack.sim.style` (``RenderStyle``),
  its static picture in :mod:`~mvtrack.sim.backgrounds` (``render_background``), its objects in
  :mod:`~mvtrack.sim.drawing`.
"""
