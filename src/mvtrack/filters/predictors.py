"""The predictors the tracker uses, by name (:data:`mvtrack.registry.PREDICTORS`).

Each class implements :class:`mvtrack.filters.base.Predictor`: a stateless object holding
parameters, and a per-track state that is a frozen dataclass of arrays with leading dimension
``N`` (one row per track), so :func:`mvtrack.types.take_rows` /
:func:`mvtrack.types.concat_rows` grow and shrink it. Units are pixels and frames (Δt = 1 frame).

=================  ==========================================================================
name               method
=================  ==========================================================================
``kalman-ca``      per-axis constant-acceleration KF, paper 1 eqs. (3)–(9)
                   (:mod:`mvtrack.filters.axis_kalman`)
``kalman-cv``      per-axis constant-velocity KF in closed form (:mod:`mvtrack.filters.cv`)
``kalman-coupled`` one 2-D KF per track, x and y in one state (full 2×2 position covariance)
                   (:mod:`mvtrack.filters.coupled_kalman`)
``rls``            per-axis RLS adaptive transversal predictor, paper 1 eqs. (10)–(15)
                   (:mod:`mvtrack.filters.rls_predictor`)
``structured``     paper 3's structured KF over body parts (:mod:`mvtrack.filters.structured`)
=================  ==========================================================================

Per-axis filters run x and y as two filters of the same model (SPEC §1.1); their state holds
both axes in one array (``x`` of shape (N, 2, n)), so all tracks and both axes are advanced by
one vectorised call — no Python loop over tracks.

Initial covariances (documented reconstruction choices, SPEC E1.11): a new track starts at its
first measurement with zero velocity (and acceleration), and
``P₀ = diag(r, vel_var[, acc_var])`` per axis: the position is known to the measurement
variance ``r``, the velocity to ``vel_var`` (default 25 px²/frame², a 5 px/frame standard
deviation), the acceleration to ``acc_var`` (default 1 px²/frame⁴).
"""

from __future__ import annotations

from typing import Any

from mvtrack import registry
from mvtrack.filters.axis_kalman import AxisKalmanState, KalmanCAPredictor, PerAxisKalmanPredictor
from mvtrack.filters.base import Predictor
from mvtrack.filters.coupled_kalman import CoupledKalmanPredictor, KalmanState
from mvtrack.filters.cv import CVState, KalmanCVPredictor
from mvtrack.filters.rls_predictor import RLSPredictor, RLSPredictorState

__all__ = [
    "PREDICTORS",
    "AxisKalmanState",
    "CVState",
    "CoupledKalmanPredictor",
    "KalmanCAPredictor",
    "KalmanCVPredictor",
    "KalmanState",
    "PerAxisKalmanPredictor",
    "RLSPredictor",
    "RLSPredictorState",
    "make_predictor",
]

#: the predictor names, in the order of :data:`mvtrack.registry.PREDICTORS`
PREDICTORS = tuple(registry.PREDICTORS)


def make_predictor(name: str, **params: Any) -> Predictor:
    """The predictor called ``name`` with constructor parameters ``params``.

    Parameters
    ----------
    name : str
        A name of :data:`mvtrack.registry.PREDICTORS` (``structured`` included).
    **params
        Keyword arguments of its class.

    Returns
    -------
    Predictor

    Raises
    ------
    ValueError
        If ``name`` is unknown (the message lists the known names) or a parameter is bad.
    """
    registry.check("predictor", name, registry.PREDICTORS)
    build = registry.load(registry.PREDICTORS[name])
    try:
        return build(**params)  # type: ignore[no-any-return]
    except TypeError as exc:
        raise ValueError(f"bad parameters for predictor {name!r}: {exc}") from None
