"""Compiled kernels written once: :func:`kernel` compiles a plain function with numba.

The per-frame kernels of the tracker (the filters of :mod:`mvtrack.filters.cv` and
:mod:`mvtrack.filters.imm`, the assignment of :mod:`mvtrack.association.assign`, the life
cycle of :mod:`mvtrack.tracking.lifecycle` and the frame step that composes them,
:mod:`mvtrack.tracking.step`) are plain Python functions over NumPy arrays, in the subset of
Python that numba compiles. :func:`kernel` compiles each one and keeps the plain function as
``fn.py_func``: the fallback where numba is not installed (or ``MVTRACK_NO_JIT=1``), and the
oracle the tests compare the compiled code with. There is no second implementation to keep
equal.

The compiled code is cached on disk, so a process after the first loads it in milliseconds.
numba keys its cache on each kernel's own source file only, while a kernel may call kernels of
other modules; so the cache lives in a folder named after a hash of every kernel module
(:data:`KERNEL_MODULES`): editing any of them moves the cache to a new folder, and nothing
needs deleting by hand. ``NUMBA_CACHE_DIR``, when set, is used as it is.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

try:
    import numba
    from numba.core import config as _numba_config
except ImportError:  # pragma: no cover - exercised only where numba is missing
    numba = None

#: whether numba compiles the kernels (``MVTRACK_NO_JIT=1`` runs the plain functions)
COMPILED = numba is not None and os.environ.get("MVTRACK_NO_JIT", "") in ("", "0")

#: the modules that define kernels (paths inside the package), hashed into the cache folder
KERNEL_MODULES = (
    "jit.py",
    "filters/cv.py",
    "filters/imm.py",
    "association/pairs.py",
    "association/assign.py",
    "association/shared.py",
    "tracking/lifecycle.py",
    "tracking/step.py",
    "detection/background.py",
    "detection/colourbg.py",
    "detection/ghosts.py",
    "detection/wings.py",
    "detection/ncc.py",
    "detection/splitmerge.py",
    "detection/claims.py",
    "detection/kinds.py",
    "detection/labelling.py",
    "video/relink.py",
    "video/stopped.py",
)

__all__ = [
    "COMPILED", "KERNEL_MODULES", "cache_dir", "compiled_here", "kernel", "on_first_compile",
    "python_call",
]

_PACKAGE = Path(__file__).resolve().parent
_cache: str | None = None
_kernels: set[int] = set()  # id() of every dispatcher made by kernel()
_notify: Callable[[], None] | None = None  # on_first_compile's callback, until it is called
_listening = False  # whether on_first_compile's listener is registered
_compiled = False  # whether a kernel was compiled in this process (seen by the listener)


def cache_dir() -> str | None:
    """The folder of the compiled kernels: ``$NUMBA_CACHE_DIR`` if set, else
    ``$XDG_CACHE_HOME/mvtrack/numba-<hash of the kernel modules>`` (``~/.cache`` by default);
    None when it cannot be created (the kernels are then compiled in every process)."""
    global _cache
    if _cache is None:
        digest = hashlib.sha1()
        for name in KERNEL_MODULES:
            digest.update((_PACKAGE / name).read_bytes())
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "mvtrack"
        path = base / f"numba-{digest.hexdigest()[:16]}"
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError:
            _cache = ""
        else:
            _cache = str(path)
    return _cache or None


def kernel(fn: F) -> F:
    """``fn`` compiled in nopython mode with an on-disk cache (:func:`cache_dir`); ``fn``
    itself without numba. Either way the result has ``py_func``, the plain function."""
    if not COMPILED:
        fn.py_func = fn  # type: ignore[attr-defined]
        return fn
    if os.environ.get("NUMBA_CACHE_DIR"):
        compiled = numba.njit(cache=True)(fn)
    elif (folder := cache_dir()) is None:
        compiled = numba.njit(fn)
    else:
        saved = _numba_config.CACHE_DIR
        _numba_config.CACHE_DIR = folder  # read once, when the cache of fn is set up
        try:
            compiled = numba.njit(cache=True)(fn)
        finally:
            _numba_config.CACHE_DIR = saved
    _kernels.add(id(compiled))
    return compiled  # type: ignore[no-any-return]


def on_first_compile(notify: Callable[[], None]) -> None:
    """Call ``notify()`` once, when numba starts to compile a kernel that its cache does not
    hold: the first run after an install or an upgrade, which spends about half a minute
    compiling before its first frame. Loading a kernel from the cache calls nothing. A later
    call replaces a ``notify`` not yet called."""
    global _notify, _listening
    if numba is None:
        return
    if not _listening:
        _listen()
        _listening = True
    _notify = notify


def compiled_here() -> bool:
    """Whether a kernel was compiled in this process since :func:`on_first_compile` was
    first called: a speed measured over such a run includes the compilation."""
    return _compiled


def _listen() -> None:
    """Register the listener of numba's compile events that :func:`on_first_compile` uses."""
    from numba.core import event

    class _FirstCompile(event.Listener):  # type: ignore[misc]
        def on_start(self, ev: event.Event) -> None:
            global _notify, _compiled
            if id(ev.data["dispatcher"]) not in _kernels:
                return
            _compiled = True
            if _notify is not None:
                notify, _notify = _notify, None
                notify()

        def on_end(self, ev: event.Event) -> None:
            pass

    event.register("numba:compile", _FirstCompile())


@contextlib.contextmanager
def _no_objmode(**_types: Any) -> Iterator[None]:
    yield


#: ``with python_call(out='intp[:]'):`` runs its block in the interpreter from compiled code
#: (numba's ``objmode``: for a call into SciPy); in the plain function it does nothing
python_call: Callable[..., Any] = _no_objmode if numba is None else numba.objmode
