"""A front end's ``shown`` hook in the frame loop: the rows it leaves out are not kept, written
or drawn (the road-user front end shows a track once it has travelled)."""

from __future__ import annotations

import numpy as np

from mvtrack.detection.travel import Travel
from mvtrack.tracking import Tracker, preset
from mvtrack.types import Detections, TrackFrame, take_rows
from mvtrack.video.loop import run_frames


class ToyFrontEnd:
    """Two detections a frame, one moving and one still; its ``shown`` hook is the road-user
    front end's (rows of tracks that have not travelled are left out)."""

    def __init__(self) -> None:
        self.k = 0
        self.travel = Travel(0.25)

    def __call__(self, frame: np.ndarray) -> Detections:
        self.k += 1
        return Detections(0, np.array([[20.0 + 4 * self.k, 15.0], [70.0, 45.0]]),
                          np.array([[10.0, 20.0], [10.0, 20.0]]))

    def shown(self, tracks: TrackFrame) -> TrackFrame:
        return take_rows(tracks, self.travel.update(tracks))


def test_the_frame_loop_keeps_only_the_rows_the_front_end_shows() -> None:
    frames = [np.zeros((60, 200, 3), np.uint8)] * 15
    res = run_frames(frames, ToyFrontEnd(), Tracker(preset("default", fps=10)), progress=False)
    ys = np.concatenate([tf.filtered_xy[:, 1] for tf in res.tracks])
    assert ys.size > 0 and (ys < 30).all()  # the still blob (y = 45) is never output
    plain = ToyFrontEnd()
    res2 = run_frames(frames, plain.__call__, Tracker(preset("default", fps=10)),
                      progress=False)
    ys2 = np.concatenate([tf.filtered_xy[:, 1] for tf in res2.tracks])
    assert (ys2 > 30).sum() >= 10  # without the hook, it is
