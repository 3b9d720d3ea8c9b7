"""The frame step of the default tracker in two compiled calls.

:class:`~mvtrack.tracking.Tracker` composes a frame from the kernels of the filter, the gate,
the assignment and the life cycle. For the default filter (``kalman-imm`` with its noise in
box sizes, the ``mahalanobis`` gate) these two kernels make that composition in compiled code,
so a frame costs two calls instead of a few dozen array operations — the difference between
0.3 and a few hundredths of a millisecond a frame at a few boxes a frame:

1. :func:`predict_assign`: the IMM's mixing and prediction
   (:func:`mvtrack.filters.imm.imm_predict`), the mixture's moment-matched prediction
   (:func:`~mvtrack.filters.imm.imm_combine`), the gate ``S = P̄ + R``
   (:mod:`mvtrack.association.gate`) and the assignment in two stages by score
   (:func:`mvtrack.association.assign.associate`);
2. :func:`update_commit`: each track's measurement
   (:func:`mvtrack.tracking.lifecycle.measurements`) and its noise, wider for a weak box
   shared with another track (:mod:`mvtrack.association.shared`), the update of each model
   and of the mode probabilities (:func:`~mvtrack.filters.imm.imm_update`), one frame of the
   life cycle with its IDs, rows and births (:func:`mvtrack.tracking.lifecycle.commit`), and
   the new tracks' filters (:meth:`mvtrack.filters.imm.KalmanIMMPredictor.init`).

The rescue of stopped vehicles (template matching) runs between the two, in Python. Nothing
here is a second implementation: each step is the function of its own module, called from here
instead of from Python; ``tests/tracking/test_step.py`` checks that both compositions give the
same tracks.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.assign import associate
from mvtrack.association.shared import measurement_var, shared
from mvtrack.filters.imm import imm_combine, imm_init, imm_predict, imm_update
from mvtrack.jit import kernel
from mvtrack.tracking.lifecycle import P_FPS, W, commit, measurements

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


@kernel
def predict_assign(
    x: FloatArray, P: FloatArray, mu: FloatArray, wh: FloatArray, accel: FloatArray,
    pi: FloatArray, rz: float, dxy: FloatArray, dwh: FloatArray, dclass: NDArray[np.int8],
    gate: float, size_w: float, rule: int, stand: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
           NDArray[np.intp]]:
    """Predict every track and assign the frame's detections.

    ``accel`` (2,): the steady and the manoeuvring acceleration std in box sizes per frame²;
    ``rz``: the measurement std in box sizes. Returns the predicted IMM state (``x``, ``P``,
    ``mu``), the gate centres (N, 2), the gate covariances ``(s_xx, s_xy, s_yy)`` (N, 3),
    the standard deviation of each predicted position (N, 2) and each track's detection;
    ``stand`` as :func:`~mvtrack.association.assign.associate` takes it.
    """
    n = x.shape[0]
    q = np.empty((n, 2, 2))
    for i in range(n):
        for ax in range(2):
            for j in range(2):
                s = accel[j] * wh[i, ax]
                q[i, j, ax] = s * s
    xp, Pp, mp = imm_predict(x, P, mu, q, pi)
    xc, Pc = imm_combine(xp, Pp, mp)
    centre = np.ascontiguousarray(xc[:, :2])
    cov = np.zeros((n, 3))
    std = np.empty((n, 2))
    for i in range(n):
        rx, ry = rz * wh[i, 0], rz * wh[i, 1]
        cov[i, 0] = Pc[i, 0, 0] + rx * rx  # S = P̄ + R
        cov[i, 2] = Pc[i, 1, 0] + ry * ry
        std[i, 0], std[i, 1] = math.sqrt(Pc[i, 0, 0]), math.sqrt(Pc[i, 1, 0])
    no_cost = np.zeros((0, 0))
    det_index = associate(centre, cov, no_cost, wh, dxy, dwh, dclass, gate, size_w, rule,
                          stand)
    return xp, Pp, mp, centre, cov, std, det_index


@kernel
def update_commit(
    xp: FloatArray, Pp: FloatArray, mp: FloatArray, ints: IntArray, floats: FloatArray,
    det_index: NDArray[np.intp], found: BoolArray, found_xy: FloatArray, dxy: FloatArray,
    dwh: FloatArray, dclass: NDArray[np.int8], cscore: FloatArray, std: FloatArray,
    centre: FloatArray, rz: float, speed2: FloatArray, k: int, params: FloatArray,
    next_id: int, next_uid: int, pi: FloatArray, t_shared: float,
):
    """Update every track with its measurement, advance the life cycle and start new tracks.

    ``speed2`` (2,): the velocity prior of a new track, (box sizes/s)² per axis;
    ``t_shared``: the overlap that makes a weak box shared (:mod:`mvtrack.association.shared`).
    Returns the next frame's IMM state and table and the outputs of
    :func:`mvtrack.tracking.lifecycle.commit`.
    """
    z, zwh, zscore, rescued, held = measurements(det_index, dxy, dwh, cscore, found, found_xy)
    wh = np.ascontiguousarray(floats[:, W:W + 2])
    r = measurement_var(rz, wh, shared(det_index, centre, wh, dxy, dwh, dclass, t_shared),
                        t_shared)
    xu, Pu, mu = imm_update(xp, Pp, mp, z, held, r)  # eqs. (3)–(5) per model, and μ
    xc, _ = imm_combine(xu, Pu, mu)
    out = commit(ints, floats, det_index, rescued, z, zwh, zscore, std, centre,
                 np.ascontiguousarray(xc[:, :2]), np.ascontiguousarray(xc[:, 2:]), dxy, dwh,
                 dclass, cscore, k, params, next_id, next_uid)
    keep, new = out[2], out[3]
    kk, b = keep.size, new.size
    x2 = np.empty((kk + b, 2, 4))
    P2 = np.empty((kk + b, 2, 2, 3))
    mu2 = np.empty((kk + b, 2))
    for a in range(kk):
        x2[a], P2[a], mu2[a] = xu[keep[a]], Pu[keep[a]], mu[keep[a]]
    f = 1.0 / params[P_FPS]
    xy = np.empty((b, 2))
    r0 = np.empty((b, 2))
    vv = np.empty((b, 2))
    for e in range(b):
        j = new[e]
        for ax in range(2):
            xy[e, ax] = dxy[j, ax]
            s = rz * dwh[j, ax]
            r0[e, ax] = s * s  # P₀ = diag(r, σ_v² (wh / fps)²)
            t = f * dwh[j, ax]
            vv[e, ax] = speed2[ax] * (t * t)
    xb, Pb, mb = imm_init(xy, r0, vv, pi)
    for e in range(b):
        x2[kk + e], P2[kk + e], mu2[kk + e] = xb[e], Pb[e], mb[e]
    return (x2, P2, mu2, *out)
