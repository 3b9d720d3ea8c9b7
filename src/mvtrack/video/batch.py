"""Many videos in parallel: one ``mvtrack track`` run per video, spread over Dask workers.

.. code-block:: text

    videos ─▶ client.map(track_one, ...)   one task per video, pure=False
           ─▶ worker: open_source ─▶ resolve_settings ─▶ track_to_folder   (as ``mvtrack track``)
           ─▶ as_completed ─▶ BatchItem per video ─▶ out_root/batch.json

:func:`track_many` runs every video through the same code path as ``mvtrack track``
(:func:`~mvtrack.video.jobs.track_one`), each into its own folder ``out_root/<video stem>/``,
so a batch gives the same ``results.txt`` as tracking the videos one after another. The work
runs on :mod:`distributed`:

- ``scheduler=None`` starts a private ``LocalCluster`` of ``workers`` processes with one thread
  each (no dashboard) and closes it at the end;
- ``scheduler="tcp://host:port"`` connects to a running Dask scheduler, whose workers may sit on
  other machines. Those workers must be able to import mvtrack and must see the video paths and
  the output folder under the same names (a shared file system); paths are made absolute before
  they are sent. See ``docs/batch.md``.

A video that fails (missing, unreadable, a bad frame mid-way) is recorded with its one-line
error and does not stop the others. ``out_root/batch.json`` (written atomically after every
finished video) lists per video its status, frames, tracks, processing speed, seconds and error.
Ctrl-C stops the videos being tracked (each writes the results of the frames it tracked),
cancels the others, closes the client and cluster and still writes ``batch.json``.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from mvtrack.config import RunSettings
from mvtrack.video.build import check_settings
from mvtrack.video.jobs import (
    STATUSES,
    BatchItem,
    finished_on_disk,
    normalise_video,
    one_line,
    output_names,
    remove_temp_files,
    track_one,
)

#: file name of the batch summary inside ``out_root``
SUMMARY_NAME = "batch.json"

_QUIET_LOGGERS = ("distributed", "tornado", "bokeh", "asyncio")


@contextlib.contextmanager
def _quiet_logs(level: int = logging.ERROR) -> Iterator[None]:
    """Raise the level of distributed's (and its libraries') loggers for the block."""
    import distributed  # noqa: F401  (its import sets up its loggers: adjust them afterwards)

    names = {n for n in logging.root.manager.loggerDict if n.startswith(_QUIET_LOGGERS)}
    loggers = [logging.getLogger(name) for name in sorted(names | set(_QUIET_LOGGERS))]
    saved = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(max(level, lg.level))
    try:
        yield
    finally:
        for lg, old in zip(loggers, saved, strict=True):
            lg.setLevel(old)


def _silence_interrupted_loop() -> None:
    """After Ctrl-C or SIGTERM: only critical messages from distributed's event loop.

    An interrupt that lands inside distributed's ``sync()`` before it has bound its future
    makes the cancel callback it scheduled fail on the loop thread (``NameError: cannot
    access free variable 'future'``, distributed 2026.8), and tornado logs that with its
    traceback. The batch has already stopped by then; the user should see one error line.
    Not undone: the loop thread may run the callback after the batch has returned.
    """
    for name in ("tornado.application", "distributed.utils"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _summary(
    items: list[BatchItem], *, workers: int | None, scheduler: str | None, seconds: float,
    settings: RunSettings, interrupted: bool,
) -> dict[str, Any]:
    counts = {s: sum(it.status == s for it in items) for s in STATUSES}
    return {
        "videos": [it.as_dict() for it in items],
        "total": len(items),
        **counts,
        "pending": sum(it.status == "pending" for it in items),
        "interrupted": interrupted,
        "workers": workers,
        "scheduler": scheduler,
        "seconds": round(seconds, 3),
        "settings": settings.as_dict(),
    }


def track_many(
    videos: Iterable[str | os.PathLike[str]],
    out_root: str | os.PathLike[str],
    settings: RunSettings | None = None,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    fps: float | None = None,
    max_frames: int | None = None,
    snapshot: Sequence[int] = (),
    progress: bool | None = None,
    on_result: Callable[[BatchItem], None] | None = None,
    timeout: float = 10.0,
    grace: float = 30.0,
) -> list[BatchItem]:
    """Track every video of ``videos`` in parallel, each into ``out_root/<video stem>/``.

    Parameters
    ----------
    videos : iterable of path or str
        Video files, image folders or stream URLs (anything ``mvtrack track`` opens).
    out_root : path
        Folder of the per-video folders (named by :func:`output_names`) and ``batch.json``.
    settings : RunSettings, optional
        The same settings for every video (default: ``RunSettings()``, as ``mvtrack track``).
    workers : int, optional
        Worker processes of the local cluster (default ``os.cpu_count()``, never more than
        the number of videos). Only for ``scheduler=None``.
    scheduler : str, optional
        Address of a running Dask scheduler (``"tcp://host:port"``). Its workers must import
        mvtrack and see the videos and ``out_root`` at the same paths (shared file system).
    fps : float, optional
        Frame rate to assume instead of each source's.
    max_frames : int, optional
        Track at most this many frames of each video.
    snapshot : sequence of int
        Frames of each video to save as annotated pictures (``frameNNNNN.png``). A video
        too short for one of them is ``failed`` with its tracks written, as ``mvtrack track``
        would exit.
    progress : bool, optional
        Force the progress bar over videos on or off (default: on when stderr is a terminal).
    on_result : callable, optional
        Called in this process with each finished :class:`BatchItem`, in completion order.
    timeout : float
        Seconds to wait for the connection to ``scheduler`` and, if it has none, for a
        worker to join it.
    grace : float
        After Ctrl-C, seconds to wait for the videos being tracked to stop and write what
        they tracked; those still running then are cancelled without results.

    Returns
    -------
    list of BatchItem
        In the order of ``videos``. Ctrl-C (``KeyboardInterrupt`` in this process) stops the
        videos being tracked, which write the results of the frames tracked so far, and
        cancels the others; both come back with ``status="cancelled"`` (``frames`` says how
        far each got); it is not re-raised.

    Raises
    ------
    ValueError
        No videos, ``workers`` < 1, ``workers`` together with ``scheduler``, or bad settings
        (checked before any worker starts).
    OSError
        The scheduler cannot be reached or has no workers, or ``out_root`` cannot be created.
    """
    settings = RunSettings() if settings is None else settings
    videos = list(videos)
    if not videos:
        raise ValueError("track_many: no videos given")
    if workers is not None and scheduler is not None:
        raise ValueError("workers applies to a local cluster only; do not give it with scheduler")
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    if max_frames is not None and max_frames < 1:
        raise ValueError(f"max_frames must be at least 1, got {max_frames}")
    check_settings(settings)

    from mvtrack.io.atomic import write_json

    root = Path(out_root).expanduser().absolute()
    if root.exists() and not root.is_dir():
        raise ValueError(f"out_root {root} is a file, not a folder")
    sources = [normalise_video(v) for v in videos]
    outs = [str(root / name) for name in output_names(sources)]
    items = [BatchItem(v, o, "pending") for v, o in zip(sources, outs, strict=True)]
    n_workers = min(workers or os.cpu_count() or 1, len(sources))
    summary_path = root / SUMMARY_NAME
    t0 = time.perf_counter()
    started = time.time()
    interrupted = False
    begun = False  # the cluster is up and out_root exists: batch.json is written from here on

    def save() -> None:
        write_json(summary_path, _summary(
            items, workers=n_workers, scheduler=scheduler,
            seconds=time.perf_counter() - t0, settings=settings, interrupted=interrupted,
        ))

    from tqdm import tqdm

    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=len(items), desc="videos", unit="video", file=sys.stderr, disable=not show,
               dynamic_ncols=True)
    try:
        with _quiet_logs(), contextlib.ExitStack() as stack:
            client = _connect(stack, scheduler, n_workers, timeout)
            from distributed import as_completed

            if scheduler is not None:
                n_workers = len(client.nthreads())  # the cluster's workers at the start

            root.mkdir(parents=True, exist_ok=True)
            begun = True
            save()
            from distributed import Event

            stop_name = f"mvtrack-batch-stop-{os.getpid()}-{time.time_ns()}"
            stop = Event(stop_name, client=client)
            futures = client.map(
                track_one, sources, outs, settings=settings, fps=fps, max_frames=max_frames,
                snapshot=tuple(snapshot),
                stop=stop_name, pure=False,
            )
            index = {f.key: i for i, f in enumerate(futures)}
            try:
                for future in as_completed(futures):
                    i = index[future.key]
                    try:
                        items[i] = BatchItem(**future.result())
                    except Exception as exc:  # the worker died, or the task could not run
                        items[i] = BatchItem(sources[i], outs[i], "failed", error=one_line(exc))
                    bar.update(1)
                    save()
                    if on_result is not None:
                        on_result(items[i])
            except KeyboardInterrupt:
                interrupted = True
                _silence_interrupted_loop()
                # the videos being tracked stop at their next frame and write what they
                # tracked; those not started return at once
                with contextlib.suppress(Exception):
                    stop.set()
                    from distributed import wait

                    wait([f for f in futures if not f.done()], timeout=grace)
                client.cancel([f for f in futures if not f.done()], force=True)
                for f in futures:  # keep what finished while we were interrupted
                    i = index[f.key]
                    if items[i].status == "pending" and f.status == "finished":
                        with contextlib.suppress(Exception):
                            items[i] = BatchItem(**f.result(timeout=1))
    except KeyboardInterrupt:  # while starting or closing the cluster
        interrupted = True
    finally:
        if interrupted:  # again: leaving _quiet_logs restored the levels
            _silence_interrupted_loop()
        bar.close()
        for i, it in enumerate(items):
            if it.status == "pending":
                items[i] = finished_on_disk(it, since=started) or BatchItem(
                    it.video, it.out, "cancelled", error="cancelled before it finished")
            if begun and items[i].status == "cancelled" and scheduler is None:
                remove_temp_files(Path(items[i].out))  # its worker was stopped mid-write
        if begun:
            save()
    return items


@contextlib.contextmanager
def _environ_kept() -> Iterator[None]:
    """Undo changes to ``os.environ`` made in the block.

    Dask's nanny sets its workers' variables (``OMP_NUM_THREADS=1``, ``PYTHONHASHSEED``, ...)
    in the environment of the process that starts them; they should not outlive the batch in
    the caller's process.
    """
    saved = dict(os.environ)
    try:
        yield
    finally:
        for key in set(os.environ) - set(saved):
            os.environ.pop(key, None)
        os.environ.update(saved)


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """Ignore SIGINT for the block (in the main thread; elsewhere do nothing).

    Processes started meanwhile keep SIGINT ignored (an ignored signal stays ignored across
    ``exec``), so Ctrl-C does not kill the local workers with a traceback each.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _connect(stack: contextlib.ExitStack, scheduler: str | None, n_workers: int,
             timeout: float) -> Any:
    """A ``distributed.Client`` on a new local cluster or on ``scheduler``; closed by ``stack``."""
    from distributed import Client, LocalCluster

    if scheduler is None:
        # Ctrl-C in a terminal reaches the whole process group; the worker processes inherit
        # an ignored SIGINT so that only this process handles it (and closes the cluster).
        # Dask sets MALLOC_TRIM_THRESHOLD_=65536 in its workers to hand memory back to the OS
        # sooner; it also turns off glibc's adaptive mmap threshold, so every frame-sized
        # array is mmap'ed, zeroed and unmapped again: 10-15 % more CPU per video here
        # (docs/bench/batch.md). A video's memory is freed when its task ends anyway.
        import dask

        with _sigint_ignored(), _environ_kept(), dask.config.set(
            {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
        ):
            cluster = stack.enter_context(LocalCluster(
                n_workers=n_workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                dashboard_address=None, silence_logs=logging.ERROR,
                # no dashboard; its health-check HTTP server on a free port, not on 8787
                scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
            ))
        return stack.enter_context(Client(cluster, timeout=timeout))
    try:
        client = Client(scheduler, timeout=timeout)
    except (OSError, TimeoutError) as exc:
        raise OSError(f"cannot connect to Dask scheduler {scheduler}: {one_line(exc)}") from None
    except ValueError as exc:
        raise ValueError(f"bad scheduler address {scheduler!r}: {one_line(exc)}") from None
    stack.enter_context(client)
    try:  # a cluster without workers would leave the batch waiting for ever
        client.wait_for_workers(1, timeout=timeout)
    except TimeoutError:
        raise OSError(
            f"Dask scheduler {scheduler} has no workers (none joined within {timeout:g} s; "
            f"start some with `dask worker {scheduler}`)"
        ) from None
    return client
