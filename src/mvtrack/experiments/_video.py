"""Shared machinery of the video experiments (X4, X5, X8): render, track, match to the truth.

A scene is rendered (:func:`mvtrack.sim.render.render_frames`), sent through the whole video
pipeline (disturbance map → tracker, with template matching for stopped vehicles), and the
output rows are matched to the ground truth frame by frame: a track row and a visible
ground-truth box are paired by minimum total centre distance (Hungarian, per frame) when their
centres are closer than ``max(min_px, frac · max(w, h))`` of the ground-truth box. From the
pairs come the per-track majority object, the tracks per object and each object's coverage by
its best single track.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mvtrack.config import RunSettings
from mvtrack.sim.scene import Scene
from mvtrack.tracking import Tracker, TrackerConfig, TrackLog
from mvtrack.video import PipelineResult, build_rescuer, resolve_settings, run_frames

#: the front end of the paper experiments (paper 1's disturbance map), named here so that
#: they keep it whatever the default of ``mvtrack track`` is
PAPER_DETECTOR = "disturbance-map"

#: paper 1's template matching (SPEC §1.1 step 3): only the tracks without a detection in
#: their gate are searched, not also the pipeline's vehicles that stand and stay foreground
#: (:meth:`mvtrack.video.rescue.StoppedVehicleRescuer.fragments`)
PAPER_TEMPLATES: dict[str, Any] = {"pieces": False}

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]


@dataclass
class SceneRun:
    """One tracked rendering of a scene."""

    scene: Scene
    log: TrackLog
    result: PipelineResult
    match: Matching


def track_scene(
    scene: Scene,
    config: TrackerConfig,
    *,
    seed: int,
    detector: str = PAPER_DETECTOR,
    detector_params: dict[str, Any] | None = None,
    templates: bool = True,
    frames: list[NDArray[np.uint8]] | None = None,
    prime: int = 0,
    template_params: dict[str, Any] | None = None,
    frame_size: tuple[float, float] | None = None,
) -> SceneRun:
    """Render ``scene`` with ``seed`` (or use ``frames``), track it, match to the truth.

    ``prime`` > 0 first shows the detector that many frames of the empty scene
    (:func:`mvtrack.sim.backgrounds.render_background`), as a camera that has been running
    before the sequence starts: the disturbance map's background then holds the empty road
    instead of ``B_0 = I_0`` with the vehicles in it (which leaves a ghost blob behind every
    vehicle that is in view at frame 0). ``frame_size`` is the tracker's image
    (:class:`~mvtrack.tracking.Tracker`: a track whose prediction leaves it ends there), as
    ``mvtrack track`` gives it (the scene's size, :func:`default_frame_size`); None for the
    papers' systems, whose tracks end after their misses only.
    """
    from mvtrack.detection import make_detector
    from mvtrack.sim.backgrounds import render_background
    from mvtrack.sim.render import render_frames

    if detector_params is None:  # the pipeline's defaults for this image size
        paper = RunSettings(detector=PAPER_DETECTOR)
        detector_params = resolve_settings(paper, scene.size, scene.fps).detector_params
    det = make_detector(detector, **detector_params)
    if prime > 0:
        empty = render_background(scene, seed)
        for _ in range(prime):
            det(empty)
    tracker = Tracker(config, frame_size=frame_size)
    rescue_settings = RunSettings(template_params=dict(template_params or {}))
    rescuer = build_rescuer(rescue_settings, tracker, det) if templates else None
    source = frames if frames is not None else render_frames(scene, seed)
    result = run_frames(source, det, tracker, rescuer=rescuer, progress=False)
    log = TrackLog()
    for tf in result.tracks:
        log.append(tf)
    return SceneRun(scene, log, result, match_to_truth(scene, log))


@dataclass
class Matching:
    """Frame-by-frame pairs of output rows and visible ground-truth rows.

    Attributes
    ----------
    gt_frame, gt_id : (G,) int64
        The visible ground-truth rows.
    gt_track : (G,) int64
        Track ID paired with each ground-truth row (−1: none).
    row_frame, row_track, row_gt : (R,) int64
        Output rows with a public ID, and the object each is paired with (0: none).
    row_assoc : (R,) bool
        The row used a detection (``det_index ≥ 0``).
    gt_xy, gt_radius : (G, 2), (G,)
        Centre of each visible ground-truth row and the pairing radius around it.
    row_xy : (R, 2)
        Output position of each row.
    row_near : (R,) int64
        The object nearest each row within its pairing radius, whatever other rows are
        paired with (0: none): the object the row *follows*.
    """

    gt_frame: IntArray
    gt_id: IntArray
    gt_track: IntArray
    row_frame: IntArray
    row_track: IntArray
    row_gt: IntArray
    row_assoc: NDArray[np.bool_]
    gt_xy: FloatArray | None = None
    gt_radius: FloatArray | None = None
    row_xy: FloatArray | None = None
    row_near: IntArray | None = None

    def associations(self) -> tuple[IntArray, IntArray]:
        """Track IDs and the number of detections each was associated with."""
        ids, inv = np.unique(self.row_track, return_inverse=True)
        return ids, np.bincount(inv, weights=self.row_assoc).astype(np.int64)

    def majority(self, min_assoc: int = 1) -> tuple[IntArray, IntArray, FloatArray]:
        """Per track with ≥ ``min_assoc`` associations: its majority object and that share.

        Returns track IDs, the object each follows most (0 when most of its rows are paired
        with nothing: a spurious track) and the share of its rows paired with that object.
        """
        ids, n_assoc = self.associations()
        ids = ids[n_assoc >= min_assoc]
        obj = np.zeros(ids.size, np.int64)
        share = np.zeros(ids.size)
        if ids.size == 0:
            return ids, obj, share
        n_obj = int(max(self.row_gt.max(initial=0), self.gt_id.max(initial=0))) + 1
        pos = np.searchsorted(ids, self.row_track)
        inside = pos < ids.size
        inside[inside] = ids[pos[inside]] == self.row_track[inside]
        counts = np.zeros((ids.size, n_obj), np.int64)
        np.add.at(counts, (pos[inside], self.row_gt[inside]), 1)
        obj = counts.argmax(axis=1)
        share = counts[np.arange(ids.size), obj] / np.maximum(counts.sum(axis=1), 1)
        return ids, obj.astype(np.int64), share

    def coverage(self, obj_id: int) -> tuple[int, float, int]:
        """Best single track of object ``obj_id``, the share of its visible frames it holds,
        and the number of distinct tracks ever paired with it."""
        sel = self.gt_id == obj_id
        tracks = self.gt_track[sel]
        n = int(sel.sum())
        held = tracks[tracks > 0]
        if n == 0 or held.size == 0:
            return -1, 0.0, 0
        ids, counts = np.unique(held, return_counts=True)
        best = int(counts.argmax())
        return int(ids[best]), float(counts[best] / n), int(ids.size)

    def follows(self, min_rows: int = 1) -> tuple[IntArray, IntArray]:
        """Per track with ≥ ``min_rows`` rows: the object it follows in most of its rows
        (non-exclusively, :attr:`row_near`; 0 when that is none)."""
        if self.row_near is None:
            raise ValueError("this Matching carries no positions (built without them)")
        ids, inv, counts = np.unique(self.row_track, return_inverse=True, return_counts=True)
        n_obj = int(max(self.row_near.max(initial=0), self.gt_id.max(initial=0))) + 1
        table = np.zeros((ids.size, n_obj), np.int64)
        np.add.at(table, (inv, self.row_near), 1)
        keep = counts >= min_rows
        return ids[keep].astype(np.int64), table[keep].argmax(axis=1).astype(np.int64)

    def followers(self, obj_id: int, frames: tuple[int, int] | None = None
                  ) -> tuple[IntArray, IntArray, int]:
        """Tracks that follow ``obj_id``, non-exclusively: IDs, and in how many of the
        object's visible frames (within ``frames = (first, last)``, if given) each has a row
        within the pairing radius of it, and the number of those frames.

        Unlike :meth:`coverage`, two tracks on one object (a vehicle whose blob split, both
        halves tracked) both follow it; the one-to-one pairing would hand its frames to one
        or the other, whichever happened to be nearer in each frame.
        """
        if self.gt_xy is None or self.row_xy is None or self.gt_radius is None:
            raise ValueError("this Matching carries no positions (built without them)")
        mask = self.gt_id == obj_id
        if frames is not None:
            mask &= (self.gt_frame >= frames[0]) & (self.gt_frame <= frames[1])
        sel = np.flatnonzero(mask)
        if sel.size == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64), 0
        order = np.argsort(self.row_frame, kind="stable")
        frames = self.row_frame[order]
        lo = np.searchsorted(frames, self.gt_frame[sel], side="left")
        hi = np.searchsorted(frames, self.gt_frame[sel], side="right")
        take = np.concatenate([order[a:b] for a, b in zip(lo, hi, strict=True)]
                              ) if sel.size else np.zeros(0, np.intp)
        which = np.repeat(np.arange(sel.size), hi - lo)
        d = np.linalg.norm(self.row_xy[take] - self.gt_xy[sel][which], axis=1)
        near = d <= self.gt_radius[sel][which]
        # one count per (track, frame) pair
        pairs = np.unique(np.stack([self.row_track[take][near], which[near]], axis=1), axis=0)
        ids, counts = np.unique(pairs[:, 0], return_counts=True) if pairs.size else (
            np.zeros(0, np.int64), np.zeros(0, np.int64))
        return ids.astype(np.int64), counts.astype(np.int64), int(sel.size)

    def followed_share(self, obj_id: int, frames: tuple[int, int] | None = None
                       ) -> tuple[int, float]:
        """The track that follows ``obj_id`` in most of its visible frames (within
        ``frames``; non-exclusively, :meth:`followers`) and the share of those frames;
        ``(-1, 0.0)`` if none."""
        ids, counts, n = self.followers(obj_id, frames)
        if ids.size == 0 or n == 0:
            return -1, 0.0
        best = int(counts.argmax())
        return int(ids[best]), float(counts[best] / n)

    def sequence(self, obj_id: int) -> tuple[IntArray, IntArray]:
        """Frames where ``obj_id`` is visible and the track paired with it (−1: none)."""
        sel = self.gt_id == obj_id
        return self.gt_frame[sel], self.gt_track[sel]


def match_to_truth(
    scene: Scene, log: TrackLog, min_px: float = 6.0, frac: float = 0.75
) -> Matching:
    """Pair output rows with visible ground-truth rows per frame (see module docstring)."""
    cols = log.columns()
    keep = cols["track_id"] > 0
    r_frame = cols["frame"][keep]
    r_id = cols["track_id"][keep]
    r_xy = cols["filtered_xy"][keep]
    r_assoc = cols["det_index"][keep] >= 0
    vis = scene.visible
    g_frame, g_id, g_xy, g_wh = scene.frame[vis], scene.id[vis], scene.xy[vis], scene.wh[vis]
    g_track = np.full(g_frame.size, -1, np.int64)
    r_gt = np.zeros(r_frame.size, np.int64)
    r_near = np.zeros(r_frame.size, np.int64)
    n = int(max(scene.n_frames, r_frame.max(initial=-1) + 1))
    g_start = np.searchsorted(g_frame, np.arange(n + 1))
    order = np.argsort(r_frame, kind="stable")
    r_start = np.searchsorted(r_frame[order], np.arange(n + 1))
    thr = np.maximum(min_px, frac * g_wh.max(axis=1))
    for f in range(n):  # one small assignment per frame
        gs = slice(g_start[f], g_start[f + 1])
        rs = order[r_start[f] : r_start[f + 1]]
        if gs.start == gs.stop or rs.size == 0:
            continue
        d = np.linalg.norm(g_xy[gs][:, None, :] - r_xy[rs][None, :, :], axis=2)
        ok = d <= thr[gs][:, None]
        if not ok.any():
            continue
        nearest = np.where(ok, d, np.inf).argmin(axis=0)  # per row, the nearest object
        r_near[rs] = np.where(ok.any(axis=0), g_id[gs.start + nearest], 0)
        cost = np.where(ok, d, 1e6)
        gi, rj = linear_sum_assignment(cost)
        good = ok[gi, rj]
        gi, rj = gi[good], rj[good]
        g_track[gs.start + gi] = r_id[rs[rj]]
        r_gt[rs[rj]] = g_id[gs.start + gi]
    return Matching(g_frame, g_id, g_track, r_frame, r_id, r_gt, r_assoc, g_xy, thr, r_xy,
                    r_near)


def breaks(frames: IntArray, tracks: IntArray) -> list[tuple[int, int, int]]:
    """Where the track paired with an object changes: ``(frame, old_id, new_id)``.

    Gaps (−1) are skipped: a change is a new track ID after a different one.
    """
    held = tracks > 0
    f, t = frames[held], tracks[held]
    change = np.flatnonzero(t[1:] != t[:-1]) + 1
    return [(int(f[i]), int(t[i - 1]), int(t[i])) for i in change]


def pipeline_blob_params(size: tuple[int, int], fps: float = 30.0) -> dict[str, Any]:
    """The disturbance map's settings ``mvtrack track`` uses for a video of ``size`` at
    ``fps`` (a 7×7 closing and area ≥ 40 px at 320×240, the ghost test, tracked pixels held
    out of the background), which the specification's experiments run as a variant."""
    paper = RunSettings(detector=PAPER_DETECTOR)
    return dict(resolve_settings(paper, size, fps).detector_params)


def prediction_errors(run: SceneRun, obj_id: int, warmup_hits: int = 6) -> dict[str, Any]:
    """How the track that holds ``obj_id`` predicted it, frame by frame.

    For every visible frame f of the object after its first paired one, the track that was
    paired with it at the last earlier frame (the track that should continue) is looked up at
    f: its gate centre ``predicted_xy`` against the true centre gives the prediction error,
    its associations before f tell whether it was still in paper 1's warm-up (fewer than
    ``warmup_hits``), and whether it took a detection at f. Frames where that track had
    already ended have NaN error.

    Returns a dict of lists: ``frame``, ``track``, ``error`` (px), ``warmup`` (bool),
    ``associated`` (bool).
    """
    cols = run.log.columns()
    frames, tracks = run.match.sequence(obj_id)
    f_all, xy_all = run.scene.trajectory(obj_id)
    out: dict[str, list[Any]] = {"frame": [], "track": [], "error": [], "warmup": [],
                                 "associated": []}
    held = -1
    by_track: dict[int, tuple[IntArray, FloatArray, NDArray[np.bool_]]] = {}
    for f, t in zip(frames.tolist(), tracks.tolist(), strict=True):  # offline, one object
        if held > 0:
            if held not in by_track:
                sel = cols["track_id"] == held
                by_track[held] = (cols["frame"][sel], cols["predicted_xy"][sel],
                                  cols["det_index"][sel] >= 0)
            fr, pred, assoc = by_track[held]
            i = np.searchsorted(fr, f)
            truth = xy_all[np.searchsorted(f_all, f)]
            out["frame"].append(f)
            out["track"].append(held)
            if i < fr.size and fr[i] == f:
                out["error"].append(float(np.linalg.norm(pred[i] - truth)))
                out["associated"].append(bool(assoc[i]))
            else:
                out["error"].append(float("nan"))
                out["associated"].append(False)
            out["warmup"].append(bool(assoc[fr < f].sum() < warmup_hits))
        if t > 0:
            held = t
    return out


def default_frame_size(scene: Scene) -> tuple[float, float]:
    """The image size ``mvtrack track`` gives the tracker of this scene's video
    (:func:`mvtrack.video.resolve_settings`): a track whose prediction leaves it ends."""
    return float(scene.size[0]), float(scene.size[1])


def default_config(scene: Scene) -> TrackerConfig:
    """The tracker configuration ``mvtrack track`` uses by default for this scene's video
    (the ``default`` preset at the scene's frame rate, as
    :func:`mvtrack.video.build_tracker_config` builds it; its image size is
    :func:`default_frame_size`)."""
    from mvtrack.video import build_tracker_config

    paper = RunSettings(detector=PAPER_DETECTOR)
    return build_tracker_config(resolve_settings(paper, scene.size, scene.fps), scene.fps)


def summarise(run: SceneRun, min_assoc: int = 5) -> dict[str, Any]:
    """Track counts of a run: tracks with ≥ ``min_assoc`` associations, tracks per object
    (by majority pairing), spurious tracks (paired with nothing most of the time), and per
    object its best track's coverage and the number of distinct tracks that held it."""
    ids, obj, _ = run.match.majority(min_assoc)
    n_obj = run.scene.n_objects
    per_object = np.bincount(obj, minlength=n_obj + 1)
    coverage = {}
    for v in range(1, n_obj + 1):
        best, cov, n_tracks = run.match.coverage(v)
        coverage[v] = {"track": best, "coverage": round(cov, 4), "tracks_seen": n_tracks}
    return {
        "tracks": int(ids.size),
        "tracks_per_object": {int(v): int(per_object[v]) for v in range(1, n_obj + 1)},
        "spurious": int((obj == 0).sum()),
        "coverage": coverage,
        "frames": run.result.n_frames,
        "processing_speed": round(run.result.processing_speed, 1),
    }


def trajectory_plot(
    run: SceneRun,
    title: str,
    *,
    group_of: Callable[[int], str] | None = None,
    spurious: str = "spurious",
    truth: bool = True,
    min_length: int = 5,
    legend_title: str | None = None,
) -> Any:
    """The run's trajectories over the empty scene, coloured by what each track follows.

    Each track (output in at least ``min_length`` frames) is put in the group of the object
    it follows in most of its rows (within the pairing radius, :meth:`Matching.follows`;
    ``group_of(obj_id)``, default the object's category) or in ``spurious`` when that is
    none; the true paths of the objects are drawn dashed beside them.
    """
    from mvtrack.sim.backgrounds import render_background
    from mvtrack.viz.plots import TrackRows, trajectory_figure

    rows = TrackRows.from_frames(run.log)
    bg = render_background(run.scene, 0)
    scene = run.scene
    name = group_of or (lambda v: str(scene.category[v - 1]))
    ids, obj = run.match.follows()
    groups = {int(t): (name(int(o)) if o > 0 else spurious) for t, o in zip(ids, obj,
                                                                          strict=True)}
    paths = {}
    if truth:
        for v in range(1, scene.n_objects + 1):
            paths[str(v)] = scene.trajectory(v)[1]
    return trajectory_figure(rows, scene.size, bg, title=title, min_length=min_length,
                             truth=paths, groups=groups, legend_title=legend_title,
                             failure_group=spurious)
