"""The multi-target tracker: predict → gate → assign → update → life cycle, per frame.

One engine for every command and every configuration: the track table is a struct of arrays
(:class:`TrackTable`) beside the predictor's batch state, and a frame is a handful of calls,
each over all tracks at once — compiled kernels where the work is per track or per pair
(:mod:`mvtrack.jit`), no Python loop over tracks:

1. **scores** (:mod:`mvtrack.tracking.scores`): each detection's calibrated score, and its
   class: high, low or dropped;
2. **predict** every track one frame (:meth:`Predictor.predict`, eqs. (6)–(7) of paper 1;
   ``kalman-cv`` with each track's noise scaled by its box, :meth:`TrackerConfig.noise`);
3. **gate** (:class:`mvtrack.association.gate.Gate`): the centre (the prediction, or paper
   1's warm-up centre) and the region each track may take a detection in;
4. **assign** (:func:`mvtrack.association.assign.associate`): high detections first, then the
   low ones for the tracks left over, by the configured rule;
5. **rescue** (optional): the confirmed tracks left without detection are offered to the video
   pipeline's template matching (:meth:`associate` returns them, :meth:`commit` takes what it
   found); those it finds are held in state ``STOPPED``;
6. **update** the predictors with the measurements (eqs. (3)–(5) of paper 1);
7. **life cycle** (:mod:`mvtrack.tracking.lifecycle`): confirm, coast, lose, hand out IDs,
   start new tracks.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.assign import HIGH, LOW, RULE_CODES, associate
from mvtrack.association.distances import resolve_gate
from mvtrack.association.gate import Gate, GateRegions, warmup_centre
from mvtrack.association.view import TrackView
from mvtrack.filters.predictors import make_predictor
from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.lifecycle import (
    CONFIRMED,
    LAST_K,
    N_FLOAT,
    N_INT,
    PREV_K,
    SCORE,
    STATE,
    TENTATIVE,
    TID,
    UID,
    advance,
    births,
    hand_out_ids,
)
from mvtrack.tracking.scores import ScoreCalibration
from mvtrack.tracking.table import LAST_XY, PREV_XY, WH, TrackTable, concat_state, take_state
from mvtrack.types import Detections, TrackFrame

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: how many confirmed detections the initial ``velocity_prior`` counts for in the scene's
#: learnt speeds (:meth:`Tracker._learn_speeds`)
PRIOR_WEIGHT = 20

#: ``rescue(uids (K,), predicted_xy (K, 2), wh (K, 2)) -> (found (K,) bool, xy (K, 2))``
RescueFn = Callable[[IntArray, FloatArray, FloatArray], tuple[Any, Any]]

__all__ = ["Pending", "RescueFn", "TrackTable", "Tracker"]


@dataclass(frozen=True)
class Pending:
    """A frame associated but not yet committed (:meth:`Tracker.associate`).

    Attributes
    ----------
    dets : Detections
        The frame's detections.
    det_index : (N,) intp
        Each live track's detection (−1: none).
    centre : (N, 2)
        The gate centres (predicted positions).
    std : (N, 2)
        Standard deviation of each predicted position along x and y.
    unmatched : (K,) intp
        The rows of the confirmed tracks without detection: the ones a rescue may hold.
    uids, wh : (K,), (K, 2)
        Their internal uids and box sizes.
    """

    dets: Detections
    det_index: NDArray[np.intp]
    centre: FloatArray
    std: FloatArray
    unmatched: NDArray[np.intp]
    uids: IntArray
    wh: FloatArray
    cscore: FloatArray
    dclass: NDArray[np.int8]
    pstate: Any
    gate: Any = None


class Tracker:
    """Multi-target tracker over arrays; one :meth:`step` per frame.

    Parameters
    ----------
    config : TrackerConfig, optional
        Predictor, gate, assignment rule and life cycle (default :class:`TrackerConfig()`).
    frame_size : (float, float), optional
        Width and height of the image: a track without detection whose prediction leaves
        the image ends there (a video's tracker knows its image; a detection file's does not).

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
        Internal uids of the rows of the last returned :class:`~mvtrack.types.TrackFrame`.

    Examples
    --------
    >>> from mvtrack.tracking import Tracker
    >>> from mvtrack.types import Detections
    >>> tracker = Tracker()
    >>> for k in range(3):
    ...     out = tracker.step(Detections(k, [[10.0 + 2 * k, 20.0]], [[4.0, 3.0]]))
    >>> out.track_id.tolist(), out.det_index.tolist()
    ([1], [0])
    """

    def __init__(self, config: TrackerConfig | None = None,
                 frame_size: tuple[float, float] | None = None) -> None:
        self.config = TrackerConfig() if config is None else config
        if not isinstance(self.config, TrackerConfig):
            raise ValueError(f"Tracker: config must be a TrackerConfig, got {type(config)}")
        c = self.config
        self.frame_size = None if frame_size is None else (float(frame_size[0]),
                                                          float(frame_size[1]))
        params = dict(c.predictor_params)
        #: the interacting multiple model filter (steady and manoeuvring)
        self._imm = c.predictor == "kalman-imm"
        if self._imm:
            params.setdefault("switch", c.mode_switching())
        self.predictor = make_predictor(c.predictor, **params)
        #: the noise follows each track's box (kalman-cv without fixed r, q)
        self.scales = c.scales_noise
        self.threshold = resolve_gate(c.distance, c.gate)
        self._size_w = 0.0 if c.size_noise is None else 1.0 / c.size_noise**2
        self._rule = RULE_CODES[c.assign]
        self._params = c.life_cycle(self.frame_size)
        self._birth_iou = np.inf if c.birth_iou is None else float(c.birth_iou)
        self._scores = (
            ScoreCalibration(c.score_scale)
            if c.score_high is not None or c.min_score > 0 else None
        )
        self._no_cost = np.zeros((0, 0))
        self.reset()

    def reset(self) -> None:
        """Forget every track; the next step starts from frame ``k = 0`` and ID 1."""
        self.tracks = TrackTable.empty()
        self.pstate = self.predictor.init(np.zeros((0, 2)))
        self._k = 0
        self.row_uids = np.zeros(0, dtype=np.int64)
        self._next_uid = 0
        self._next_id = 1
        # the scene's speeds, E[(v / box size)²] per axis in (sizes/s)², learnt from the
        # confirmed tracks' detections; it starts as velocity_prior² worth PRIOR_WEIGHT of them
        self._v2 = np.full(2, float(self.config.velocity_prior) ** 2 * PRIOR_WEIGHT)
        self._v2n = float(PRIOR_WEIGHT)
        if self._scores is not None:
            self._scores.reset()

    def prime_scores(self, scores: Any) -> None:
        """Calibrate the ``"auto"`` score scale on ``scores`` (every score of an offline run)
        instead of on the scores seen so far."""
        if self._scores is not None:
            self._scores.prime(scores)

    @property
    def n_tracks(self) -> int:
        """Number of live tracks (tentative included)."""
        return len(self.tracks)

    @property
    def n_ids(self) -> int:
        """Public IDs handed out so far."""
        return self._next_id - 1

    # --------------------------------------------------------------------------------- a frame

    def step(self, dets: Detections, rescue: RescueFn | None = None) -> TrackFrame:
        """Process one frame of detections; return the output rows of this frame.

        Parameters
        ----------
        dets : Detections
            This frame's detections (any row order; ``det_index`` in the output refers to it).
        rescue : callable, optional
            ``rescue(uids, predicted_xy, wh) -> (found, xy)``, consulted for the confirmed
            tracks that got no detection this frame; tracks with ``found`` True are updated
            with ``xy`` and take state ``STOPPED`` (kept alive, same ID).

        Returns
        -------
        TrackFrame
            One row per track shown (:mod:`mvtrack.tracking.lifecycle`): ``CONFIRMED`` rows
            carry the detection they used, ``COASTING`` rows the prediction, ``STOPPED`` rows
            the template-match position.
        """
        pending = self.associate(dets)
        found = xy = None
        if rescue is not None and pending.unmatched.size:
            found, xy = rescue(pending.uids, pending.centre[pending.unmatched], pending.wh)
        return self.commit(pending, found, xy)

    def associate(self, dets: Detections) -> Pending:
        """Steps 1–4 of a frame: scores, predict, gate, assign (the tracker is not changed
        until :meth:`commit`)."""
        m = dets.xy.shape[0]
        if self._scores is None or m == 0:
            cscore = np.ones(m)
            dclass = np.full(m, HIGH, np.int8)
        else:
            cscore = self._scores(dets.score)
            c = self.config
            high = cscore >= (0.0 if c.score_high is None else c.score_high)
            dclass = np.where(cscore >= c.min_score, np.where(high, HIGH, LOW), 0)
            dclass = dclass.astype(np.int8)
        tab, ps = self.tracks, self.pstate
        n = len(tab)
        if n == 0:
            e = np.zeros((0, 2))
            return Pending(dets, np.zeros(0, np.intp), e, e, np.zeros(0, np.intp),
                           np.zeros(0, np.int64), e, cscore, dclass, ps)
        ps = self._predict(ps, tab)
        gate = self._gate(ps, tab, self._k)
        cost = self._no_cost if gate.quadratic else gate.matrix(dets.xy, dets.wh)
        det_index = associate(gate.view.xy, gate.cov, np.ascontiguousarray(cost),
                              tab.floats[:, WH], dets.xy, dets.wh, dclass, gate.threshold,
                              gate.size_weight, gate.size_log, self._rule)
        cov = gate.view.cov
        std = np.sqrt(np.stack([cov[:, 0, 0], cov[:, 1, 1]], axis=1))
        unmatched = ((det_index < 0) & (tab.ints[:, STATE] != TENTATIVE)).nonzero()[0]
        return Pending(dets, det_index, gate.view.xy, std, unmatched,
                       tab.ints[unmatched, UID], tab.floats[unmatched][:, WH], cscore, dclass,
                       ps, gate)

    def commit(self, pending: Pending, found: Any = None, xy: Any = None) -> TrackFrame:
        """Steps 5–7 of a frame: the rescued tracks (``found``, ``xy`` for the rows of
        ``pending.unmatched``), update, life cycle, births; returns the frame's rows."""
        dets, det_index, k = pending.dets, pending.det_index, self._k
        tab, ps = self.tracks, pending.pstate
        n = len(tab)
        ints, flo = tab.ints.copy(), tab.floats.copy()
        out = None
        if n:
            # each track's detection (x, y, w, h, score); the last row (index −1) is none
            drow = np.empty((len(dets) + 1, 5))
            drow[:-1, :2], drow[:-1, 2:4], drow[:-1, 4] = dets.xy, dets.wh, pending.cscore
            drow[-1] = (np.nan, np.nan, np.nan, np.nan, 0.0)
            zrow = drow[det_index]
            z, zwh, zscore = zrow[:, :2], zrow[:, 2:4], zrow[:, 4]
            matched = det_index >= 0
            rescued = self._rescued(pending, found, xy, z)
            held = matched | rescued
            ps = self._update(ps, z, held, flo[:, WH])
            delete, confirmed_now, show = advance(
                ints, flo, det_index, rescued, z, zwh, zscore, pending.std, pending.centre, k,
                self._params,
            )
            if confirmed_now.any():
                self._next_id = hand_out_ids(ints, confirmed_now, self._next_id)
            pos, vel = self.predictor.position(ps), self.predictor.velocity(ps)
            if self.scales:
                self._learn_speeds(vel, flo, matched & (ints[:, STATE] == CONFIRMED))
            r = show.nonzero()[0]
            out = (ints[r, TID], ints[r, STATE], det_index[r].astype(np.int64), z[r], pos[r],
                   pending.centre[r], flo[r][:, WH], vel[r], ints[r, UID])
            if delete.any():
                keep = (~delete).nonzero()[0]
                ints, flo, ps = ints[keep], flo[keep], take_state(ps, keep)
        born = None
        used = np.zeros(len(dets), bool)
        used[det_index[det_index >= 0]] = True
        new = births(dets.xy, dets.wh, pending.dclass, used, self.predictor.position(ps)
                     if len(ints) else np.zeros((0, 2)), flo[:, WH], self._birth_iou)
        if new.size:
            ints, flo, ps, born = self._births(ints, flo, ps, dets, new, pending.cscore, k)
        self.tracks, self.pstate = TrackTable(ints, flo), ps
        self._k = k + 1
        return self._frame(dets.frame, out, born)

    # ---------------------------------------------------------------------------- internals

    def _predict(self, ps: Any, tab: TrackTable) -> Any:
        """Time update; ``kalman-cv`` with each track's own noise."""
        if self.scales:
            wh = tab.floats[:, WH]
            if self._imm:
                return self.predictor.predict(ps, *self.config.accelerations(wh))
            return self.predictor.predict(ps, self.config.accelerations(wh)[0])
        return self.predictor.predict(ps)

    def _update(self, ps: Any, z: FloatArray, held: BoolArray, wh: FloatArray) -> Any:
        """Measurement update of the held tracks (NaN rows of ``z`` keep the prediction)."""
        if self.scales:
            return self.predictor.update(ps, z, held, self.config.noise(wh)[0])
        return self.predictor.update(ps, z, held)

    def _gate(self, ps: Any, tab: TrackTable, k: int) -> Gate:
        """The gates of the predicted tracks (:class:`~mvtrack.association.gate.Gate`)."""
        pred, c = self.predictor, self.config
        wh = tab.floats[:, WH]
        centre = pred.position(ps)
        if c.warmup:
            centre = warmup_centre(centre, tab.hits, tab.last_xy, tab.prev_xy, tab.last_k,
                                   tab.prev_k, k, c.warmup)
        cov = pred.position_cov(ps)
        if self.scales:
            S = pred.innovation_cov(ps, c.noise(wh)[0])
        else:
            S = pred.innovation_cov(ps)
        view = TrackView(centre, cov, S, pred.velocity(ps), wh)
        return Gate.build(c.distance, view, self.threshold, size_weight=self._size_w,
                          **c.distance_params)

    def _learn_speeds(self, vel: FloatArray, flo: FloatArray, sel: BoolArray) -> None:
        """Add the speeds of the tracks ``sel`` (in box sizes per second) to the scene's."""
        if sel.any():
            rel = vel[sel] * self.config.fps / flo[sel][:, WH]
            self._v2 += (rel * rel).sum(axis=0)
            self._v2n += int(sel.sum())

    def _rescued(self, pending: Pending, found: Any, xy: Any, z: FloatArray) -> BoolArray:
        """The tracks held by template matching; their positions go into ``z`` (in place)."""
        rescued = np.zeros(z.shape[0], dtype=bool)
        if found is None:
            return rescued
        cand = pending.unmatched
        found = np.asarray(found, dtype=bool).reshape(-1)
        rxy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        if found.shape[0] != cand.size or rxy.shape[0] != cand.size:
            raise ValueError(
                f"rescue must return a mask and (K, 2) positions for the K={cand.size} tracks "
                f"it was given; got {found.shape[0]} and {rxy.shape[0]} rows"
            )
        found &= np.isfinite(rxy).all(axis=1)
        sel = cand[found]
        rescued[sel] = True
        z[sel] = rxy[found]
        return rescued

    def _births(self, ints: IntArray, flo: FloatArray, ps: Any, dets: Detections,
                new: NDArray[np.intp], cscore: FloatArray, k: int
                ) -> tuple[IntArray, FloatArray, Any, tuple | None]:
        """New tentative tracks from the detections ``new``; confirmed at once when one
        detection confirms (the papers' presets)."""
        b = new.size
        xy, wh = dets.xy[new], dets.wh[new]
        bi = np.zeros((b, N_INT), np.int64)
        bi[:, UID] = np.arange(self._next_uid, self._next_uid + b)
        self._next_uid += b
        bi[:, TID] = -1
        bi[:, STATE] = TENTATIVE
        bi[:, 3] = 1  # hits
        bi[:, 5] = 1  # age
        bi[:, LAST_K] = bi[:, PREV_K] = k
        bf = np.zeros((b, N_FLOAT))
        bf[:, LAST_XY] = bf[:, PREV_XY] = xy
        bf[:, WH] = wh
        bf[:, SCORE] = cscore[new]
        c = self.config
        if c.confirm_hits <= 1:
            now = bf[:, SCORE] >= c.confirm_score
            bi[now, STATE] = CONFIRMED
            self._next_id = hand_out_ids(bi, now, self._next_id)
        if self.scales:
            r, vv = c.noise(wh, self._v2 / self._v2n)
            new_ps = self.predictor.init(xy, r, vv)
        else:
            new_ps = self.predictor.init(xy)
        born = None
        show = (bi[:, STATE] != TENTATIVE) | c.output_tentative
        if show.any():
            s = show.nonzero()[0]
            born = (bi[s, TID], bi[s, STATE], new[s].astype(np.int64), xy[s],
                    self.predictor.position(new_ps)[s], np.full((s.size, 2), np.nan), wh[s],
                    self.predictor.velocity(new_ps)[s], bi[s, UID])
        if ints.shape[0] == 0:
            return bi, bf, new_ps, born
        return (np.concatenate([ints, bi]), np.concatenate([flo, bf]),
                concat_state(ps, new_ps), born)

    def _frame(self, frame: int, out: tuple | None, born: tuple | None) -> TrackFrame:
        """This frame's :class:`TrackFrame`: the existing tracks' rows, then the new tracks'
        (each ``(columns..., uids)`` or ``None``); sets :attr:`row_uids`."""
        parts = [p for p in (out, born) if p is not None and p[0].size]
        if not parts:
            self.row_uids = np.zeros(0, dtype=np.int64)
            return TrackFrame.empty(frame)
        if len(parts) == 1:
            cols = parts[0]
        else:
            cols = tuple(np.concatenate([a, b]) for a, b in zip(*parts, strict=True))
        self.row_uids = cols[-1]
        return TrackFrame(frame, *cols[:-1])

    def gates(self) -> GateRegions:
        """The gates the next :meth:`step` applies, one per live track (tentative included),
        as regions to draw; the tracker is not changed."""
        tab = self.tracks
        if len(tab) == 0:
            return GateRegions(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 2)),
                               np.zeros((0, 2, 2)), self.threshold)
        ps = self._predict(self.pstate, tab)
        return self._gate(ps, tab, self._k).regions(tab.uid, tab.track_id)
