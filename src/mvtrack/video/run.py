"""Whole runs: a video in, an output folder out (results, annotated video, plots, summary).

:func:`track_video` is what ``mvtrack track`` and each job of ``mvtrack batch`` run: it opens
the source, fills in the size-dependent settings (:mod:`mvtrack.video.settings`), builds the
parts (:mod:`mvtrack.video.build`) and calls :func:`track_to_folder`, which runs the frame loop
(:func:`mvtrack.video.loop.run_frames`) and writes the files. Both then call
:func:`write_tables`, which adds the tables computed from the whole run (``states.csv``, and
the analytics files), so a batch folder holds the files of a ``track`` folder.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.config import RunSettings
from mvtrack.types import Detections, TrackFrame
from mvtrack.video.build import build_detector, build_rescuer, build_tracker
from mvtrack.video.loop import PipelineResult, run_frames
from mvtrack.video.settings import resolve_settings

Image = NDArray[np.uint8]


@dataclass
class RunOutput:
    """A finished run: the loop's result, the files written and the summary."""

    result: PipelineResult
    log: Any  # mvtrack.tracking.TrackLog
    summary: dict[str, Any]
    paths: dict[str, Path]


def snapshot_frames(snapshot: int | Sequence[int] | None,
                    max_frames: int | None = None) -> tuple[int, ...]:
    """The frame indices to save as pictures, sorted and once each (``--snapshot``, which
    may be given more than once); none for None.

    Raises
    ------
    InputError
        A negative index, or one at or past ``max_frames`` (the frames to be tracked).
    """
    from mvtrack.errors import InputError

    if snapshot is None:
        return ()
    shots = tuple(sorted({int(snapshot)} if isinstance(snapshot, int) else set(snapshot)))
    if shots and shots[0] < 0:
        raise InputError(f"--snapshot must be a frame index >= 0, got {shots[0]}")
    if shots and max_frames is not None and shots[-1] >= max_frames:
        raise InputError(f"--snapshot {shots[-1]} is past the last frame tracked "
                         f"(--max-frames {max_frames}: frames 0 to {max_frames - 1})")
    return shots


def missed_snapshot(run: RunOutput, snapshot: int | Sequence[int] | None,
                    video: str | int) -> str | None:
    """The one-line error for the first ``snapshot`` frame that a source of unknown length
    did not reach (nothing was saved for it; the tracks were written), or None."""
    missed = [k for k in snapshot_frames(snapshot) if f"snapshot {k}" not in run.paths]
    if not missed:
        return None
    n = run.result.n_frames
    return (f"--snapshot {missed[0]}: {video} ended after {n} frames (0 to {n - 1}), so that "
            f"frame was not saved")


def _track_lengths(log: Any) -> NDArray[np.int64]:
    ids = log.columns()["track_id"]
    ids = ids[ids > 0]
    return np.unique(ids, return_counts=True)[1] if ids.size else np.zeros(0, dtype=np.int64)


def track_to_folder(
    frames: Iterable[Image],
    *,
    fps: float,
    size: tuple[int, int],
    settings: RunSettings,
    out: str | os.PathLike[str],
    max_frames: int | None = None,
    total: int | None = None,
    source: str = "",
    progress: bool | None = None,
    parts: tuple[Any, Any] | None = None,
    source_error: Callable[[], str | None] | None = None,
    snapshot: int | Sequence[int] | None = None,
    flush: float | None = None,
    masks: str | os.PathLike[str] | None = None,
    reread: Callable[[], Iterable[Image]] | None = None,
) -> RunOutput:
    """Track ``frames`` and write everything into the folder ``out``.

    Files (each written atomically; a failure leaves no partial file):

    - ``results.txt`` — MOTChallenge results (frame, id, left, top, w, h, conf, -1, -1, -1)
      of the rows with a measurement (confirmed, or stopped and held by template matching);
      coasting predictions are drawn in the video, and written only with
      ``settings.coasting`` (``--coasting``);
    - ``tracks.mp4`` — the annotated video (unless ``settings.video`` is False): boxes in
      their state colour, IDs, the trails of the tracks in the frame and the gates the
      tracker applies to the next frame for the confirmed tracks drawn
      (:meth:`~mvtrack.tracking.Tracker.gates`: the filter's innovation ellipses by
      default, circles for the Euclidean gate);
    - ``trajectories.png`` — every track's path over the first frame;
    - ``summary.json`` — frames, tracks, states histogram, ``processing_speed`` (frames
      processed per second; ``video_fps`` is the frame rate), settings, ``ended_early``;
    - ``frameNNNNN.png`` — one annotated frame, if ``snapshot`` is given;
    - with ``masks``, the front end's foreground of every frame as a 0/255 PNG in that
      folder (:class:`mvtrack.io.masks.MaskWriter`, one file per frame, each written
      atomically).

    Ctrl-C during the loop ends it early; the files are still written for the frames
    processed (``summary["interrupted"]``).

    With ``settings.offline`` the rows are revised once every frame is tracked
    (:mod:`mvtrack.video.offline`: confirmed tracks written from their first detection, every
    row smoothed), and the files hold the revised rows. The annotated video and the snapshot
    are then drawn in a second pass over the frames (``reread``), without gates (they are
    the live tracker's).

    With ``flush`` (seconds) the run streams (:mod:`mvtrack.video.stream`): ``results.txt`` and
    ``states.csv`` are created at once and every ``flush`` seconds get the rows of the frames
    tracked since, whole lines synced to disk, so they can be read while the run goes on and
    are valid at every moment; memory stays flat on an endless stream. At the end both files
    hold exactly what a run without ``flush`` writes, and so do the summary's figures;
    ``trajectories.png`` draws the last
    :data:`~mvtrack.video.stream.TRAJECTORY_FRAMES` frames only, and the summary gains
    ``flush_seconds``. ``tracks.mp4`` is still written whole at the end.

    Parameters
    ----------
    frames : iterable of (H, W, 3) uint8
        The video.
    fps : float
        Frame rate of the video (converts the tracker's time-based parameters).
    size : (W, H)
        Frame size.
    settings : RunSettings
        Detector, tracker and output settings.
    out : path
        Output folder (created).
    max_frames : int, optional
        Stop after this many frames.
    total : int, optional
        Expected number of frames, for the progress bar.
    source : str
        Name of the video, for the summary.
    progress : bool, optional
        Force the progress bar on or off.
    parts : (detector, tracker), optional
        Ready-made parts instead of building them from ``settings``.
    source_error : callable, optional
        Asked after the loop why the source ended early (e.g. ``lambda: src.error`` of a
        :class:`~mvtrack.io.video.FrameSource`); its answer goes to ``result.error``.
    snapshot : int or sequence of int, optional
        Also save the annotated frames with these indices as ``frameNNNNN.png`` (lossless),
        with or without the video; each is ``paths["snapshot N"]``.
    flush : float, optional
        Stream ``results.txt`` and ``states.csv``, appending every ``flush`` seconds (> 0).
    masks : path, optional
        Folder for the foreground masks; the front end must have a ``mask`` (every
        background-model front end has; ``hog`` has not).
    reread : callable, optional
        Gives the frames again, for the drawing pass of an offline run with a video or a
        snapshot (required then).

    Raises
    ------
    InputError
        ``masks`` with a front end that has no foreground mask, or a folder that cannot be
        created; an offline run that streams (``flush``) or must draw without ``reread``
        (before any frame is read).
    """
    import cv2

    from mvtrack.errors import InputError
    from mvtrack.io.atomic import atomic_path, write_json
    from mvtrack.tracking import TrackLog
    from mvtrack.video.loop import flags_of, progress_bar, shown_scores
    from mvtrack.video.offline import OfflineRows
    from mvtrack.video.relink import Relinker
    from mvtrack.video.stream import StreamingOutput
    from mvtrack.viz.annotate import TrailBuffer, annotate_frame, shown_gates
    from mvtrack.viz.plots import TrackRows, save_figure, trajectory_figure

    if parts is None:
        settings = resolve_settings(settings, size, fps)
        detector, tracker = build_detector(settings), build_tracker(settings, fps)
    else:
        detector, tracker = parts
    shots = snapshot_frames(snapshot)
    offline = None
    if settings.offline:
        if flush is not None:
            raise InputError("--offline revises rows after the last frame: it cannot stream "
                             "(--flush)")
        if (settings.video or shots) and reread is None:
            raise InputError("--offline draws the video in a second pass over the source, "
                             "which cannot be read twice: add --no-video (and no --snapshot)")
        offline = tracker = OfflineRows(tracker)
    mask_writer = _mask_writer(masks, detector) if masks is not None else None
    rescuer = build_rescuer(settings, tracker, detector) if settings.templates else None
    relinker = Relinker(fps, settings.relink) if settings.relink.enabled else None
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths: dict[str, Path] = {}
    log = TrackLog()
    background: list[Image] = []
    config = tracker.config
    label = f"{config.predictor} | {config.distance} | {config.assign}"
    stream = None
    if flush is not None:  # both files exist (empty) before the first frame
        gap = getattr(config, "max_misses", None)
        if gap is not None and relinker is not None:  # a relinked ID pauses up to the window
            gap += relinker.window
        stream = StreamingOutput(out, flush, gap=gap, fps=fps,
                                 coasting=settings.coasting)
        log = stream.log
        paths.update(stream.paths)

    with contextlib.ExitStack() as stack:
        if stream is not None:
            stack.callback(stream.close)  # what was tracked is written, whatever happens
        writer = None
        if settings.video:
            dest = out / "tracks.mp4"
            tmp = stack.enter_context(atomic_path(dest))
            writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
            if not writer.isOpened():
                raise OSError(f"cannot write video {dest} (OpenCV has no MPEG-4 encoder)")
            stack.callback(writer.release)  # runs before atomic_path renames the file
            paths["video"] = dest
        trails = TrailBuffer(settings.trail)
        live = None  # lines, zones, running counts and speeds drawn on the video
        if settings.analytics is not None and (writer is not None or shots):
            from mvtrack.analytics import settings_from_dict
            from mvtrack.viz.overlay import LiveAnalytics

            scene = settings_from_dict(settings.analytics, "[analytics]")
            live = LiveAnalytics(scene, scene.fps or fps)

        def on_frame(k: int, image: Image, dets: Detections, tracks: TrackFrame) -> None:
            if mask_writer is not None:
                mask_writer.write(k, detector.mask, (image.shape[1], image.shape[0]))
            if stream is None:
                log.append(tracks)
            else:
                stream.add(tracks, flags_of(detector, len(dets)), shown_scores(rescuer, relinker))
            if offline is not None:
                offline.add(tracks, dets)
            if k == 0:
                background.append(image.copy())
            if offline is None:
                draw(k, image, tracks, settings.gates)

        def draw(k: int, image: Image, tracks: TrackFrame, with_gates: bool) -> None:
            shot = k in shots
            if writer is None and not shots:
                return
            trails.push(tracks)
            if live is not None:
                live.push(tracks)
            if writer is None and not shot:
                return
            gates: dict[str, Any] = {}
            if with_gates:  # the next frame's gates of the confirmed tracks drawn
                g = shown_gates(tracker.gates(), tracks,
                                None if relinker is None else relinker.shown)
                gates = {"gate_center": g.center, "gate_cov": g.shape, "gate_r2": g.r2}
            text = [f"frame {k}  tracks {len(tracks)}", label]
            img = annotate_frame(image, tracks, trails=trails, text=text, **gates)
            if live is not None:
                live.draw(img)
            if writer is not None:
                writer.write(img)
            if shot:
                dest = out / f"frame{k:05d}.png"
                with atomic_path(dest) as tmp_png:
                    if not cv2.imwrite(str(tmp_png), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
                        raise OSError(f"cannot write {dest}")
                paths[f"snapshot {k}"] = dest

        result = run_frames(
            frames, detector, tracker, rescuer=rescuer, max_frames=max_frames,
            on_frame=on_frame, total=total, progress=progress, keep=stream is None,
            relink=relinker, offline=offline,
        )
        if stream is not None:
            stream.close()
        if result.error is None and source_error is not None and not result.interrupted:
            result.error = source_error()
        if offline is not None:
            log = offline.finish(log, relinker.shown if relinker is not None else None)
            if reread is not None and (writer is not None or shots):
                bar = progress_bar(len(log), "drawing", progress)
                try:  # the second pass: the revised rows drawn on the frames again
                    for k, (image, tracks) in enumerate(zip(reread(), log, strict=False)):
                        draw(k, image, tracks, False)
                        bar.update(1)
                except KeyboardInterrupt:  # the video keeps the frames drawn
                    result.interrupted = True
                finally:
                    bar.close()

    if stream is None:
        paths["results"] = out / "results.txt"
        log.write_mot(paths["results"], include_coasting=settings.coasting)
        rows = TrackRows.from_frames(log.frames_with_rows())
        lengths = _track_lengths(log)
        n_tracks = len(lengths)
        track_length = {
            "median": float(np.median(lengths)) if lengths.size else 0.0,
            "max": int(lengths.max()) if lengths.size else 0,
        }
        states = rows.state_histogram()
        drawn = f"{n_tracks} tracks"
    else:
        rows = stream.recent.track_rows()
        n_tracks, track_length = stream.stats.n_tracks, stream.stats.lengths()
        states = stream.stats.state_histogram()
        drawn = f"{n_tracks} tracks, the last {stream.recent.frames} frames drawn"
        if result.n_frames <= stream.recent.frames:
            drawn = f"{n_tracks} tracks"
    name = Path(source).name if source else "video"
    fig = trajectory_figure(
        rows, size, background[0] if background else None,
        title=f"{name}: {drawn} ({label})",
    )
    paths["trajectories"] = out / "trajectories.png"
    save_figure(fig, paths["trajectories"])
    summary = {
        "source": source,
        "frames": result.n_frames,
        "video_fps": fps,
        "size": list(size),
        "tracks": n_tracks,
        "track_length_frames": track_length,
        "detections": result.n_detections,
        "states": states,
        "processing_speed": round(result.processing_speed, 2) if result.n_frames else None,
        "seconds": round(result.seconds, 3),
        "ended_early": result.ended_early,
        "interrupted": result.interrupted,
        "error": result.error,
        "settings": settings.as_dict(),
        "tracker": _config_dict(config, getattr(tracker, "frame_size", None)),
        "files": {k: v.name for k, v in paths.items()},
    }
    if stream is not None:
        summary["flush_seconds"] = stream.interval
    if mask_writer is not None:
        summary["masks"] = {"folder": str(mask_writer.folder), "written": mask_writer.written}
    paths["summary"] = out / "summary.json"
    summary["files"]["summary"] = "summary.json"
    write_json(paths["summary"], summary)
    return RunOutput(result, log, summary, paths)


def _mask_writer(folder: str | os.PathLike[str], detector: Any) -> Any:
    """A :class:`~mvtrack.io.masks.MaskWriter` for ``folder``, or a one-line error when the
    front end has no foreground mask or the folder cannot be made."""
    from mvtrack.errors import InputError
    from mvtrack.io.masks import MaskWriter

    if not hasattr(detector, "mask"):
        name = getattr(detector, "name", type(detector).__name__)
        raise InputError(f"--masks: the front end {name!r} has no foreground mask")
    try:
        return MaskWriter(folder)
    except OSError as exc:
        raise InputError(f"--masks: cannot create the folder {folder} ({exc.strerror or exc})"
                         ) from None


def write_tables(
    run: RunOutput, out: str | os.PathLike[str], settings: RunSettings, *,
    fps: float | None = None,
) -> dict[str, Path]:
    """Write the tables of a finished run into its folder ``out``; returns their paths.

    - ``states.csv`` (:func:`mvtrack.analytics.outputs.states_table`: every row's state, its
      evidence, the template score of the rows held by template matching, speed, blob),
      unless the run streamed it (``--flush``: it is in ``run.paths`` already);
    - with an ``[analytics]`` table in ``settings`` and a source that did not fail:
      ``counts.csv``, ``movements.csv``, ``speeds.csv`` and ``tracks.csv``
      (:func:`mvtrack.analytics.analyse_folder` of ``results.txt``).

    What ``mvtrack track`` and each job of ``mvtrack batch`` run after :func:`track_video`.

    Parameters
    ----------
    run : RunOutput
        What :func:`track_to_folder` returned.
    out : path
        The run's output folder.
    settings : RunSettings
        The run's settings (only ``analytics`` is read).
    fps : float, optional
        Frame rate to assume for the analytics (default: the ``[analytics]`` table's
        ``fps``, else the video's, from ``summary.json``).

    Returns
    -------
    dict of str to Path
        ``states`` (when written here) and the analytics tables, by name.
    """
    from mvtrack.analytics.outputs import states_table, write_outputs, write_table

    out = Path(out)
    res = run.result
    paths: dict[str, Path] = {}
    if "states" not in run.paths:  # a streaming run wrote it as it went
        paths["states"] = write_table(out / "states.csv",
                                      states_table(run.log, res.flags, res.scores,
                                                   fps=float(run.summary["video_fps"])))
    if settings.analytics is not None and res.error is None:
        from mvtrack.analytics import analyse_folder, settings_from_dict

        scene = settings_from_dict(settings.analytics, "[analytics]")
        paths.update(write_outputs(analyse_folder(out, scene, fps), out))
    return paths


def _config_dict(config: Any, frame_size: Any = None) -> dict[str, Any]:
    out = {}
    for f in dataclasses.fields(config):
        value = getattr(config, f.name)
        out[f.name] = dict(value) if isinstance(value, Mapping) else value
    out["frame_size"] = None if frame_size is None else list(frame_size)  # from the video
    return out


def track_video(
    video: str | int,
    out: str | os.PathLike[str],
    settings: RunSettings,
    *,
    fps: float | None = None,
    max_frames: int | None = None,
    progress: bool | None = None,
    snapshot: int | Sequence[int] | None = None,
    flush: float | None = None,
    masks: str | os.PathLike[str] | None = None,
    take: Callable[[Iterable[Image]], Iterable[Image]] | None = None,
) -> RunOutput:
    """Open ``video``, build its parts for its size and frame rate, and :func:`track_to_folder`.

    What ``mvtrack track`` and each job of ``mvtrack batch`` run. Everything that can be wrong
    with the source or the settings fails before any file is written.

    Parameters
    ----------
    video : str or int
        Video file, image folder, camera index or stream URL (see
        :func:`mvtrack.io.video.open_source`).
    out : path
        Output folder.
    settings : RunSettings
        Settings as the user gave them; the size-dependent defaults are filled in here
        (:func:`resolve_settings`).
    fps : float, optional
        Frame rate to assume instead of the source's.
    max_frames, progress, snapshot, flush, masks
        As in :func:`track_to_folder`.
    take : callable, optional
        Wraps the source's frames on their way to the tracker (a batch job's stop flag, which
        ends the loop as Ctrl-C does).

    Raises
    ------
    InputError
        Missing, unreadable or empty source; bad settings; a ``snapshot`` past the last
        frame of a source whose length is known.
    """
    from mvtrack.io.video import open_source

    src = open_source(video, fps=fps)
    with src:
        check_reach(snapshot, src.frame_count, max_frames, video)
        resolved = resolve_settings(settings, src.size, src.fps)
        parts = (build_detector(resolved), build_tracker(resolved, src.fps))
        frames: Iterable[Image] = (frame for _, frame in src)
        return track_to_folder(
            frames if take is None else take(frames), fps=src.fps, size=src.size, settings=resolved,
            out=out, max_frames=max_frames, total=src.frame_count, source=str(video),
            progress=progress, parts=parts, source_error=lambda: src.error, snapshot=snapshot,
            flush=flush, masks=masks, reread=source_reader(video, fps),
        )


def check_reach(snapshot: int | Sequence[int] | None, frame_count: int | None,
                max_frames: int | None, video: str | int) -> None:
    """Refuse, before any file is written, a ``snapshot`` frame past the last frame to be
    tracked of a source of ``frame_count`` frames (None: unknown, nothing is refused)."""
    from mvtrack.errors import InputError

    last = frame_count if max_frames is None else min(frame_count or max_frames, max_frames)
    late = [k for k in snapshot_frames(snapshot) if last is not None and k >= last]
    if late:
        raise InputError(f"--snapshot {late[0]} is past the last frame {last - 1} of {video}"
                         + ("" if last == frame_count else
                            f" tracked (--max-frames {max_frames})"))


def source_reader(video: str | int, fps: float | None) -> Callable[[], Iterable[Image]] | None:
    """Reads a file or image folder again (an offline run's drawing pass); None for a camera
    or a network stream, which give other frames when opened again."""
    from mvtrack.io.video import open_source, source_kind

    if source_kind(video) != "file":
        return None

    def frames() -> Iterable[Image]:
        with open_source(video, fps=fps) as again:
            for _, frame in again:
                yield frame

    return frames
