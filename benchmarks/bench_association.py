"""Time gating + assignment per frame for crowd-like scenes of N = M = 10 ... 10 000 targets.

Scene: N targets uniform in a 1920×1080 plane with 40×30 px boxes (±10 %); predicted positions
off the truth by N(0, 1.5²) px per axis; detections at the truth plus N(0, 2²) px, 10 % missed,
Poisson(3) false alarms, rows shuffled. P̄ = 2.25 I, S = P̄ + 4 I (R = σ² = 4 px²), velocities
random 1–6 px/frame. Prints the median over repeats of ``candidate_pairs`` and of ``assign`` per
distance and rule, in ms per frame, and (with ``--md``) writes the Markdown table.

    python benchmarks/bench_association.py [--sizes 10 100 1000 10000]
        [--md docs/bench/association.md]
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

from mvtrack.association import TrackView, assign, candidate_pairs
from mvtrack.association.optimal import _components
from mvtrack.types import Detections

CASES = [  # (distance, distance parameters, assignment rule, optimal solver); default gates
    ("euclidean", {}, "nearest", "auto"),
    ("euclidean", {}, "greedy", "auto"),
    ("euclidean", {}, "optimal", "auto"),
    ("euclidean", {}, "optimal", "dense"),
    ("euclidean", {}, "optimal", "sparse"),
    ("mahalanobis", {}, "optimal", "auto"),
    ("coupled", {"use_innovation": True}, "optimal", "auto"),
    ("iou", {}, "optimal", "auto"),
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 10000])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--md", type=Path, default=None, help="write the Markdown table here")
    args = ap.parse_args()

    rows = []
    for n in args.sizes:
        rng = np.random.default_rng(args.seed)
        view, dets = crowd_frame(n, rng)
        m = len(dets)
        for dist, params, rule, solver in CASES:
            if solver == "dense" and n > 1000:
                continue  # one dense LSA per giant cluster: quadratic memory
            ti, dj, c = candidate_pairs(view, dets, dist, **params)
            labels = _components(ti, dj, n, m)
            used = np.zeros(n + m, dtype=bool)
            used[ti] = True
            used[n + dj] = True
            largest = int(np.bincount(labels[used]).max()) if ti.size else 0
            t_gate, w_gate = _median_ms(args.repeats, candidate_pairs, view, dets, dist, **params)
            t_assign, w_assign = _median_ms(
                args.repeats, assign, ti, dj, c, n, m, rule, solver=solver
            )
            a = assign(ti, dj, c, n, m, rule, solver=solver)
            row = (
                n,
                m,
                dist,
                rule if rule != "optimal" else f"optimal ({solver})",
                ti.size,
                largest,
                len(a),
                t_gate,
                t_assign,
                t_gate + t_assign,
                w_gate + w_assign,
            )
            rows.append(row)
            print(
                "N={:>6} M={:>6} {:<12} {:<18} pairs={:>7} largest cluster={:>6} matched={:>6} "
                "gate {:8.3f} ms  assign {:8.3f} ms  total {:8.3f} ms (wall {:8.3f} ms)".format(
                    *row
                ),
                flush=True,
            )
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
            "Command: `python benchmarks/bench_association.py --md docs/bench/association.md`",
            "",
            "| N | M | distance | rule | gated pairs | largest cluster | matched | gate ms "
            "| assign ms | total ms | wall total ms |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in rows:
            lines.append(
                "| {} | {} | {} | {} | {} | {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.3f} |".format(
                    *r
                )
            )
        lines += [
            "",
            "`largest cluster` is the number of tracks + detections in the biggest connected",
            "component of the gate graph. The exact optimal assignment costs roughly linear",
            "time while clusters stay small; once the gate is wide relative to the spacing of",
            "the targets (the 20 px Euclidean gate at N = 10 000, where neighbours are ~14 px",
            "apart) the graph percolates into one giant cluster and the sparse solve grows",
            "faster than linearly. The χ² gates (mahalanobis, coupled) scale with the filters'",
            "uncertainty and keep the clusters small.",
        ]
        lines += _growth(rows)
        write_text(args.md, "\n".join(lines) + "\n")
        print(f"wrote {args.md}")


if __name__ == "__main__":
    main()
