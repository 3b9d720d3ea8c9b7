"""Simulation speed: scene building, simulated detections and video rendering, one core.

Rows:

* ``render`` — :func:`mvtrack.sim.render.render_frames` over the whole scene (background drawn
  once, then per frame: crop at the jitter, draw that frame's objects, occluders, noise),
  frames per second; no encoding.
* ``build`` — a scene builder (``crowd`` with N targets × 300 frames), seconds.
* ``detections`` — :func:`mvtrack.sim.detections.detections_from_scene` for the crowd with
  the crowd scene's defaults (σ = 2 px, size σ = 1 px, 10 % missed, Poisson(3) clutter), seconds.

OpenCV runs on one thread and BLAS is pinned to one thread before NumPy loads. Each figure is
the median of ``--repeats`` runs, as wall-clock time and as CPU time of the process (the
latter is the fairer figure on a shared, loaded machine).

Usage::

    python benchmarks/bench_render.py               # 3 repeats, Markdown table
    python benchmarks/bench_render.py --repeats 5
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from mvtrack.sim import scenes as S  # noqa: E402
from mvtrack.sim.detections import detections_from_scene  # noqa: E402
from mvtrack.sim.render import render_frames  # noqa: E402


def _median_time(fn: Callable[[], object], repeats: int) -> tuple[float, float]:
    """Median wall-clock and median CPU seconds of ``fn`` (CPU time is less sensitive to
    other jobs on a shared machine)."""
    wall, cpu = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu)


def _render_all(scene: S.Scene, size: tuple[int, int] | None = None) -> None:
    for _ in render_frames(scene, 0, size=size):
        pass


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    load = os.getloadavg()[0]
    r = args.repeats
    rows: list[tuple[str, str, str, str]] = []

    renders = [
        ("x4 (flat, no noise)", S.x4_nine_vehicles(), None),
        ("x5 (intersection, σ=3 noise, ±1 px jitter)", S.x5_intersection(0), None),
        ("x8 (plaza, σ=2 noise, occluder)", S.x8_splitting_group(0), None),
        ("x5 at 768×576", S.x5_intersection(0), (768, 576)),
        ("crowd N=1000, 1920×1080", S.crowd(1000, frames=30, seed=0), None),
    ]
    for label, scene, size in renders:
        t, c = _median_time(lambda scene=scene, size=size: _render_all(scene, size), r)
        w, h = size or scene.size
        rows.append((f"render {label}", f"{w}×{h}", f"{scene.n_frames / t:,.0f} frames/s",
                     f"{scene.n_frames / c:,.0f} frames/s"))
        print(rows[-1], flush=True)

    for n in (1_000, 10_000):
        t, c = _median_time(lambda n=n: S.crowd(n, frames=300, seed=0), r)
        rows.append((f"build crowd N={n:,}, 300 frames", "1920×1080", f"{t:.2f} s",
                     f"{c:.2f} s"))
        print(rows[-1], flush=True)
        scene = S.crowd(n, frames=300, seed=0)
        t, c = _median_time(lambda scene=scene: detections_from_scene(
            scene, np.random.default_rng(0)), r)
        rows.append((f"detections crowd N={n:,}, 300 frames", "1920×1080", f"{t:.2f} s",
                     f"{c:.2f} s"))
        print(rows[-1], flush=True)

    print()
    print(f"load average before the run: {load:.1f} (1 min), after: {os.getloadavg()[0]:.1f}")
    print()
    print("| what | size | median (wall clock) | median (CPU time) |")
    print("|---|---|---|---|")
    for what, size, value, cpu in rows:
        print(f"| {what} | {size} | {value} | {cpu} |")


if __name__ == "__main__":
    main()
