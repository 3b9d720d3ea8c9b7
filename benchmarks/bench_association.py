"""Time gating + assignment per frame for crowd-like scenes of N = M = 10 ... 10 000 targets.

Scene: N targets uniform in a 1920×1080 plane with 40×30 px boxes (±10 %); predicted positions
off the truth by N(0, 1.5²) px per axis; detections at the truth plus N(0, 2²) px, 10 % missed,
Poisson(3) false alarms, rows shuffled. P̄ = 2.25 I, S = P̄ + 4 I (R = σ² = 4 px²), velocities
random 1–6 px/frame. For each distance (its default gate, :func:`mvtrack.association.
resolve_gate`) and rule: the gate (``Gate.build(distance, view, gate).pairs(dxy, dwh)``) and
the assignment of its pairs (:func:`mvtrack.association.assign`, the tracker's cost ``u`` of
an unmatched pair: the gate), and the tracker's whole association of a frame in one compiled
call (:func:`mvtrack.association.assign.associate`: the default gate with its size term,
every detection in the first stage), and the same call with the ``iou`` gate (its pairs found
among overlapping boxes). Prints the median over repeats in ms per frame, and (with ``--md``)
writes the Markdown table; ``--previous`` puts the totals of an earlier run's table (the
Markdown this script wrote, for example before a change) beside today's, with their ratios.

    python benchmarks/bench_association.py [--sizes 10 100 1000 10000]
        [--md docs/bench/association.md] [--previous old.md]
"""

from __future__ import annotations

import argparse
import itertools
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from mvtrack.association import Gate, TrackView, assign, resolve_gate
from mvtrack.association.assign import HIGH, NO_STAND, RULE_CODES, associate
from mvtrack.types import Detections

#: the tracker's size term: w_s = 1 / size_noise², size_noise 0.25 (docs/settings.md)
SIZE_W = 1.0 / 0.25**2

CASES = [  # (distance, distance parameters, assignment rule, size term weight)
    ("euclidean", {}, "nearest", 0.0),
    ("euclidean", {}, "greedy", 0.0),
    ("euclidean", {}, "optimal", 0.0),
    ("mahalanobis", {}, "optimal", 0.0),
    ("mahalanobis", {}, "optimal", SIZE_W),
    ("coupled", {"use_innovation": True}, "optimal", 0.0),
    ("iou", {}, "optimal", 0.0),
]


def crowd_frame(n: int, rng: np.random.Generator) -> tuple[TrackView, Detections]:
    """One frame of the crowd scene: the predicted tracks and the shuffled detections."""
    size = np.array([1920.0, 1080.0])
    truth = rng.uniform(0, 1, (n, 2)) * size
    wh = np.array([40.0, 30.0]) * rng.uniform(0.9, 1.1, (n, 2))
    speed = rng.uniform(1, 6, n)
    ang = rng.uniform(0, 2 * np.pi, n)
    vel = np.stack([speed * np.cos(ang), speed * np.sin(ang)], axis=1)
    pred = truth + rng.normal(0, 1.5, (n, 2))
    cov = np.broadcast_to(2.25 * np.eye(2), (n, 2, 2)).copy()
    view = TrackView(pred, cov, cov + 4.0 * np.eye(2), vel, wh)
    seen = rng.random(n) >= 0.1
    z = truth[seen] + rng.normal(0, 2, (int(seen.sum()), 2))
    zwh = wh[seen] + rng.normal(0, 1, (int(seen.sum()), 2))
    k = rng.poisson(3)
    z = np.vstack([z, rng.uniform(0, 1, (k, 2)) * size])
    zwh = np.vstack([zwh, np.tile([40.0, 30.0], (k, 1))])
    perm = rng.permutation(z.shape[0])
    return view, Detections(0, z[perm], zwh[perm])


def _median_ms(
    repeats: int, fn: Callable[..., Any], *args: Any, **kwargs: Any
) -> tuple[float, float]:
    """Median CPU time of this process and median wall time of ``fn(*args)``, in ms.

    On a shared machine the wall time includes waiting for a core; the process CPU time
    (``time.process_time``) is the steadier figure of the work done.
    """
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        fn(*args, **kwargs)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return 1e3 * float(np.median(cpu)), 1e3 * float(np.median(wall))


def _largest(ti: np.ndarray, dj: np.ndarray, n: int, m: int) -> int:
    """Tracks + detections in the largest connected component of the gate graph."""
    if ti.size == 0:
        return 0
    g = coo_matrix((np.ones(ti.size), (ti, n + dj)), shape=(n + m, n + m))
    _, labels = connected_components(g, directed=False)
    used = np.zeros(n + m, dtype=bool)
    used[ti] = True
    used[n + dj] = True
    return int(np.bincount(labels[used]).max())


def _row(n: int, m: int, dist: str, rule: str, ti: np.ndarray, dj: np.ndarray, matched: int,
         t_gate: float, t_assign: float, wall: float, total: float | None = None) -> tuple:
    """One row of the table (printed as it is made)."""
    total = t_gate + t_assign if total is None else total
    row = (n, m, dist, rule, int(ti.size), _largest(ti, dj, n, m), matched, t_gate,
           t_assign, total, wall)
    print(
        "N={:>6} M={:>6} {:<24} {:<20} pairs={:>7} largest cluster={:>6} matched={:>6} "
        "gate {:8.3f} ms  assign {:8.3f} ms  total {:8.3f} ms (wall {:8.3f} ms)".format(*row),
        flush=True,
    )
    return row


def _ms(x: float) -> str:
    return "–" if not np.isfinite(x) else f"{x:.3f}"


def _growth(rows: list[tuple]) -> list[str]:
    """Markdown lines: how the total time of each case grows per 10× N."""
    by_case: dict[tuple[str, str], dict[int, float]] = {}
    pairs: dict[tuple[str, str], dict[int, int]] = {}
    for n, _m, dist, rule, p, _big, _k, _g, _a, total, _w in rows:
        by_case.setdefault((dist, rule), {})[n] = total
        pairs.setdefault((dist, rule), {})[n] = p
    out = [
        "",
        "Growth of the total CPU time per 10× N (×10 per decade is linear in N; the gated",
        "pairs in brackets show how crowded the gate graph gets):",
        "",
    ]
    for (dist, rule), t in by_case.items():
        ns = sorted(t)
        steps = [
            f"{a}→{b}: ×{t[b] / t[a]:.1f} ({pairs[dist, rule][b]} pairs)"
            for a, b in itertools.pairwise(ns)
        ]
        out.append(f"- {dist}, {rule}: " + "; ".join(steps))
    return out


def _ratio(was: float, now: float) -> str:
    if not (np.isfinite(was) and np.isfinite(now)) or now <= 0:
        return "–"
    return f"×{was / now:,.1f}" if was / now < 100 else f"×{was / now:,.0f}"


def _previous(path: Path) -> dict[tuple[int, str, str], tuple[float, float]]:
    """The gate and total ms of each (N, distance, rule) row of a table this script wrote."""
    out: dict[tuple[int, str, str], tuple[float, float]] = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 11 or not cells[0].isdigit():
            continue

        def num(text: str) -> float:
            return float("nan") if text in ("–", "") else float(text)

        out[int(cells[0]), cells[2], cells[3]] = (num(cells[7]), num(cells[9]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 10000])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--md", type=Path, default=None, help="write the Markdown table here")
    ap.add_argument("--previous", type=Path, default=None,
                    help="an earlier run's Markdown table: its gate and total times beside "
                    "today's, with the ratios")
    args = ap.parse_args()
    previous = _previous(args.previous) if args.previous is not None else {}

    rows = []
    for n in args.sizes:
        rng = np.random.default_rng(args.seed)
        view, dets = crowd_frame(n, rng)
        m = len(dets)
        for dist, params, rule, size_w in CASES:
            g = resolve_gate(dist)

            def gate_pairs(dist: str = dist, g: float = g, size_w: float = size_w,
                           params: dict[str, Any] = params, view: TrackView = view,
                           dets: Detections = dets) -> Any:
                return Gate.build(dist, view, g, size_weight=size_w, **params).pairs(
                    dets.xy, dets.wh)

            ti, dj, c = gate_pairs()  # also loads the compiled kernels before the clock
            t_gate, w_gate = _median_ms(args.repeats, gate_pairs)
            a = assign(ti, dj, c, n, m, rule, unmatched_cost=g)
            t_assign, w_assign = _median_ms(
                args.repeats, assign, ti, dj, c, n, m, rule, unmatched_cost=g
            )
            name = dist + (" + size term" if size_w else "")
            rows.append(_row(n, m, name, rule, ti, dj, len(a), t_gate, t_assign,
                             w_gate + w_assign))
        # the tracker's association of a frame: one compiled call (pairs and assignment),
        # with the default gate and with the iou gate (its pairs among overlapping boxes)
        dclass = np.full(m, HIGH, dtype=np.int8)
        for dist in ("mahalanobis", "iou"):
            g = resolve_gate(dist)
            gate = Gate.build(dist, view, g, size_weight=SIZE_W)
            call = (gate.view.xy, gate.cov, np.zeros((0, 0)), gate.view.wh,
                    np.ascontiguousarray(dets.xy), np.ascontiguousarray(dets.wh), dclass, g,
                    SIZE_W, RULE_CODES["optimal"], NO_STAND, gate.search)
            matched = int((associate(*call) >= 0).sum())
            t_frame, w_frame = _median_ms(args.repeats, associate, *call)
            ti, dj, _ = gate.pairs(dets.xy, dets.wh)
            rows.append(_row(n, m, f"{dist} + size term", "associate (one call)", ti, dj,
                             matched, float("nan"), float("nan"), w_frame, total=t_frame))
    if args.md is not None:
        from mvtrack.io.atomic import write_text

        lines = [
            "## Association: gating + assignment per frame",
            "",
            "Crowd-like frame (see `benchmarks/bench_association.py`): N targets in 1920×1080,",
            "40×30 px boxes, detections σ = 2 px, 10 % missed, Poisson(3) clutter, shuffled.",
            f"Median of {args.repeats} repeats, ms per frame: CPU time of the process "
            "(`time.process_time`) for gate, assign and total, and the wall-clock total. "
            f"Measured on a shared 2-core machine ({platform.processor() or platform.machine()}, "
            f"Python {platform.python_version()}) while other jobs ran (load average "
            f"{os.getloadavg()[0]:.1f}), so wall times include waiting for a core and all "
            "figures are indicative.",
            "",
            "Command: `python benchmarks/bench_association.py --sizes "
            + " ".join(str(n) for n in args.sizes) + f" --repeats {args.repeats} --md {args.md}"
            + (f" --previous {args.previous}`" if previous else "`"),
            "",
            "| N | M | distance | rule | gated pairs | largest cluster | matched | gate ms "
            "| assign ms | total ms | wall total ms |"
            + (" previous gate / total ms | previous / today, gate / total |" if previous
               else ""),
            "|---|---|---|---|---|---|---|---|---|---|---|" + ("---|---|" if previous else ""),
        ]
        for r in rows:
            cells = [str(x) for x in r[:7]] + [_ms(x) for x in r[7:]]
            if previous:
                was = previous.get((r[0], r[2], r[3]))
                cells += ["–", "–"] if was is None else [
                    f"{_ms(was[0])} / {_ms(was[1])}",
                    f"{_ratio(was[0], r[7])} / {_ratio(was[1], r[9])}"]
            lines.append("| " + " | ".join(cells) + " |")
        lines += [
            "",
            "*associate (one call)*: the tracker's association of a frame, pairs and assignment",
            "in one compiled call (`mvtrack.association.assign.associate`), as `Tracker.step`",
            "runs it with the default gate; the other rows time `Gate.build(...).pairs` and",
            "`assign` apart, from Python. `largest cluster` is the number of tracks +",
            "detections in the biggest connected component of the gate graph: the optimal",
            "assignment solves a component of at most 4 tracks and 4 detections by enumeration",
            "and a larger one with SciPy, so its time grows with the clusters. The quadratic",
            "gates (euclidean, mahalanobis, coupled) find their pairs through a grid of",
            "detection cells (`mvtrack.association.pairs`), so their time grows with the pairs;",
            "`iou` finds its pairs among the boxes that overlap (a grid of cells the size of",
            "the median box, `pairs.overlap_pairs`), so its time grows with the pairs too",
            "(`coupled-literal`, not timed here, is a dense N × M matrix, `Gate.dense`).",
            "`euclidean` here is the pixel gate of 100 px² (10 px; `resolve_gate`), as the",
            "`paper1` preset's 20 px circle: the tracker's Euclidean gate without a gate is in",
            "box sizes (`docs/association.md`), the same search.",
        ]
        if previous:
            lines += [
                "",
                f"*previous*: the gate and total CPU times of `{args.previous}`, an earlier run",
                "of this script on the same scenes (same seed); *previous / today*: how many",
                "times faster today's is (below 1: slower).",
            ]
        lines += _growth(rows)
        write_text(args.md, "\n".join(lines) + "\n")
        print(f"wrote {args.md}")


if __name__ == "__main__":
    main()
