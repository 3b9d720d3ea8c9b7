"""Stopped vehicles: template matching of a track's last appearance (paper 1, SPEC §1.1 step 3).

A vehicle that stops fades into the disturbance-map background (about ``1/β_min`` = 50 frames
of memory) and its blob vanishes. Paper 1 finds such vehicles again by template matching
("vehicle recognition"); SPEC §1.1 [R] fixes the details: for a confirmed track with no
detection in its gate, the grey patch of its last detected bounding box is searched by
normalised cross-correlation (NCC) within the gate radius of the prediction, and a match with
NCC ≥ 0.8 holds the track (the tracker puts it in state ``STOPPED``, same ID).

:class:`TemplateBank` keeps one template per track, keyed by an integer ``uid`` (the caller's
identity of the track), and takes arrays in: it knows nothing of the tracker.

* :meth:`TemplateBank.observe` records the detected boxes of this frame's tracks (arrays, no
  per-track work); the grey patch is cut *lazily*, only when a track is first missed, from the
  frame of its last detection (the bank keeps that one frame). A track that is detected again
  gets its template refreshed the same way at its next miss.
* :meth:`TemplateBank.rescue` matches the missed tracks (few per frame; the only per-track
  loop, each on a small search window); :meth:`TemplateBank.bind` wraps it as a
  ``rescue(uids, predicted_xy, wh) -> (found, xy)`` callback.
* :meth:`TemplateBank.retain` / :meth:`TemplateBank.drop` forget deleted tracks.

The per-track rows of last detected boxes are :class:`~mvtrack.detection.track_boxes.TrackBoxes`
(which :class:`TemplateBank` extends); the cutting of a template and its NCC search inside the
gate are :func:`~mvtrack.detection.ncc.cut_template` and
:func:`~mvtrack.detection.ncc.search_gate`.

The video package connects the bank to the tracker (:mod:`mvtrack.video.rescue`).

Coordinates follow :mod:`mvtrack.detection.blobs`: pixel ``(col, row)`` has centre
``(x, y) = (col, row)``; a box of centre ``x`` and width ``w`` covers columns
``x − (w − 1)/2 … x + (w − 1)/2``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mvtrack.detection.ncc import Template, cut_template, search_gate
from mvtrack.detection.track_boxes import TrackBoxes

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]
Image = NDArray[np.uint8]
RescueFn = Callable[[IntArray, FloatArray, FloatArray], tuple[BoolArray, FloatArray]]


class TemplateBank(TrackBoxes):
    """Last appearances of tracks and their normalised cross-correlation search.

    Parameters
    ----------
    min_score : float, default 0.8
        Accept a match when its NCC (``cv2.TM_CCOEFF_NORMED``) is at least this
        (SPEC §1.1 [R]).
    gate_radius : float, default 20
        Search radius in pixels around the prediction, used when :meth:`rescue` is not given
        one (paper 1's 20 px system gate, SPEC §1.1).
    min_size : int, default 4
        Templates narrower or lower than this (pixels, after clipping to the image) are not
        kept: too small to correlate reliably.
    min_std : float, default 2.0
        Templates whose grey-level standard deviation is below this are not kept (a flat
        patch has no defined NCC).
    min_pixels : int, default 50
        With object masks (see :meth:`observe`), templates with fewer object pixels than this
        are not kept: over a few dozen pixels an NCC of 0.8 is reached by chance somewhere in
        a textured search window (on vtest.avi, 20-pixel templates held dozens of fragments
        of the lawn and pavement).
    min_travel : float, default 1.0
        A track is searched only once its last detection lies at least ``min_travel`` box
        lengths (the larger side of its last box) and at least ``min_travel_px`` pixels from
        its first, and it has ``min_hits`` detections. A template of a static place always
        matches the static scene, so without this guard every spurious track on clutter (a
        flickering fragment, a "ghost" left where a parked object drove off) would be held for
        ever; a vehicle that *stops* has always driven there first. 0 disables each part.
    min_travel_px : float, default 10
        See ``min_travel``.
    min_hits : int, default 5
        See ``min_travel``.
    min_fill : float, default 0.5
        A detection whose box area is below ``min_fill`` times the track's reference area (a
        running maximum of its box areas that decays by 1 % per detection, so it follows
        real changes of size within ~70 detections) does not refresh the template: a vehicle
        fading into the background, whose blob shrinks over tens of frames, or a person
        reduced to a fragment, keeps the template of its last full appearance. 0 refreshes
        on every detection.
    max_drift : float or None, default 5.0
        Search only tracks whose prediction lies within ``max_drift`` px of their last
        detection or template match. A stopped vehicle's filter has come to rest where it was
        last seen (its blob takes tens of frames to fade), while an object that was merely
        missed (occluded, merged with another blob, leaving) is predicted to have moved on:
        the tracker coasts it, and the bank spends no search on it. ``None`` disables the check.

    Attributes
    ----------
    uids : (T,) int64
        Tracks that have a recorded detection (sorted).
    """

    def __init__(
        self,
        min_score: float = 0.8,
        gate_radius: float = 20.0,
        min_size: int = 4,
        min_std: float = 2.0,
        min_pixels: int = 50,
        min_travel: float = 1.0,
        min_travel_px: float = 10.0,
        min_hits: int = 5,
        min_fill: float = 0.5,
        max_drift: float | None = 5.0,
        smooth: float = 1.0,
    ) -> None:
        if not (-1.0 <= min_score <= 1.0):
            raise ValueError(f"min_score must be an NCC in [-1, 1], got {min_score}")
        if not (math.isfinite(gate_radius) and gate_radius >= 0):
            raise ValueError(f"gate_radius must be a non-negative number of px, got {gate_radius}")
        if min_size < 1:
            raise ValueError(f"min_size must be ≥ 1 px, got {min_size}")
        if not min_std >= 0:
            raise ValueError(f"min_std must be ≥ 0, got {min_std}")
        if not (math.isfinite(min_travel) and min_travel >= 0):
            raise ValueError(f"min_travel must be ≥ 0 box lengths, got {min_travel}")
        if not (math.isfinite(min_travel_px) and min_travel_px >= 0):
            raise ValueError(f"min_travel_px must be ≥ 0 px, got {min_travel_px}")
        if min_hits < 0:
            raise ValueError(f"min_hits must be ≥ 0, got {min_hits}")
        if not (0.0 <= min_fill <= 1.0):
            raise ValueError(f"min_fill must be in [0, 1], got {min_fill}")
        if max_drift is not None and not max_drift >= 0:
            raise ValueError(f"max_drift must be ≥ 0 px or None, got {max_drift}")
        if not (math.isfinite(smooth) and smooth >= 0):
            raise ValueError(f"smooth must be ≥ 0 px, got {smooth}")
        self.min_score = float(min_score)
        self.gate_radius = float(gate_radius)
        self.min_size = int(min_size)
        self.min_std = float(min_std)
        self.min_pixels = int(min_pixels)
        self.min_travel = float(min_travel)
        self.min_travel_px = float(min_travel_px)
        self.min_hits = int(min_hits)
        self.min_fill = float(min_fill)
        self.max_drift = None if max_drift is None else float(max_drift)
        self.smooth = float(smooth)
        self._pad = math.ceil(3 * self.smooth) if self.smooth > 0 else 0
        self.clear()

    def clear(self) -> None:
        """Forget everything."""
        super().clear()
        self._templates: dict[int, Template] = {}

    def _forget(self, uids: list[int]) -> None:
        for u in uids:
            self._templates.pop(u, None)

    def _freeze(self, i: int) -> None:
        self._current(i)

    # ------------------------------------------------------------------------- templates
    def _cut(self, i: int) -> Template | None:
        """Grey patch of track row ``i``'s last full-size detected box, from the kept frame."""
        if self._frame is None:
            return None
        return cut_template(
            self._frame, self._mask, self._f[i, self._BOX], int(self._f[i, self._TICK]),
            min_size=self.min_size, min_pixels=self.min_pixels, min_std=self.min_std,
            smooth=self.smooth, pad=self._pad,
        )

    def template(self, uid: int) -> Image | None:
        """The grey patch held for ``uid`` (cut now if it is due), or ``None``."""
        i = int(np.searchsorted(self.uids, uid))
        if i >= self.uids.size or self.uids[i] != uid:
            return None
        t = self._current(i)
        return None if t is None else t.patch

    def _current(self, i: int) -> Template | None:
        uid = int(self.uids[i])
        t = self._templates.get(uid)
        tick = int(self._f[i, self._TICK])
        due = t is None or t.tick < tick
        if due and tick == self._tick:  # last detected in the kept frame
            t = self._cut(i)
            if t is None:
                self._templates.pop(uid, None)
            else:
                self._templates[uid] = t
        return t

    # ---------------------------------------------------------------------------- search
    def rescue(
        self,
        frame: Image,
        uids: ArrayLike,
        predicted_xy: ArrayLike,
        wh: ArrayLike | None = None,
        gate_radius: float | ArrayLike | None = None,
    ) -> tuple[BoolArray, FloatArray, FloatArray]:
        r"""Search the missed tracks ``uids`` by NCC around their predictions (SPEC §1.1 [R]).

        For each track with a template :math:`T` (its last detected box, grey) the normalised
        cross-correlation

        .. math::

            \mathrm{NCC}(u, v) = \frac{\sum (T - \bar T)(I_{u,v} - \bar I_{u,v})}
                                     {\sqrt{\sum (T - \bar T)^2 \sum (I_{u,v} - \bar I_{u,v})^2}}

        (``cv2.TM_CCOEFF_NORMED``) is evaluated for every placement whose box centre lies within
        ``gate_radius`` of the prediction (a circle; the search window is clipped to the
        image), and the best placement is accepted if its NCC ≥ ``min_score``. A track whose
        template, placed at the prediction, would stick out of the image is not searched (an
        object leaving the picture has not stopped); this also keeps the loop short.

        Parameters
        ----------
        frame : (H, W, 3) or (H, W) uint8
            The current frame.
        uids : (K,) int
            Internal identities of the confirmed tracks that got no detection.
        predicted_xy : (K, 2)
            Their predicted centres (the gate centres).
        wh : (K, 2), optional
            Their box sizes; unused (the template keeps the size of the last detected box),
            accepted for the tracker's callback signature.
        gate_radius : float or (K,) floats, optional
            Search radius in px, one for all or one per track (default: the bank's
            ``gate_radius``).

        Returns
        -------
        found : (K,) bool
            NCC ≥ ``min_score`` inside the gate (always False for tracks without a template
            or that are not :attr:`eligible`, or predicted more than ``max_drift`` px from
            their last detection).
        xy : (K, 2) float64
            Centre of the best match (NaN where not found).
        score : (K,) float64
            Best NCC inside the gate (NaN where there was no template or no room to search).
        """
        uids = np.asarray(uids, np.int64).reshape(-1)
        pxy = np.asarray(predicted_xy, np.float64).reshape(-1, 2)
        if pxy.shape[0] != uids.size:
            raise ValueError(f"rescue: {uids.size} uids but {pxy.shape[0]} predicted positions")
        k = uids.size
        radii = np.broadcast_to(
            np.asarray(self.gate_radius if gate_radius is None else gate_radius, np.float64),
            (k,)).tolist()
        found = np.zeros(k, bool)
        out = np.full((k, 2), np.nan)
        score = np.full(k, np.nan)
        if k == 0 or self._u.size == 1:
            return found, out, score
        height, width = frame.shape[:2]
        pos, has = self._rows(uids)
        rows = self._f[pos].tolist()
        p_list = pxy.tolist()
        max_drift2 = None if self.max_drift is None else self.max_drift**2
        # the only per-track loop, over the missed (lost) tracks, a few per frame: the checks
        # below are a handful of float operations each (cheaper in plain Python than array
        # operations over so few rows), then one NCC of a template over a small window
        # around its gate for those that qualify (one cv2 call on that region; there is no
        # batched form of matchTemplate for templates and windows of different sizes)
        for j in np.flatnonzero(has).tolist():
            f = rows[j]
            if not self._eligible_row(f):  # tracks that have driven somewhere ...
                continue
            px, py = p_list[j]
            bx, by, bw, bh = f[0:4]
            if max_drift2 is not None:  # ... and have come to rest where last seen
                # (its last detection or match, or the box of its template: a vehicle fading
                # into the background leaves fragments of its blob that wander inside its box)
                dx, dy = px - f[4], py - f[5]
                ex, ey = px - bx, py - by
                if not min(dx * dx + dy * dy, ex * ex + ey * ey) <= max_drift2:  # NaN: False
                    continue
            elif not (math.isfinite(px) and math.isfinite(py)):
                continue
            # a box placed on the prediction that sticks out of the image: leaving, not
            # stopped. The exact test (on the template) follows; this bound of it spares the
            # cutting of a template for leaving tracks.
            hx, hy = (bw - 1.0) / 2.0, (bh - 1.0) / 2.0
            sx, sy = px - bx, py - by
            if not (
                sx + max(bx - hx, 0.0) >= -1.0
                and sy + max(by - hy, 0.0) >= -1.0
                and sx + min(bx + hx, width) <= width + 0.5
                and sy + min(by + hy, height) <= height + 0.5
            ):
                continue
            t = self._current(int(pos[j]))
            if t is None:
                continue
            res = search_gate(frame, t, px, py, radii[j], self.smooth, self._pad)
            if res is None:  # leaving the image, or only flat placements inside the gate
                continue
            best, mx, my = res
            score[j] = best
            if best >= self.min_score:
                found[j] = True
                out[j] = (mx, my)
                self._f[pos[j], self._LAST] = out[j]  # held: the match is its last place
        return found, out, score

    def bind(self, frame: Image, gate_radius: float | ArrayLike | None = None) -> RescueFn:
        """``rescue(uids, predicted_xy, wh) -> (found, xy)`` on ``frame`` (a tracker's callback)."""

        def rescue(
            uids: IntArray, predicted_xy: FloatArray, wh: FloatArray
        ) -> tuple[BoolArray, FloatArray]:
            found, xy, _ = self.rescue(frame, uids, predicted_xy, wh, gate_radius)
            return found, xy

        return rescue
