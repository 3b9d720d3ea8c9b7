"""The multi-target tracker: predict → gate → assign → update → life cycle, per frame.

One engine for every command and every configuration: the track table is a struct of arrays
(:class:`TrackTable`) beside the predictor's batch state, and a frame is a few calls over all
tracks at once — compiled kernels where the work is per track or per pair (:mod:`mvtrack.jit`),
no Python loop over tracks:

1. **scores** (:mod:`mvtrack.tracking.scores`): each detection's calibrated score and class
   (high, low, dropped);
2. **predict** every track one frame (:meth:`Predictor.predict`, eqs. (6)–(7) of paper 1; the
   default ``kalman-imm`` with its noise in box sizes, :meth:`TrackerConfig.accelerations`);
3. **gate** (:class:`mvtrack.association.gate.Gate`): each track's centre (the prediction, or
   paper 1's warm-up centre) and region;
4. **assign** (:func:`mvtrack.association.assign.associate`): the high detections first, then
   the low ones for the tracks left over;
5. **rescue** (optional): the confirmed tracks left without detection are offered to the video
   pipeline's template matching (:meth:`associate` returns them in a :class:`Pending`,
   :meth:`commit` takes what it found); the ones found are held in state ``STOPPED``;
6. **update** the predictors with their measurements (eqs. (3)–(5) of paper 1);
7. **life cycle** (:func:`mvtrack.tracking.lifecycle.commit`): confirm, coast, lose, hand out
   IDs, write the frame's rows, start new tracks.

For the default family (``kalman-imm``, ``mahalanobis``) steps 2–4 and 6–7 each run as one
compiled call (:mod:`mvtrack.tracking.step`) that composes the same kernels; any other
predictor or distance composes them from here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.assign import HIGH, LOW, RULE_CODES, associate
from mvtrack.association.gate import Gate, GateRegions, tracker_gate, warmup_centre
from mvtrack.association.shared import OFF, measurement_var, shared
from mvtrack.association.view import TrackView
from mvtrack.filters.imm import IMMState
from mvtrack.filters.predictors import make_predictor
from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.lifecycle import STATE, TENTATIVE, UID, commit, measurements, standing
from mvtrack.tracking.scores import ScoreCalibration
from mvtrack.tracking.step import predict_assign, update_commit
from mvtrack.tracking.table import WH, TrackTable, concat_state, take_state
from mvtrack.types import Detections, TrackFrame

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: how many confirmed detections the initial ``velocity_prior`` counts for in the scene's
#: learnt speeds (:attr:`Tracker.speed_prior`)
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
    cscore, dclass : (M,), (M,)
        The detections' calibrated scores and classes.
    pstate : dataclass
        The predicted state of the filter.
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


class Tracker:
    """Multi-target tracker over arrays; one :meth:`step` per frame.

    Parameters
    ----------
    config : TrackerConfig, optional
        Predictor, gate, assignment rule and life cycle (default :class:`TrackerConfig()`).
    frame_size : (float, float), optional
        Width and height of the image: a track without detection whose prediction leaves
        the image ends there (a video's tracker knows its image; a detection file's does not).
    fused : bool
        Run the default family's frame as two compiled calls (:mod:`mvtrack.tracking.step`);
        False composes the same kernels from Python (the tests compare the two).

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
    ...     out = tracker.step(Detections(k, [[100.0 + 2 * k, 80.0]], [[40.0, 90.0]]))
    >>> out.track_id.tolist(), out.det_index.tolist()
    ([1], [0])
    """

    def __init__(self, config: TrackerConfig | None = None,
                 frame_size: tuple[float, float] | None = None, fused: bool = True) -> None:
        self.config = c = TrackerConfig() if config is None else config
        if not isinstance(c, TrackerConfig):
            raise ValueError(f"Tracker: config must be a TrackerConfig, got {type(config)}")
        self.frame_size = None if frame_size is None else (float(frame_size[0]),
                                                          float(frame_size[1]))
        params = dict(c.predictor_params)
        imm = c.predictor == "kalman-imm"
        if imm:
            params.setdefault("switch", c.mode_switching())
        self.predictor = make_predictor(c.predictor, **params)
        #: the noise follows each track's box (kalman-imm, kalman-cv without fixed r, q)
        self.scales = c.scales_noise
        #: the default family runs as two compiled calls (mvtrack.tracking.step)
        self.fused = (fused and imm and self.scales and c.distance == "mahalanobis"
                      and not c.distance_params and not c.warmup)
        f2 = 1.0 / c.fps**2
        self._accel = np.array([c.accel_noise * f2, c.manoeuvre_noise * f2])
        self._pi = self.predictor.transitions() if imm else None
        self.threshold, self._box_var = tracker_gate(
            c.distance, c.gate, c.measurement_noise, c.velocity_prior, c.accel_noise, c.fps)
        self._size_w = 0.0 if c.size_noise is None else 1.0 / c.size_noise**2
        self._rule = RULE_CODES[c.assign]
        self._t_shared = OFF if c.shared_iou is None else float(c.shared_iou)
        self._params = c.life_cycle(self.frame_size)
        self._scores = (
            ScoreCalibration(c.score_scale)
            if c.score_high is not None or c.min_score > 0 else None
        )
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
    def steps(self) -> int:
        """Frames processed so far: the step number of the frame being processed (the unit of
        the tracks' ``last_k``)."""
        return self._k

    @property
    def n_ids(self) -> int:
        """Public IDs handed out so far."""
        return self._next_id - 1

    @property
    def speed_prior(self) -> FloatArray:
        """The velocity variance of a new track, (box sizes/s)² along x and y: the mean of
        ``(v / box)²`` over the confirmed tracks' detections so far, with ``velocity_prior²``
        counted as :data:`PRIOR_WEIGHT` of them (an empirical-Bayes prior: a new object moves
        like the scene's objects; a highway's cars open wider first gates than a campus's
        walkers)."""
        return self._v2 / self._v2n

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
        cscore, dclass = self._classes(dets)
        tab, ps = self.tracks, self.pstate
        n = len(tab)
        if n == 0:
            e = np.zeros((0, 2))
            return Pending(dets, np.zeros(0, np.intp), e, e, np.zeros(0, np.intp),
                           np.zeros(0, np.int64), e, cscore, dclass, ps)
        wh = np.ascontiguousarray(tab.floats[:, WH])  # one layout: one compiled kernel
        stand = standing(tab.ints, tab.floats)  # a held track takes only what lies in its box
        if self.fused:  # the same steps in one compiled call (mvtrack.tracking.step)
            x, P, mu, centre, _, std, det_index = predict_assign(
                ps.x, ps.P, ps.mu, wh, self._accel, self._pi, self.config.measurement_noise,
                dets.xy, dets.wh, dclass, self.threshold, self._size_w, self._rule, stand,
            )
            ps = IMMState(x, P, mu)
        else:
            ps = self._predict(ps, tab)
            gate = self._gate(ps, tab, self._k)
            det_index = associate(gate.view.xy, gate.cov, gate.dense(dets.xy, dets.wh), wh,
                                  dets.xy, dets.wh, dclass, gate.threshold, gate.size_weight,
                                  self._rule, stand, gate.search)
            centre, c = gate.view.xy, gate.view.cov
            std = np.sqrt(np.stack([c[:, 0, 0], c[:, 1, 1]], axis=1))
        unmatched = ((det_index < 0) & (tab.ints[:, STATE] != TENTATIVE)).nonzero()[0]
        return Pending(dets, det_index, centre, std, unmatched, tab.ints[unmatched, UID],
                       wh[unmatched], cscore, dclass, ps)

    def commit(self, pending: Pending, found: Any = None, xy: Any = None) -> TrackFrame:
        """Steps 5–7 of a frame: the rescued tracks (``found``, ``xy`` for the rows of
        ``pending.unmatched``), update, life cycle, births; returns the frame's rows."""
        dets, det_index, k = pending.dets, pending.det_index, self._k
        tab, ps = self.tracks, pending.pstate
        n = len(tab)
        fmask, fxy = self._found(pending, found, xy, n)
        ints, flo = tab.ints.copy(), tab.floats.copy()
        if self.fused:
            x, P, mu, *out = update_commit(
                ps.x, ps.P, ps.mu, ints, flo, det_index, fmask, fxy, dets.xy, dets.wh,
                pending.dclass, pending.cscore, pending.std, pending.centre,
                self.config.measurement_noise, self.speed_prior, k, self._params,
                self._next_id, self._next_uid, self._pi, self._t_shared,
            )
            ps = IMMState(x, P, mu)
        else:
            z, zwh, zscore, rescued, held = measurements(det_index, dets.xy, dets.wh,
                                                         pending.cscore, fmask, fxy)
            if n:
                ps = self._update(ps, z, held, np.ascontiguousarray(flo[:, WH]), pending)
            pos, vel = self.predictor.position(ps), self.predictor.velocity(ps)
            out = commit(ints, flo, det_index, rescued, z, zwh, zscore, pending.std,
                         pending.centre, np.ascontiguousarray(pos), np.ascontiguousarray(vel),
                         dets.xy, dets.wh, pending.dclass, pending.cscore, k, self._params,
                         self._next_id, self._next_uid)
            keep, new = out[2], out[3]
            ps = take_state(ps, keep)
            if new.size:
                new_ps = self._init(dets.xy[new], dets.wh[new])
                ps = concat_state(ps, new_ps) if keep.size else new_ps
        ints2, flo2, _, _, *rows, next_id, next_uid, speed2, n_speed = out
        self._next_id, self._next_uid = int(next_id), int(next_uid)
        if self.scales and n_speed:
            self._v2 += speed2
            self._v2n += n_speed
        self.tracks, self.pstate = TrackTable(ints2, flo2), ps
        self._k = k + 1
        self.row_uids = rows[-1]
        return TrackFrame(dets.frame, *rows[:-1])

    # ---------------------------------------------------------------------------- internals

    def _classes(self, dets: Detections) -> tuple[FloatArray, NDArray[np.int8]]:
        """Each detection's calibrated score and class (high, low or dropped)."""
        m = dets.xy.shape[0]
        if self._scores is None or m == 0:
            return np.ones(m), np.full(m, HIGH, np.int8)
        cscore = self._scores(dets.score)
        c = self.config
        high = cscore >= (0.0 if c.score_high is None else c.score_high)
        dclass = np.where(cscore >= c.min_score, np.where(high, HIGH, LOW), 0)
        return cscore, dclass.astype(np.int8)

    def _found(self, pending: Pending, found: Any, xy: Any, n: int
               ) -> tuple[BoolArray, FloatArray]:
        """The rescue's answer spread over the ``n`` tracks (mask and positions)."""
        fmask = np.zeros(n, dtype=bool)
        fxy = np.zeros((n, 2))
        if found is None:
            return fmask, fxy
        cand = pending.unmatched
        found = np.asarray(found, dtype=bool).reshape(-1)
        rxy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        if found.shape[0] != cand.size or rxy.shape[0] != cand.size:
            raise ValueError(
                f"rescue must return a mask and (K, 2) positions for the K={cand.size} tracks "
                f"it was given; got {found.shape[0]} and {rxy.shape[0]} rows"
            )
        fmask[cand] = found
        fxy[cand] = rxy
        return fmask, fxy

    def _predict(self, ps: Any, tab: TrackTable) -> Any:
        """Time update; ``kalman-imm`` and ``kalman-cv`` with each track's own noise."""
        if not self.scales:
            return self.predictor.predict(ps)
        q = self.config.accelerations(tab.floats[:, WH])
        return self.predictor.predict(ps, *q) if self._pi is not None else \
            self.predictor.predict(ps, q[0])

    def _update(self, ps: Any, z: FloatArray, held: BoolArray, wh: FloatArray,
                pending: Pending) -> Any:
        """Measurement update of the held tracks (NaN rows of ``z`` keep the prediction);
        a shared box's noise is wider (:mod:`mvtrack.association.shared`)."""
        if self.scales:
            d = pending.dets
            is_shared = shared(pending.det_index, pending.centre, wh, d.xy, d.wh,
                               pending.dclass, self._t_shared)
            r = measurement_var(self.config.measurement_noise, wh, is_shared, self._t_shared)
            return self.predictor.update(ps, z, held, r)
        return self.predictor.update(ps, z, held)

    def _init(self, xy: FloatArray, wh: FloatArray) -> Any:
        """The filters of new tracks at ``xy`` with boxes ``wh``."""
        if self.scales:
            return self.predictor.init(xy, *self.config.noise(wh, self.speed_prior))
        return self.predictor.init(xy)

    def _gate(self, ps: Any, tab: TrackTable, k: int) -> Gate:
        """The gates of the predicted tracks (:class:`~mvtrack.association.gate.Gate`)."""
        pred, c = self.predictor, self.config
        wh = tab.floats[:, WH]
        centre = pred.position(ps)
        if c.warmup:
            centre = warmup_centre(centre, tab.hits, tab.last_xy, tab.prev_xy, tab.last_k,
                                   tab.prev_k, k, c.warmup)
        cov = pred.position_cov(ps)
        S = pred.innovation_cov(ps, c.noise(wh)[0]) if self.scales else pred.innovation_cov(ps)
        view = TrackView(centre, cov, S, pred.velocity(ps), wh)
        return Gate.build(c.distance, view, self.threshold, size_weight=self._size_w,
                          box_var=self._box_var, **c.distance_params)

    def gates(self) -> GateRegions:
        """The gates the next :meth:`step` applies, one per live track (tentative included),
        as regions to draw; the tracker is not changed."""
        tab = self.tracks
        if len(tab) == 0:
            return GateRegions(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 2)),
                               np.zeros((0, 2, 2)), self.threshold)
        ps = self._predict(self.pstate, tab)
        return self._gate(ps, tab, self._k).regions(tab.uid, tab.track_id)
