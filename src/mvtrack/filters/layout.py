"""Component-first layout of batches of small filters, shared by the fast kernels.

A batch of ``B`` filters is held component-first: the state as an array ``(n, B)``, the
symmetric covariance packed as its upper triangle ``(n(n+1)/2, B)`` (:func:`packed_index`).
Every scalar of a closed-form filter equation is then one contiguous vector of length B.
Large batches are processed in chunks of :data:`CHUNK` filters (:func:`chunked`) so the
temporaries stay in cache; every filter is independent, so the results do not depend on it.

The predictors keep their per-track states in this layout too (:func:`to_components`,
:func:`from_components`, :func:`axes_flat`: x and y of ``N`` tracks as ``2N`` filters).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray

__all__ = [
    "CHUNK",
    "axes_flat",
    "chunked",
    "diag2",
    "finite",
    "from_components",
    "lincomb",
    "pack",
    "packed_index",
    "to_components",
    "unpack",
]

#: filters per chunk (keeps about 20 temporaries of CHUNK doubles in the L2/L3 cache)
CHUNK = 16384


def packed_index(n: int) -> np.ndarray:
    """``idx[i, j]``: row of component ``P_ij`` in the packed upper triangle (symmetric)."""
    idx = np.zeros((n, n), dtype=np.intp)
    k = 0
    for i in range(n):
        for j in range(i, n):
            idx[i, j] = idx[j, i] = k
            k += 1
    return idx


def pack(P: FloatArray) -> FloatArray:
    """Full symmetric matrices ``(…, n, n)`` -> packed upper triangles ``(…, n(n+1)/2)``."""
    n = P.shape[-1]
    iu = np.triu_indices(n)
    return P[..., iu[0], iu[1]]


def unpack(p: FloatArray, n: int) -> FloatArray:
    """Packed upper triangles ``(…, n(n+1)/2)`` -> full symmetric matrices ``(…, n, n)``."""
    return p[..., packed_index(n)]


def chunked(fn: Callable[..., None], arrays: list[np.ndarray], B: int, n_scratch: int) -> None:
    """Call ``fn(scratch, *slices)`` on column slices ``[s:s+CHUNK]`` of every array.

    ``scratch`` is a list of ``n_scratch`` float vectors of the chunk's length, reused across
    chunks (no allocation per chunk).
    """
    size = min(B, CHUNK)
    buf = np.empty((n_scratch, size), dtype=arrays[0].dtype)
    for s in range(0, B, CHUNK):
        e = min(s + CHUNK, B)
        scratch = [row[: e - s] for row in buf]
        fn(scratch, *[a[..., s:e] for a in arrays])


def finite(a: np.ndarray) -> BoolArray:
    """``np.isfinite`` for float arrays; all true for object arrays (counting numbers)."""
    if a.dtype == object:
        return np.ones(a.shape, dtype=bool)
    return np.isfinite(a)


def lincomb(terms: list[tuple[float, FloatArray]], out: FloatArray, tmp: FloatArray) -> None:
    """``out[:] = Σ c·a`` over ``terms`` (zero coefficients already dropped; none empty)."""
    c0, a0 = terms[0]
    rest = terms[1:]
    if c0 == 1.0 and rest and rest[0][0] == 1.0:
        np.add(a0, rest[0][1], out=out)
        rest = rest[1:]
    elif c0 == 1.0 and rest:
        np.multiply(rest[0][1], rest[0][0], out=out)
        out += a0
        rest = rest[1:]
    elif c0 == 1.0:
        np.copyto(out, a0)
    else:
        np.multiply(a0, c0, out=out)
    for c, a in rest:
        if c == 1.0:
            out += a
        else:
            np.multiply(a, c, out=tmp)
            out += tmp


def diag2(a: FloatArray) -> FloatArray:
    """(N, 2) -> (N, 2, 2) diagonal matrices."""
    out = np.zeros((a.shape[0], 2, 2))
    out[:, 0, 0] = a[:, 0]
    out[:, 1, 1] = a[:, 1]
    return out


def to_components(a: FloatArray) -> FloatArray:
    """Logical (N, 2, K) -> component-first buffer (K, 2N); no copy if already laid out so."""
    N, _, K = a.shape
    return np.ascontiguousarray(np.transpose(a, (2, 1, 0))).reshape(K, 2 * N)


def from_components(buf: FloatArray, N: int) -> FloatArray:
    """Component-first buffer (K, 2N) -> logical (N, 2, K) view (memory stays component-first)."""
    return np.transpose(buf.reshape(buf.shape[0], 2, N), (2, 1, 0))


def axes_flat(a: FloatArray) -> FloatArray:
    """(N, 2) -> (2N,) with all x values first, then all y values (the component order)."""
    return np.ascontiguousarray(a.T).reshape(-1)
