"""The multi-target tracker: predict → gate → assign → update → life cycle, per frame.

All track state is a struct of arrays (:class:`TrackTable`, one row per live track) plus the
predictor's batch state; a frame costs a fixed number of array operations whatever the number
of tracks, and no Python loop runs over tracks. The pipeline is SPEC §1.1 steps 4–5 (paper 1)
and §2.1 steps 3–5 (paper 2):

1. **predict** every track one frame (:meth:`Predictor.predict`, eqs. (6)–(7) of paper 1);
   with ``warmup`` the gate centre is paper 1's ``2 y_k − y_{k−1}`` until 2M associations;
2. **gate and assign** (:class:`mvtrack.tracking.stages.Associator`): the first stage with
   the configured distance, gate and rule, then optionally a **second gate**, a **recovery
   stage** (an established track that lost its target may take a leftover detection near
   its last measurement; its predictor restarts there) and a **low-score stage**; the
   gating and assignment arithmetic is in :mod:`mvtrack.association`;
4. **rescue** (optional): confirmed tracks that got no detection are offered to the video
   pipeline's template matching; the ones it finds are held in state ``STOPPED``;
5. **update** the predictors with the assigned measurements (eqs. (3)–(5) of paper 1);
6. **life cycle** (:mod:`mvtrack.tracking.lifecycle`): confirm, coast, delete, and start new
   tentative tracks from the unassigned detections (new-target recognition, SPEC §2.1 step 4;
   with scores, the high ones and the isolated low ones, ``low_birth_iou``);
   a coasting track's rows are output only for its first ``coast_output`` seconds.

Every predictor is built by :func:`mvtrack.filters.predictors.make_predictor`; the default
``kalman-cv`` is the closed form of :mod:`mvtrack.filters.cv`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.discs import DENSE_LSA, size_apart
from mvtrack.association.regions import GateRegions
from mvtrack.filters.cv import CVState
from mvtrack.filters.predictors import make_predictor
from mvtrack.tracking import compiled
from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.lifecycle import (
    CONFIRMED,
    TENTATIVE,
    birth_order,
    count_hits,
    hand_out_ids,
    next_state,
)
from mvtrack.tracking.relink import empty_gallery, pair_new_tracks
from mvtrack.tracking.stages import Associator
from mvtrack.tracking.table import (
    AGE,
    BIRTH_COLS,
    LAST_K,
    LAST_XY,
    MISSES,
    PREV_K,
    PREV_XY,
    STATE,
    TID,
    UID,
    WH,
    TrackTable,
    concat_state,
    detection_rows,
    kept_rows,
    put_state,
    take_state,
    uid_ramp,
)
from mvtrack.types import Detections, TrackFrame

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: ``rescue(uids (K,), predicted_xy (K, 2), wh (K, 2)) -> (found (K,) bool, xy (K, 2))``
RescueFn = Callable[[IntArray, FloatArray, FloatArray], tuple[Any, Any]]

_NONE = np.zeros(0, dtype=np.intp)

__all__ = ["RescueFn", "TrackTable", "Tracker"]


def _build_predictor(config: TrackerConfig) -> Any:
    """The configured predictor (:func:`mvtrack.filters.predictors.make_predictor`)."""
    return make_predictor(config.predictor, **_predictor_params(config))


def _predictor_params(config: TrackerConfig) -> dict[str, Any]:
    """Predictor keyword arguments: the user's, plus the physical priors converted to frames."""
    params = dict(config.predictor_params)
    fp = config.frames()
    if fp.r is not None:
        params.setdefault("r", fp.r)  # px²
    cv = config.predictor == "kalman-cv" or (
        config.predictor == "kalman-coupled" and params.get("kind", "cv") == "cv"
    )
    if fp.accel_std is not None and cv:
        params.setdefault("q", fp.accel_std**2)  # px²/frame⁴
    if fp.init_velocity_std is not None:
        params.setdefault("vel_var", fp.init_velocity_std**2)  # px²/frame²
    return params


class Tracker:
    """Multi-target tracker over arrays; one :meth:`step` per frame.

    Parameters
    ----------
    config : TrackerConfig, optional
        Predictor, distance, assignment rule, gate and life cycle (default
        :class:`TrackerConfig()`).
    core : {"auto", "numpy"}
        ``"auto"``: frames of at most :data:`~mvtrack.association.discs.DENSE_LSA` track ×
        detection pairs run through the compiled step (:mod:`mvtrack.tracking.compiled`)
        when it covers ``config`` (the default family); ``"numpy"``: always the array step.
        Both give the same tracks.

    Raises
    ------
    ValueError
        Unknown predictor, distance or assignment rule, or bad parameters.

    Attributes
    ----------
    tracks : TrackTable
        The live tracks after the last step (tentative ones included).
    pstate : dataclass
        The predictor's batch state, row-aligned with ``tracks``.
    row_uids : (K,) int64
        Internal uids of the rows of the last returned :class:`~mvtrack.types.TrackFrame`
        (the ids the ``rescue`` callback is given), row-aligned with it.

    Examples
    --------
    >>> from mvtrack.tracking import Tracker, TrackerConfig
    >>> from mvtrack.types import Detections
    >>> tracker = Tracker(TrackerConfig(confirm_hits=2))
    >>> for k in range(3):
    ...     out = tracker.step(Detections(k, [[10.0 + 2 * k, 20.0]], [[4.0, 3.0]]))
    >>> out.track_id.tolist(), out.det_index.tolist()
    ([1], [0])
    """

    def __init__(self, config: TrackerConfig | None = None, core: str = "auto") -> None:
        self.config = TrackerConfig() if config is None else config
        if not isinstance(self.config, TrackerConfig):
            raise ValueError(f"Tracker: config must be a TrackerConfig, got {type(config)}")
        if core not in ("auto", "numpy"):
            raise ValueError(f"Tracker: core must be 'auto' or 'numpy', got {core!r}")
        self._fp = self.config.frames()
        self.predictor = _build_predictor(self.config)
        #: the association stages (gate centres, first stage, second gate, recovery, low)
        self.associator = Associator(self.config, self.predictor)
        #: the compiled step's settings, or None when it does not cover the configuration
        self._compiled = (
            compiled.params(self.config, self.associator, self.predictor)
            if core == "auto" and compiled.covers(self.config, self.predictor) else None
        )
        self._birth_row = np.array([0, -1, TENTATIVE, 1, 0, 1, 0, 0], dtype=np.int64)
        rw = self.config.relink_window
        self._relink_window = 0 if rw is None else max(1, round(rw * self.config.fps))
        self._uid_ramp = uid_ramp(16)
        self.reset()

    def reset(self) -> None:
        """Forget every track; the next step starts from frame ``k = 0`` and ID 1."""
        self.tracks = TrackTable.empty()
        self.pstate = self.predictor.init(np.zeros((0, 2)))
        self._k = 0
        self.row_uids = np.zeros(0, dtype=np.int64)
        self._next_uid = 0
        self._next_id = 1
        self._gone = empty_gallery()  # confirmed tracks ended within the relink window
        if self.associator.scores is not None:
            self.associator.scores.reset()

    def prime_scores(self, scores: Any) -> None:
        """Calibrate the ``"auto"`` score scale on ``scores`` (every score of an offline run)
        instead of on the scores seen so far (:class:`~mvtrack.tracking.scores.ScoreCalibration`).
        """
        if self.associator.scores is not None:
            self.associator.scores.prime(scores)

    @property
    def n_tracks(self) -> int:
        """Number of live tracks (tentative included)."""
        return len(self.tracks)

    @property
    def n_ids(self) -> int:
        """Public IDs handed out so far."""
        return self._next_id - 1

    def step(self, dets: Detections, rescue: RescueFn | None = None) -> TrackFrame:
        """Process one frame of detections; return the output rows of this frame.

        Parameters
        ----------
        dets : Detections
            This frame's detections (any row order; ``det_index`` in the output refers to it).
        rescue : callable, optional
            ``rescue(uids, predicted_xy, wh) -> (found, xy)``, consulted for the non-tentative
            tracks that got no detection this frame; tracks with ``found`` True are updated
            with ``xy`` and take state ``STOPPED`` (kept alive, same ID).

        Returns
        -------
        TrackFrame
            One row per live track with a public ID (and tentative ones with ID −1 if
            ``config.output_tentative``): ``CONFIRMED`` rows carry the detection they used,
            ``COASTING`` rows the prediction, ``STOPPED`` rows the template-match position.
        """
        k, tab, ps, pred = self._k, self.tracks, self.pstate, self.predictor
        m = dets.xy.shape[0]
        drow = detection_rows(dets)  # x, y, w, h per detection, then a row of NaN
        sel = self.associator.score_select(dets) if m else None  # (high, low), None: all high
        out = None
        n = tab.ints.shape[0]
        if n and self._compiled is not None and rescue is None and n * m <= DENSE_LSA:
            tab, ps, out, ud = self._step_compiled(tab, ps, dets, drow, sel, k)
        elif n == 0:
            if sel is None:
                ud = np.arange(m)
            elif self.config.low_birth_iou is not None and sel[1].size:
                ud = self.associator.low_births(dets, drow, sel, sel[0])
            else:
                ud = sel[0]
        else:
            ps = pred.predict(ps)  # time update, eqs. (6)–(7) of paper 1
            gxy, f2, r_rows = self.associator.centres(tab, ps, k)
            det_index, n_matched, ud, recovered = self.associator.associate(
                tab, ps, gxy, f2, r_rows, dets, drow, sel, k
            )
            tab, ps, matched, rescued, z = self._update(
                tab, ps, gxy, r_rows, det_index, n_matched, recovered, drow, rescue, k
            )
            tab, ps, out = self._life_cycle(tab, ps, gxy, det_index, matched, rescued, z)
        born = None
        if ud.size:
            tab, ps, born = self._births(tab, ps, drow, ud, k)
        self.tracks, self.pstate = tab, ps
        self._k = k + 1
        return self._frame(dets.frame, out, born)

    # ---------------------------------------------------------------------------- internals

    def _step_compiled(
        self, tab: TrackTable, ps: Any, dets: Detections, drow: FloatArray,
        sel: tuple[NDArray[np.intp], NDArray[np.intp]] | None, k: int,
    ) -> tuple[TrackTable, Any, tuple, NDArray[np.intp]]:
        """Predict, associate, update and the next states in one compiled call
        (:func:`mvtrack.tracking.compiled.frame_step`), then the relinking, the IDs and the
        output rows as in :meth:`_life_cycle`."""
        hi, lo = (np.arange(dets.xy.shape[0]), _NONE) if sel is None else sel
        ints, flo, x, P, gxy, z, det_index, delete, confirmed_now, ud = compiled.frame_step(
            tab.ints, tab.floats, ps.x, ps.P, drow, np.ascontiguousarray(dets.score), hi, lo,
            k, *self._compiled
        )
        tab, ps, out = self._close(
            TrackTable(ints, flo), CVState(x, P), gxy, det_index, z, delete, confirmed_now
        )
        return tab, ps, out, ud

    def _update(
        self, tab: TrackTable, ps: Any, gxy: FloatArray, r_rows: FloatArray | None,
        det_index: IntArray, n_matched: int, recovered: NDArray[np.intp] | None,
        drow: FloatArray, rescue: RescueFn | None, k: int,
    ) -> tuple[TrackTable, Any, BoolArray, BoolArray | None, FloatArray]:
        """Rescue, the measurement update of the predictors and of the table's columns
        (counters, last measurements, box size); returns the new table and state, the
        matched and rescued tracks and each track's measurement ``z`` (NaN: none)."""
        pred = self.predictor
        # each track's detection (x, y, w, h); NaN for the tracks without one (index −1)
        zwh = drow.take(det_index, 0)
        matched = det_index >= 0
        if self.associator.partial is not None and n_matched:
            zwh = self._complete_partial(zwh, tab.floats[:, WH], matched)
        z = zwh[:, :2]
        rescued = None
        held = matched
        if rescue is not None:
            rescued = self._rescue(rescue, tab, gxy, matched, z)  # fills z in place
            if rescued is not None:
                held = matched | rescued
        if r_rows is None:
            ps = pred.update(ps, z, held)  # measurement update, eqs. (3)–(5) of paper 1
        else:
            ps = pred.update(ps, z, held, r_rows)  # the same with r f² per track
        if recovered is not None:  # restart the predictor at the re-acquired detection
            new = (pred.init(z[recovered]) if r_rows is None
                   else pred.init(z[recovered], r_rows[recovered]))
            ps = put_state(ps, recovered, new)
        ints, flo = tab.ints.copy(), tab.floats.copy()
        count_hits(ints, matched, held)
        np.copyto(ints[:, PREV_K], ints[:, LAST_K], where=held)
        np.copyto(ints[:, LAST_K], k, where=held)
        held2 = held[:, None]
        np.copyto(flo[:, PREV_XY], flo[:, LAST_XY], where=held2)
        np.copyto(flo[:, LAST_XY], z, where=held2)
        if n_matched:  # box size: exponential average of the associated detections
            wh = flo[:, WH]
            np.add(wh, self.config.size_smoothing * (zwh[:, 2:] - wh), out=wh,
                   where=matched[:, None])
        return TrackTable(ints, flo), ps, matched, rescued, z

    def _complete_partial(self, zwh: FloatArray, twh: FloatArray, matched: BoolArray
                          ) -> FloatArray:
        """The measurements ``zwh`` (x, y, w, h per track) with each partial view
        (:func:`~mvtrack.association.discs.partial_views`: a matched detection the size gate
        let through although the boxes' sizes differ by more than its factor) replaced by the
        track's own box standing on the detection's bottom edge, ``(x_d, y_d + h_d/2 − h_t/2,
        w_t, h_t)``; ``zwh`` itself when there is none."""
        part = size_apart(twh, zwh[:, 2:], self.config.size_gate)
        part &= matched
        if not np.count_nonzero(part):
            return zwh
        zwh = zwh.copy()
        tp = twh[part]
        zwh[part, 1] += 0.5 * (zwh[part, 3] - tp[:, 1])  # the foot point: bottom edges equal
        zwh[part, 2:] = tp  # the size of the visible part says nothing of the object's
        return zwh

    def _life_cycle(
        self, tab: TrackTable, ps: Any, gxy: FloatArray, det_index: IntArray,
        matched: BoolArray, rescued: BoolArray | None, z: FloatArray,
    ) -> tuple[TrackTable, Any, tuple]:
        """Confirm, coast, delete (:func:`~mvtrack.tracking.lifecycle.next_state`); returns
        the surviving tracks and their state, and this frame's output columns and uids of
        the tracks shown."""
        fp, ints = self._fp, tab.ints
        state, delete, confirmed_now = next_state(ints, matched, rescued, fp)
        size = self.config.frame_size
        if size is not None:  # a track whose prediction left the image without a detection
            held = matched if rescued is None else matched | rescued
            out_x = (gxy[:, 0] < 0) | (gxy[:, 0] >= size[0])
            delete |= ~held & (out_x | (gxy[:, 1] < 0) | (gxy[:, 1] >= size[1]))
        ints[:, STATE] = state
        return self._close(tab, ps, gxy, det_index, z, delete, confirmed_now)

    def _close(
        self, tab: TrackTable, ps: Any, gxy: FloatArray, det_index: IntArray, z: FloatArray,
        delete: BoolArray, confirmed_now: BoolArray,
    ) -> tuple[TrackTable, Any, tuple]:
        """The end of the life cycle, the new states set in ``tab``: keep the ended tracks
        for relinking, relink or give IDs to the tracks confirmed now, this frame's output
        columns and uids, and the deletions."""
        fp, pred, ints, flo = self._fp, self.predictor, tab.ints, tab.floats
        state = ints[:, STATE]
        if self._relink_window:
            self._keep_ended(ints, flo, ps, delete)
        if np.count_nonzero(confirmed_now):
            if self._relink_window and self._gone[0].size:
                self._relink(ints, flo, confirmed_now, z)  # old IDs for some, in place
            self._next_id = hand_out_ids(ints, confirmed_now, self._next_id)
        show = ~delete if self.config.output_tentative else ~delete & (state != TENTATIVE)
        if fp.coast_output is not None:  # long coasting: alive, but no longer output
            show &= ints[:, MISSES] <= fp.coast_output
        rows = show.nonzero()[0]
        oi = ints.take(rows, 0)
        of = np.concatenate(  # one gather for all float columns of the output
            [z, pred.position(ps), gxy, flo[:, WH], pred.velocity(ps)], axis=1
        ).take(rows, 0)
        out = (
            oi[:, TID], oi[:, STATE], det_index.take(rows), of[:, 0:2], of[:, 2:4],
            of[:, 4:6], of[:, 6:8], of[:, 8:10],
        )
        if np.count_nonzero(delete):
            keep = kept_rows(delete)
            tab = tab.take(keep)
            ps = take_state(ps, keep)
        return tab, ps, (out, oi[:, UID])

    def _keep_ended(self, ints: Any, flo: Any, ps: Any, delete: BoolArray) -> None:
        """Add the confirmed tracks deleted this frame to the relink gallery and forget
        those that ended more than ``relink_window`` ago (:mod:`mvtrack.tracking.relink`)."""
        tid, kg, fg = self._gone
        gone = (delete & (ints[:, TID] > 0)).nonzero()[0]
        if gone.size == 0 and (kg.size == 0 or self._k - kg.min() <= self._relink_window):
            return  # nothing ended now and nothing expired
        if gone.size:
            rows = np.column_stack([flo[gone][:, LAST_XY], self.predictor.velocity(ps)[gone],
                                    flo[gone][:, WH]])
            tid = np.concatenate([tid, ints[gone, TID]])
            kg = np.concatenate([kg, ints[gone, LAST_K]])
            fg = np.concatenate([fg, rows])
        live = self._k - kg <= self._relink_window
        self._gone = (tid[live], kg[live], fg[live])

    def _relink(self, ints: Any, flo: Any, confirmed_now: BoolArray, z: FloatArray) -> None:
        """Give the tracks confirmed now that continue an ended one its public ID (in place;
        they leave ``confirmed_now`` and the gallery)."""
        rows = confirmed_now.nonzero()[0]
        born = self._k - ints[rows, AGE] + 1
        fp = self._fp
        shown = fp.coast_output if fp.coast_output is not None else fp.max_misses
        a, b = pair_new_tracks(z[rows], flo[rows][:, WH], born, self._k, self._gone,
                               self.config.relink_reach, self._relink_window, shown)
        if a.size:
            ints[rows[a], TID] = self._gone[0][b]
            confirmed_now[rows[a]] = False
            keep = np.ones(self._gone[0].size, bool)
            keep[b] = False
            self._gone = tuple(x[keep] for x in self._gone)

    def _frame(self, frame: int, out: tuple | None, born: tuple | None) -> TrackFrame:
        """This frame's :class:`TrackFrame`: the existing tracks' rows ``out``, then the new
        tracks' ``born`` (each ``(columns, uids)`` or ``None``); sets :attr:`row_uids`."""
        if born is None:
            if out is None:
                self.row_uids = np.zeros(0, dtype=np.int64)
                return TrackFrame.empty(frame)
            self.row_uids = out[1]
            return TrackFrame(frame, *out[0])
        if out is None:
            self.row_uids = born[1]
            return TrackFrame(frame, *born[0])
        self.row_uids = np.concatenate([out[1], born[1]])
        return TrackFrame(
            frame, *[np.concatenate([a, b]) for a, b in zip(out[0], born[0], strict=True)]
        )

    def _rescue(
        self,
        rescue: RescueFn,
        tab: TrackTable,
        gxy: FloatArray,
        matched: BoolArray,
        z: FloatArray,
    ) -> BoolArray | None:
        """Offer unmatched non-tentative tracks to ``rescue``; found positions go into ``z``."""
        cand = (~matched & (tab.state != TENTATIVE)).nonzero()[0]
        if cand.size == 0:
            return None
        found, rxy = rescue(tab.uid[cand], gxy[cand], tab.wh[cand])
        found = np.asarray(found, dtype=bool).reshape(-1)
        rxy = np.asarray(rxy, dtype=np.float64).reshape(-1, 2)
        if found.shape[0] != cand.size or rxy.shape[0] != cand.size:
            raise ValueError(
                f"rescue must return a mask and (K, 2) positions for the K={cand.size} tracks "
                f"it was given; got {found.shape[0]} and {rxy.shape[0]} rows"
            )
        found &= np.isfinite(rxy).all(axis=1)
        rescued = np.zeros(len(tab), dtype=bool)
        sel = cand[found]
        rescued[sel] = True
        z[sel] = rxy[found]
        return rescued


    def _births(
        self, tab: TrackTable, ps: Any, drow: FloatArray, ud: NDArray[np.intp], k: int
    ) -> tuple[TrackTable, Any, tuple | None]:
        """New tentative tracks from the unassigned detections ``ud`` (SPEC §2.1 step 4);
        ``drow`` are the detections' rows ``x, y, w, h``
        (:func:`~mvtrack.tracking.table.detection_rows`)."""
        a, b = self.associator, ud.size
        src = drow.take(ud, 0)
        if b > 1:
            order = birth_order(src[:, :2])
            ud, src = ud.take(order), src.take(order, 0)
        floats = src.take(BIRTH_COLS, 1)  # last_xy, prev_xy (both the detection), wh
        xy, wh = floats[:, LAST_XY], floats[:, WH]
        if a.scale_r and np.count_nonzero(wh > a.ref):  # r f² from the detection's box
            r_new = self.predictor.r * a.r_factor(a.size_scale2(wh))
            new_ps = self.predictor.init(xy, r_new)
        else:
            new_ps = self.predictor.init(xy)
        row = self._birth_row  # uid, track_id, state, hits, misses, age, last_k, prev_k
        row[UID] = self._next_uid
        row[LAST_K] = row[PREV_K] = k
        if b > self._uid_ramp.shape[0]:
            self._uid_ramp = uid_ramp(2 * b)
        ints = row + self._uid_ramp[:b]  # uids next_uid, next_uid + 1, ...
        self._next_uid += b
        one = self._fp.confirm_hits <= 1
        if one:  # confirmed by their first detection: public IDs now
            ints[:, STATE] = CONFIRMED
            ints[:, TID] = np.arange(self._next_id, self._next_id + b)
            self._next_id += b
        born = None
        if one or self.config.output_tentative:
            born = (
                ints[:, TID], ints[:, STATE], ud.astype(np.int64), xy,
                self.predictor.position(new_ps), np.full((b, 2), np.nan), wh,
                self.predictor.velocity(new_ps),
            )
        if born is not None:
            born = (born, ints[:, UID])
        if tab.ints.shape[0] == 0:
            return TrackTable(ints, floats), new_ps, born
        tab = TrackTable(np.concatenate([tab.ints, ints]), np.concatenate([tab.floats, floats]))
        return tab, concat_state(ps, new_ps), born

    def gates(self) -> GateRegions:
        """The gates the next :meth:`step` applies, one per live track (tentative included).

        The predictor state is advanced one frame (the tracker is not changed). The centre is
        the prediction, or paper 1's warm-up centre ``2 y_k − y_{k−1}`` while a track has
        fewer than ``warmup_hits`` associations (SPEC §1.1 [R]). The shape is the configured
        distance's region (:func:`~mvtrack.association.regions.gate_shapes`); the Euclidean
        gates of boxes larger than ``size_ref`` are stretched to ``diag(f_x², f_y²)``, and the
        Mahalanobis disc of the closed-form ``kalman-cv`` is ``(P̄ + r f²) I``, as
        :meth:`step` applies them. The second stage's gates (``second_gate``) are stretched
        the same way; the recovery stage is not a gate around the centre and is left out.
        """
        ps = self.predictor.predict(self.pstate)
        return self.associator.regions(self.tracks, ps, self._k)
