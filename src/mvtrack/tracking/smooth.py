"""Offline smoothing of each track: the Rauch–Tung–Striebel fixed-interval smoother.

Online, a row can only use the measurements up to its frame: the filtered position and the
running box size lag behind a walker that turns, and one detection twice too wide moves the
box for a frame or two. Offline every measurement of the track is known, so each row gets the
smoothed estimate from all of them (Rauch, Tung & Striebel 1965), with the tracker's own noise:

- **position**, per axis, a constant-velocity model in continuous time with white
  acceleration over the ``Δt`` seconds between two rows, measured with
  ``R = (measurement_noise · w)²`` (``w`` the track's box along the axis):

  ``F = [[1, Δt], [0, 1]]``,  ``Q = q² [[Δt³/3, Δt²/2], [Δt²/2, Δt]]``,

  where the acceleration is that of the online ``kalman-imm``'s two modes, steady
  (``a_1 = accel_noise``) and manoeuvring (``a_2 = manoeuvre_noise``, box sizes/s²), each
  row weighing them by their probability given its measurement: the modes switch as a
  Markov chain with the mean times ``τ_m`` of :data:`~mvtrack.tracking.config.MODE_TIMES`,

  ``μ̄_m = μ_m e^{−Δt/τ_m} + μ_{m'} (1 − e^{−Δt/τ_{m'}})`` (from the stationary
  ``μ_m = τ_m / Σ τ`` at a track's first row),

  each mode explains the innovation ``e = z − H F x`` on both axes with
  ``S_m = H (F P Fᵀ + Q_m) Hᵀ + R``,

  ``μ_m ∝ μ̄_m Π_axes N(e; 0, S_m)``,  ``q² = (Σ_m μ_m a_m²) w²``

  (the two modes' ``Q`` moment-matched, as the online filter's gate matches their
  covariances). A track that walks steadily is smoothed with the steady mode's stiffness; a
  car that brakes, or a track that jumps to its neighbour at a low frame rate, is not
  smeared over the rows around the jump;

- **box size**, ``ln w`` and ``ln h``, a random walk of :data:`SIZE_DRIFT` per √s measured
  with the detection's box, ``R = measurement_noise²`` (a box off by a tenth of its size).

Forward (the Kalman filter), for a row ``k`` with a measurement ``z``:

``x̄_k = F x_{k−1}``,  ``P̄_k = F P_{k−1} Fᵀ + Q``,  ``K = P̄_k Hᵀ (H P̄_k Hᵀ + R)⁻¹``,
``x_k = x̄_k + K (z − H x̄_k)``,  ``P_k = (I − K H) P̄_k``;

backward, from the last row of the track:

``C_k = P_k Fᵀ P̄_{k+1}⁻¹``,  ``x̂_k = x_k + C_k (x̂_{k+1} − x̄_{k+1})``.

The tracks are processed together, one row of every track per step (a track's ``j``-th row
with all others' ``j``-th), so the cost is a few array operations per row of the longest
track, whatever the number of tracks.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.tracking.config import MODE_TIMES, TrackerConfig
from mvtrack.tracking.log import concat_rows, split_rows
from mvtrack.types import TrackFrame

FloatArray = NDArray[np.float64]

#: σ_s, std of the random walk of ``ln`` box size, per √s: a walker's box changes by about
#: a tenth of its size in a second as it nears or leaves the camera; chosen by leave-one-out
#: over the frame-rate sweep (``docs/bench/framerate.md``)
SIZE_DRIFT = 0.1


def smooth_tracks(frames: list[TrackFrame], sizes: list[FloatArray],
                  config: TrackerConfig) -> list[TrackFrame]:
    """Every row's position, velocity and box replaced by its track's smoothed estimate.

    Parameters
    ----------
    frames : list of TrackFrame
        A run's output, in increasing frame order.
    sizes : list of (N_k, 2) float arrays
        Each row's detection box ``(w, h)``; NaN for a row without detection.
    config : TrackerConfig
        ``fps``, ``measurement_noise``, ``accel_noise``, ``manoeuvre_noise`` and
        ``velocity_prior``.

    Returns
    -------
    list of TrackFrame
        The same rows (IDs, states, detections and measurements unchanged) with
        ``filtered_xy``, ``velocity`` (px/frame) and ``wh`` smoothed; rows without a
        public ID (tentative tracks) are left as they are.
    """
    if not frames:
        return []
    c = concat_rows(frames)
    uid = c["track_id"]
    order = np.flatnonzero(uid > 0)
    if order.size == 0:
        return list(frames)
    order = order[np.lexsort((c["frame"][order], uid[order]))]  # by track, then frame
    u = uid[order]
    first = np.concatenate([[True], u[1:] != u[:-1]])
    starts = np.flatnonzero(first)
    lengths = np.diff(np.concatenate([starts, [u.size]]))
    rank = np.empty(lengths.size, np.int64)  # the longest track first
    rank[np.argsort(-lengths, kind="stable")] = np.arange(lengths.size)
    track = np.cumsum(first) - 1
    step = np.arange(u.size) - starts[track]  # each row's place in its track
    # step-major: the j-th rows of all tracks in one slice, longest track first, so that the
    # tracks with a j-th row are a prefix of those with a (j − 1)-th
    order = order[np.lexsort((rank[track], step))]
    n_at = np.bincount(step)
    off = np.concatenate([[0], np.cumsum(n_at)])

    t = c["frame"][order] / config.fps  # seconds
    w = c["wh"][order]  # the tracker's box: the scale of the noise
    z = c["measured_xy"][order]
    zs = np.log(np.concatenate(sizes)[order])
    has_z = np.isfinite(z).all(axis=1)[:, None]
    has_s = np.isfinite(zs).all(axis=1)[:, None]
    sz = config.measurement_noise
    accel = np.array([config.accel_noise, config.manoeuvre_noise])
    taus = np.asarray(MODE_TIMES, dtype=float)
    mu = np.empty((order.size, 2))  # each row's weight of the steady and manoeuvring mode
    mu[:n_at[0]] = taus / taus.sum()  # the stationary weights

    # forward: filtered (x, v, P00, P01, P11) and predicted, per row and axis; size (s, Ps)
    shape = (order.size, 2)
    x, v, p00, p01, p11 = (np.empty(shape) for _ in range(5))
    xb, vb, b00, b01, b11 = (np.empty(shape) for _ in range(5))
    s, ps, sb, psb = (np.empty(shape) for _ in range(4))
    r = slice(0, n_at[0])
    x[r] = np.where(has_z[r], z[r], c["filtered_xy"][order][r])
    v[r] = 0.0
    p00[r] = (sz * w[r]) ** 2
    p01[r] = 0.0
    p11[r] = (config.velocity_prior * w[r]) ** 2  # a new track's velocity
    s[r] = np.where(has_s[r], zs[r], np.log(w[r]))
    ps[r] = sz**2
    for j in range(1, n_at.size):
        r = slice(off[j], off[j] + n_at[j])  # this step's rows
        q = slice(off[j - 1], off[j - 1] + n_at[j])  # the same tracks' rows before
        dt = (t[r] - t[q])[:, None]
        xb[r] = x[q] + dt * v[q]  # x̄ = F x
        vb[r] = v[q]
        c00 = p00[q] + 2 * dt * p01[q] + dt**2 * p11[q]  # F P Fᵀ
        m = has_z[r]
        rr = (sz * w[r]) ** 2
        e = np.where(m, z[r] - xb[r], 0.0)
        # the two modes' a priori weights over dt, then their likelihoods of the innovation
        # (both axes): the weight of each mode's Q given this row's measurement
        stay = np.exp(-dt / taus)  # (n, 2): each mode kept over Δt
        prior = mu[q] * stay + mu[q][:, ::-1] * (1 - stay[:, ::-1])  # Markov switching
        # S_m = H P̄_m Hᵀ + R per row, axis and mode; log N(e; 0, S_m) summed over the axes
        sm = (c00 + rr)[:, :, None] + (w[r] ** 2 * dt**3 / 3)[:, :, None] * accel**2
        ll = np.where(m[:, :, None], -0.5 * (e[:, :, None] ** 2 / sm + np.log(sm)), 0.0)
        ll = ll.sum(axis=1)
        post = prior * np.exp(ll - ll.max(axis=1, keepdims=True))
        mu[r] = post / post.sum(axis=1, keepdims=True)
        a2 = (mu[r] @ accel**2)[:, None] * w[r] ** 2  # Q of the modes, moment-matched
        b00[r] = c00 + a2 * dt**3 / 3  # P̄ = F P Fᵀ + Q
        b01[r] = p01[q] + dt * p11[q] + a2 * dt**2 / 2
        b11[r] = p11[q] + a2 * dt
        sb[r], psb[r] = s[q], ps[q] + SIZE_DRIFT**2 * dt
        gain = b00[r] + rr  # H P̄ Hᵀ + R
        k0 = np.where(m, b00[r] / gain, 0.0)  # K = P̄ Hᵀ / (H P̄ Hᵀ + R); 0 without z
        k1 = np.where(m, b01[r] / gain, 0.0)
        x[r] = xb[r] + k0 * e
        v[r] = vb[r] + k1 * e
        p00[r] = b00[r] - k0 * b00[r]  # P = (I − K H) P̄
        p01[r] = b01[r] - k0 * b01[r]
        p11[r] = b11[r] - k1 * b01[r]
        g = np.where(has_s[r], psb[r] / (psb[r] + sz**2), 0.0)
        s[r] = sb[r] + g * np.where(has_s[r], zs[r] - sb[r], 0.0)
        ps[r] = (1 - g) * psb[r]

    # backward: x̂ = x + C (x̂' − x̄'), C = P Fᵀ P̄'⁻¹ (' the next row of the track)
    for j in range(n_at.size - 2, -1, -1):
        r = slice(off[j], off[j] + n_at[j + 1])  # the rows with a next one
        q = slice(off[j + 1], off[j + 1] + n_at[j + 1])
        dt = (t[q] - t[r])[:, None]
        f00, f01 = p00[r] + dt * p01[r], p01[r]  # P Fᵀ
        f10, f11 = p01[r] + dt * p11[r], p11[r]
        det = b00[q] * b11[q] - b01[q] ** 2
        i00, i01, i11 = b11[q] / det, -b01[q] / det, b00[q] / det  # P̄'⁻¹
        ex, ev = x[q] - xb[q], v[q] - vb[q]
        x[r] += (f00 * i00 + f01 * i01) * ex + (f00 * i01 + f01 * i11) * ev
        v[r] += (f10 * i00 + f11 * i01) * ex + (f10 * i01 + f11 * i11) * ev
        s[r] += ps[r] / psb[q] * (s[q] - sb[q])

    c["filtered_xy"][order] = x
    c["velocity"][order] = v / config.fps  # px/frame
    c["wh"][order] = np.exp(s)
    return split_rows(frames, c, np.ones(uid.size, bool))

