"""The floor of a NumPy tracker step at MOT15 densities, beside mvtrack's step, paired.

What does a per-frame step cost in NumPy when it does only what SORT does? ``BareTracker.step``
is the least a Kalman tracker over arrays can do per frame: a constant-velocity prediction per
axis (state ``x, v`` and one shared 2 × 2 covariance per track), squared Euclidean costs with
one gate, one ``scipy.optimize.linear_sum_assignment``, the measurement update of the matched
tracks, a miss counter, deletion and births — no scores, no box-size noise, no size term, no
IMM, no life-cycle states, no output rows. It and ``mvtrack.tracking.Tracker.step`` (default
preset, the sequence's frame rate), once as the default runs it (``fused=True``: the frame in
two compiled calls, :mod:`mvtrack.tracking.step`) and once composed from Python
(``fused=False``: the same compiled kernels called one by one, as every configuration outside
the default family runs; the same tracks), run over every frame of each MOT15 development
sequence in alternating rounds; the figures are the medians of the rounds. The bare step is
what a tracker written in NumPy pays in array calls at these densities (4–10 boxes a frame);
mvtrack's step does more per frame and is compiled.

Usage::

    python benchmarks/bench_numpy_floor.py --rounds 9 --out docs/bench/numpy-floor.md
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data" / "real"
SEQUENCES = {"TUD-Campus": 25.0, "TUD-Stadtmitte": 25.0, "ADL-Rundle-6": 30.0, "KITTI-17": 10.0}
GATE2 = 400.0  # px², the squared gate
MAX_MISSES = 7


class BareTracker:
    """Arrays ``x`` (N, 4) = position and velocity, ``p`` (N, 3) = the per-axis covariance
    ``[[p00, p01], [p01, p11]]``, ``miss`` (N,)."""

    def __init__(self, q: float = 1.0, r: float = 4.0, p_v: float = 100.0) -> None:
        self.q, self.r, self.p_v = q, r, p_v
        self.x = np.zeros((0, 4))
        self.p = np.zeros((0, 3))
        self.miss = np.zeros(0, dtype=np.int64)

    def step(self, z: np.ndarray) -> None:
        x, p, q, r = self.x, self.p, self.q, self.r
        x[:, :2] += x[:, 2:]  # x̄ = F x, F = [[1, 1], [0, 1]] per axis
        p = np.column_stack([  # P̄ = F P Fᵀ + Q, Q = diag(q, q) per axis
            p[:, 0] + 2 * p[:, 1] + p[:, 2] + q, p[:, 1] + p[:, 2], p[:, 2] + q])
        n, m = x.shape[0], z.shape[0]
        miss = self.miss + 1
        new = z
        if n and m:
            cost = ((z[None, :, :] - x[:, None, :2]) ** 2).sum(axis=2)
            cost[cost > GATE2] = 1e9
            ti, dj = linear_sum_assignment(cost)
            ok = cost[ti, dj] < 1e9
            ti, dj = ti[ok], dj[ok]
            s = p[ti, 0] + r  # innovation variance, H = [1, 0]
            k0, k1 = p[ti, 0] / s, p[ti, 1] / s  # Kalman gain
            e = z[dj] - x[ti, :2]
            x[ti, :2] += k0[:, None] * e
            x[ti, 2:] += k1[:, None] * e
            p[ti] = np.column_stack([(1 - k0) * p[ti, 0], (1 - k0) * p[ti, 1],
                                     p[ti, 2] - k1 * p[ti, 1]])  # P = (I − K H) P̄
            miss[ti] = 0
            used = np.zeros(m, dtype=bool)
            used[dj] = True
            new = z[~used]
        keep = miss <= MAX_MISSES
        x, p, miss = x[keep], p[keep], miss[keep]
        if new.shape[0]:
            b = new.shape[0]
            x = np.concatenate([x, np.column_stack([new, np.zeros((b, 2))])])
            p = np.concatenate([p, np.tile([r, 0.0, self.p_v], (b, 1))])
            miss = np.concatenate([miss, np.zeros(b, dtype=np.int64)])
        self.x, self.p, self.miss = x, p, miss


def _time(make: Any, frames: list[Any]) -> float:
    tracker, total = make(), 0.0
    for f in frames:
        t0 = time.perf_counter()
        tracker.step(f)
        total += time.perf_counter() - t0
    return 1000.0 * total / len(frames)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--out", type=Path, help="also write the Markdown report here")
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        print(f"error: {DATA} not found (the MOT15 development sequences)", file=sys.stderr)
        return 2
    from mvtrack.io.mot import read_detections
    from mvtrack.tracking import Tracker, preset

    lines = [
        "## The floor of a NumPy step (MOT15 development sequences)", "",
        f"Command: `python benchmarks/bench_numpy_floor.py --rounds {args.rounds}"
        + (f" --out {args.out}`" if args.out else "`"), "",
        __doc__.split("\n\n")[1].replace("\n", " "), "",
        f"Measured on a shared 2-core machine while other work ran (Python "
        f"{platform.python_version()}, NumPy {np.__version__}, load average "
        f"{os.getloadavg()[0]:.1f} at the start): the absolute times move with the load, the "
        f"ratios of one round are what to read; {args.rounds} alternating rounds, medians.", "",
        "| sequence | detections per frame | bare NumPy step, ms | mvtrack step (fused), ms | "
        "fused / bare | mvtrack step (composed), ms | composed / bare | composed / fused |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for seq, fps in SEQUENCES.items():
        dets = list(read_detections(DATA / seq / "det.txt"))
        boxes = [d.xy for d in dets]
        config = preset("default", fps=fps)
        for fused in (True, False):  # an untimed pass: every compiled kernel loaded first
            _time(lambda c=config, f=fused: Tracker(c, fused=f), dets)
        _time(BareTracker, boxes)
        bare, fast, comp = [], [], []
        for _ in range(args.rounds):
            bare.append(_time(BareTracker, boxes))
            fast.append(_time(lambda c=config: Tracker(c), dets))
            comp.append(_time(lambda c=config: Tracker(c, fused=False), dets))
        mb, mf, mc = (statistics.median(x) for x in (bare, fast, comp))
        per = sum(len(b) for b in boxes) / len(boxes)
        lines.append(f"| {seq} | {per:.1f} | {mb:.3f} | {mf:.3f} | ×{mf / mb:.2f} | {mc:.3f} "
                     f"| ×{mc / mb:.2f} | ×{mc / mf:.2f} |")
        print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    if args.out:
        from mvtrack.io.atomic import write_text

        write_text(args.out, text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
