"""Per-target cost of one predict + update step of the tracker's predictors.

For batch sizes 1 … 100 000 it times ``update(predict(state), z, mask)`` of the predictor
classes the tracker uses (``kalman-ca`` per axis, ``kalman-coupled``, ``rls`` per axis) and
prints the time per target and per target-axis (the per-axis filters run two 1-D filters per
target; the coupled filter is counted as two axes too). Each figure is the median (and the
minimum) over ``--repeats`` timed blocks of ``--steps`` frames, after one warm-up block.
Single-threaded BLAS is forced so the numbers are one core's. The main figures are CPU time
of this process (``time.process_time``), which on a shared machine is much closer to the
cost on an idle core than wall time; the wall-clock median is printed beside it.

Run::

    python benchmarks/bench_filters.py [--sizes 1 10 100 1000 10000 100000] [--repeats 7]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import time

import numpy as np

from mvtrack.filters.predictors import make_predictor

PREDICTORS = [("kalman-ca", 2), ("kalman-coupled", 2), ("rls", 2), ("kalman-cv", 2)]


def bench(name: str, N: int, steps: int, repeats: int) -> tuple[float, float, float]:
    """Median wall time, median CPU time and minimum CPU time (s) per frame for N targets."""
    rng = np.random.default_rng(0)
    p = make_predictor(name)
    start = rng.uniform(0, 1000, size=(N, 2))
    vel = rng.normal(0, 2, size=(N, 2))
    state = p.init(start)
    z = start + vel * np.arange(1, steps + 1)[:, None, None] + rng.normal(0, 1, (steps, N, 2))
    masks = rng.random((steps, N)) > 0.05
    wall, cpu = [], []
    for block in range(repeats + 1):
        t0, c0 = time.perf_counter(), time.process_time()
        for t in range(steps):
            state = p.update(p.predict(state), z[t], masks[t])
        if block:
            wall.append((time.perf_counter() - t0) / steps)
            cpu.append((time.process_time() - c0) / steps)
        state = p.init(start)
    return float(np.median(wall)), float(np.median(cpu)), float(min(cpu))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+",
                    default=[1, 10, 100, 1000, 10000, 100000])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--steps", type=int, default=0,
                    help="frames per timed block (default: enough for ~50 ms)")
    args = ap.parse_args()
    print("| predictor | N targets | CPU µs / frame | CPU ns / target | CPU ns / target-axis "
          "| min CPU ns / target-axis | wall ns / target-axis |")
    print("|---|---|---|---|---|---|---|")
    for name, axes in PREDICTORS:
        for N in args.sizes:
            steps = args.steps or max(3, min(200, 2_000_000 // max(N, 1) // 20))
            wall, cpu, best = bench(name, N, steps, args.repeats)
            print(f"| {name} | {N} | {cpu * 1e6:.1f} | {cpu / N * 1e9:.0f} | "
                  f"{cpu / N / axes * 1e9:.0f} | {best / N / axes * 1e9:.0f} | "
                  f"{wall / N / axes * 1e9:.0f} |", flush=True)


if __name__ == "__main__":
    main()
