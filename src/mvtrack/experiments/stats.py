"""Counting statistics of the experiments: rates with binomial confidence intervals, and the
exact paired test for two methods run on the same seeds."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.stats import binomtest


def binomial_ci(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion ``k / n`` (``(nan, nan)`` when n = 0).

    .. math::

        \\frac{\\hat p + \\frac{z^2}{2n} \\pm z \\sqrt{\\frac{\\hat p (1 - \\hat p)}{n}
        + \\frac{z^2}{4n^2}}}{1 + \\frac{z^2}{n}}
    """
    k, n = int(k), int(n)
    if n == 0:
        return float("nan"), float("nan")
    if not 0 <= k <= n:
        raise ValueError(f"need 0 <= k <= n, got k = {k}, n = {n}")
    ci = binomtest(k, n).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


def rate(k: int, n: int) -> dict[str, Any]:
    """``{"k", "n", "rate", "ci95"}`` of ``k`` successes in ``n`` trials (JSON-ready)."""
    lo, hi = binomial_ci(k, n)
    return {"k": int(k), "n": int(n), "rate": float(k / n) if n else float("nan"),
            "ci95": [lo, hi]}


def rate_of(flags: NDArray[np.bool_] | list[bool]) -> dict[str, Any]:
    """:func:`rate` of a boolean outcome per trial."""
    f = np.asarray(flags, dtype=bool)
    return rate(int(f.sum()), int(f.size))


def paired(a: NDArray[np.bool_] | list[bool], b: NDArray[np.bool_] | list[bool]) -> dict[str, Any]:
    """Two methods' outcomes on the same trials: discordant counts and the exact McNemar test.

    Returns ``{"only_a", "only_b", "p"}``: trials where only ``a`` (only ``b``) is True, and the
    two-sided binomial p-value of the discordant split (1 when there is none).
    """
    a, b = np.asarray(a, bool), np.asarray(b, bool)
    if a.shape != b.shape:
        raise ValueError(f"outcomes differ in shape: {a.shape} vs {b.shape}")
    only_a, only_b = int((a & ~b).sum()), int((b & ~a).sum())
    p = binomtest(only_a, only_a + only_b).pvalue if only_a + only_b else 1.0
    return {"only_a": only_a, "only_b": only_b, "p": float(p)}


def fmt_rate(r: dict[str, Any]) -> str:
    """``"k/n (lo–hi %)"`` for a Markdown table."""
    lo, hi = r["ci95"]
    if r["n"] == 0:
        return "0/0"
    return f"{r['k']}/{r['n']} ({100 * lo:.0f}–{100 * hi:.0f} %)"
