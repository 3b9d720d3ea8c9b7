"""What association knows about the predicted tracks (:class:`TrackView`) and the detections."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.types import Detections

FloatArray = NDArray[np.float64]

__all__ = ["TrackView", "det_arrays"]


@dataclass(frozen=True)
class TrackView:
    """What association needs to know about ``N`` predicted tracks.

    Attributes
    ----------
    xy : (N, 2) float64
        Predicted positions (x̄, ȳ), the gate centres.
    cov : (N, 2, 2) float64
        Predicted position covariance P̄ (paper 2's P̄x, P̄y are its diagonal).
    S : (N, 2, 2) float64
        Innovation covariance S = H P̄ Hᵀ + R.
    velocity : (N, 2) float64
        Predicted velocity (v̄x, v̄y) in pixels per frame.
    wh : (N, 2) float64
        Box width and height in pixels (zeros for point targets).
    """

    xy: FloatArray
    cov: FloatArray
    S: FloatArray
    velocity: FloatArray
    wh: FloatArray

    def __post_init__(self) -> None:
        xy = np.asarray(self.xy, dtype=np.float64).reshape(-1, 2)
        n = xy.shape[0]
        shapes = {"cov": (n, 2, 2), "S": (n, 2, 2), "velocity": (n, 2), "wh": (n, 2)}
        object.__setattr__(self, "xy", xy)
        for name, shape in shapes.items():
            arr = np.asarray(getattr(self, name), dtype=np.float64)
            if arr.shape != shape:
                raise ValueError(f"TrackView.{name} must have shape {shape}, got {arr.shape}")
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.xy.shape[0])

    @classmethod
    def from_arrays(
        cls,
        xy: FloatArray,
        *,
        cov: FloatArray | float | None = None,
        S: FloatArray | float | None = None,
        velocity: FloatArray | None = None,
        wh: FloatArray | None = None,
    ) -> TrackView:
        """Build a view, broadcasting scalars: ``cov=1.0`` means P̄ = I for every track.

        Missing ``cov`` defaults to the identity, missing ``S`` to ``cov``, missing ``velocity``
        and ``wh`` to zeros.
        """
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        n = xy.shape[0]

        def _cov(value: Any, default: FloatArray) -> FloatArray:
            if value is None:
                return default
            arr = np.asarray(value, dtype=np.float64)
            if arr.ndim == 0:
                return np.broadcast_to(arr * np.eye(2), (n, 2, 2)).copy()
            return np.broadcast_to(arr, (n, 2, 2)).copy()

        cov_a = _cov(cov, np.broadcast_to(np.eye(2), (n, 2, 2)).copy())
        s_a = _cov(S, cov_a.copy())
        vel = np.zeros((n, 2)) if velocity is None else np.broadcast_to(velocity, (n, 2))
        box = np.zeros((n, 2)) if wh is None else np.broadcast_to(wh, (n, 2))
        return cls(xy, cov_a, s_a, np.array(vel, dtype=np.float64), np.array(box, np.float64))

    @classmethod
    def from_predictor(cls, predictor: Any, state: Any, wh: FloatArray) -> TrackView:
        """The view of predicted tracks from a :class:`mvtrack.filters.base.Predictor`."""
        return cls(
            predictor.position(state),
            predictor.position_cov(state),
            predictor.innovation_cov(state),
            predictor.velocity(state),
            wh,
        )


def det_arrays(dets: Detections | FloatArray) -> tuple[FloatArray, FloatArray]:
    """Centres (M, 2) and sizes (M, 2) of ``dets`` (a :class:`Detections` or an (M, 2) array)."""
    if isinstance(dets, Detections):
        return dets.xy, dets.wh
    xy = np.asarray(dets, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"dets must be Detections or an (M, 2) array, got shape {xy.shape}")
    return xy, np.zeros_like(xy)
