"""Settings scaled to the image: the papers' pixel values are for 320×240 video (SPEC §1.4)."""

from __future__ import annotations

import dataclasses

from mvtrack.config import RunSettings

#: the image size the papers' pixel parameters refer to (SPEC §1.4: 320×240)
REFERENCE_SIZE = (320, 240)

#: front ends that size their own blob stage (no size-dependent ``min_area``, ``close_size``)
OWN_BLOB_STAGE = frozenset({"scene", "road-users"})


#: seconds a tracked pixel is kept out of the disturbance map's background (``hold``), and
#: seconds a pixel of the road-user front end stays foreground before it is absorbed
HOLD_SECONDS = 60.0

#: seconds between two ghost tests of the road-user front end
GHOST_SECONDS = 2.0

#: the road-user front end's smallest blob, in pixels of the papers' 320×240 image (scaled
#: by ``s²``, as the other front ends' ``min_area = 40 s²``): chosen by leave-one-out over
#: the four US-101 clips and KITTI-17 end to end (``benchmarks/bench_vehicles.py
#: --loo-e2e``, docs/bench/vehicles.md)
ROAD_USERS_AREA = 40.0


def resolve_settings(
    settings: RunSettings, size: tuple[int, int], fps: float = 30.0
) -> RunSettings:
    """Fill in the size-dependent defaults the user left open, for a ``size`` (W, H) video
    at ``fps`` frames per second.

    With ``s² = W·H / (320·240)`` (the papers' 320×240, SPEC §1.4):

    - blob stage: ``min_area = 40 s²`` px and a 7×7 closing (``close_size = 7``), which merges
      fragments a few pixels apart — two-tone vehicles and clothes otherwise split into
      several blobs, the "segmentation splits vehicles by colour" of paper 1 (SPEC §1.5).
      The closing is not scaled with the image: a larger one merges people walking side by
      side in 768×576 video. SPEC §1.1 [R] (opening only, area ≥ 20 px) is
      ``close_size = 0, min_area = 20``;
    - the tracker (any preset): the image's size (``frame_size``), so that a track whose
      prediction leaves the image ends there. It is the only tracker value a video derives:
      the tracker's noise and gates are in box sizes, the same for any image
      (:mod:`mvtrack.tracking.config`), and ``summary.json`` prints it with the settings.

    - for the disturbance map (not in paper 1): its ghosts tested every 5 frames
      (``ghost_every = 5``), so a vehicle that stood keeps its track when it leaves
      (``docs/video-pipeline.md``, measured on X5, X8, the stop-and-go queue and vtest.avi);
      its blobs divided among the confirmed tracks predicted into them (``track_split``,
      without merging fragments, ``track_merge = False``: merging held X8's walking group
      together as it split up); and the pixels
      under the confirmed tracks' predicted boxes kept out of its background for up to
      ``HOLD_SECONDS`` (``hold``, in frames at ``fps``), so a vehicle that waits in a queue
      stays foreground and leaves no ghost when it drives on; one that stands longer is
      absorbed (``docs/video-pipeline.md``).

    - for the road-user front end (``"road-users"``): a pixel that stays foreground (a car
      that waits) is absorbed after ``HOLD_SECONDS`` (``absorb_after``, frames at ``fps``),
      and ghosts are looked for every ``GHOST_SECONDS`` (``ghost_every``); its smallest
      blob is ``ROAD_USERS_AREA s²`` pixels of the frame (``min_area``, given in its
      working pixels: times ``scale²``), its closing sized from the objects it learns.

    The tracker values are only scaled up: images smaller than 320×240 keep them.

    The blob-stage defaults are for the front ends whose blobs are found at the frame's size;
    the scene front end (``"scene"``) works on a reduced frame and sizes its closing from its
    size prior, so it keeps its own defaults (:class:`~mvtrack.detection.scene.SceneDetector`).

    Values present in ``settings`` are kept; the paper presets are not touched.
    """
    w, h = size
    s2 = (w * h) / (REFERENCE_SIZE[0] * REFERENCE_SIZE[1])
    det = dict(settings.detector_params)
    if settings.detector not in OWN_BLOB_STAGE:
        det.setdefault("min_area", float(round(40.0 * s2)))
        det.setdefault("close_size", 7)
    if settings.detector == "road-users":  # its times in seconds, at the video's rate
        scale = float(det.get("scale", 1.0))
        det.setdefault("min_area", float(round(ROAD_USERS_AREA * s2 * scale * scale)))
        det.setdefault("absorb_after", min(max(1, round(HOLD_SECONDS * fps)), 65534))
        det.setdefault("ghost_every", max(1, round(GHOST_SECONDS * fps)))
    if settings.detector == "disturbance-map":
        det.setdefault("ghost_every", 5)
        det.setdefault("hold", max(1, round(HOLD_SECONDS * fps)))
        if "track_split" not in det:  # a blob that several tracks predict into is divided
            det["track_split"] = True
            det.setdefault("track_merge", False)
    tracker = dict(settings.tracker)
    tracker.setdefault("frame_size", [float(w), float(h)])  # Tracker(frame_size=...)
    return dataclasses.replace(settings, detector_params=det, tracker=tracker)

