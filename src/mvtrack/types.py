"""Frozen containers of arrays that flow between the stages of the pipeline, and the row
helpers of batch states.

Conventions: ``M`` detections, ``K`` output rows; image x points right, y down, in pixels.

A *batch state* is a dataclass whose array fields share a leading dimension, one row per
target (the predictor states of :mod:`mvtrack.filters.predictors`); the tracker grows and
shrinks it with :func:`take_rows` and :func:`concat_rows`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
T = TypeVar("T")


class TrackState(IntEnum):
    """Life-cycle state of a track, carried in every output row."""

    TENTATIVE = 0  #: not yet confirmed (no public ID yet)
    CONFIRMED = 1  #: associated with a detection this frame
    COASTING = 2  #: missed this frame; the predicted box is output and flagged
    STOPPED = 3  #: held by template matching (a vehicle that stopped, paper 1)
    DELETED = 4  #: ended; never output again


@dataclass(frozen=True)
class Detections:
    """The ``M`` detections of one frame.

    Attributes
    ----------
    frame : int
        Frame index (0-based).
    xy : (M, 2) float64
        Centre (x, y) in pixels.
    wh : (M, 2) float64
        Box width and height in pixels (non-negative).
    score : (M,) float64
        Confidence; 1.0 where the source gives none.
    area : (M,) float64
        Foreground pixel count for blobs, ``w * h`` otherwise.
    """

    frame: int
    xy: FloatArray
    wh: FloatArray
    score: FloatArray = field(default=None)  # type: ignore[assignment]
    area: FloatArray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        xy = np.ascontiguousarray(self.xy, dtype=np.float64).reshape(-1, 2)  # one layout
        wh = np.ascontiguousarray(self.wh, dtype=np.float64).reshape(-1, 2)  # for the kernels
        m = xy.shape[0]
        if wh.shape[0] != m:
            raise ValueError(f"Detections: xy has {m} rows but wh has {wh.shape[0]}")
        score = np.ones(m) if self.score is None else np.asarray(self.score, np.float64)
        area = wh.prod(axis=1) if self.area is None else np.asarray(self.area, np.float64)
        if score.shape != (m,) or area.shape != (m,):
            raise ValueError("Detections: score and area must have one value per detection")
        object.__setattr__(self, "xy", xy)
        object.__setattr__(self, "wh", wh)
        object.__setattr__(self, "score", score)
        object.__setattr__(self, "area", area)

    def __len__(self) -> int:
        return int(self.xy.shape[0])

    @classmethod
    def empty(cls, frame: int) -> Detections:
        """No detections in ``frame``."""
        return cls(frame, np.zeros((0, 2)), np.zeros((0, 2)))

    @classmethod
    def from_tlwh(
        cls, frame: int, tlwh: FloatArray, score: FloatArray | None = None
    ) -> Detections:
        """From MOTChallenge boxes ``(left, top, width, height)``."""
        tlwh = np.asarray(tlwh, dtype=np.float64).reshape(-1, 4)
        return cls(frame, tlwh[:, :2] + tlwh[:, 2:] / 2, tlwh[:, 2:].copy(), score)

    @property
    def tlwh(self) -> FloatArray:
        """Boxes as ``(left, top, width, height)``, shape (M, 4)."""
        return np.hstack([self.xy - self.wh / 2, self.wh])

    @property
    def xyxy(self) -> FloatArray:
        """Boxes as ``(x1, y1, x2, y2)``, shape (M, 4)."""
        return np.hstack([self.xy - self.wh / 2, self.xy + self.wh / 2])

    def take(self, idx: IntArray | NDArray[np.bool_]) -> Detections:
        """A subset (or reordering) of the detections."""
        return Detections(self.frame, self.xy[idx], self.wh[idx], self.score[idx], self.area[idx])


@dataclass(frozen=True)
class TrackFrame:
    """The tracker's output for one frame: ``K`` rows, one per live track with a public ID.

    Attributes
    ----------
    frame : int
        Frame index (0-based).
    track_id : (K,) int64
        Public IDs, consecutive from 1 in order of confirmation.
    state : (K,) int64
        :class:`TrackState` values.
    det_index : (K,) int64
        Row of the frame's :class:`Detections` that updated the track, ``-1`` when none
        (coasting, or stopped and held by template matching).
    measured_xy : (K, 2) float64
        The associated measurement (NaN when ``det_index == -1``, except for ``STOPPED``
        rows, which carry the template-match position).
    filtered_xy : (K, 2) float64
        The filter's position after this frame's update (the prediction when missed).
    predicted_xy : (K, 2) float64
        The prediction made before this frame's update (the gate centre).
    wh : (K, 2) float64
        Box width and height.
    velocity : (K, 2) float64
        Estimated velocity in pixels per frame.
    """

    frame: int
    track_id: IntArray
    state: IntArray
    det_index: IntArray
    measured_xy: FloatArray
    filtered_xy: FloatArray
    predicted_xy: FloatArray
    wh: FloatArray
    velocity: FloatArray

    def __len__(self) -> int:
        return int(self.track_id.shape[0])

    @property
    def tlwh(self) -> FloatArray:
        """Output boxes ``(left, top, width, height)`` centred on the filtered position."""
        return np.hstack([self.filtered_xy - self.wh / 2, self.wh])

    @classmethod
    def empty(cls, frame: int) -> TrackFrame:
        """A frame with no tracks."""
        z1 = np.zeros(0, dtype=np.int64)
        z2 = np.zeros((0, 2))
        return cls(frame, z1, z1.copy(), z1.copy(), z2, z2.copy(), z2.copy(), z2.copy(), z2.copy())


# --------------------------------------------------------------------------- batch states


def _is_batched(value: Any) -> bool:
    return isinstance(value, np.ndarray) and value.ndim >= 1


def take_rows(state: T, idx: np.ndarray) -> T:
    """Rows ``idx`` (int indices or a boolean mask) of every array field of ``state``."""
    changes = {
        f.name: getattr(state, f.name)[idx]
        for f in dataclasses.fields(state)  # type: ignore[arg-type]
        if _is_batched(getattr(state, f.name))
    }
    return dataclasses.replace(state, **changes)  # type: ignore[type-var]


def concat_rows(a: T, b: T) -> T:
    """Rows of ``a`` followed by rows of ``b``; non-array fields are taken from ``a``."""
    changes = {
        f.name: np.concatenate([getattr(a, f.name), getattr(b, f.name)])
        for f in dataclasses.fields(a)  # type: ignore[arg-type]
        if _is_batched(getattr(a, f.name))
    }
    return dataclasses.replace(a, **changes)  # type: ignore[type-var]


def n_rows(state: Any) -> int:
    """Length of the leading dimension of the first array field."""
    for f in dataclasses.fields(state):
        value = getattr(state, f.name)
        if _is_batched(value):
            return int(value.shape[0])
    return 0
