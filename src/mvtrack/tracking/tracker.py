"""The multi-target tracker: predict → gate → assign → update → life cycle, per frame.

All track state is a struct of arrays (:class:`TrackTable`, one row per live track) plus the
predictor's batch state; a frame costs a fixed number of array operations whatever the number
of tracks, and no Python loop runs over tracks. The pipeline is SPEC §1.1 steps 4–5 (paper 1)
and §2.1 steps 3–5 (paper 2):

1. **predict** every track one frame (:meth:`Predictor.predict`, eqs. (6)–(7) of paper 1);
   with ``warmup`` the gate centre is paper 1's ``2 y_k − y_{k−1}`` until 2M associations;
2. **gate and assign** with the configured distance, gate and rule — through
   :mod:`mvtrack.tracking.associate` for the disc-shaped gates (``euclidean``, and
   ``mahalanobis`` with the closed-form ``kalman-cv``), otherwise through
   :func:`mvtrack.association.candidate_pairs` and :func:`mvtrack.association.assign`;
   for boxes larger than ``size_ref`` the Euclidean gates stretch per axis with the box and
   the measurement noise with it, and the Euclidean cost gets a box-size term
   (``size_weight``);
3. optionally a **second stage** (``second_gate``: a wider Euclidean gate for the tracks and
   detections left over) and a **recovery stage** (``recover_speed``: an established track
   that lost its target may take a leftover detection near its last measurement; its
   predictor restarts there, so a target that bounced or turned keeps its ID);
4. **rescue** (optional): confirmed tracks that got no detection are offered to the video
   pipeline's template matching; the ones it finds are held in state ``STOPPED``;
5. **update** the predictors with the assigned measurements (eqs. (3)–(5) of paper 1);
6. **life cycle** (:mod:`mvtrack.tracking.lifecycle`): confirm, coast, delete, and start new
   tentative tracks from the unassigned detections (new-target recognition, SPEC §2.1 step 4);
   a coasting track's rows are output only for its first ``coast_output`` seconds.

``kalman-cv`` runs in the closed form of :mod:`mvtrack.tracking.fastkf` (the same filter as
:mod:`mvtrack.filters.predictors`' ``kalman-cv``, tested equal to 1e-9); every other predictor
is built by :func:`mvtrack.filters.predictors.make_predictor`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.assign import assign as assign_pairs
from mvtrack.association.distances import TrackView, get_distance
from mvtrack.association.gating import candidate_pairs
from mvtrack.association.regions import SHAPE_PARAMS, GateRegions, axis_shapes, gate_shapes
from mvtrack.filters.predictors import make_predictor
from mvtrack.tracking import associate as fast_assoc
from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.config import _round as _round_frames
from mvtrack.tracking.fastkf import CVState, FastCVPredictor
from mvtrack.tracking.lifecycle import (
    CONFIRMED,
    TENTATIVE,
    birth_order,
    count_hits,
    hand_out_ids,
    next_state,
)
from mvtrack.tracking.log import TrackLog, backfill, drop_short_tracks, interpolate_gaps
from mvtrack.tracking.scores import ScoreCalibration, duplicates
from mvtrack.types import Detections, TrackFrame, concat_rows, take_rows

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: ``rescue(uids (K,), predicted_xy (K, 2), wh (K, 2)) -> (found (K,) bool, xy (K, 2))``
_EMPTY = np.zeros(0, dtype=np.intp)

RescueFn = Callable[[IntArray, FloatArray, FloatArray], tuple[Any, Any]]


#: integer columns of :class:`TrackTable`
UID, TID, STATE, HITS, MISSES, AGE, LAST_K, PREV_K = range(8)
N_INT = 8
#: float columns: last measurement (x, y), the one before (x, y), box (w, h)
LAST_XY, PREV_XY, WH = slice(0, 2), slice(2, 4), slice(4, 6)
N_FLOAT = 6
#: the float columns of a new track from its detection's ``x, y, w, h``
_BIRTH_COLS = np.array([0, 1, 0, 1, 2, 3])


@dataclass(frozen=True)
class TrackTable:
    """The ``N`` live tracks as a struct of arrays (the predictor state is kept beside it).

    The columns are stored in two blocks, one ``int64`` and one ``float64``, so that growing
    and shrinking the table costs two array operations (``types.take_rows`` / ``concat_rows``
    work on it too); the properties give each column by name.

    Attributes
    ----------
    ints : (N, 8) int64
        ``uid, track_id, state, hits, misses, age, last_k, prev_k``.
    floats : (N, 6) float64
        ``last_xy (2), prev_xy (2), wh (2)``.
    """

    ints: IntArray
    floats: FloatArray

    def __len__(self) -> int:
        return int(self.ints.shape[0])

    @classmethod
    def empty(cls) -> TrackTable:
        """No tracks."""
        return cls(np.zeros((0, N_INT), dtype=np.int64), np.zeros((0, N_FLOAT)))

    def take(self, idx: NDArray[np.intp] | slice) -> TrackTable:
        """Rows ``idx`` (row indices, or a slice: views)."""
        if isinstance(idx, slice):
            return TrackTable(self.ints[idx], self.floats[idx])
        return TrackTable(self.ints.take(idx, 0), self.floats.take(idx, 0))

    @property
    def uid(self) -> IntArray:
        """(N,) internal identity, unique for the tracker's life, given at birth."""
        return self.ints[:, UID]

    @property
    def track_id(self) -> IntArray:
        """(N,) public ID (consecutive from 1 in order of confirmation), −1 while tentative."""
        return self.ints[:, TID]

    @property
    def state(self) -> IntArray:
        """(N,) :class:`~mvtrack.types.TrackState` after the last frame."""
        return self.ints[:, STATE]

    @property
    def hits(self) -> IntArray:
        """(N,) associations with a detection (the birth detection counts)."""
        return self.ints[:, HITS]

    @property
    def misses(self) -> IntArray:
        """(N,) consecutive frames without a detection or template match."""
        return self.ints[:, MISSES]

    @property
    def age(self) -> IntArray:
        """(N,) frames since birth (1 in the birth frame)."""
        return self.ints[:, AGE]

    @property
    def last_k(self) -> IntArray:
        """(N,) step number of the last measurement."""
        return self.ints[:, LAST_K]

    @property
    def prev_k(self) -> IntArray:
        """(N,) step number of the measurement before it (= last_k after one)."""
        return self.ints[:, PREV_K]

    @property
    def last_xy(self) -> FloatArray:
        """(N, 2) last measurement."""
        return self.floats[:, LAST_XY]

    @property
    def prev_xy(self) -> FloatArray:
        """(N, 2) the measurement before the last (= last after one)."""
        return self.floats[:, PREV_XY]

    @property
    def wh(self) -> FloatArray:
        """(N, 2) box size, exponentially smoothed over the associated detections."""
        return self.floats[:, WH]


def _take_state(state: Any, idx: NDArray[np.intp] | slice) -> Any:
    if type(state) is CVState:
        if isinstance(idx, slice):
            return CVState(state.x[idx], state.P[idx])
        return CVState(state.x.take(idx, 0), state.P.take(idx, 0))
    return take_rows(state, idx)


def _kept_rows(delete: BoolArray) -> NDArray[np.intp] | slice:
    """The rows not in ``delete``: a slice when they are the first ones (only the last rows
    end, as when last frame's false alarms end), else their indices."""
    keep = (~delete).nonzero()[0]
    if keep.size == 0 or keep[-1] == keep.size - 1:
        return slice(0, keep.size)
    return keep


def _uid_ramp(b: int) -> IntArray:
    """(b, 8) int64: 0, 1, ..., b − 1 in the uid column, 0 elsewhere (added to a birth row)."""
    ramp = np.zeros((b, N_INT), dtype=np.int64)
    ramp[:, UID] = np.arange(b)
    return ramp


def _detection_rows(dets: Detections) -> FloatArray:
    """(M + 1, 4): each detection's ``x, y, w, h``, then a row of NaN (the one index −1 takes,
    so that one ``take`` by a track's detection index also fills the tracks without one)."""
    m = dets.xy.shape[0]
    rows = np.empty((m + 1, 4))
    rows[:m, :2] = dets.xy
    rows[:m, 2:] = dets.wh
    rows[m] = np.nan
    return rows


def _put_state(state: Any, idx: NDArray[np.intp], new: Any) -> Any:
    """A copy of the batch ``state`` with rows ``idx`` replaced by the rows of ``new``."""
    changes = {}
    for f in dataclasses.fields(state):
        a = getattr(state, f.name)
        if isinstance(a, np.ndarray) and a.ndim >= 1:
            a = a.copy()
            a[idx] = getattr(new, f.name)
            changes[f.name] = a
    return dataclasses.replace(state, **changes)


def _concat_state(a: Any, b: Any) -> Any:
    if type(a) is CVState:
        return CVState(np.concatenate([a.x, b.x]), np.concatenate([a.P, b.P]))
    return concat_rows(a, b)


def _build_predictor(config: TrackerConfig) -> Any:
    """The configured predictor; ``kalman-cv`` in its closed form when its parameters allow."""
    params = _predictor_params(config)
    if config.predictor == "kalman-cv" and set(params) <= {"q", "r", "vel_var"}:
        make_predictor("kalman-cv", **params)  # same validation and error messages
        return FastCVPredictor(**params)
    return make_predictor(config.predictor, **params)


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

    def __init__(self, config: TrackerConfig | None = None) -> None:
        self.config = TrackerConfig() if config is None else config
        if not isinstance(self.config, TrackerConfig):
            raise ValueError(f"Tracker: config must be a TrackerConfig, got {type(config)}")
        self._fp = self.config.frames()
        self.predictor = _build_predictor(self.config)
        self._distance = get_distance(self.config.distance)
        self._distance_params = dict(self.config.distance_params)
        # the fast association path (mvtrack.tracking.associate) serves the disc-shaped gates
        self._fast_gate: str | None = None
        if not self._distance_params:
            if self.config.distance == "euclidean":
                self._fast_gate = "euclidean"
            elif self.config.distance == "mahalanobis" and isinstance(
                self.predictor, FastCVPredictor
            ):
                self._fast_gate = "mahalanobis"
        self._assign_params = dict(self.config.assign_params)
        sg = self.config.second_gate
        self._gate2 = None if sg is None else float(sg) ** 2
        self._gate = self._distance.gate if self.config.gate is None else float(self.config.gate)
        # scaling of the detection-related pixel values with the box size (config.size_ref)
        ref = self.config.size_ref
        self._ref = None if ref is None else float(ref)
        self._inv_ref2 = None if ref is None else 1.0 / float(ref) ** 2
        self._scale_r = self._inv_ref2 is not None and isinstance(self.predictor, FastCVPredictor)
        # box-size term of the Euclidean costs (in the units of the position cost)
        self._size_w = float(self.config.size_weight) if self._fast_gate == "euclidean" else 0.0
        # size gate of the Euclidean stages (config.size_gate)
        sgate = self.config.size_gate
        self._size_gate = (
            float(sgate) if sgate is not None and self._fast_gate == "euclidean" else None
        )
        self._birth_row = np.array([0, -1, TENTATIVE, 1, 0, 1, 0, 0], dtype=np.int64)
        self._uid_ramp = _uid_ramp(16)
        self._recover_hits = max(self.config.recover_min_hits, self._fp.confirm_hits)
        c = self.config
        self._scores = (
            ScoreCalibration(c.score_scale)
            if c.score_high is not None or c.min_score > 0 or c.nms_iou is not None
            else None
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
        if self._scores is not None:
            self._scores.reset()

    def prime_scores(self, scores: Any) -> None:
        """Calibrate the ``"auto"`` score scale on ``scores`` (every score of an offline run)
        instead of on the scores seen so far (:class:`~mvtrack.tracking.scores.ScoreCalibration`).
        """
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
        fp = self._fp
        k = self._k
        tab = self.tracks
        n = tab.ints.shape[0]
        m = dets.xy.shape[0]
        pred = self.predictor
        out = None
        ps = self.pstate
        drow = _detection_rows(dets)
        sel = self._score_select(dets) if m else None  # (high, low) rows, or None: all high
        if n == 0:
            ud = np.arange(m) if sel is None else sel[0]
        else:
            ps = pred.predict(ps)  # time update, eqs. (6)–(7) of paper 1
            gxy = pred.position(ps)
            if fp.warmup_hits:
                gxy = self._warmup_centre(tab, gxy, k)
            f2 = r_rows = None  # size factors, only when a box is larger than size_ref
            if self._ref is not None and np.count_nonzero(tab.floats[:, WH] > self._ref):
                f2 = self._size_scale2(tab.floats[:, WH])
                if self._scale_r:
                    r_rows = pred.r * self._r_factor(f2)  # r max(f_x, f_y)² per track
            staged = False
            first = dets if sel is None else dets.take(sel[0])  # the high detections
            if len(first) == 0:
                mt = md = ud = _EMPTY
            elif self._fast_gate is not None:
                mt, md, ud, staged = self._associate_fast(
                    ps, gxy, first, f2, r_rows, tab.floats[:, WH]
                )
            else:
                mt, md, ud = self._associate(ps, gxy, tab, first)
            if sel is not None:  # back to the rows of dets
                md, ud = sel[0].take(md), sel[0].take(ud)
            det_index = np.empty(n, dtype=np.int64)
            det_index.fill(-1)
            det_index[mt] = md
            if self._gate2 is not None and not staged and ud.size and mt.size < n:
                mt2, md2 = self._second_stage(gxy, det_index, drow, ud, f2, tab.floats[:, WH])
                if mt2.size:
                    det_index[mt2] = md2
                    mt, md = np.concatenate([mt, mt2]), np.concatenate([md, md2])
                    used = np.zeros(m, dtype=bool)
                    used[md2] = True
                    ud = ud[~used[ud]]
            recovered = None
            if self._fp.recover_speed is not None and ud.size and mt.size < n:
                mt2, md2 = self._recover(tab, det_index, drow, ud, k, f2)
                if mt2.size:
                    det_index[mt2] = md2
                    mt, md = np.concatenate([mt, mt2]), np.concatenate([md, md2])
                    used = np.zeros(m, dtype=bool)
                    used[md2] = True
                    ud = ud[~used[ud]]
                    recovered = mt2
            if sel is not None and sel[1].size and mt.size < n:  # low detections, last
                mt2, md2 = self._low_stage(ps, gxy, tab, det_index, drow, sel[1], f2, r_rows)
                if mt2.size:
                    det_index[mt2] = md2
                    mt, md = np.concatenate([mt, mt2]), np.concatenate([md, md2])
            # each track's detection (x, y, w, h); NaN for the tracks without one (index −1)
            zwh = drow.take(det_index, 0)
            z = zwh[:, :2]
            matched = det_index >= 0
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
                ps = _put_state(ps, recovered, new)
            ints, flo = tab.ints.copy(), tab.floats.copy()
            count_hits(ints, matched, held)
            np.copyto(ints[:, PREV_K], ints[:, LAST_K], where=held)
            np.copyto(ints[:, LAST_K], k, where=held)
            held2 = held[:, None]
            np.copyto(flo[:, PREV_XY], flo[:, LAST_XY], where=held2)
            np.copyto(flo[:, LAST_XY], z, where=held2)
            if mt.size:  # box size: exponential average of the associated detections
                wh = flo[:, WH]
                np.add(wh, self.config.size_smoothing * (zwh[:, 2:] - wh), out=wh,
                       where=matched[:, None])
            state, delete, confirmed_now = next_state(ints, matched, rescued, fp)
            ints[:, STATE] = state
            if np.count_nonzero(confirmed_now):
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
            out_uid = oi[:, UID]
            tab = TrackTable(ints, flo)
            if np.count_nonzero(delete):
                keep = _kept_rows(delete)
                tab = tab.take(keep)
                ps = _take_state(ps, keep)
        born = None
        if ud.size:
            tab, ps, born, born_uid = self._births(tab, ps, drow, ud, k)
        self.tracks, self.pstate = tab, ps
        self._k = k + 1
        if born is None:
            if out is None:
                self.row_uids = np.zeros(0, dtype=np.int64)
                return TrackFrame.empty(dets.frame)
            self.row_uids = out_uid
            return TrackFrame(dets.frame, *out)
        if out is None:
            self.row_uids = born_uid
            return TrackFrame(dets.frame, *born)
        self.row_uids = np.concatenate([out_uid, born_uid])
        return TrackFrame(
            dets.frame, *[np.concatenate([a, b]) for a, b in zip(out, born, strict=True)]
        )

    # ---------------------------------------------------------------------------- internals

    def _score_select(self, dets: Detections) -> tuple[NDArray[np.intp], NDArray[np.intp]] | None:
        """The high and the low detections (rows of ``dets``) by calibrated score, without
        the dropped ones (below ``min_score``, or duplicates of a better box); ``None`` when
        every detection is high and none is dropped."""
        if self._scores is None:
            return None
        c = self._scores(dets.score)
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
        """Last stage: the established (non-tentative) tracks still unmatched against the low
        detections ``lo``, with the first stage's distance and gate around the prediction
        (``score_high``). ``drow`` are the detections' rows ``x, y, w, h``."""
        cand = ((det_index < 0) & (tab.ints[:, STATE] != TENTATIVE)).nonzero()[0]
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
        if cand.size * lo.size <= fast_assoc.DENSE_LSA:
            mt, md = fast_assoc.dense_optimal(txy, left[:, :2], scale, self._gate, size)
        else:
            ti, dj, cost = fast_assoc.gate_pairs(txy, left[:, :2], scale, self._gate, size)
            if ti.size == 0:
                return _EMPTY, _EMPTY
            mt, md = fast_assoc.optimal(ti, dj, cost, cand.size, lo.size, self._gate)
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
        self, ps: Any, gxy: FloatArray, dets: Detections, f2: FloatArray | None,
        r_rows: FloatArray | None, twh: FloatArray,
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp], bool]:
        """Gate and assign through :mod:`mvtrack.tracking.associate` (disc-shaped gates);
        the flag says whether the second stage was done too. ``f2`` (N, 2) stretches the
        Euclidean gates per axis (``Δx²/f_x² + Δy²/f_y² <= gate``), ``r_rows`` (N,) are the
        tracks' measurement variances, ``twh`` (N, 2) their box sizes (for the size term of
        the Euclidean cost, ``config.size_weight``)."""
        n, m = gxy.shape[0], dets.xy.shape[0]
        scale = f2
        size = self._size_term(twh, dets.wh)
        if self._fast_gate == "mahalanobis":
            r = self.predictor.r if r_rows is None else r_rows
            scale = self.predictor.position_var(ps) + r  # S = (P̄ + r) I
        rule = self.config.assign
        staged = False
        if rule == "optimal" and not self._assign_params and n * m <= fast_assoc.DENSE_LSA:
            if self._gate2 is not None:  # both stages from one distance matrix
                mt, md, ud = fast_assoc.dense_two_stage(
                    gxy, dets.xy, scale, self._gate, self._gate2, f2, size
                )
                return mt, md, ud, True
            else:
                mt, md = fast_assoc.dense_optimal(gxy, dets.xy, scale, self._gate, size)
        elif rule == "optimal" and not self._assign_params:
            ti, dj, cost = fast_assoc.gate_pairs(gxy, dets.xy, scale, self._gate, size)
            mt, md = fast_assoc.optimal(ti, dj, cost, n, m, self._gate)
        else:
            ti, dj, cost = fast_assoc.gate_pairs(gxy, dets.xy, scale, self._gate, size)
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
        (:func:`_detection_rows`)."""
        cand = (det_index < 0).nonzero()[0]
        g = self._gate2
        scale = None if f2 is None else f2.take(cand, 0)
        left = drow.take(ud, 0)
        size = self._size_term(twh.take(cand, 0), left[:, 2:])
        txy, dxy = gxy.take(cand, 0), left[:, :2]
        if cand.size * ud.size <= fast_assoc.DENSE_LSA:  # the same result, one dense solve
            mt, md = fast_assoc.dense_optimal(txy, dxy, scale, g, size)
            return cand[mt], ud[md]
        ti, dj, cost = fast_assoc.gate_pairs(txy, dxy, scale, g, size)
        if ti.size == 0:
            return _EMPTY, _EMPTY
        mt, md = fast_assoc.optimal(ti, dj, cost, cand.size, ud.size, g)
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
        ``x, y, w, h`` (:func:`_detection_rows`). Returns the recovered track rows and their
        detections.
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
            margin = margin * np.sqrt(self._r_factor(f2[cand]))
        radius = self._fp.recover_speed * (k - ints.take(cand, 0)[:, LAST_K]) + margin
        r2 = radius * radius
        tf = tab.floats.take(cand, 0)
        last_xy = tf[:, LAST_XY]
        left = drow.take(ud, 0)
        dxy = left[:, :2]
        size = None  # the size gate only (no size term in this cost)
        if self._size_gate is not None:
            size = (tf[:, WH], left[:, 2:], 0.0, self._size_gate)
        if cand.size * ud.size <= fast_assoc.DENSE_LSA:
            mt, md = fast_assoc.dense_optimal(last_xy, dxy, r2, 1.0, size)
        else:
            ti, dj, cost = fast_assoc.gate_pairs(last_xy, dxy, r2, 1.0, size)
            mt, md = fast_assoc.optimal(ti, dj, cost, cand.size, ud.size, 1.0)
        return cand[mt], ud[md]

    def _size_term(self, twh: FloatArray, dwh: FloatArray) -> fast_assoc.SizeTerm | None:
        """The size term (``size_weight``) and size gate (``size_gate``) of a Euclidean stage
        for tracks of box sizes ``twh`` against detections of sizes ``dwh``, or ``None``."""
        if self._size_gate is not None:
            return (twh, dwh, self._size_w, self._size_gate)
        return (twh, dwh, self._size_w) if self._size_w else None

    def _size_scale2(self, wh: FloatArray) -> FloatArray:
        """Per-axis size factors squared, ``(f_x², f_y²) = max(1, (w, h)² / size_ref²)``, (N, 2)
        (1 for boxes without a size)."""
        return np.fmax(wh * wh * self._inv_ref2, 1.0)  # fmax: NaN → 1

    @staticmethod
    def _r_factor(f2: FloatArray) -> FloatArray:
        """``max(f_x, f_y)²`` (N,): the factor of the measurement variance (the larger axis's,
        so that the one isotropic variance covers the noisier axis)."""
        return np.maximum(f2[:, 0], f2[:, 1])

    def _warmup_centre(self, tab: TrackTable, pxy: FloatArray, k: int) -> FloatArray:
        """Paper 1's warm-up gate centre (SPEC §1.1 [R]).

        Until a track has ``2M = 6`` associations the gate centre is the linear extrapolation
        of its last two measurements, ``2 y_k − y_{k−1}`` for consecutive frames (scaled by the
        elapsed frames after misses), and ``y_k`` after a single association.
        """
        warm = tab.hits < self._fp.warmup_hits
        if not np.count_nonzero(warm):
            return pxy
        span = np.maximum(tab.last_k - tab.prev_k, 1)[:, None]
        gap = (k - tab.last_k)[:, None]
        last = tab.last_xy
        centre = last + (last - tab.prev_xy) * (gap / span)  # 2y_k − y_{k−1}, SPEC §1.1 [R]
        return np.where(warm[:, None], centre, pxy)

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
    ) -> tuple[TrackTable, Any, tuple | None, IntArray]:
        """New tentative tracks from the unassigned detections ``ud`` (SPEC §2.1 step 4);
        ``drow`` are the detections' rows ``x, y, w, h`` (:func:`_detection_rows`)."""
        b = ud.size
        src = drow.take(ud, 0)
        if b > 1:
            order = birth_order(src[:, :2])
            ud, src = ud.take(order), src.take(order, 0)
        floats = src.take(_BIRTH_COLS, 1)  # last_xy, prev_xy (both the detection), wh
        xy, wh = floats[:, LAST_XY], floats[:, WH]
        if self._scale_r and np.count_nonzero(wh > self._ref):  # r f² from the detection's box
            r_new = self.predictor.r * self._r_factor(self._size_scale2(wh))
            new_ps = self.predictor.init(xy, r_new)
        else:
            new_ps = self.predictor.init(xy)
        row = self._birth_row  # uid, track_id, state, hits, misses, age, last_k, prev_k
        row[UID] = self._next_uid
        row[LAST_K] = row[PREV_K] = k
        if b > self._uid_ramp.shape[0]:
            self._uid_ramp = _uid_ramp(2 * b)
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
        uid = ints[:, UID]
        if tab.ints.shape[0] == 0:
            return TrackTable(ints, floats), new_ps, born, uid
        tab = TrackTable(np.concatenate([tab.ints, ints]), np.concatenate([tab.floats, floats]))
        return tab, _concat_state(ps, new_ps), born, uid

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
        tab, pred, n = self.tracks, self.predictor, len(self.tracks)
        ps = pred.predict(self.pstate)
        gxy = pred.position(ps)
        if self._fp.warmup_hits:
            gxy = self._warmup_centre(tab, gxy, self._k)
        f2 = None  # as in step: size factors only when a box is larger than size_ref
        if self._ref is not None and np.count_nonzero(tab.floats[:, WH] > self._ref):
            f2 = self._size_scale2(tab.floats[:, WH])
        if self._fast_gate == "euclidean":
            shape = axis_shapes(f2, n)
        elif self._fast_gate == "mahalanobis":
            r = pred.r * self._r_factor(f2) if f2 is not None and self._scale_r else pred.r
            shape = axis_shapes(pred.position_var(ps) + r, n)  # S = (P̄ + r) I
        else:
            params = {k: v for k, v in self._distance_params.items() if k in SHAPE_PARAMS}
            _, shape, _ = gate_shapes(
                self.config.distance, gxy, pred.position_cov(ps), pred.innovation_cov(ps),
                pred.velocity(ps), self._gate, **params,
            )
        second = None if self._gate2 is None else axis_shapes(f2, n)
        return GateRegions(tab.uid.copy(), tab.track_id.copy(), np.array(gxy), shape, second,
                           self._gate, self._gate2)


def track_detections(
    frames: Iterable[Detections],
    config: TrackerConfig | None = None,
    rescue: RescueFn | None = None,
    scores: Any = None,
) -> TrackLog:
    """Run a fresh :class:`Tracker` over ``frames`` (one :class:`Detections` per frame).

    Frames must come in increasing order; a frame index that skips ahead is filled with empty
    frames so that the predictors advance one step per frame. With ``config.backfill`` (and
    without ``output_tentative``) a confirmed track's rows start at its first detection
    (:func:`mvtrack.tracking.log.backfill`); with ``config.interpolate`` the gaps a track
    bridged are written in full, interpolated (:func:`mvtrack.tracking.log.interpolate_gaps`).

    The ``"auto"`` score scale is calibrated on the scores seen so far, as online (the same
    thresholds mean the same in both modes); ``scores`` (for example every score of the file)
    calibrates it on those instead (:meth:`Tracker.prime_scores`). On the MOT15 development
    sequences the run-so-far calibration measured better offline too
    (``docs/bench/mot15-defaults.md``).
    """
    config = TrackerConfig() if config is None else config
    own = isinstance(config, TrackerConfig)
    late = own and config.backfill and not config.output_tentative
    fill = own and config.interpolate
    inner = config.replace(output_tentative=True) if late else config
    if fill:  # every coasting row, to be interpolated or cut to coast_output afterwards
        inner = inner.replace(coast_output=None)
    tracker = Tracker(inner)
    if scores is not None:
        tracker.prime_scores(scores)
    out: list[TrackFrame] = []
    uids: list[IntArray] = []
    last = None
    for dets in frames:
        if last is not None:
            if dets.frame <= last:
                raise ValueError(
                    f"track_detections: frame {dets.frame} does not follow frame {last}"
                )
            for f in range(last + 1, dets.frame):
                out.append(tracker.step(Detections.empty(f), rescue))
                uids.append(tracker.row_uids)
        out.append(tracker.step(dets, rescue))
        uids.append(tracker.row_uids)
        last = dets.frame
    if late:
        out = backfill(out, uids)
    if fill:
        out = interpolate_gaps(out, config.frames().coast_output)
    if own and config.min_track_length is not None:  # whole tracks shorter than this go
        out = drop_short_tracks(out, _round_frames(config.min_track_length * config.fps))
    log = TrackLog()
    for tf in out:
        log.append(tf)
    return log
