"""Frames in, tracks out: the video glue of paper 1's system (SPEC §1.1, Fig. 1).

.. code-block:: text

    video ─▶ settings.resolve_settings (pixel values scaled to the image)
          ─▶ build: detector, tracker, rescuer (stopped vehicles, rescue.py)
          ─▶ loop.run_frames: detector ─▶ Detections ─▶ Tracker.step(dets, rescue) ─▶ TrackFrame
          ─▶ run.track_to_folder: results.txt, tracks.mp4, trajectories.png, summary.json
          ─▶ run.write_tables: states.csv; counts, movements, speeds, tracks.csv ([analytics])

Nothing below this package imports it: the tracker and the detection front ends know nothing
of each other; the video glue connects them.
"""

from mvtrack.video.build import (
    build_detector,
    build_rescuer,
    build_tracker,
    build_tracker_config,
    check_settings,
)
from mvtrack.video.loop import HeldScores, PipelineResult, progress_bar, run_frames
from mvtrack.video.rescue import StoppedVehicleRescuer, TemplateRescuer
from mvtrack.video.run import RunOutput, track_to_folder, track_video, write_tables
from mvtrack.video.settings import REFERENCE_SIZE, resolve_settings

__all__ = [
    "REFERENCE_SIZE",
    "HeldScores",
    "PipelineResult",
    "RunOutput",
    "StoppedVehicleRescuer",
    "TemplateRescuer",
    "build_detector",
    "build_rescuer",
    "build_tracker",
    "build_tracker_config",
    "check_settings",
    "progress_bar",
    "resolve_settings",
    "run_frames",
    "track_to_folder",
    "track_video",
    "write_tables",
]
