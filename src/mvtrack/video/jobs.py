"""One video of a batch: its record, its output folder's name, the worker task that tracks it.

:func:`track_one` is the Dask task of :func:`mvtrack.video.batch.track_many`: it tracks one
video exactly as ``mvtrack track`` does and never raises; the :class:`BatchItem` it returns
(as a dict) is one entry of ``batch.json``.
"""

from __future__ import annotations

import contextlib
import glob
import os
import re
import time
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from mvtrack.config import RunSettings

#: the statuses of a :class:`BatchItem`
STATUSES: tuple[str, ...] = ("ok", "failed", "cancelled")



@dataclass
class BatchItem:
    """The outcome of one video of a batch.

    Attributes
    ----------
    video : str
        The video as given to the worker (an absolute path, or a URL).
    out : str
        Its output folder.
    status : str
        ``"ok"``; ``"failed"`` (``error`` says why; a video that broke off mid-way keeps the
        files of the frames before); ``"cancelled"`` (Ctrl-C before or while it ran).
    frames : int
        Frames tracked.
    tracks : int
        Tracks found.
    processing_speed : float or None
        Frames its tracking loop processed per second.
    seconds : float
        Wall time of the task on its worker (open, track, write files).
    error : str or None
        One-line reason for a failed or cancelled video.
    """

    video: str
    out: str
    status: str = "cancelled"
    frames: int = 0
    tracks: int = 0
    processing_speed: float | None = None
    seconds: float = 0.0
    error: str | None = None

    @property
    def ok(self) -> bool:
        """True when the video was tracked to its end."""
        return self.status == "ok"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (one entry of ``batch.json``)."""
        return asdict(self)


# --------------------------------------------------------------------------- naming


def normalise_video(video: str | os.PathLike[str]) -> str:
    """An absolute path for a local video (so remote workers see the same name); URLs unchanged."""
    from mvtrack.io.video import source_kind

    text = os.fspath(video)
    if source_kind(text) == "stream":
        return text
    return str(Path(text).expanduser().absolute())


def output_names(videos: Sequence[str | os.PathLike[str]]) -> list[str]:
    """Folder names for ``videos``: each stem, told apart by its folders where stems collide.

    A stem that no other video shares names the folder as it is (``a/cam.avi`` gives ``cam``).
    Videos whose stems collide are named by as many of their parent folders as tell them apart,
    joined with ``_``: ``a/cam.avi`` beside ``b/cam.avi`` gives ``a_cam`` and ``b_cam``, and the
    image folders of a MOT layout, ``US101-1/img1`` beside ``US101-2/img1``, give ``US101-1_img1``
    and ``US101-2_img1``. Names that the folders cannot tell apart (the same video given twice)
    get ``-2``, ``-3``, ... in input order, skipping any name already taken. Names are compared
    case-insensitively, so the folders differ on case-insensitive file systems too.

    Examples
    --------
    >>> output_names(["x/a/cam.avi", "y/b/cam.avi", "cam-2.mp4", "z/b/cam.mp4", "frames/"])
    ['a_cam', 'y_b_cam', 'cam-2', 'z_b_cam', 'frames']
    >>> output_names(["s/v.avi", "s/v.avi"])
    ['s_v', 's_v-2']
    """
    paths = [_name_parts(video) for video in videos]
    depth = [1] * len(paths)
    while True:  # widen each colliding name by one folder until none collides or none can widen
        names = [_join(parts, d) for parts, d in zip(paths, depth, strict=True)]
        counts = Counter(name.lower() for name in names)
        widen = [i for i, name in enumerate(names)
                 if counts[name.lower()] > 1 and depth[i] < len(paths[i])]
        if not widen:
            break
        for i in widen:
            depth[i] += 1
    taken: set[str] = set()
    unique: list[str] = []
    for stem in names:
        name, n = stem, 1
        while name.lower() in taken:
            n += 1
            name = f"{stem}-{n}"
        taken.add(name.lower())
        unique.append(name)
    return unique


def _name_parts(video: str | os.PathLike[str]) -> list[str]:
    """A video's stem and then its parent folders, innermost first, each made safe for a name."""
    text = os.fspath(video).rstrip("/\\")
    path = Path(text)
    parts = [path.stem] + [p.name for p in path.parents if p.name]
    safe = [re.sub(r"[^\w.-]+", "_", part).strip(".") for part in parts]
    return [safe[0] or "video"] + [part for part in safe[1:] if part]


def _join(parts: list[str], depth: int) -> str:
    """The name of ``depth`` parts: the outermost folder first, the stem last."""
    return "_".join(reversed(parts[:depth]))


# --------------------------------------------------------------------------- one video (worker)


def one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if isinstance(exc, (ValueError, OSError)) and text else (
        f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    )


def track_one(
    video: str,
    out: str,
    settings: RunSettings,
    *,
    fps: float | None = None,
    max_frames: int | None = None,
    snapshot: Sequence[int] = (),
    stop: str | None = None,
) -> dict[str, Any]:
    """Track one video into ``out`` exactly as ``mvtrack track`` does; never raises.

    This is the Dask task of :func:`mvtrack.video.batch.track_many` (it also runs on its own).
    OpenCV is limited to one thread (``cv2.setNumThreads(1)``): the parallelism is one video
    per worker.

    Parameters
    ----------
    video : str
        Path or URL, opened with :func:`mvtrack.io.video.open_source`.
    out : str
        Output folder: the files of ``mvtrack track`` (``results.txt``, ``states.csv``,
        ``summary.json``, ``trajectories.png``, ``tracks.mp4``; with an ``[analytics]`` table
        in ``settings`` also ``counts.csv``, ``movements.csv``, ``speeds.csv``,
        ``tracks.csv``: :func:`mvtrack.video.run.write_tables`).
    settings : RunSettings
        As built by ``mvtrack track`` from its options; the size-dependent defaults are filled
        in here for this video's size (:func:`mvtrack.video.resolve_settings`).
    fps : float, optional
        Frame rate to assume instead of the source's.
    max_frames : int, optional
        Stop after this many frames.
    snapshot : sequence of int
        Frames to save as annotated pictures; a source that ends before one of them is
        ``failed`` with that frame named and the tracks written.
    stop : str, optional
        Name of a :class:`distributed.Event` (in a Dask task only): once it is set, the frame
        loop ends as on Ctrl-C and the files of the frames tracked so far are written, so an
        interrupted batch keeps the partial results of the videos it was tracking.

    Returns
    -------
    dict
        The fields of :class:`BatchItem`. Errors (a missing or unreadable file, a source
        that breaks off, a bad setting) become ``status="failed"`` with a one-line ``error``;
        Ctrl-C in the worker becomes ``status="cancelled"`` with the frames done so far.
    """
    import cv2

    from mvtrack.video.run import missed_snapshot, track_video, write_tables

    cv2.setNumThreads(1)
    t0 = time.perf_counter()
    item = BatchItem(video=video, out=out, status="failed")
    try:
        flag = None if stop is None else _StopFlag(stop)
        if flag is not None and flag.is_set():  # the batch was interrupted before this video
            raise KeyboardInterrupt
        run = track_video(video, out, settings, fps=fps, max_frames=max_frames,
                          progress=False, snapshot=snapshot,
                          take=None if flag is None else flag.frames)
        write_tables(run, out, settings, fps=fps)  # as `mvtrack track` does after its run
    except KeyboardInterrupt:
        item.status, item.error = "cancelled", "interrupted before any frame was tracked"
    except Exception as exc:  # one video's failure must not end the batch
        item.error = one_line(exc)
    else:
        res, summary = run.result, run.summary
        item.frames, item.tracks = res.n_frames, int(summary["tracks"])
        item.processing_speed = summary["processing_speed"]
        if res.interrupted:
            item.status = "cancelled"
            item.error = f"interrupted after {res.n_frames} frames; results so far are in {out}"
        elif res.error is not None:
            item.error = f"{' '.join(res.error.split())}; results so far are in {out}"
        elif (missed := missed_snapshot(run, snapshot, video)) is not None:
            item.error = f"{missed}; the tracks are in {out}"
        else:
            item.status = "ok"
    item.seconds = round(time.perf_counter() - t0, 3)
    return item.as_dict()


class _StopFlag:
    """A :class:`distributed.Event` looked at no more often than every ``every`` seconds."""

    def __init__(self, name: str, every: float = 0.25) -> None:
        from distributed import Event

        self.event = Event(name)
        self.every = every

    def is_set(self) -> bool:
        return bool(self.event.is_set())

    def frames(self, frames: Iterable[Any]) -> Iterator[Any]:
        """``frames`` until the event is set; then ``KeyboardInterrupt``, which the frame loop
        takes as Ctrl-C (it writes what was tracked)."""
        last = time.monotonic()
        for frame in frames:
            now = time.monotonic()
            if now - last >= self.every:
                last = now
                if self.is_set():
                    raise KeyboardInterrupt
            yield frame


def finished_on_disk(item: BatchItem, since: float) -> BatchItem | None:
    """The item of a run whose result did not reach us but whose files did.

    After Ctrl-C a video that was running may still complete before its worker stops; its
    ``summary.json`` (written last, atomically) then shows a full run newer than ``since``.
    """
    import json

    path = Path(item.out) / "summary.json"
    try:
        if path.stat().st_mtime < since:
            return None
        summary = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if summary.get("ended_early", True) or summary.get("source") != item.video:
        return None
    return BatchItem(item.video, item.out, "ok", frames=int(summary["frames"]),
                     tracks=int(summary["tracks"]),
                     processing_speed=summary.get("processing_speed"),
                     seconds=float(summary.get("seconds", 0.0)))


#: the files :func:`mvtrack.video.track_to_folder` and :func:`mvtrack.video.write_tables`
#: write (each through a temporary file)
_OUTPUTS = ("results.txt", "summary.json", "trajectories.png", "tracks.mp4", "states.csv",
            "counts.csv", "movements.csv", "speeds.csv", "tracks.csv")


def remove_temp_files(folder: Path) -> None:
    """Delete the temporary files a stopped worker left half-written in ``folder``."""
    for name in _OUTPUTS:
        for tmp in folder.glob(f".{glob.escape(name)}.*{Path(name).suffix}"):
            with contextlib.suppress(OSError):
                tmp.unlink()
