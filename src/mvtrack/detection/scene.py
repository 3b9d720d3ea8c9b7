"""The scene front end as the video pipeline runs it (``--detector scene``): :class:`SceneDetector`.

The front end itself (per-pixel background, shadows, blobs, size prior, split and merge) is
:class:`~mvtrack.detection.scene_frontend.SceneFrontEnd`; what it takes from the tracker beside
it, and the online and offline runs of the two over a clip, are in
:mod:`mvtrack.detection.feedback`. Their names are importable from here too.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.feedback import (
    TrackFeedback,
    detect_with_tracker,
    isolated,
    predicted_boxes,
    two_pass,
)
from mvtrack.detection.frameloop import (
    BOOTSTRAPS,
    check_bootstrap,
    input_size_mask,
    read_ahead,
)
from mvtrack.detection.scene_frontend import SceneFrontEnd, complete_bodies
from mvtrack.types import Detections, TrackFrame

__all__ = [
    "BOOTSTRAPS",
    "SceneDetector",
    "SceneFrontEnd",
    "TrackFeedback",
    "complete_bodies",
    "detect_with_tracker",
    "isolated",
    "predicted_boxes",
    "two_pass",
]

Image = NDArray[np.uint8]


class SceneDetector:
    """The scene front end as a frame loop runs it (``--detector scene``).

    A :class:`SceneFrontEnd` and its :class:`TrackFeedback`, behind the small interface of
    :func:`mvtrack.video.run_frames`:

    - ``prepare(frames)``: with ``bootstrap="start"`` the first ``bootstrap_frames`` frames are
      read ahead and the background starts from their temporal median (people in view from the
      first frame are then not learnt into it); the frames are then given back unchanged, so
      the loop still sees every frame from the first. ``"none"``: the first frame is the
      background (it gives no detections);
    - ``detector(frame, index=None) -> Detections`` with the predicted boxes of the tracker's
      confirmed tracks from the last :meth:`observe`;
    - ``observe(dets, tracks)`` after each ``tracker.step``: the size prior learns from the
      isolated, moving, confirmed tracks of plain blobs (:class:`TrackFeedback`);
    - :attr:`flags` (plain / merged / split of each box of the last frame) and :attr:`mask`
      (the foreground at the input frame's size, for the stopped-object templates).

    Parameters
    ----------
    bootstrap : "start" or "none", default "start"
    bootstrap_frames : int, default 20
        Frames read ahead for the median (fewer if the video is shorter).
    learn : bool, default True
        Teach the size prior from the tracker's tracks.
    work_pixels, min_area, close_size, close_frac, trim, split, reject, complete, verify
        As in :class:`SceneFrontEnd` (``min_area`` and ``close_size`` in working pixels).
    """

    name = "scene"

    def __init__(
        self,
        work_pixels: int = 110_000,
        *,
        bootstrap: str = "start",
        bootstrap_frames: int = 20,
        learn: bool = True,
        min_area: float = 30.0,
        close_size: int = 5,
        close_frac: float = 0.15,
        trim: float = 0.2,
        split: bool = True,
        reject: bool = True,
        complete: float | None = 0.85,
        verify: float | None = None,
    ) -> None:
        check_bootstrap(bootstrap)
        if int(bootstrap_frames) < 1:
            raise ValueError(f"bootstrap_frames must be at least 1, got {bootstrap_frames}")
        self.frontend = SceneFrontEnd(
            work_pixels, close_size=close_size, close_frac=close_frac, min_area=min_area,
            trim=trim, split=split, reject=reject, complete=complete, verify=verify,
        )
        self.feedback = TrackFeedback(self.frontend, learn=learn)
        self.bootstrap = bootstrap
        self.bootstrap_frames = int(bootstrap_frames)
        self._shape: tuple[int, int] | None = None

    @property
    def flags(self) -> NDArray[np.int8]:
        """Plain / merged / split flag of each box of the last frame."""
        return self.frontend.flags

    @property
    def mask(self) -> Image | None:
        """The cleaned foreground mask of the last frame at the input frame's size."""
        return input_size_mask(self.frontend.mask, self._shape)

    def prepare(self, frames: Iterable[Image]) -> Iterator[Image]:
        """``frames`` again, every one of them, the front end's background started on the way
        from the frames read ahead (the class docstring;
        :func:`~mvtrack.detection.frameloop.read_ahead`)."""
        count = 0 if self.bootstrap == "none" else self.bootstrap_frames
        yield from read_ahead(frames, count, self._bootstrap)

    def _bootstrap(self, head: list[Image]) -> None:
        self.frontend.bootstrap(head, max_frames=self.bootstrap_frames)

    def __call__(self, frame: Image, index: int | None = None) -> Detections:
        """Detections of ``frame`` (``index``: its frame number, default the count so far)."""
        self._shape = frame.shape[:2]
        return self.frontend(frame, index, predicted=self.feedback.predicted)

    def observe(self, dets: Detections, tracks: TrackFrame) -> None:
        """Teach the prior and keep the predicted boxes for the next frame."""
        self.feedback.observe(dets, self.frontend.flags, tracks)
