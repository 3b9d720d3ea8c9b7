"""The association stages of one frame, composed: gate centres, the first stage, the second
gate, the recovery stage, the low-score stage; the box-size term and size gate of the
Euclidean stages.

:class:`Associator` holds the settings the stages read (resolved once from the
:class:`~mvtrack.tracking.config.TrackerConfig`) and runs them in order
(:meth:`Associator.associate`); the gating and assignment arithmetic itself is in
:mod:`mvtrack.association`. The stages (SPEC §1.1 step 4, §2.1 step 3):

1. **gate centres** (:meth:`Associator.centres`): the predictions, or paper 1's warm-up
   centre ``2 y_k − y_{k−1}`` until ``warmup_hits`` associations; for boxes larger than
   ``size_ref`` the per-axis size factors ``f²`` (the Euclidean gates stretch with the box)
   and the measurement variances ``r f²``;
2. **first stage**: the high-score detections with the configured distance, gate and rule —
   the disc-shaped gates (``euclidean``, and ``mahalanobis`` with the closed-form
   ``kalman-cv``) through the fast disc-gate path, any other through
   :func:`~mvtrack.association.gating.candidate_pairs` and
   :func:`~mvtrack.association.assign.assign`; the Euclidean cost gets a box-size term
   (``size_weight``) and a size gate (``size_gate``);
3. **second gate** (``second_gate``): a wider Euclidean gate for the tracks and detections
   left over;
4. **recovery** (``recover_speed``): an established track that lost its target may take a
   leftover detection near its last measurement (its predictor restarts there);
5. **low-score stage** (``score_high``): established tracks still unmatched against the
   low-score detections, with the first stage's distance and gate;
6. **births** (:meth:`Associator.low_births`): the high detections left over, and the low ones
   that overlap no living track, no high detection and no better low one
   (``low_birth_iou``), start tentative tracks.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association import discs, gating
from mvtrack.association.assign import assign as assign_pairs
from mvtrack.association.distances import TrackView, get_distance, resolve_gate
from mvtrack.association.gating import candidate_pairs
from mvtrack.association.regions import SHAPE_PARAMS, GateRegions, axis_shapes, gate_shapes
from mvtrack.filters.cv import KalmanCVPredictor
from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.lifecycle import STOPPED, TENTATIVE
from mvtrack.tracking.scores import ScoreCalibration, duplicates, isolated
from mvtrack.tracking.table import HITS, LAST_K, LAST_XY, STATE, WH, TrackTable
from mvtrack.types import Detections

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_EMPTY = np.zeros(0, dtype=np.intp)


class Associator:
    """The association stages of the tracker, with their settings resolved from ``config``.

    Parameters
    ----------
    config : TrackerConfig
        The tracker's configuration (distance, gate, rule, second gate, recovery, size and
        score settings).
    predictor : Predictor
        The tracker's predictor (its state gives the gate centres and covariances).
    """

    def __init__(self, config: TrackerConfig, predictor: Any) -> None:
        self.config = config
        self.predictor = predictor
        self._fp = config.frames()
        self._distance = get_distance(config.distance)
        self._distance_params = dict(config.distance_params)
        # the fast association path serves the disc-shaped gates
        self._fast_gate: str | None = None
        if not self._distance_params:
            if config.distance == "euclidean":
                self._fast_gate = "euclidean"
            elif config.distance == "mahalanobis" and isinstance(predictor, KalmanCVPredictor):
                self._fast_gate = "mahalanobis"
        self._assign_params = dict(config.assign_params)
        sg = config.second_gate
        self._gate2 = None if sg is None else float(sg) ** 2
        self._gate = resolve_gate(self._distance, config.gate)
        # scaling of the detection-related pixel values with the box size (config.size_ref)
        ref = config.size_ref
        self.ref = None if ref is None else float(ref)
        self._inv_ref2 = None if ref is None else 1.0 / float(ref) ** 2
        #: whether the measurement variance scales with the box (closed-form kalman-cv only)
        self.scale_r = self._inv_ref2 is not None and isinstance(predictor, KalmanCVPredictor)
        # box-size term of the Euclidean costs (in the units of the position cost)
        self._size_w = float(config.size_weight) if self._fast_gate == "euclidean" else 0.0
        # size gate of the Euclidean stages (config.size_gate)
        sgate = config.size_gate
        self._size_gate = (
            float(sgate) if sgate is not None and self._fast_gate == "euclidean" else None
        )
        #: tolerance of the partial views the size gate lets through (config.partial_tolerance)
        self.partial = (
            None if self._size_gate is None or config.partial_tolerance is None
            else float(config.partial_tolerance)
        )
        self._recover_hits = max(config.recover_min_hits, self._fp.confirm_hits)
        c = config
        self.scores = (
            ScoreCalibration(c.score_scale)
            if c.score_high is not None or c.min_score > 0 or c.nms_iou is not None
            else None
        )

    def centres(
        self, tab: TrackTable, ps: Any, k: int
    ) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
        """Gate centres ``gxy`` (N, 2) of the predicted state ``ps``, the size factors ``f2``
        (N, 2) and the per-track measurement variances ``r_rows`` (N,) (both ``None`` unless
        a box is larger than ``size_ref``)."""
        gxy = self.predictor.position(ps)
        if self._fp.warmup_hits:
            gxy = gating.warmup_centre(  # paper 1's 2 y_k − y_{k−1}, SPEC §1.1 [R]
                gxy, tab.hits, tab.last_xy, tab.prev_xy, tab.last_k, tab.prev_k, k,
                self._fp.warmup_hits,
            )
        f2 = r_rows = None  # size factors, only when a box is larger than size_ref
        if self.ref is not None and np.count_nonzero(tab.floats[:, WH] > self.ref):
            f2 = self.size_scale2(tab.floats[:, WH])
            if self.scale_r:
                r_rows = self.predictor.r * self.r_factor(f2)  # r max(f_x, f_y)² per track
        return gxy, f2, r_rows

    def associate(
        self, tab: TrackTable, ps: Any, gxy: FloatArray, f2: FloatArray | None,
        r_rows: FloatArray | None, dets: Detections, drow: FloatArray,
        sel: tuple[NDArray[np.intp], NDArray[np.intp]] | None, k: int,
    ) -> tuple[IntArray, int, NDArray[np.intp], NDArray[np.intp] | None]:
        """All stages of one frame, in order.

        ``sel`` are the high and low detection rows (:meth:`score_select`; ``None``: all
        high), ``drow`` the detections' rows ``x, y, w, h``
        (:func:`~mvtrack.tracking.table.detection_rows`). Returns each track's detection row
        ``det_index`` (N,) (−1: none), the number of matched tracks, the detections left
        unassigned (high ones only) and the tracks the recovery stage re-acquired (or
        ``None``).
        """
        n = tab.ints.shape[0]
        m = dets.xy.shape[0]
        staged = False
        m1 = m if sel is None else sel[0].size  # the high detections
        if m1 == 0:
            mt = md = ud = _EMPTY
        elif self._fast_gate is not None:
            high = drow if sel is None else drow.take(sel[0], 0)  # x, y, w, h (+ NaN row)
            mt, md, ud, staged = self._associate_fast(
                ps, gxy, high[:m1, :2], high[:m1, 2:], f2, r_rows, tab.floats[:, WH]
            )
        else:
            first = dets if sel is None else dets.take(sel[0])
            mt, md, ud = self._associate(ps, gxy, tab, first)
        if sel is not None:  # back to the rows of dets
            md, ud = sel[0].take(md), sel[0].take(ud)
        det_index = np.empty(n, dtype=np.int64)
        det_index.fill(-1)
        det_index[mt] = md
        matched = mt.size
        if self._gate2 is not None and not staged and ud.size and matched < n:
            mt2, md2 = self._second_stage(gxy, det_index, drow, ud, f2, tab.floats[:, WH])
            matched, ud = _add_pairs(det_index, matched, ud, mt2, md2, m)
        recovered = None
        if self._fp.recover_speed is not None and ud.size and matched < n:
            mt2, md2 = self._recover(tab, det_index, drow, ud, k, f2)
            if mt2.size:
                recovered = mt2
            matched, ud = _add_pairs(det_index, matched, ud, mt2, md2, m)
        if sel is not None and sel[1].size and matched < n:  # low detections, last
            mt2, md2 = self._low_stage(ps, gxy, tab, det_index, drow, sel[1], f2, r_rows)
            if mt2.size:
                det_index[mt2] = md2
                matched += mt2.size
        if self.config.stopped_margin is not None and matched:
            matched, ud, recovered = self._standing(tab, det_index, drow, matched, ud,
                                                    recovered, sel)
        if self.config.low_birth_iou is not None and sel is not None and sel[1].size:
            ud = self.low_births(dets, drow, sel, ud, tab, det_index, gxy)
        return det_index, matched, ud, recovered

    def low_births(
        self, dets: Detections, drow: FloatArray,
        sel: tuple[NDArray[np.intp], NDArray[np.intp]], ud: NDArray[np.intp],
        tab: TrackTable | None = None, det_index: IntArray | None = None,
        gxy: FloatArray | None = None,
    ) -> NDArray[np.intp]:
        """The detections that start tentative tracks: the high ones left unassigned ``ud``
        and the low ones (``sel[1]``) not taken by a track (``det_index``) that overlap no
        high detection, no better-scored such low detection and no predicted box (centres
        ``gxy``) of a track of ``tab`` that lives on (established, or tentative and matched
        now: an unmatched tentative track ends, and the object it was born on may start
        again) by ``low_birth_iou`` or more (:func:`~mvtrack.tracking.scores.isolated`)."""
        lo = sel[1]
        if det_index is not None and det_index.size:
            taken = np.zeros(drow.shape[0], dtype=bool)
            taken[det_index] = True  # −1 marks the NaN row at the end of drow
            lo = lo[~taken.take(lo)]
        if lo.size == 0:
            return ud
        hb = drow.take(sel[0], 0)
        oxy, owh = hb[:, :2], hb[:, 2:]
        if tab is not None and gxy is not None and det_index is not None and gxy.shape[0]:
            rows = ((tab.ints[:, STATE] != TENTATIVE) | (det_index >= 0)).nonzero()[0]
            if rows.size:
                oxy = np.concatenate([oxy, gxy.take(rows, 0)])
                owh = np.concatenate([owh, tab.floats.take(rows, 0)[:, WH]])
        box = drow.take(lo, 0)
        ok = isolated(box[:, :2], box[:, 2:], dets.score.take(lo), oxy, owh,
                      self.config.low_birth_iou)
        if not np.count_nonzero(ok):
            return ud
        return np.concatenate([ud, lo.compress(ok)])  # births are sorted by position

    def _standing(
        self, tab: TrackTable, det_index: IntArray, drow: FloatArray, matched: int,
        ud: NDArray[np.intp], recovered: NDArray[np.intp] | None,
        sel: tuple[NDArray[np.intp], NDArray[np.intp]] | None,
    ) -> tuple[int, NDArray[np.intp], NDArray[np.intp] | None]:
        """Undo the matches of the tracks held by template matching in the previous frame
        (``STOPPED``) to detections whose centre lies farther than half the track's box's
        longer side plus ``stopped_margin`` from its last measurement and whose box does not
        come within ``stopped_margin`` of it (``det_index`` in place); a detection
        freed so, if high and taken by no other track, is unassigned again. Returns the new
        ``matched``, ``ud`` and ``recovered``."""
        rows = ((tab.ints[:, STATE] == STOPPED) & (det_index >= 0)).nonzero()[0]
        if rows.size == 0:
            return matched, ud, recovered
        flo = tab.floats.take(rows, 0)
        box = drow.take(det_index.take(rows), 0)
        margin = self.config.stopped_margin
        d = box[:, :2] - flo[:, LAST_XY]
        reach = flo[:, WH].max(axis=1) / 2 + margin
        # or the detection's box holds where it stands (vehicles of a queue that drive on
        # together merge into one blob whose centre lies between them)
        out = np.maximum(np.abs(d) - box[:, 2:] / 2, 0.0)
        far = rows[(np.hypot(d[:, 0], d[:, 1]) > reach) & (np.hypot(out[:, 0], out[:, 1]) > margin)]
        if far.size == 0:
            return matched, ud, recovered
        freed = det_index[far]
        det_index[far] = -1
        freed = freed[~np.isin(freed, det_index)]  # non-exclusive rules may share a detection
        if sel is not None:
            freed = freed[np.isin(freed, sel[0])]  # a low detection starts nothing
        if freed.size:
            ud = np.union1d(ud, freed).astype(np.intp)
        if recovered is not None:
            recovered = recovered[~np.isin(recovered, far)]
            recovered = recovered if recovered.size else None
        return matched - far.size, ud, recovered

    def score_select(self, dets: Detections) -> tuple[NDArray[np.intp], NDArray[np.intp]] | None:
        """The high and the low detections (rows of ``dets``) by calibrated score, without
        the dropped ones (below ``min_score``, or duplicates of a better box); ``None`` when
        every detection is high and none is dropped."""
        if self.scores is None:
            return None
        c = self.scores(dets.score)
        cfg = self.config
        keep = c >= cfg.min_score
        if cfg.nms_iou is not None:
            keep &= ~duplicates(dets.xy, dets.wh, dets.score, cfg.nms_iou)
        high = keep if cfg.score_high is None else keep & (c >= cfg.score_high)
        if high.all():
            return None
        return high.nonzero()[0], (keep & ~high).nonzero()[0]

    def _low_stage(
        self, ps: Any, gxy: FloatArray, tab: TrackTable, det_index: IntArray,
        drow: FloatArray, lo: NDArray[np.intp], f2: FloatArray | None,
        r_rows: FloatArray | None,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Last stage: the established (non-tentative; any with ``low_tentative``) tracks still
        unmatched against the low detections ``lo``, with the first stage's distance and gate
        around the prediction (``score_high``). ``drow`` are the detections' rows ``x, y, w, h``."""
        free = det_index < 0
        cand = (free if self.config.low_tentative
                else free & (tab.ints[:, STATE] != TENTATIVE)).nonzero()[0]
        if cand.size == 0:
            return _EMPTY, _EMPTY
        left = drow.take(lo, 0)
        pred = self.predictor
        if self._fast_gate is None:
            view = TrackView(
                gxy.take(cand, 0), pred.position_cov(ps)[cand], pred.innovation_cov(ps)[cand],
                pred.velocity(ps)[cand], tab.floats[cand, WH],
            )
            sub = Detections(0, left[:, :2], left[:, 2:])
            ti, dj, cost = candidate_pairs(
                view, sub, self._distance, self._gate, **self._distance_params
            )
            a = assign_pairs(ti, dj, cost, cand.size, lo.size, self.config.assign,
                             **self._assign_params)
            return cand[a.track], lo[a.det]
        scale = None if f2 is None else f2.take(cand, 0)
        if self._fast_gate == "mahalanobis":
            r = pred.r if r_rows is None else r_rows[cand]
            scale = pred.position_var(ps)[cand] + r  # S = (P̄ + r) I
        size = self._size_term(tab.floats[cand, WH], left[:, 2:])
        txy = gxy.take(cand, 0)
        if cand.size * lo.size <= discs.DENSE_LSA:
            mt, md = discs.dense_optimal(txy, left[:, :2], scale, self._gate, size)
        else:
            ti, dj, cost = discs.gate_pairs(txy, left[:, :2], scale, self._gate, size)
            if ti.size == 0:
                return _EMPTY, _EMPTY
            mt, md = discs.optimal(ti, dj, cost, cand.size, lo.size, self._gate)
        return cand[mt], lo[md]

    def _associate(
        self, ps: Any, gxy: FloatArray, tab: TrackTable, dets: Detections
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
        """Gate and assign through :mod:`mvtrack.association` (any distance and rule)."""
        pred = self.predictor
        view = TrackView(
            gxy, pred.position_cov(ps), pred.innovation_cov(ps), pred.velocity(ps), tab.wh
        )
        ti, dj, cost = candidate_pairs(
            view, dets, self._distance, self._gate, **self._distance_params
        )
        a = assign_pairs(ti, dj, cost, len(tab), len(dets), self.config.assign,
                         **self._assign_params)
        return a.track, a.det, a.unmatched_dets

    def _associate_fast(
        self, ps: Any, gxy: FloatArray, dxy: FloatArray, dwh: FloatArray,
        f2: FloatArray | None, r_rows: FloatArray | None, twh: FloatArray,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp], bool]:
        """Gate and assign through :mod:`mvtrack.association.discs` (disc-shaped gates);
        ``dxy``, ``dwh`` (M, 2) are the detections' centres and sizes; the flag says whether the
        second stage was done too. ``f2`` (N, 2) stretches the
        Euclidean gates per axis (``Δx²/f_x² + Δy²/f_y² <= gate``), ``r_rows`` (N,) are the
        tracks' measurement variances, ``twh`` (N, 2) their box sizes (for the size term of
        the Euclidean cost, ``config.size_weight``)."""
        n, m = gxy.shape[0], dxy.shape[0]
        scale = f2
        size = self._size_term(twh, dwh)
        if self._fast_gate == "mahalanobis":
            r = self.predictor.r if r_rows is None else r_rows
            scale = self.predictor.position_var(ps) + r  # S = (P̄ + r) I
        rule = self.config.assign
        staged = False
        if rule == "optimal" and not self._assign_params and n * m <= discs.DENSE_LSA:
            if self._gate2 is not None:  # both stages from one distance matrix
                mt, md, ud = discs.dense_two_stage(
                    gxy, dxy, scale, self._gate, self._gate2, f2, size
                )
                return mt, md, ud, True
            else:
                mt, md = discs.dense_optimal(gxy, dxy, scale, self._gate, size)
        elif rule == "optimal" and not self._assign_params:
            ti, dj, cost = discs.gate_pairs(gxy, dxy, scale, self._gate, size)
            mt, md = discs.optimal(ti, dj, cost, n, m, self._gate)
        else:
            ti, dj, cost = discs.gate_pairs(gxy, dxy, scale, self._gate, size)
            a = assign_pairs(ti, dj, cost, n, m, rule, **self._assign_params)
            mt, md = a.track, a.det
        used = np.zeros(m, dtype=bool)
        used[md] = True
        return mt, md, (~used).nonzero()[0], staged

    def _second_stage(
        self, gxy: FloatArray, det_index: IntArray, drow: FloatArray, ud: NDArray[np.intp],
        f2: FloatArray | None, twh: FloatArray,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Second association stage: the tracks left unmatched by the first stage against the
        detections left unassigned, with the wider Euclidean gate ``second_gate`` (px, stretched
        per axis by the size factors ``f_x, f_y``) around the prediction (gated global nearest
        neighbour on the squared distance). ``drow`` are the detections' rows ``x, y, w, h``
        (:func:`~mvtrack.tracking.table.detection_rows`)."""
        cand = (det_index < 0).nonzero()[0]
        g = self._gate2
        scale = None if f2 is None else f2.take(cand, 0)
        left = drow.take(ud, 0)
        size = self._size_term(twh.take(cand, 0), left[:, 2:])
        txy, dxy = gxy.take(cand, 0), left[:, :2]
        if cand.size * ud.size <= discs.DENSE_LSA:  # the same result, one dense solve
            mt, md = discs.dense_optimal(txy, dxy, scale, g, size)
            return cand[mt], ud[md]
        ti, dj, cost = discs.gate_pairs(txy, dxy, scale, g, size)
        if ti.size == 0:
            return _EMPTY, _EMPTY
        mt, md = discs.optimal(ti, dj, cost, cand.size, ud.size, g)
        return cand[mt], ud[md]

    def _recover(
        self, tab: TrackTable, det_index: IntArray, drow: FloatArray, ud: NDArray[np.intp],
        k: int, f2: FloatArray | None = None,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Second association stage: lost confirmed tracks vs unassigned detections.

        A confirmed (or coasting, or stopped) track with at least ``recover_min_hits``
        associations, measured within the last ``recover_window``, that has no detection in
        its gate may take an unassigned detection within ``r = v_max Δk + margin`` of its last
        measurement, Δk the frames since that measurement (the margin times ``max(f_x, f_y)``
        when the box size scales the gates); pairs are chosen by the gated
        global nearest neighbour on ``|z − y_last|² / r²``. ``drow`` are the detections' rows
        ``x, y, w, h`` (:func:`~mvtrack.tracking.table.detection_rows`). Returns the recovered
        track rows and their detections.
        """
        ints = tab.ints
        cand = (
            (det_index < 0)
            # established: tentative tracks always have fewer than confirm_hits hits
            & (ints[:, HITS] >= self._recover_hits)
            & (ints[:, LAST_K] >= k - self._fp.recover_window)
        ).nonzero()[0]
        if cand.size == 0:
            return _EMPTY, _EMPTY
        margin = self.config.recover_margin
        if f2 is not None:
            margin = margin * np.sqrt(self.r_factor(f2[cand]))
        radius = self._fp.recover_speed * (k - ints.take(cand, 0)[:, LAST_K]) + margin
        r2 = radius * radius
        tf = tab.floats.take(cand, 0)
        last_xy = tf[:, LAST_XY]
        left = drow.take(ud, 0)
        dxy = left[:, :2]
        size = None  # the size gate only (no size term in this cost)
        if self._size_gate is not None:
            size = discs.size_term(tf[:, WH], left[:, 2:], 0.0, self._size_gate, self.partial)
        if cand.size * ud.size <= discs.DENSE_LSA:
            mt, md = discs.dense_optimal(last_xy, dxy, r2, 1.0, size)
        else:
            ti, dj, cost = discs.gate_pairs(last_xy, dxy, r2, 1.0, size)
            mt, md = discs.optimal(ti, dj, cost, cand.size, ud.size, 1.0)
        return cand[mt], ud[md]

    def _size_term(self, twh: FloatArray, dwh: FloatArray) -> discs.SizeTerm | None:
        """The size term and size gate of a Euclidean stage (:func:`discs.size_term`)."""
        return discs.size_term(twh, dwh, self._size_w, self._size_gate, self.partial)

    def size_scale2(self, wh: FloatArray) -> FloatArray:
        """Per-axis size factors squared (:func:`gating.size_factors2`) for boxes ``wh``."""
        return gating.size_factors2(wh, self._inv_ref2)

    r_factor = staticmethod(gating.r_factor)

    def regions(self, tab: TrackTable, ps: Any, k: int) -> GateRegions:
        """The gates of the tracks ``tab`` with predicted state ``ps`` at step ``k``
        (:meth:`mvtrack.tracking.tracker.Tracker.gates`).

        The centre is the prediction, or paper 1's warm-up centre ``2 y_k − y_{k−1}`` while a
        track has fewer than ``warmup_hits`` associations (SPEC §1.1 [R]). The shape is the
        configured distance's region (:func:`~mvtrack.association.regions.gate_shapes`); the
        Euclidean gates of boxes larger than ``size_ref`` are stretched to
        ``diag(f_x², f_y²)``, and the Mahalanobis disc of the closed-form ``kalman-cv`` is
        ``(P̄ + r f²) I``, as the first stage applies them. The second stage's gates
        (``second_gate``) are stretched the same way; the recovery stage is not a gate around
        the centre and is left out.
        """
        pred, n = self.predictor, len(tab)
        gxy, f2, r_rows = self.centres(tab, ps, k)
        if self._fast_gate == "euclidean":
            shape = axis_shapes(f2, n)
        elif self._fast_gate == "mahalanobis":
            r = pred.r if r_rows is None else r_rows
            shape = axis_shapes(pred.position_var(ps) + r, n)  # S = (P̄ + r) I
        else:
            params = {p: v for p, v in self._distance_params.items() if p in SHAPE_PARAMS}
            _, shape, _ = gate_shapes(
                self.config.distance, gxy, pred.position_cov(ps), pred.innovation_cov(ps),
                pred.velocity(ps), self._gate, **params,
            )
        second = None if self._gate2 is None else axis_shapes(f2, n)
        return GateRegions(tab.uid.copy(), tab.track_id.copy(), np.array(gxy), shape, second,
                           self._gate, self._gate2)


def _add_pairs(
    det_index: IntArray, matched: int, ud: NDArray[np.intp], mt2: NDArray[np.intp],
    md2: NDArray[np.intp], m: int,
) -> tuple[int, NDArray[np.intp]]:
    """Record a later stage's pairs ``(mt2, md2)`` in ``det_index`` (in place); the new
    number of matched tracks and the detections of ``ud`` still unassigned."""
    if mt2.size == 0:
        return matched, ud
    det_index[mt2] = md2
    used = np.zeros(m, dtype=bool)
    used[md2] = True
    return matched + mt2.size, ud[~used[ud]]
