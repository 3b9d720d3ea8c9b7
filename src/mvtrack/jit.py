"""Compiled kernels written once: :func:`kernel` compiles a plain function with numba.

The per-frame kernels of the tracker (the closed-form filter of :mod:`mvtrack.filters.cv`,
the staged assignment of :mod:`mvtrack.association.assign`, the life cycle of
:mod:`mvtrack.tracking.lifecycle`) are plain Python functions over NumPy arrays, in the
subset of Python that numba compiles. :func:`kernel` compiles each one (cached on disk, so a
process after the first loads it in milliseconds) and keeps the plain function as
``fn.py_func``: the fallback where numba is not installed, and the oracle the tests compare
the compiled code with. There is no second implementation to keep equal.

numba's on-disk cache is keyed on the source file of each kernel. A kernel therefore reads
only its own module's globals and calls only kernels of its own module; kernels of different
modules meet in Python (:meth:`mvtrack.tracking.Tracker.step`), so editing any file
invalidates exactly the cached kernels it holds and nothing needs deleting by hand.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

try:
    import numba
except ImportError:  # pragma: no cover - exercised only where numba is missing
    numba = None

#: whether numba compiles the kernels (``MVTRACK_NO_JIT=1`` runs the plain functions)
COMPILED = numba is not None and os.environ.get("MVTRACK_NO_JIT", "") in ("", "0")

__all__ = ["COMPILED", "kernel", "python_call"]


def kernel(fn: F) -> F:
    """``fn`` compiled in nopython mode with an on-disk cache; ``fn`` itself without numba.

    Either way the result has ``py_func``, the plain function.
    """
    if not COMPILED:
        fn.py_func = fn  # type: ignore[attr-defined]
        return fn
    return numba.njit(cache=True)(fn)  # type: ignore[no-any-return]


@contextlib.contextmanager
def _no_objmode(**_types: Any) -> Iterator[None]:
    yield


#: ``with python_call(out='intp[:]'):`` runs its block in the interpreter from compiled code
#: (numba's ``objmode``: for a call into SciPy); in the plain function it does nothing
python_call: Callable[..., Any] = _no_objmode if numba is None else numba.objmode
