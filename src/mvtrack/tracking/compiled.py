"""The tracker's frame step compiled (numba) for small frames: predict, all association
stages, the measurement update and the life-cycle states in one call.

At the densities of the MOTChallenge sequences (4–10 boxes a frame) the NumPy step
(:meth:`mvtrack.tracking.tracker.Tracker.step`) spends its time in the number of array calls,
about 200 of them a frame, not in arithmetic. :func:`frame_step` does the same work as loops
over the ``N × M`` pairs in one compiled call. It computes what the NumPy step computes, in the
same floating-point operations in the same order, so the two give the same tracks
(``tests/tracking/test_compiled.py`` runs both side by side):

1. predict, eqs. (6)–(7) of paper 1 in the closed form of :mod:`mvtrack.filters.cv`;
2. the gate centres and size factors ``f² = max(1, (w, h)² / size_ref²)``
   (:func:`mvtrack.association.gating.size_factors2`) with ``r f²`` per track;
3. the first and second Euclidean stages of :func:`mvtrack.association.discs.dense_two_stage`
   with the size term, the size gate and its partial views
   (:func:`~mvtrack.association.discs.size_apart`,
   :func:`~mvtrack.association.discs.partial_views`);
4. the recovery stage and the low-score stage of :class:`mvtrack.tracking.stages.Associator`;
5. the low-score births (:func:`mvtrack.tracking.scores.isolated`);
6. the measurement update, eqs. (3)–(5) of paper 1, with the partial views completed
   (:meth:`Tracker._complete_partial`), and the table's counters, last measurements and box
   sizes;
7. the next states, deletions and confirmations (:func:`mvtrack.tracking.lifecycle.next_state`).

A component of the gate graph in which a track or a detection has two gated partners is
solved by SciPy's ``linear_sum_assignment`` on the same matrix the NumPy step gives it (a
call back into Python; about one frame in ten on MOT15). The tracker uses this step when its
settings are ones it covers (:func:`covers`) and the frame is small (``N × M`` at most
:data:`mvtrack.association.discs.DENSE_LSA`); otherwise, and when numba is not installed, the
NumPy step runs.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.lifecycle import COASTING, CONFIRMED, TENTATIVE
from mvtrack.tracking.table import AGE, HITS, LAST_K, MISSES, PREV_K, STATE

try:  # numba is a dependency; without it (an unusual platform) the NumPy step runs
    from numba import njit, objmode
except ImportError:  # pragma: no cover - exercised only where numba is missing
    njit = objmode = None

__all__ = ["available", "covers", "frame_step"]

# The table's columns and the states are frozen into the compiled code; numba's cache sees
# changes to this file only, so after changing them in table.py or lifecycle.py delete the
# cache (__pycache__/compiled.*.nbi, .nbc) — tests/tracking/test_compiled.py fails until then.


def available() -> bool:
    """Whether numba is installed."""
    return njit is not None


def covers(config: TrackerConfig, predictor: Any) -> bool:
    """Whether :func:`frame_step` computes the step of ``config``: the closed-form
    ``kalman-cv`` predictor, the Euclidean distance without parameters and the ``optimal``
    rule (the tracker's default family), no warm-up centre and no standing test."""
    from mvtrack.filters.cv import KalmanCVPredictor

    return (
        available()
        and type(predictor) is KalmanCVPredictor
        and float(predictor._Ft[2, 0]) == 1.0  # one frame per step
        and config.distance == "euclidean"
        and not config.distance_params
        and config.assign == "optimal"
        and not config.assign_params
        and not config.frames().warmup_hits
        and config.stopped_margin is None
    )


def _lsa_py(cost: NDArray[np.float64]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``linear_sum_assignment(cost)`` as ``intp`` arrays (what the compiled code expects)."""
    rows, cols = linear_sum_assignment(cost)
    return rows.astype(np.intp), cols.astype(np.intp)


#: positions in the float parameters of :func:`frame_step` (:func:`params`)
(_QA, _QB, _QC, _R, _VEL_VAR, _REF, _INV_REF2, _GATE, _GATE2, _SIZE_W, _RHO, _EPS,
 _REC_SPEED, _REC_MARGIN, _LOW_IOU, _SMOOTH, _FRAME_W, _FRAME_H) = range(18)
#: positions in the integer parameters
(_REC_WINDOW, _REC_HITS, _LOW_TENTATIVE, _CONFIRM_HITS, _CONFIRM_WINDOW, _TENT_MISSES,
 _MAX_MISSES) = range(7)


def params(config: TrackerConfig, associator: Any, predictor: Any
           ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The settings :func:`frame_step` reads, as a float and an integer array (a setting that
    is off is −1)."""
    a, fp = associator, config.frames()

    def off(v: Any) -> float:
        return -1.0 if v is None else float(v)

    size = config.frame_size
    f = np.array([
        *predictor._qvec, predictor.r, predictor.vel_var, off(a.ref), off(a._inv_ref2),
        a._gate, off(a._gate2), a._size_w, off(a._size_gate), off(a.partial),
        off(fp.recover_speed), config.recover_margin, off(config.low_birth_iou),
        config.size_smoothing, off(None if size is None else size[0]),
        off(None if size is None else size[1]),
    ])
    i = np.array([
        fp.recover_window, a._recover_hits, int(config.low_tentative), fp.confirm_hits,
        fp.confirm_window, fp.tentative_max_misses, fp.max_misses,
    ], dtype=np.int64)
    return f, i


if njit is not None:

    @njit(cache=True)
    def _lsa(cost):  # pragma: no cover - compiled
        """SciPy's ``linear_sum_assignment`` (a call back into Python)."""
        with objmode(rows="intp[:]", cols="intp[:]"):
            rows, cols = _lsa_py(cost)
        return rows, cols

    @njit(cache=True)
    def _take(a, idx, c0, c1):  # pragma: no cover - compiled
        """Rows ``idx`` of columns ``c0:c1`` of ``a``, a new contiguous array."""
        out = np.empty((idx.size, c1 - c0))
        for r in range(idx.size):
            for c in range(c0, c1):
                out[r, c - c0] = a[idx[r], c]
        return out

    @njit(cache=True)
    def _apart(tw, th, dw, dh, limit):  # pragma: no cover - compiled
        """:func:`mvtrack.association.discs.size_apart` for one pair (``limit = ln ρ``; NaN
        sizes are never apart)."""
        a = abs(math.log(dw) - math.log(tw)) * 0.5
        b = abs(math.log(dh) - math.log(th))
        return a == a and b == b and max(a, b) > limit

    @njit(cache=True)
    def _partial(tw, th, dw, dh, dx, dy, eps):  # pragma: no cover - compiled
        """:func:`mvtrack.association.discs.partial_views` for one pair."""
        return (abs(dy + 0.5 * (dh - th)) <= eps * th and dh < th
                and abs(dx) + 0.5 * dw <= (0.5 + 0.5 * eps) * tw)

    @njit(cache=True)
    def _costs(txy, dxy, scale, axis, twh, dwh, rho, eps, reach):  # pragma: no cover
        """Gate costs of every track × detection pair, ``inf`` where the size gate refuses.

        ``axis``: ``Δx²/s_x + Δy²/s_y`` with ``scale`` (N, 2) (the Euclidean stages, eq. (8)
        of paper 2 over the size factors), else ``(Δx² + Δy²)/s`` with ``s = scale[:, 0]``
        (the recovery stage). The size gate of factor ``rho`` (≤ 0: none) lets the partial
        views of tolerance ``eps`` (< 0: none) through among the pairs with cost ≤ ``reach``
        (``discs._mask_apart``)."""
        n, m = txy.shape[0], dxy.shape[0]
        cost = np.empty((n, m))
        limit = math.log(rho) if rho > 0 else 0.0
        for i in range(n):
            for j in range(m):
                dx = dxy[j, 0] - txy[i, 0]
                dy = dxy[j, 1] - txy[i, 1]
                if axis:
                    c = dx * dx / scale[i, 0] + dy * dy / scale[i, 1]
                else:
                    c = (dx * dx + dy * dy) / scale[i, 0]
                if rho > 0 and _apart(twh[i, 0], twh[i, 1], dwh[j, 0], dwh[j, 1], limit):
                    if not (eps >= 0 and c <= reach and _partial(
                            twh[i, 0], twh[i, 1], dwh[j, 0], dwh[j, 1], dx, dy, eps)):
                        c = np.inf
                cost[i, j] = c
        return cost

    @njit(cache=True)
    def _solve(cost, ti, dj, gate, weight, twh, dwh, sx):  # pragma: no cover - compiled
        """The optimal pairs among tracks ``ti`` and detections ``dj`` of ``cost``
        (``discs.dense_optimal`` from its gated matrix): every gated pair when each track and
        detection has at most one (``discs._isolated``, pairs in row-major order), else one
        ``linear_sum_assignment`` of ``cost + weight · min(s, gate)`` (``s`` the size
        difference over the size factors ``sx``; ``weight`` 0: none), ``2 gate`` where not
        gated. Returns the rows of ``cost`` matched and their columns."""
        n, m = ti.size, dj.size
        rdeg = np.zeros(n, dtype=np.intp)
        cdeg = np.zeros(m, dtype=np.intp)
        lone = True
        count = 0
        for a in range(n):
            for b in range(m):
                if cost[ti[a], dj[b]] <= gate:
                    rdeg[a] += 1
                    cdeg[b] += 1
                    count += 1
                    if rdeg[a] > 1 or cdeg[b] > 1:
                        lone = False
        if lone:
            rows = np.empty(count, dtype=np.intp)
            cols = np.empty(count, dtype=np.intp)
            t = 0
            for a in range(n):
                for b in range(m):
                    if cost[ti[a], dj[b]] <= gate:
                        rows[t] = ti[a]
                        cols[t] = dj[b]
                        t += 1
            return rows, cols
        u = 2.0 * gate
        full = np.empty((n, m))
        for a in range(n):
            i = ti[a]
            for b in range(m):
                j = dj[b]
                c = cost[i, j]
                if not c <= gate:
                    full[a, b] = u
                elif weight != 0.0:  # discs._add_size over discs._size_matrix
                    p = dwh[j, 0] - twh[i, 0]
                    q = dwh[j, 1] - twh[i, 1]
                    s = p * p / sx[i, 0] + q * q / sx[i, 1]
                    full[a, b] = c + weight * min(s, gate)
                else:
                    full[a, b] = c
        r, c2 = _lsa(full)
        keep = 0
        for t in range(r.size):
            if full[r[t], c2[t]] < u:
                keep += 1
        rows = np.empty(keep, dtype=np.intp)
        cols = np.empty(keep, dtype=np.intp)
        keep = 0
        for t in range(r.size):
            if full[r[t], c2[t]] < u:
                rows[keep] = ti[r[t]]
                cols[keep] = dj[c2[t]]
                keep += 1
        return rows, cols

    @njit(cache=True)
    def _overlap(ax, ay, aw, ah, bx, by, bw, bh, iou):  # pragma: no cover - compiled
        """``IoU ≥ iou`` of two boxes (:func:`mvtrack.tracking.scores._overlap_at_least`)."""
        aw2, ah2, bw2, bh2 = aw / 2, ah / 2, bw / 2, bh / 2
        sx = min(ax + aw2, bx + bw2) - max(ax - aw2, bx - bw2)
        sy = min(ay + ah2, by + bh2) - max(ay - ah2, by - bh2)
        inter = max(sx, 0.0) * max(sy, 0.0)
        areas = aw * ah + bw * bh
        return inter * (1.0 + iou) >= iou * areas and inter > 0

    @njit(cache=True)
    def _isolated(box, score, oxy, owh, iou):  # pragma: no cover - compiled
        """:func:`mvtrack.tracking.scores.isolated` (``box`` rows ``x, y, w, h``)."""
        m, k = box.shape[0], oxy.shape[0]
        keep = np.ones(m, dtype=np.bool_)
        for i in range(m):
            for j in range(k):
                if _overlap(box[i, 0], box[i, 1], box[i, 2], box[i, 3], oxy[j, 0], oxy[j, 1],
                            owh[j, 0], owh[j, 1], iou):
                    keep[i] = False
                    break
        idx = np.nonzero(keep)[0]
        c = idx.size
        if c < 2:
            return keep
        # scores.duplicates among the kept ones: greedy, best score first (ties: x, then y,
        # then row order), a box overlapped by a better kept one goes
        order = np.empty(c, dtype=np.intp)
        for t in range(c):  # insertion sort on (−score, x, y), stable
            a = idx[t]
            p = t
            while p > 0:
                b = order[p - 1]
                if (-score[b] > -score[a] or (-score[b] == -score[a] and (
                        box[b, 0] > box[a, 0] or (box[b, 0] == box[a, 0]
                                                  and box[b, 1] > box[a, 1])))):
                    order[p] = b
                    p -= 1
                else:
                    break
            order[p] = a
        dup = np.zeros(m, dtype=np.bool_)
        for t in range(c):
            a = order[t]
            if dup[a]:
                continue
            for t2 in range(t + 1, c):
                b = order[t2]
                if _overlap(box[a, 0], box[a, 1], box[a, 2], box[a, 3], box[b, 0],
                            box[b, 1], box[b, 2], box[b, 3], iou):
                    dup[b] = True
        for t in range(c):
            if dup[idx[t]]:
                keep[idx[t]] = False
        return keep

    @njit(cache=True)
    def _frame_step(ints, flo, x, P, drow, score, hi, lo, k, pf, pi):  # pragma: no cover
        n = ints.shape[0]
        m = drow.shape[0] - 1
        # 1. predict, eqs. (6)–(7) of paper 1 (closed form, Δt = 1)
        xp = np.empty_like(x)
        Pp = np.empty_like(P)
        for i in range(n):
            xp[i, 0] = x[i, 0] + x[i, 2]
            xp[i, 1] = x[i, 1] + x[i, 3]
            xp[i, 2] = x[i, 2]
            xp[i, 3] = x[i, 3]
            a, b, c = P[i, 0], P[i, 1], P[i, 2]
            Pp[i, 0] = a + b * 2.0 + c + pf[_QA]
            Pp[i, 1] = b + c + pf[_QB]
            Pp[i, 2] = c + pf[_QC]
        gxy = xp[:, :2]
        twh = flo[:, 4:6]
        # 2. size factors f² = max(1, wh² / size_ref²) and variances r f², when a box is larger
        f2 = np.ones((n, 2))
        rr = np.empty(n)
        rr[:] = pf[_R]
        scaled = False
        if pf[_INV_REF2] >= 0:
            for i in range(n):
                if twh[i, 0] > pf[_REF] or twh[i, 1] > pf[_REF]:
                    scaled = True
                    break
        if scaled:
            for i in range(n):
                for d in range(2):
                    v = twh[i, d] * twh[i, d] * pf[_INV_REF2]
                    f2[i, d] = v if v > 1.0 else 1.0  # fmax: NaN → 1
                rr[i] = pf[_R] * max(f2[i, 0], f2[i, 1])
        det_index = np.full(n, -1, dtype=np.int64)
        gate, gate2, rho, eps, w = pf[_GATE], pf[_GATE2], pf[_RHO], pf[_EPS], pf[_SIZE_W]
        # 3. first and second stage (discs.dense_two_stage) on the high detections
        m1 = hi.size
        hxy, hwh = _take(drow, hi, 0, 2), _take(drow, hi, 2, 4)
        free_d = np.ones(m1, dtype=np.bool_)
        matched = 0
        if m1 > 0 and n > 0:
            reach = max(gate, gate2) if gate2 >= 0 else gate
            cost = _costs(gxy, hxy, f2, True, twh, hwh, rho, eps, reach)
            rows, cols = _solve(cost, np.arange(n), np.arange(m1), gate, w, twh, hwh, f2)
            for t in range(rows.size):
                det_index[rows[t]] = hi[cols[t]]
                free_d[cols[t]] = False
            matched = rows.size
            if gate2 >= 0 and matched < n and matched < m1:
                lt = np.nonzero(det_index < 0)[0]
                ld = np.nonzero(free_d)[0]
                rows, cols = _solve(cost, lt, ld, gate2, w, twh, hwh, f2)
                for t in range(rows.size):
                    det_index[rows[t]] = hi[cols[t]]
                    free_d[cols[t]] = False
                matched += rows.size
        ud = hi[free_d]
        # 4. recovery: lost established tracks near their last measurement
        recovered = np.zeros(n, dtype=np.bool_)
        if pf[_REC_SPEED] >= 0 and ud.size and matched < n:
            cand = np.nonzero((det_index < 0) & (ints[:, HITS] >= pi[_REC_HITS])
                              & (ints[:, LAST_K] >= k - pi[_REC_WINDOW]))[0]
            if cand.size:
                r2 = np.empty((cand.size, 1))  # the radius v_max Δk + margin, squared
                for a in range(cand.size):
                    i = cand[a]
                    margin = pf[_REC_MARGIN]
                    if scaled:
                        margin = margin * math.sqrt(max(f2[i, 0], f2[i, 1]))
                    radius = pf[_REC_SPEED] * float(k - ints[i, LAST_K]) + margin
                    r2[a, 0] = radius * radius
                lxy, cwh = _take(flo, cand, 0, 2), _take(flo, cand, 4, 6)
                uxy, uwh = _take(drow, ud, 0, 2), _take(drow, ud, 2, 4)
                cost = _costs(lxy, uxy, r2, False, cwh, uwh, rho, eps, 1.0)
                rows, cols = _solve(cost, np.arange(cand.size), np.arange(ud.size), 1.0, 0.0,
                                    cwh, uwh, f2)
                if rows.size:
                    used = np.zeros(ud.size, dtype=np.bool_)
                    for t in range(rows.size):
                        det_index[cand[rows[t]]] = ud[cols[t]]
                        recovered[cand[rows[t]]] = True
                        used[cols[t]] = True
                    matched += rows.size
                    ud = ud[~used]
        # 5. the low-score stage: established tracks still free against the low detections
        if lo.size and matched < n:
            free = det_index < 0
            if not pi[_LOW_TENTATIVE]:
                free &= ints[:, STATE] != TENTATIVE
            cand = np.nonzero(free)[0]
            if cand.size:
                cxy, cwh, cf2 = _take(xp, cand, 0, 2), _take(flo, cand, 4, 6), _take(f2, cand, 0, 2)
                lxy, lwh = _take(drow, lo, 0, 2), _take(drow, lo, 2, 4)
                cost = _costs(cxy, lxy, cf2, True, cwh, lwh, rho, eps, gate)
                rows, cols = _solve(cost, np.arange(cand.size), np.arange(lo.size), gate, w,
                                    cwh, lwh, cf2)
                for t in range(rows.size):
                    det_index[cand[rows[t]]] = lo[cols[t]]
                matched += rows.size
        # 6. low-score births: the low detections left that overlap nothing living
        if pf[_LOW_IOU] >= 0 and lo.size:
            taken = np.zeros(m + 1, dtype=np.bool_)
            for i in range(n):
                taken[det_index[i]] = True  # −1: the NaN row
            lo2 = lo[~taken[lo]]
            if lo2.size:
                # the high detections and the predicted boxes of the tracks that live on
                live = np.nonzero((ints[:, STATE] != TENTATIVE) | (det_index >= 0))[0]
                oxy = np.concatenate((hxy, _take(xp, live, 0, 2)))
                owh = np.concatenate((hwh, _take(flo, live, 4, 6)))
                box = _take(drow, lo2, 0, 4)
                ok = _isolated(box, score[lo2], oxy, owh, pf[_LOW_IOU])
                if np.count_nonzero(ok):
                    ud = np.concatenate((ud, lo2[ok]))
        # 7. measurement update, eqs. (3)–(5) of paper 1, and the table's columns
        zwh = np.empty((n, 4))
        limit = math.log(rho) if rho > 0 else 0.0
        for i in range(n):
            zwh[i] = drow[det_index[i]]
            if eps >= 0 and det_index[i] >= 0 and _apart(
                    twh[i, 0], twh[i, 1], zwh[i, 2], zwh[i, 3], limit):
                # a partial view: the track's box standing on the detection's bottom edge
                zwh[i, 1] += 0.5 * (zwh[i, 3] - twh[i, 1])
                zwh[i, 2], zwh[i, 3] = twh[i, 0], twh[i, 1]
        xn = xp.copy()
        Pn = Pp.copy()
        ints = ints.copy()
        flo = flo.copy()
        z = zwh[:, :2].copy()
        for i in range(n):
            hit = det_index[i] >= 0
            if hit:
                nu0 = z[i, 0] - xp[i, 0]
                nu1 = z[i, 1] - xp[i, 1]
                a, b, c = Pp[i, 0], Pp[i, 1], Pp[i, 2]
                if nu0 + nu1 == nu0 + nu1:
                    wi = 1.0 / (a + rr[i])  # 1/S, eq. (3)
                    ga, gb = a * wi, b * wi  # K = [a, b]ᵀ / S
                    xn[i, 0] = xp[i, 0] + ga * nu0  # eq. (4)
                    xn[i, 1] = xp[i, 1] + ga * nu1
                    xn[i, 2] = xp[i, 2] + gb * nu0
                    xn[i, 3] = xp[i, 3] + gb * nu1
                    Pn[i, 0] = a * (1.0 - ga)  # eq. (5)
                    Pn[i, 1] = b * (1.0 - ga)
                    Pn[i, 2] = c - b * gb
                if recovered[i]:  # the predictor restarts at the re-acquired detection
                    xn[i, 0], xn[i, 1], xn[i, 2], xn[i, 3] = z[i, 0], z[i, 1], 0.0, 0.0
                    Pn[i, 0], Pn[i, 1], Pn[i, 2] = rr[i], 0.0, pf[_VEL_VAR]
                ints[i, HITS] += 1
                ints[i, MISSES] = 0
                ints[i, PREV_K] = ints[i, LAST_K]
                ints[i, LAST_K] = k
                flo[i, 2], flo[i, 3] = flo[i, 0], flo[i, 1]
                flo[i, 0], flo[i, 1] = z[i, 0], z[i, 1]
                for d in range(2):
                    flo[i, 4 + d] = flo[i, 4 + d] + pf[_SMOOTH] * (zwh[i, 2 + d] - flo[i, 4 + d])
            else:
                ints[i, MISSES] += 1
            ints[i, AGE] += 1
        # 8. life cycle (lifecycle.next_state) and the frame's edge
        delete = np.zeros(n, dtype=np.bool_)
        confirmed_now = np.zeros(n, dtype=np.bool_)
        for i in range(n):
            hit = det_index[i] >= 0
            misses, age = ints[i, MISSES], ints[i, AGE]
            tentative = ints[i, STATE] == TENTATIVE
            now = tentative and ints[i, HITS] >= pi[_CONFIRM_HITS] and age <= pi[_CONFIRM_WINDOW]
            confirmed_now[i] = now
            if tentative and not now:
                ints[i, STATE] = TENTATIVE
                delete[i] = misses > pi[_TENT_MISSES] or age >= pi[_CONFIRM_WINDOW]
            else:
                ints[i, STATE] = CONFIRMED if hit else COASTING
                delete[i] = misses > pi[_MAX_MISSES]
            if pf[_FRAME_W] >= 0 and not hit:
                gx, gy = gxy[i, 0], gxy[i, 1]
                if gx < 0 or gx >= pf[_FRAME_W] or gy < 0 or gy >= pf[_FRAME_H]:
                    delete[i] = True
        return ints, flo, xn, Pn, gxy, z, det_index, delete, confirmed_now, ud


def frame_step(
    ints: NDArray[np.int64], flo: NDArray[np.float64], x: NDArray[np.float64],
    P: NDArray[np.float64], drow: NDArray[np.float64], score: NDArray[np.float64],
    hi: NDArray[np.intp], lo: NDArray[np.intp], k: int, pf: NDArray[np.float64],
    pi: NDArray[np.int64],
) -> tuple[Any, ...]:
    """One frame of the tracker (module docstring) on the table ``ints``, ``flo``
    (:class:`~mvtrack.tracking.table.TrackTable`) and the ``kalman-cv`` state ``x``, ``P``
    (:class:`~mvtrack.filters.cv.CVState`), the detections' rows ``drow``
    (:func:`~mvtrack.tracking.table.detection_rows`) and raw scores ``score``, the high and
    low detection rows ``hi``, ``lo`` (sorted) at step ``k``, and the settings ``pf``, ``pi``
    (:func:`params`).

    Returns
    -------
    ints, flo, x, P
        The updated table (states set) and predictor state, rows as given (none removed).
    gxy : (N, 2)
        Gate centres (the predictions).
    z : (N, 2)
        Each track's measurement (NaN: none).
    det_index : (N,) int64
        Each track's detection row (−1: none).
    delete, confirmed_now : (N,) bool
        The tracks that end this frame and those confirmed just now.
    ud : (B,) intp
        The detections that start tentative tracks, high ones first.
    """
    return _frame_step(ints, flo, x, P, drow, score, hi, lo, k, pf, pi)
