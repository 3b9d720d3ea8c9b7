"""The interface every predictor offers to the tracker.

A predictor is a stateless object (its parameters only); the per-track state is a dataclass
of arrays with a leading batch dimension ``N`` (one row per track), so the tracker can grow and
shrink it with :func:`mvtrack.types.take_rows` and :func:`mvtrack.types.concat_rows`.
Positions are 2-D image coordinates in pixels; time is in frames (Δt = 1 frame): the tracker
converts physical units (seconds, pixels per second) to frames before it builds a predictor.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@runtime_checkable
class Predictor(Protocol):
    """Batched next-position predictor for ``N`` tracks moving in the image plane."""

    #: name under which the tracker knows it (``kalman-ca``, ``kalman-cv``, ...)
    name: str

    def init(self, xy: FloatArray) -> Any:
        """State of ``K`` new tracks whose first measurement is ``xy`` (K, 2)."""
        ...

    def predict(self, state: Any) -> Any:
        """Advance every track one frame (the time update)."""
        ...

    def update(self, state: Any, z: FloatArray, mask: BoolArray) -> Any:
        """Measurement update with ``z`` (N, 2); rows where ``mask`` is False keep the prediction.

        Rows of ``z`` holding NaN are treated as missing whatever ``mask`` says.
        """
        ...

    def position(self, state: Any) -> FloatArray:
        """Current position estimate (N, 2): the prediction after :meth:`predict`, the filtered
        position after :meth:`update`."""
        ...

    def velocity(self, state: Any) -> FloatArray:
        """Current velocity estimate (N, 2), pixels per frame."""
        ...

    def position_cov(self, state: Any) -> FloatArray:
        """Covariance (N, 2, 2) of the current position estimate (P̄ after :meth:`predict`)."""
        ...

    def innovation_cov(self, state: Any) -> FloatArray:
        """Innovation covariance S = H P̄ Hᵀ + R (N, 2, 2) of the next measurement."""
        ...


def check_xy(name: str, xy: FloatArray) -> FloatArray:
    """``xy`` as a float64 array of shape (K, 2) (ValueError otherwise)."""
    a = np.asarray(xy, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 2:
        raise ValueError(f"{name} must have shape (K, 2), got {a.shape}")
    return a


def check_shapes(z: FloatArray, mask: BoolArray, N: int) -> tuple[FloatArray, BoolArray]:
    """``z`` as a float64 array of shape (N, 2) and ``mask`` a boolean array of shape (N,)
    (ValueError otherwise)."""
    z = np.asarray(z, dtype=np.float64)
    if z.shape != (N, 2):
        raise ValueError(f"z must have shape ({N}, 2), got {z.shape}")
    m = np.asarray(mask)
    if m.shape != (N,) or m.dtype != np.bool_:
        raise ValueError(f"mask must be a boolean array of shape ({N},), got {m.shape}")
    return z, m


def check_z_mask(z: FloatArray, mask: BoolArray, N: int) -> tuple[FloatArray, BoolArray]:
    """``z`` (N, 2) and the rows that carry a measurement (mask true and no NaN/inf)."""
    z, m = check_shapes(z, mask, N)
    return z, m & np.isfinite(z).all(axis=1)
