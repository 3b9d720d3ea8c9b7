"""Linear motion models for the Kalman filter: F, H, Q, R of paper 1 eqs. (1)–(2) and (8)–(9).

Every model is a :class:`LinearModel` of plain NumPy matrices. Per-axis models (constant
acceleration, constant velocity) describe one image axis; the tracker runs x and y as two
independent filters of the same model (SPEC §1.1: "predictors run independently per axis").
The coupled model holds x and y in one state with a 2-D measurement.

Units are whatever the caller uses consistently: the tracker uses pixels and frames
(Δt = 1 frame), the 1-D experiment of paper 1 metres and seconds (Δt = 1/30 s, E1.7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from mvtrack.filters.base import FloatArray

__all__ = [
    "LinearModel",
    "check_positive",
    "constant_acceleration",
    "constant_velocity",
    "coupled",
]


def check_positive(name: str, value: float) -> float:
    """``value`` as a float if it is finite and > 0, else a ValueError naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return v


@dataclass(frozen=True)
class LinearModel:
    """A linear Gaussian state-space model, eqs. (1)–(2) of paper 1.

    .. math::
        x_{k+1} = F x_k + w_k,\\; w_k \\sim N(0, Q) \\quad (1) \\qquad
        z_k = H x_k + v_k,\\; v_k \\sim N(0, R) \\quad (2)

    (The paper calls the transition matrix ``A``.)

    Attributes
    ----------
    F : ndarray (n, n)
        State transition matrix.
    H : ndarray (m, n)
        Measurement matrix.
    Q : ndarray (n, n)
        Process noise covariance (symmetric positive semi-definite).
    R : ndarray (m, m)
        Measurement noise covariance (symmetric positive definite).

    Raises
    ------
    ValueError
        If a matrix has the wrong shape, holds NaN/inf, or Q/R are not symmetric, Q is not
        positive semi-definite or R is not positive definite.
    """

    F: FloatArray
    H: FloatArray
    Q: FloatArray
    R: FloatArray

    def __post_init__(self) -> None:
        mats = {}
        for name in ("F", "H", "Q", "R"):
            a = np.array(getattr(self, name), dtype=np.float64)
            if a.ndim != 2:
                raise ValueError(f"{name} must be a 2-D matrix, got shape {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{name} holds NaN or infinite values")
            a.setflags(write=False)
            mats[name] = a
        n = mats["F"].shape[0]
        m = mats["H"].shape[0]
        if mats["F"].shape != (n, n):
            raise ValueError(f"F must be square, got shape {mats['F'].shape}")
        if mats["H"].shape != (m, n):
            raise ValueError(f"H must have shape (m, {n}), got {mats['H'].shape}")
        if mats["Q"].shape != (n, n):
            raise ValueError(f"Q must have shape ({n}, {n}), got {mats['Q'].shape}")
        if mats["R"].shape != (m, m):
            raise ValueError(f"R must have shape ({m}, {m}), got {mats['R'].shape}")
        for name in ("Q", "R"):
            a = mats[name]
            if not np.allclose(a, a.T, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(a).max())):
                raise ValueError(f"{name} must be symmetric")
        tol = 1e-12 * max(1.0, float(np.abs(mats["Q"]).max()))
        if np.linalg.eigvalsh(mats["Q"]).min() < -tol:
            raise ValueError("Q must be positive semi-definite")
        if np.linalg.eigvalsh(mats["R"]).min() <= 0.0:
            raise ValueError("R must be positive definite")
        for name, a in mats.items():
            object.__setattr__(self, name, a)

    @property
    def n(self) -> int:
        """State dimension."""
        return int(self.F.shape[0])

    @property
    def m(self) -> int:
        """Measurement dimension."""
        return int(self.H.shape[0])


def constant_acceleration(dt: float = 1.0, q: float = 0.5, r: float = 5.0) -> LinearModel:
    """Per-axis constant-acceleration model, eqs. (8)–(9) of paper 1.

    State ``[p, v, a]`` (position, velocity, acceleration) of one axis.

    .. math::
        x_{k+1} = \\begin{bmatrix}1&\\Delta t&\\Delta t^2/2\\\\0&1&\\Delta t\\\\0&0&1
        \\end{bmatrix} x_k + G w_k,\\; G = [0, 0, 1]^T \\quad (8) \\qquad
        y_k = [1\\,0\\,0] x_k + v_k \\quad (9)

    so ``Q = G q Gᵀ = diag(0, 0, q)`` (E1.7) and ``R = [[r]]``.

    Parameters
    ----------
    dt : float
        Sampling interval Δt (> 0).
    q : float
        Process-noise variance of the acceleration increment (paper: 0.5).
    r : float
        Measurement-noise variance (paper: 5).
    """
    dt = check_positive("dt", dt)
    q = check_positive("q", q)
    r = check_positive("r", r)
    F = np.array([[1.0, dt, 0.5 * dt * dt], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])  # eq. (8)
    G = np.array([[0.0], [0.0], [1.0]])  # eq. (8)
    H = np.array([[1.0, 0.0, 0.0]])  # eq. (9)
    return LinearModel(F=F, H=H, Q=G @ G.T * q, R=np.array([[r]]))


def constant_velocity(dt: float = 1.0, q: float = 0.5, r: float = 5.0) -> LinearModel:
    """Per-axis constant-velocity model (white-noise acceleration), state ``[p, v]``.

    .. math::
        x_{k+1} = \\begin{bmatrix}1&\\Delta t\\\\0&1\\end{bmatrix} x_k + G w_k,\\quad
        G = [\\Delta t^2/2,\\; \\Delta t]^T,\\quad Q = G q G^T,\\quad H = [1\\,0]

    The acceleration acts as white noise of variance ``q`` per step (the discrete white-noise
    acceleration model); this is the CV analogue of eqs. (8)–(9) of paper 1.

    Parameters
    ----------
    dt, q, r : float
        Sampling interval, acceleration-noise variance, measurement-noise variance (all > 0).
    """
    dt = check_positive("dt", dt)
    q = check_positive("q", q)
    r = check_positive("r", r)
    F = np.array([[1.0, dt], [0.0, 1.0]])
    G = np.array([[0.5 * dt * dt], [dt]])
    H = np.array([[1.0, 0.0]])
    return LinearModel(F=F, H=H, Q=G @ G.T * q, R=np.array([[r]]))


def coupled(
    kind: Literal["cv", "ca"] = "cv", dt: float = 1.0, q: float = 0.5, r: float = 5.0
) -> LinearModel:
    """Coupled 2-D model: x and y in one state with a 2-D measurement ``[x, y]``.

    The state is ordered by derivative, then axis: ``[x, y, vx, vy]`` for ``kind="cv"`` and
    ``[x, y, vx, vy, ax, ay]`` for ``kind="ca"``, i.e. ``F = F_axis ⊗ I₂``,
    ``Q = Q_axis ⊗ I₂``, ``H = [I₂ 0]``, ``R = r I₂``. The model itself is separable; the
    state covariance of a filter using it is a full 2-D covariance, which is what the
    coupled confidence region of paper 2 (SPEC §2) needs.

    Parameters
    ----------
    kind : {"cv", "ca"}
        Per-axis dynamics: constant velocity or constant acceleration (eq. (8) of paper 1).
    dt, q, r : float
        As in :func:`constant_velocity` / :func:`constant_acceleration`.
    """
    if kind == "cv":
        axis = constant_velocity(dt, q, r)
    elif kind == "ca":
        axis = constant_acceleration(dt, q, r)
    else:
        raise ValueError(f"kind must be 'cv' or 'ca', got {kind!r}")
    eye = np.eye(2)
    return LinearModel(
        F=np.kron(axis.F, eye),
        H=np.kron(axis.H, eye),
        Q=np.kron(axis.Q, eye),
        R=np.kron(axis.R, eye),
    )
