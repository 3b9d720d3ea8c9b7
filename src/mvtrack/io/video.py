"""Frames in: video files, image folders, cameras and stream URLs through OpenCV.

:func:`open_source` is the one entry point. It returns a :class:`FrameSource`: an iterable of
``(index, frame)`` pairs, ``frame`` a BGR ``uint8`` array of shape ``(H, W, 3)``, with the
frame rate and size of the source, usable as a context manager::

    with open_source("traffic.avi") as src:
        for k, frame in src:
            ...
        if src.ended_early:
            print(src.error)  # a stream dropped: keep the tracks so far

Problems found when opening (a missing path, a file OpenCV cannot decode, a source with no frames)
raise :class:`mvtrack.errors.InputError` with a one-line message. A source that stops delivering
frames part-way (a dropped stream, a truncated file, a corrupt image in a folder) does not raise:
iteration ends and ``ended_early`` / ``error`` say why, so the caller can keep what it tracked.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.errors import InputError
from mvtrack.io.images import read_image

Frame = NDArray[np.uint8]

#: File extensions read from an image folder (case-insensitive), in sorted file-name order.
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm")

#: Frame rate assumed when the source does not report one (image folders, some streams):
#: paper 1's 30 fps (SPEC §1.4).
DEFAULT_FPS = 30.0

_URL = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*://")


def _as_bgr(frame: NDArray, where: str) -> Frame:
    """Coerce a decoded frame to 3-channel BGR uint8 (OpenCV may hand back grey or 16-bit)."""
    if frame.dtype != np.uint8:
        if frame.dtype == np.uint16:
            frame = (frame >> 8).astype(np.uint8)
        else:
            raise InputError(f"{where}: unsupported pixel type {frame.dtype}")
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if frame.shape[2] == 4:
        return cv2.cvtColor(frame, cv2.COLOR_BGRA2BGR)
    return frame


class FrameSource:
    """A single-pass sequence of ``(index, BGR uint8 frame)``; see :func:`open_source`.

    Attributes
    ----------
    name : str
        The source as given (path, camera index or URL), for messages.
    kind : str
        ``"file"``, ``"folder"``, ``"camera"`` or ``"stream"``.
    fps : float
        Frames per second reported by the source, else the ``fps`` given to
        :func:`open_source`, else :data:`DEFAULT_FPS`.
    fps_reported : bool
        Whether ``fps`` came from the source itself.
    size : tuple[int, int]
        Frame width and height in pixels.
    frame_count : int or None
        Number of frames when known in advance (files, folders), else ``None``.
    frames_read : int
        Frames delivered so far.
    ended_early : bool
        True when iteration stopped before the source's end (dropped stream, truncated file,
        unreadable image). ``error`` then holds a one-line explanation.
    error : str or None
        Why the source ended early, else ``None``.
    """

    kind: str = ""

    def __init__(
        self,
        name: str,
        fps: float,
        fps_reported: bool,
        size: tuple[int, int],
        frame_count: int | None,
    ) -> None:
        self.name = name
        self.fps = float(fps)
        self.fps_reported = fps_reported
        self.size = size
        self.frame_count = frame_count
        self.frames_read = 0
        self.ended_early = False
        self.error: str | None = None
        self._closed = False
        self._started = False

    # -- iteration ---------------------------------------------------------------------------
    def __iter__(self) -> Iterator[tuple[int, Frame]]:
        if self._started:
            raise RuntimeError(f"{self.name}: a frame source can be iterated only once")
        self._started = True
        try:
            for frame in self._frames():
                if self._closed:
                    return
                if (frame.shape[1], frame.shape[0]) != self.size:
                    w, h = self.size
                    self._fail(
                        f"frame {self.frames_read} is {frame.shape[1]}×{frame.shape[0]}, "
                        f"not {w}×{h} like the first"
                    )
                    return
                k = self.frames_read
                self.frames_read += 1
                yield k, frame
        finally:
            self.close()

    def _frames(self) -> Iterator[Frame]:  # pragma: no cover - abstract
        raise NotImplementedError

    def _fail(self, why: str) -> None:
        self.ended_early = True
        self.error = f"{self.kind} {self.name} ended early after {self.frames_read} frames: {why}"

    # -- resources ---------------------------------------------------------------------------
    def close(self) -> None:
        """Release the underlying capture (idempotent)."""
        self._closed = True

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        w, h = self.size
        n = "?" if self.frame_count is None else self.frame_count
        return (
            f"<{type(self).__name__} {self.kind} {self.name!r} {w}×{h} "
            f"{self.fps:g} fps, {n} frames>"
        )


class CaptureSource(FrameSource):
    """Frames from a ``cv2.VideoCapture`` (file, camera or stream URL)."""

    def __init__(self, cap: cv2.VideoCapture, name: str, kind: str, fps: float | None) -> None:
        self.kind = kind
        self._cap = cap
        ok, first = cap.read()
        if not ok or first is None:
            cap.release()
            if kind == "file":
                raise InputError(f"video file {name} has no frames (empty or undecodable)")
            raise InputError(f"{kind} {name} delivered no frames")
        self._first: Frame | None = _as_bgr(first, name)
        reported = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        fps_ok = math.isfinite(reported) and 0.0 < reported <= 1000.0
        n = cap.get(cv2.CAP_PROP_FRAME_COUNT)
        count = int(n) if kind == "file" and math.isfinite(n) and n > 0 else None
        super().__init__(
            name,
            fps if fps is not None else (reported if fps_ok else DEFAULT_FPS),
            fps is None and fps_ok,
            (int(first.shape[1]), int(first.shape[0])),
            count,
        )

    def _frames(self) -> Iterator[Frame]:
        first, self._first = self._first, None
        if first is not None:
            yield first
        while not self._closed:
            ok, frame = self._cap.read()
            if not ok or frame is None:
                if self.kind in ("camera", "stream"):
                    # A live source has no natural end: a failed read means it dropped.
                    self._fail("the source stopped delivering frames")
                elif self.frame_count is not None and self.frames_read < self.frame_count:
                    self._fail(
                        f"could not decode frame {self.frames_read} of "
                        f"{self.frame_count} (truncated or corrupt file)"
                    )
                return
            yield _as_bgr(frame, self.name)

    def close(self) -> None:
        super().close()
        self._first = None
        self._cap.release()


class FolderSource(FrameSource):
    """Frames from the image files of a folder, in sorted file-name order."""

    kind = "folder"

    def __init__(self, folder: Path, fps: float | None) -> None:
        self._files = sorted(
            (p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_EXTENSIONS),
            key=lambda p: p.name,
        )
        if not self._files:
            raise InputError(
                f"image folder {folder} contains no image files ({', '.join(IMAGE_EXTENSIONS)})"
            )
        first = read_image(self._files[0])
        if first is None:
            raise InputError(f"cannot read image {self._files[0]} (not an image or corrupt)")
        self._first: Frame | None = first
        super().__init__(
            str(folder),
            DEFAULT_FPS if fps is None else fps,
            False,
            (int(first.shape[1]), int(first.shape[0])),
            len(self._files),
        )

    def _frames(self) -> Iterator[Frame]:
        first, self._first = self._first, None
        if first is not None:
            yield first
        for path in self._files[1:]:
            frame = read_image(path)
            if frame is None:
                self._fail(f"cannot read image {path.name}")
                return
            yield frame

    def close(self) -> None:
        super().close()
        self._first = None


def _capture(src: str, threads: int | None) -> cv2.VideoCapture:
    """``cv2.VideoCapture(src)``, with ``threads`` decoder threads if the backend takes them."""
    if threads is not None:
        cap = cv2.VideoCapture(src, cv2.CAP_ANY, [cv2.CAP_PROP_N_THREADS, threads])
        if cap.isOpened():
            return cap
        cap.release()  # a backend without the property: open it plainly
    return cv2.VideoCapture(src)


def source_kind(src: str | Path | int) -> str:
    """What :func:`open_source` opens ``src`` as: ``"camera"`` (an ``int`` or an integer
    string), ``"stream"`` (a URL such as ``rtsp://…``) or ``"file"`` (a video file or an
    image folder, the only kind that gives the same frames when opened again)."""
    if isinstance(src, int) or (isinstance(src, str) and src.strip().isdigit()):
        return "camera"
    return "stream" if isinstance(src, str) and _URL.match(src) else "file"


def open_source(
    src: str | Path | int, *, fps: float | None = None, threads: int | None = None
) -> FrameSource:
    """Open a video file, an image folder, a camera or a stream URL.

    Parameters
    ----------
    src : str, Path or int
        A video file path; a folder of images (read in sorted file-name order, see
        :data:`IMAGE_EXTENSIONS`); a camera index (an ``int`` or an integer string such as
        ``"0"``); or a stream URL (``rtsp://``, ``http://``, ...).
    fps : float, optional
        Frame rate to use instead of the one reported by the source. Folders report none and
        default to :data:`DEFAULT_FPS`.
    threads : int, optional
        Decoder threads for files and streams (``cv2.CAP_PROP_N_THREADS``, honoured by the
        FFmpeg backend); default: OpenCV's choice, which is several on a multi-core machine.
        One thread costs the least CPU time per frame (what the benchmarks measure).

    Returns
    -------
    FrameSource
        Iterable of ``(index, frame)`` with ``fps``, ``size`` (W, H), ``frame_count``; a context
        manager that releases the capture.

    Raises
    ------
    InputError
        The path does not exist, OpenCV cannot open or decode it, or it holds no frames.
    ValueError
        ``fps`` is not positive, or ``threads`` is less than 1.
    """
    if fps is not None and not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"open_source: fps must be positive, got {fps}")
    if threads is not None and threads < 1:
        raise ValueError(f"open_source: threads must be at least 1, got {threads}")
    if isinstance(src, bool):
        raise InputError(f"video source must be a path, camera index or URL, got {src!r}")
    kind = source_kind(src)
    if kind == "camera":
        index = int(src)
        cap = cv2.VideoCapture(index)
        if not cap.isOpened():
            cap.release()
            raise InputError(f"cannot open camera {index} (no such device or it is busy)")
        return CaptureSource(cap, str(index), "camera", fps)
    if kind == "stream":
        cap = _capture(str(src), threads)
        if not cap.isOpened():
            cap.release()
            raise InputError(f"cannot open stream {src} (unreachable or unsupported)")
        return CaptureSource(cap, src, "stream", fps)
    path = Path(src).expanduser()
    if not path.exists():
        raise InputError(f"video source {path} does not exist")
    if path.is_dir():
        return FolderSource(path, fps)
    try:
        with path.open("rb") as fh:
            fh.read(1)
    except OSError as exc:
        raise InputError(f"cannot read video file {path}: {exc.strerror or exc}") from exc
    cap = _capture(str(path), threads)
    if not cap.isOpened():
        cap.release()
        raise InputError(
            f"cannot read video file {path}: OpenCV could not open it "
            "(not a video, or an unsupported codec)"
        )
    return CaptureSource(cap, str(path), "file", fps)
