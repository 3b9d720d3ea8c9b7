"""SIGTERM handled like SIGINT: what ``timeout``, ``docker stop``, systemd and batch schedulers
send ends a command the way Ctrl-C does, with exit status 143 instead of 130.

Python's default for SIGTERM is to die at once, with no ``finally`` blocks run: no results
file, no summary, a hidden temporary MP4 left in the output folder. Inside
:func:`sigterm_as_interrupt` the first SIGTERM raises :class:`Terminated` (a
``KeyboardInterrupt``) in the main thread instead, so every place that keeps what was done on
Ctrl-C (the frame loop of ``mvtrack track``, the batch client) keeps it on SIGTERM too. Later
SIGTERMs are ignored while those files are written.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType
from typing import Any

#: exit status of a command ended by SIGTERM (128 + 15, as a shell reports it)
EXIT_TERMINATED = 128 + signal.SIGTERM
#: exit status of a command ended by SIGINT (Ctrl-C)
EXIT_INTERRUPTED = 128 + signal.SIGINT


class Terminated(KeyboardInterrupt):
    """Raised in the main thread by the first SIGTERM inside :func:`sigterm_as_interrupt`."""


_received = threading.Event()
_reported = threading.Event()


def reported() -> None:
    """Say that the command printed its own ``error: interrupted ...`` line."""
    _reported.set()


def was_reported() -> bool:
    """Whether the command printed its own line (:func:`reported`) in this block."""
    return _reported.is_set()


def terminated() -> bool:
    """Whether a SIGTERM arrived inside the current :func:`sigterm_as_interrupt` block."""
    return _received.is_set()


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    if _received.is_set():
        return  # the files of the first one are being written
    _received.set()
    raise Terminated


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Inside the block, SIGTERM raises :class:`Terminated` like Ctrl-C raises
    ``KeyboardInterrupt`` (main thread only; elsewhere the block changes nothing)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _received.clear()
    _reported.clear()
    old = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def interrupt_status() -> int:
    """143 after a SIGTERM, else 130."""
    return EXIT_TERMINATED if terminated() else EXIT_INTERRUPTED


def interrupt_word() -> str:
    """``terminated`` after a SIGTERM, else ``interrupted``."""
    return "terminated" if terminated() else "interrupted"


class Deferred:
    """What :func:`deferred` hands out: whether a signal asked the loop to stop."""

    def __init__(self) -> None:
        self.signum: int | None = None

    @property
    def requested(self) -> bool:
        """A SIGINT or SIGTERM arrived."""
        return self.signum is not None

    def until(self, items: Iterator[Any] | Any) -> Iterator[Any]:
        """``items`` one by one, until a signal arrives (checked before each item)."""
        for item in items:
            if self.requested:
                return
            yield item


@contextlib.contextmanager
def deferred() -> Iterator[Deferred]:
    """Inside the block, SIGINT and SIGTERM only ask the loop to stop (:meth:`Deferred.until`)
    between two items, so a run over frames ends at a frame boundary with what it did, and its
    results are written whole (main thread only; elsewhere the block changes nothing)."""
    stop = Deferred()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def on_signal(signum: int, frame: FrameType | None) -> None:
        if signum == signal.SIGTERM:
            _received.set()
        if stop.signum is None:
            stop.signum = signum

    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
