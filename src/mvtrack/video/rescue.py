"""Stopped vehicles: the tracker ↔ template bank glue (paper 1, SPEC §1.1 step 3).

A vehicle that stops fades into the disturbance-map background and its blob vanishes; the
tracker offers its confirmed tracks that got no detection to a ``rescue`` callback, and the
ones found by template matching are held in state ``STOPPED``. A vehicle that stands but
stays foreground in pieces (its body of the road's colour) is held the same way: the frame
loop leaves the detections inside its template's box out of the tracker's step
(:meth:`StoppedVehicleRescuer.fragments`).
:class:`~mvtrack.detection.template.TemplateBank` (arrays in, no tracker) keeps the
appearances and does the NCC search; here :class:`TemplateRescuer` maps the tracker's output
rows to its uids and feeds the bank, and :class:`StoppedVehicleRescuer` accepts only what a
stopped vehicle looks like.

Both keep, per frame, the NCC score of every match they accepted, and after the tracker's step
give it to the rows the tracker held with it (:attr:`StoppedVehicleRescuer.held_scores`, by
public track ID): the evidence of the ``stopped`` rows of ``states.csv``. The tracker's
``rescue(uids, predicted_xy, wh) -> (found, xy)`` callback does not carry it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.analytics.outputs import STOPPED_SIDES_PER_S
from mvtrack.errors import InputError
from mvtrack.tracking.lifecycle import STATE
from mvtrack.types import Detections, TrackFrame, TrackState
from mvtrack.video.loop import NO_SCORES, HeldScores, RescueFn
from mvtrack.video.stopped import (
    accept_stopped,
    cached_matches,
    missed_places,
    standing_pieces,
)

if TYPE_CHECKING:
    from mvtrack.detection.template import TemplateBank

Image = NDArray[np.uint8]
IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]
_NO_UIDS = np.zeros(0, np.int64)
_NO_VALUES = np.zeros(0, np.float64)
#: a template bank without boxes: its sentinel row only
_EMPTY_BANK = (np.array([np.iinfo(np.int64).max], np.int64), np.full((1, 13), np.nan))


def held_scores(
    tracker: Any, tracks: TrackFrame, uids: IntArray, scores: FloatArray
) -> HeldScores:
    """The rows of ``tracks`` in state ``STOPPED`` with the score of their accepted match.

    Parameters
    ----------
    tracker : mvtrack.tracking.Tracker
        Its ``row_uids`` (row-aligned with ``tracks``) give each row's internal uid; a
        tracker without them is looked up through ``tracker.tracks`` by public ID.
    tracks : TrackFrame
        The tracker's output of this frame.
    uids, scores : (K,) arrays
        The uids of the matches accepted this frame and their NCC.

    Returns
    -------
    HeldScores
        ``(track_id, score)`` of the stopped rows whose uid is among ``uids``.
    """
    stopped = np.flatnonzero(tracks.state == int(TrackState.STOPPED))
    if stopped.size == 0 or uids.size == 0:
        return NO_SCORES
    ids = tracks.track_id[stopped]
    row_uids = getattr(tracker, "row_uids", None)
    if row_uids is not None and len(row_uids) == len(tracks):
        row_uid = np.asarray(row_uids, np.int64)[stopped]
    else:
        row_uid = _uids_of_ids(tracker.tracks, ids)
    order = np.argsort(uids, kind="stable")
    pos = np.minimum(np.searchsorted(uids[order], row_uid), uids.size - 1)
    ok = uids[order][pos] == row_uid
    # an NCC is at most 1; float32 sums can round a perfect match a hair above
    return HeldScores(ids[ok], np.minimum(scores[order][pos][ok], 1.0))


def standing_uids(tracker: Any, tracks: TrackFrame) -> IntArray:
    """The internal uids (sorted) of the rows of ``tracks`` whose track stands: the filter's
    speed is below the box's shorter side per second (``speed · fps < min(w, h)``, the
    ``motion`` of ``states.csv``, :data:`~mvtrack.analytics.outputs.STOPPED_SIDES_PER_S`).
    None (empty) for a tracker without ``row_uids`` or a frame rate."""
    fps = getattr(getattr(tracker, "config", None), "fps", None)
    row_uids = getattr(tracker, "row_uids", None)
    if not fps or row_uids is None or len(row_uids) != len(tracks) or len(tracks) == 0:
        return _NO_UIDS
    speed = np.hypot(tracks.velocity[:, 0], tracks.velocity[:, 1]) * float(fps)
    still = speed < STOPPED_SIDES_PER_S * tracks.wh.min(axis=1)
    return np.sort(np.asarray(row_uids, np.int64)[still])


def _member(a: IntArray, sorted_b: IntArray) -> NDArray[np.bool_]:
    """``np.isin(a, b)`` for a sorted ``b``."""
    if a.size == 0 or sorted_b.size == 0:
        return np.zeros(a.size, bool)
    pos = np.minimum(np.searchsorted(sorted_b, a), sorted_b.size - 1)
    return sorted_b[pos] == a


def _arrays(table: Any) -> tuple[IntArray, FloatArray]:
    """A :class:`~mvtrack.tracking.table.TrackTable`'s integer and float columns,
    C-contiguous, for the kernels of :mod:`mvtrack.video.stopped`."""
    return np.ascontiguousarray(table.ints, np.int64), np.ascontiguousarray(table.floats)


def _uids_of_ids(table: Any, ids: IntArray) -> IntArray:
    """Internal uid of each public ID in ``ids`` through a track table (−1: unknown)."""
    t_uid = np.asarray(table.uid, np.int64)
    t_id = np.asarray(table.track_id, np.int64)
    if not (t_id.size and ids.size):
        return np.full(ids.size, -1, np.int64)
    order = np.argsort(t_id, kind="stable")
    pos = np.minimum(np.searchsorted(t_id[order], ids), t_id.size - 1)
    return np.where(t_id[order][pos] == ids, t_uid[order][pos], -1)


class StoppedVehicleRescuer:
    """Template matching restricted to what a stopped vehicle looks like.

    Paper 1 uses template matching for one case: a vehicle that *stopped* and faded into the
    disturbance-map background (SPEC §1.1 step 3). A bare NCC search also "finds" other things,
    and a track held that way never ends:

    - a track that never moved (a ghost blob where a parked vehicle left, a pole flickering
      under camera jitter) has a template of static scenery, which matches forever — the
      template bank searches only tracks that have driven somewhere
      (:class:`~mvtrack.detection.template.TemplateBank`, ``min_travel``);
    - a duplicate track (two blobs of one two-tone vehicle) whose detection went to its twin
      follows the moving vehicle by template, frame after frame.

    - a vehicle of the road's colour, missed for a frame while it drives on, leaves the road
      behind it, which matches its template at its last place: the track stands as a ghost.

    So the search is centred on the track's last measured position, a match is accepted only
    if it lies within ``max_shift`` px of it (a stopped vehicle stands where it was last seen),
    the track's velocity since then would not have carried its box off that place
    (:func:`~mvtrack.video.stopped.could_stand`), and no detection of this frame covers the
    match (a detected object has not faded). All checks are compiled passes over the missed
    tracks (:mod:`mvtrack.video.stopped`).

    Parameters
    ----------
    inner : TemplateRescuer
        The NCC search (:class:`TemplateRescuer`).
    tracker : mvtrack.tracking.Tracker
        Its ``tracks`` table gives each uid's last measurement.
    max_shift : float
        Largest distance (px) between the match and the last measured position.
    pieces : bool, default True
        Hold a vehicle that stands by its template also when it stays foreground, whole or
        in pieces (:meth:`fragments`), and keep holding it under a blob that reaches out of
        its template's box; False: paper 1's rule, only tracks without a detection in their
        gate are searched (SPEC §1.1 step 3; the paper experiments).

    Attributes
    ----------
    held_scores : HeldScores
        After :meth:`observe`: the public ID of each row of the frame held by template
        matching (state ``STOPPED``) and the NCC score of its accepted match.
    """

    #: default ``max_shift`` in px
    MAX_SHIFT = 4.0
    #: a covering detection larger than this many times the track's box is a merged blob
    MERGED = 2.5

    def __init__(self, inner: Any, tracker: Any, max_shift: float = MAX_SHIFT,
                 pieces: bool = True) -> None:
        if not max_shift > 0:
            raise InputError(f"template settings: max_shift must be > 0, got {max_shift}")
        self.inner = inner
        self.tracker = tracker
        self.max_shift = float(max_shift)
        self.pieces = bool(pieces)
        self.held_scores: HeldScores = NO_SCORES
        self._accepted: tuple[IntArray, FloatArray] = (_NO_UIDS, _NO_VALUES)
        self._standing: IntArray = _NO_UIDS
        # the matches :meth:`fragments` found in the frame it was given (the frame, uids,
        # centres, scores): the callback of that frame takes them instead of searching again
        self._found: tuple[Any, IntArray, FloatArray, FloatArray] | None = None

    def callback(self, image: Image, dets: Detections) -> RescueFn:
        """``rescue(uids, predicted_xy, wh) -> (found, xy)`` for this frame.

        The NCC scores of the matches it accepts are kept for :meth:`observe`.
        """
        tab = self.tracker.tracks
        self._accepted = (_NO_UIDS, _NO_VALUES)  # the tracker may not call it this frame

        def rescue(uids: Any, predicted_xy: Any, wh: Any) -> tuple[Any, Any]:
            search = self.inner.search(image)  # only on frames with missed tracks
            uids = np.ascontiguousarray(uids, np.int64).reshape(-1)
            wh = np.ascontiguousarray(wh, np.float64).reshape(-1, 2)
            ints, floats = _arrays(tab)
            # each track's row, last measurement, template box and the place where its
            # vehicle was last seen (the box's centre when the last measurement lies within
            # one box length of it: the fragments of a fading vehicle wander inside its box)
            at, last, box, centre = missed_places(ints, floats, uids, *self._bank_rows())
            # every missed track is searched, the ones that cannot stand too: the bank cuts a
            # template from its kept frame only when it is searched (the next frame's search
            # of a track that slowed down needs it)
            found, xy, score = self._find(search, uids, last, centre, wh, image)
            if found.any():
                # it must have been able to stop there (a vehicle missed while it drives on
                # leaves the road behind it to match its template), and no detection of
                # about its size may cover it (a detected object has not faded); a blob
                # several times its size is vehicles merged into one (a queue that starts
                # again): the vehicle is found inside it. So is a vehicle held by its template
                # in the last frame (it stands) under a blob that reaches beyond its
                # template's box: a car passing close by has merged with its pieces
                velocity, frames = self._motion(tab, at)
                stood = ints[at, STATE] == int(TrackState.STOPPED) if self._boxes() else \
                    np.zeros(uids.size, bool)
                accept_stopped(found, xy, velocity, frames, wh, box, stood, dets.xy, dets.wh,
                               self.MERGED, self.max_shift)
                self._accepted = (uids[found], score[found])
            return found, xy

        return rescue

    def _find(self, search: RescueFn, uids: IntArray, last: FloatArray, centre: FloatArray,
              wh: FloatArray, image: Image) -> tuple[NDArray[np.bool_], FloatArray, FloatArray]:
        """The search of :meth:`callback`: around where each vehicle was last seen
        (``centre``), and around its last measurement where that place differs and the
        vehicle is not found there."""
        # a stopped vehicle stands where it was last measured: search around that place,
        # not around the prediction, which keeps drifting with the last velocity estimate
        found, xy, score = self._search(search, uids, centre, wh, image)
        again = ~found & (centre != last).any(axis=1)
        if again.any():
            f2, xy2, s2 = self._search(search, uids[again], last[again], wh[again])
            found[again], xy[again], score[again] = f2, xy2, s2
        return found, xy, score

    def _boxes(self) -> bool:
        """Whether the pieces of standing vehicles are held (a bank that keeps boxes)."""
        return self.pieces and hasattr(getattr(self.inner, "bank", None), "boxes")

    def _bank_rows(self) -> tuple[IntArray, FloatArray]:
        """The template bank's sorted uids (sentinel last) and rows, box in columns 0–3
        (:meth:`~mvtrack.detection.track_boxes.TrackBoxes.rows`); a bank without boxes gives
        none (NaN boxes)."""
        bank = getattr(self.inner, "bank", None)
        if bank is None or not hasattr(bank, "boxes"):
            return _EMPTY_BANK
        return bank.rows()

    def _motion(self, tab: Any, at: IntArray) -> tuple[FloatArray, IntArray]:
        """The velocities of the tracks at rows ``at`` of ``tab`` and the frames since their last
        measurement, for :func:`~mvtrack.video.stopped.accept_stopped`; NaN velocities (they
        could stand) with a tracker that does not give them."""
        tr = self.tracker
        predictor, state = getattr(tr, "predictor", None), getattr(tr, "pstate", None)
        steps = getattr(tr, "steps", None)
        if predictor is None or state is None or steps is None:
            return np.full((at.size, 2), np.nan), np.zeros(at.size, np.int64)
        velocity = np.ascontiguousarray(np.asarray(predictor.velocity(state), np.float64)[at])
        return velocity, np.ascontiguousarray(steps - tab.last_k[at], np.int64)

    def fragments(self, image: Image, dets: Detections) -> NDArray[np.bool_]:
        """The detections of this frame that belong to a vehicle that stands: to be left out
        of the tracker's step, so that :meth:`callback` holds the vehicle whole by its
        template.

        A vehicle that stands does not always stay one blob: where its body has the road's
        colour (a grey car on grey asphalt) only its edges, windows and shadow differ from
        the background, and its blob is a piece of it — its rear half, one side. Given to the
        tracker, such pieces shrink and shift the vehicle's box frame after frame (and the
        template bank, refreshed with them, forgets the whole vehicle). A detection belongs
        to a vehicle that stands when, for a confirmed track,

        - the track stands: the filter's speed was below its box's shorter side per second
          in the last frame (:func:`standing_uids`, the ``motion`` of ``states.csv``),
        - the track was last measured within reach of its template's box (its last
          full-size detection; as :func:`~mvtrack.video.stopped.missed_places`),
        - the detection lies inside that box widened by ``max_shift`` px on every side,
        - and the template matches (NCC ≥ the bank's ``min_score``, over the template's own
          object pixels) within ``max_shift`` px of that box's centre: the vehicle still
          stands, whole, where it was last seen whole.

        The vehicle is then held by its template as one that faded completely (paper 1's
        stopped vehicle, SPEC §1.1 step 3): its rows are ``stopped``, with the NCC score,
        whether its blob was a piece of it or the whole of it. A vehicle that drives on
        leaves its template's place (no match within ``max_shift``), and its detections are
        kept. The search runs only for the tracks that stand with a detection inside their
        template's box, a few per frame.

        Returns
        -------
        (M,) bool
            True for the detections to leave out.
        """
        out = np.zeros(len(dets), bool)
        bank = getattr(self.inner, "bank", None)
        if not (self.pieces and len(dets) and self._standing.size and hasattr(bank, "boxes")
                and len(bank)):
            return out
        tab = self.tracker.tracks
        uids, box, inside = standing_pieces(*_arrays(tab), self._standing,
                                            *self._bank_rows(), dets.xy, dets.wh, self.max_shift)
        if uids.size == 0:
            return out
        found, xy, score = self._search(self.inner.search(image), uids, box[:, :2],
                                        box[:, 2:])
        self._found = (image, uids[found], xy[found], score[found])
        return inside[found].any(axis=0)

    def _search(
        self, search: RescueFn, uids: IntArray, centre: NDArray[np.float64], wh: Any,
        image: Image | None = None,
    ) -> tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:
        """NCC search around ``centre``; matches farther than ``max_shift`` from it refused.
        Returns ``found``, ``xy`` and the NCC ``score`` of each track. The tracks that
        :meth:`fragments` found in ``image`` (searched around the same centre, the box of
        their template) are not searched again."""
        cache = self._found
        found = np.zeros(uids.size, bool)
        xy = np.full((uids.size, 2), np.nan)
        score = np.full(uids.size, np.nan)
        if image is not None and cache is not None and cache[0] is image and cache[1].size:
            hit = cached_matches(cache[1], cache[2], uids, np.ascontiguousarray(centre),
                                 self.max_shift)
            found = hit >= 0
            xy[found], score[found] = cache[2][hit[found]], cache[3][hit[found]]
        rest = np.flatnonzero(~found)
        if rest.size:
            f_sub, xy_sub, s_sub = search(uids[rest], centre[rest],
                                          np.asarray(wh, np.float64).reshape(-1, 2)[rest])
            xy[rest], score[rest] = xy_sub, s_sub
            d = xy[rest] - centre[rest]  # the match must sit where the vehicle was last seen
            found[rest] = np.asarray(f_sub, bool) & (np.hypot(d[:, 0], d[:, 1]) <= self.max_shift)
        return found, xy, score

    def observe(self, image: Image, dets: Detections, tracks: TrackFrame) -> None:
        """Feed the template bank; set :attr:`held_scores` for this frame's rows; keep the
        tracks that stand (:meth:`fragments`)."""
        self.inner.observe(image, dets, tracks)
        self.held_scores = held_scores(self.tracker, tracks, *self._accepted)
        self._standing = standing_uids(self.tracker, tracks)


def search_radii(tracker: Any, uids: Any, default: float) -> FloatArray:
    """The search radius in px of each track ``uids`` (internal uids): the semi-major axis of
    its gate region.

    The tracker's gate of a track (:meth:`~mvtrack.tracking.Tracker.gates`, the gate the
    step being made applies) is the region :math:`(z - c)^T C^{-1} (z - c) \\le r^2`; the
    farthest a detection may lie from the centre is :math:`\\sqrt{r^2 \\lambda_{max}(C)}`
    (:func:`mvtrack.viz.annotate.gate_ellipses`). For the Euclidean gate that is its radius
    (paper 1's 20 px circle); for the default, the filter's innovation covariance, it grows
    with the box and with the time a track has gone without detection. ``default`` (the
    bank's ``gate_radius``) where the tracker has no gates, where the gate is not a region
    about the prediction (``iou``, ``coupled-literal``) or where ``uids`` holds no live track.
    """
    uids = np.asarray(uids, np.int64).reshape(-1)
    if uids.size == 0 or not hasattr(tracker, "gates"):
        return np.full(uids.size, float(default))
    return lookup_radii(radius_table(tracker.gates()), uids, default)


def radius_table(gates: Any) -> tuple[IntArray, FloatArray]:
    """The uids of the tracker's gates (sorted, stable) and each gate's semi-major axis in px
    (:func:`search_radii`; NaN where the gate is not a finite region)."""
    from mvtrack.viz.annotate import gate_ellipses

    if len(gates) == 0:
        return _NO_UIDS, _NO_VALUES
    order = np.argsort(gates.uid, kind="stable")
    shape = gates.shape[order]
    radius = np.full(order.size, np.nan)
    ok = np.isfinite(shape.reshape(-1, 4)).all(axis=1) & math.isfinite(gates.r2)
    if ok.any():
        radius[ok] = gate_ellipses(shape[ok], gates.r2)[0][:, 0]
    return np.asarray(gates.uid, np.int64)[order], radius


def lookup_radii(table: tuple[IntArray, FloatArray], uids: IntArray, default: float
                 ) -> FloatArray:
    """The radius of each of ``uids`` in a :func:`radius_table`; ``default`` where it has no
    finite one."""
    known, radius = table
    out = np.full(uids.size, float(default))
    if known.size == 0 or uids.size == 0:
        return out
    pos = np.minimum(np.searchsorted(known, uids), known.size - 1)
    hit = (known[pos] == uids) & np.isfinite(radius[pos])
    out[hit] = radius[pos[hit]]
    return out


class TemplateRescuer:
    """Adapter between a :class:`TemplateBank` and ``Tracker.step(dets, rescue=...)``.

    Per frame ``k``::

        dets = detector(frame)
        out = tracker.step(dets, rescue=rescuer.callback(frame))
        rescuer.observe(frame, dets, out)

    Parameters
    ----------
    bank : TemplateBank
        The templates and the search parameters.
    tracker : mvtrack.tracking.Tracker, optional
        The tracker whose output is observed: needed to map the public IDs of its output rows
        to the internal ``uid`` the rescue callback receives, and to forget deleted tracks.
        May be given later with :meth:`attach`.
    gate_radius : float, optional
        Search radius in px for every track; default: each track's from its gate region in
        the tracker (:func:`search_radii`), the bank's ``gate_radius`` where it has none.
    detector : FrontEnd, optional
        The detection front end; its foreground ``mask`` after each frame restricts the
        templates to the objects' own pixels (see :meth:`TemplateBank.observe`). Strongly
        recommended: without it a template is the whole box, road included, and it can keep
        matching the empty road after a pedestrian or vehicle has left.

    Attributes
    ----------
    held_scores : HeldScores
        After :meth:`observe`: the public ID of each row of the frame held by a match of
        :meth:`callback` (state ``STOPPED``) and the NCC score of that match.
    """

    def __init__(
        self,
        bank: TemplateBank,
        tracker: Any = None,
        gate_radius: float | None = None,
        detector: Any = None,
    ) -> None:
        self.bank = bank
        self.tracker = tracker
        self.detector = detector
        self._radius = None if gate_radius is None else float(gate_radius)
        self.held_scores: HeldScores = NO_SCORES
        self._accepted: tuple[IntArray, FloatArray] = (_NO_UIDS, _NO_VALUES)
        # the radii of the tracker's gates, read once per state of the tracker (the searches
        # before its step and inside it see the same one): (its track table, radius_table)
        self._radii: tuple[Any, Any] | None = None

    def attach(self, tracker: Any) -> None:
        """Use ``tracker`` (and forget templates of any previous one)."""
        self.tracker = tracker
        self.bank.clear()

    def radii(self, uids: Any) -> FloatArray:
        """The search radius in px of each track ``uids``: ``gate_radius`` if given, else its
        gate's (:func:`search_radii`, read once per state of the tracker)."""
        uids = np.asarray(uids, np.int64).reshape(-1)
        if self._radius is not None:
            return np.full(uids.size, self._radius)
        table = self._radii_now()
        if table is None:
            return np.full(uids.size, self.bank.gate_radius)
        return lookup_radii(table, uids, self.bank.gate_radius)

    def search(self, frame: Image) -> RescueFn:
        """``search(uids, predicted_xy, wh) -> (found, xy, score)`` on ``frame``: the bank's
        NCC search of each track within its radius (:meth:`radii`,
        :meth:`TemplateBank.rescue`), with the best NCC of each track (NaN where it was not
        searched)."""
        bank = self.bank

        def search(uids: Any, predicted_xy: Any, wh: Any) -> tuple[Any, Any, Any]:
            return bank.rescue(frame, uids, predicted_xy, wh, self.radii(uids))

        return search

    def _radii_now(self) -> tuple[IntArray, FloatArray] | None:
        """The radii of the tracker's gates for its next step, a :func:`radius_table` (None:
        a tracker without gates); computed once per state of the tracker (a step replaces its
        track table)."""
        tracker = self.tracker
        if not hasattr(tracker, "gates"):
            return None
        table = getattr(tracker, "tracks", None)
        if self._radii is None or self._radii[0] is not table or table is None:
            self._radii = (table, radius_table(tracker.gates()))
        return self._radii[1]

    def callback(self, frame: Image) -> RescueFn:
        """The ``rescue`` argument of ``tracker.step`` for ``frame``; the NCC scores of the
        matches it finds are kept for :meth:`observe`."""
        search = self.search(frame)
        self._accepted = (_NO_UIDS, _NO_VALUES)

        def rescue(uids: Any, predicted_xy: Any, wh: Any) -> tuple[Any, Any]:
            found, xy, score = search(uids, predicted_xy, wh)
            self._accepted = (np.asarray(uids, np.int64).reshape(-1)[found], score[found])
            return found, xy

        return rescue

    def observe(self, frame: Image, dets: Detections, tracks: TrackFrame) -> None:
        """Record the detected boxes of this frame's tracks; forget deleted tracks.

        Rows of ``tracks`` with ``det_index ≥ 0`` and a public ID are stored under the
        tracker's internal uid (``tracker.row_uids``, row-aligned with its last output; or, for
        a tracker without it, looked up through ``tracker.tracks`` by ``track_id``) with the
        detection's box (the last detected appearance). Deleted tracks are forgotten once the
        bank holds more tracks than the tracker has live ones (so at most twice as many).
        """
        if self.tracker is None:
            raise ValueError("TemplateRescuer: attach a tracker before observing frames")
        det = tracks.det_index
        rows = det >= 0
        if getattr(getattr(self.tracker, "config", None), "output_tentative", True):
            rows &= tracks.track_id > 0  # tentative rows (ID −1) are output too
        row_uids = getattr(self.tracker, "row_uids", None)
        if row_uids is not None and len(row_uids) == len(det):
            uids = row_uids[rows]
            d = det[rows]
        else:
            uids, d = self._uids_by_id(tracks.track_id[rows], det[rows])
        table = self.tracker.tracks
        if self.bank.uids.size > len(table):  # some are dead: forget them
            self.bank.retain(table.uid)
        mask = getattr(self.detector, "mask", None) if self.detector is not None else None
        self.bank.observe(frame, uids, dets.xy[d], dets.wh[d], mask)
        self.held_scores = held_scores(self.tracker, tracks, *self._accepted)

    def _uids_by_id(self, ids: IntArray, det: IntArray) -> tuple[IntArray, IntArray]:
        """Internal uids of public ``ids`` through ``tracker.tracks`` (unknown ones dropped)."""
        uids = _uids_of_ids(self.tracker.tracks, ids)
        known = uids >= 0
        return uids[known], det[known]
