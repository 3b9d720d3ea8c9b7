"""Generic helpers for dataclasses whose array fields share a leading batch dimension.

Predictor states (:mod:`mvtrack.filters.predictors`) are such dataclasses; the tracker keeps
one per predictor and grows or shrinks it with :func:`take` and :func:`concat`.
"""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")


def _is_batched(value: Any) -> bool:
    return isinstance(value, np.ndarray) and value.ndim >= 1


def take(state: T, idx: np.ndarray) -> T:
    """Rows ``idx`` (int indices or a boolean mask) of every array field of ``state``."""
    changes = {
        f.name: getattr(state, f.name)[idx]
        for f in dataclasses.fields(state)  # type: ignore[arg-type]
        if _is_batched(getattr(state, f.name))
    }
    return dataclasses.replace(state, **changes)  # type: ignore[type-var]


def concat(a: T, b: T) -> T:
    """Rows of ``a`` followed by rows of ``b``; non-array fields are taken from ``a``."""
    changes = {
        f.name: np.concatenate([getattr(a, f.name), getattr(b, f.name)])
        for f in dataclasses.fields(a)  # type: ignore[arg-type]
        if _is_batched(getattr(a, f.name))
    }
    return dataclasses.replace(a, **changes)  # type: ignore[type-var]


def batch_size(state: Any) -> int:
    """Length of the leading dimension of the first array field."""
    for f in dataclasses.fields(state):
        value = getattr(state, f.name)
        if _is_batched(value):
            return int(value.shape[0])
    return 0
