"""Tracker speed and accuracy on the "crowd" scene of issue 3, against today's trackers.

Scene: N targets in a 1920×1080 plane, 300 frames at 30 fps, constant velocity with speed
uniform in 1–6 px/frame plus white acceleration σ = 0.05 px/frame² per axis, elastic
reflection at the borders, 40×30 px boxes ±10 %. Detections: centre noise σ = 2 px, size noise
σ = 1 px, miss probability 0.1, Poisson(3) false alarms per frame, rows shuffled.

Timing is tracker-only (``Tracker.step`` over pre-built detections: predict, gate, assign,
update, life cycle; no I/O, no scene generation), on one core (BLAS threads pinned to 1 before
NumPy loads), median of ``--repeats`` runs; both the CPU time of the process and the wall time
are printed (on a shared machine the CPU time is the steadier of the two), with the load
average and the cost of one tiny NumPy operation for context. Accuracy is MOTA / IDF1 from
motmetrics' ``MOTAccumulator`` fed with IoU distances computed here (match when IoU ≥ 0.5),
on the output rows including coasting ones.

Usage::

    python benchmarks/bench_tracker.py                       # N = 10, 100, 1000, 10000
    python benchmarks/bench_tracker.py --n 10 100 --predictor kalman-ca --distance iou
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

from mvtrack.tracking import Tracker, TrackerConfig, TrackLog  # noqa: E402
from mvtrack.types import Detections  # noqa: E402

W, H = 1920.0, 1080.0

#: ms per frame at N = 10 / 100 / 1000 measured on this machine for the same scene (issue 3)
PEERS_MS = {
    "SORT in Rust (ioutrack)": (0.08, 0.5, 22),
    "trackpy": (0.23, 0.7, 10.5),
    "Python SORT": (1.6, 10, 132),
    "Norfair": (1.5, 12, 300),
    "motpy": (3, 10, 106),
    "supervision ByteTrack": (2.3, 15, 169),
    "Stone Soup GNN": (22, 141, 1900),
}


def crowd_scene(
    n: int, frames: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Ground truth: centres (frames, n, 2) and box sizes (n, 2) of the crowd scene."""
    wh = np.array([40.0, 30.0]) * rng.uniform(0.9, 1.1, (n, 2))
    p = rng.uniform([0.0, 0.0], [W, H], (n, 2))
    ang = rng.uniform(0.0, 2 * np.pi, n)
    v = rng.uniform(1.0, 6.0, n)[:, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    xy = np.empty((frames, n, 2))
    size = np.array([W, H])
    for k in range(frames):  # loop over frames, vectorised over targets
        xy[k] = p
        v = v + 0.05 * rng.standard_normal((n, 2))  # white acceleration, σ = 0.05 px/frame²
        p = p + v
        low, high = p < 0.0, p > size  # elastic reflection at the borders
        p = np.where(low, -p, np.where(high, 2 * size - p, p))
        v = np.where(low | high, -v, v)
    return xy, wh


def crowd_detections(
    xy: np.ndarray, wh: np.ndarray, rng: np.random.Generator
) -> list[Detections]:
    """Noisy, incomplete, cluttered and shuffled detections of the crowd scene."""
    frames, n, _ = xy.shape
    out = []
    for k in range(frames):
        seen = rng.random(n) >= 0.1  # miss probability 0.1
        dxy = xy[k, seen] + 2.0 * rng.standard_normal((int(seen.sum()), 2))  # σ = 2 px
        dwh = wh[seen] + 1.0 * rng.standard_normal((int(seen.sum()), 2))  # σ = 1 px
        nf = rng.poisson(3.0)  # false alarms
        fxy = rng.uniform([0.0, 0.0], [W, H], (nf, 2))
        fwh = np.array([40.0, 30.0]) * rng.uniform(0.9, 1.1, (nf, 2))
        allxy = np.vstack([dxy, fxy])
        allwh = np.maximum(np.vstack([dwh, fwh]), 1.0)
        perm = rng.permutation(allxy.shape[0])  # rows shuffled
        out.append(Detections(k, allxy[perm], allwh[perm]))
    return out


def sim_scene(
    n: int, frames: int, seed: int
) -> tuple[np.ndarray, np.ndarray, list[Detections]]:
    """The same scene from the project's simulator (:func:`mvtrack.sim.crowd.crowd`, which
    keeps the speed inside 1–6 px/frame and reflects the whole box inside the image)."""
    from mvtrack.sim.crowd import crowd
    from mvtrack.sim.detections import detections_from_scene

    scene = crowd(n, frames, seed=seed)
    xy = scene.xy.reshape(frames, n, 2)
    wh = scene.wh.reshape(frames, n, 2)[0]
    dets = detections_from_scene(scene, np.random.default_rng(seed + 1))
    return xy, wh, dets


def run_tracker(
    config: TrackerConfig, frames: list[Detections]
) -> tuple[float, float, TrackLog]:
    """CPU seconds and wall seconds spent in ``Tracker.step`` over all frames, and the log."""
    tracker = Tracker(config)
    outs = []
    c0, t0 = time.process_time(), time.perf_counter()
    for dets in frames:
        outs.append(tracker.step(dets))
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    log = TrackLog()
    for tf in outs:
        log.append(tf)
    return cpu, wall, log


def small_op_us() -> float:
    """Cost of one tiny NumPy operation (µs), to put the figures in context of the load."""
    a = np.zeros(10)
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(20000):
            a + a
        best = min(best, (time.perf_counter() - t0) / 20000 * 1e6)
    return best


def _iou(a_xy: np.ndarray, a_wh: np.ndarray, b_xy: np.ndarray, b_wh: np.ndarray) -> np.ndarray:
    lo = np.maximum(a_xy[:, None] - a_wh[:, None] / 2, b_xy[None] - b_wh[None] / 2)
    hi = np.minimum(a_xy[:, None] + a_wh[:, None] / 2, b_xy[None] + b_wh[None] / 2)
    inter = np.clip(hi - lo, 0.0, None).prod(axis=2)
    union = a_wh.prod(axis=1)[:, None] + b_wh.prod(axis=1)[None] - inter
    return inter / union


def accuracy(xy: np.ndarray, wh: np.ndarray, log: TrackLog, iou: float = 0.5) -> dict:
    """MOTA, IDF1 and counts from motmetrics with our IoU distance matrices."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import motmetrics as mm
    rows = log.to_mot(include_coasting=True)
    acc = mm.MOTAccumulator(auto_id=False)
    frame_col = rows[:, 0].astype(np.int64) - 1
    bounds = np.searchsorted(frame_col, np.arange(xy.shape[0] + 1))
    gt_ids = np.arange(1, xy.shape[1] + 1)
    for k in range(xy.shape[0]):
        r = rows[bounds[k] : bounds[k + 1]]
        hyp_xy = r[:, 2:4] + r[:, 4:6] / 2
        d = 1.0 - _iou(xy[k], wh, hyp_xy, r[:, 4:6])
        d[d > 1.0 - iou] = np.nan
        acc.update(gt_ids, r[:, 1].astype(np.int64), d, frameid=k)
    mh = mm.metrics.create()
    s = mh.compute(
        acc,
        metrics=["mota", "idf1", "num_switches", "num_false_positives", "num_misses"],
        name="x",
    )
    return {
        "MOTA": float(s["mota"].iloc[0]),
        "IDF1": float(s["idf1"].iloc[0]),
        "IDSW": int(s["num_switches"].iloc[0]),
        "FP": int(s["num_false_positives"].iloc[0]),
        "FN": int(s["num_misses"].iloc[0]),
    }


def variants() -> list[tuple[str, TrackerConfig]]:
    """The default and one-change-at-a-time alternatives (docs/bench/tracker.md)."""
    from mvtrack.tracking import paper1, paper2

    return [
        ("default", TrackerConfig()),
        ("predictor kalman-cv (the IMM's steady filter alone)",
         TrackerConfig(predictor="kalman-cv")),
        ("no size term in the gate (size_noise = None)", TrackerConfig(size_noise=None)),
        ("every coasting row output (coast_std = inf)", TrackerConfig(coast_std=math.inf)),
        ("no loss by uncertainty (lost_std = None)", TrackerConfig(lost_std=None)),
        ("no birth test (birth_iou = None)", TrackerConfig(birth_iou=None)),
        ("Euclidean gate in box sizes", TrackerConfig(distance="euclidean", gate=None)),
        ("IoU 0.7", TrackerConfig(distance="iou", gate=None)),
        ("confirm on 3 hits", TrackerConfig(confirm_hits=3)),
        ("greedy instead of optimal", TrackerConfig(assign="greedy")),
        ("kalman-ca (q = 0.05)",
         TrackerConfig(predictor="kalman-ca", predictor_params={"q": 0.05})),
        ("rls", TrackerConfig(predictor="rls")),
        ('`paper1("kalman-ca")` preset', paper1("kalman-ca")),
        ('`paper1("rls")` preset', paper1("rls")),
        ("`paper2(fps=30)` preset", paper2(fps=30.0)),
    ]


def main(argv: list[str] | None = None) -> int:
    """Print the table (and optionally write JSON)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[10, 100, 1000, 10000])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--accuracy-max-n", type=int, default=1000,
                    help="compute MOTA/IDF1 only up to this N (dense IoU in the evaluator)")
    ap.add_argument("--predictor", default=None)
    ap.add_argument("--distance", default=None)
    ap.add_argument("--assign", default=None)
    ap.add_argument("--gate", type=float, default=None)
    ap.add_argument("--confirm-hits", type=int, default=None)
    ap.add_argument("--max-misses", type=int, default=None)
    ap.add_argument("--json", default=None, help="also write the figures to this JSON file")
    ap.add_argument("--scene", choices=("own", "sim"), default="own",
                    help="generate the scene here (own) or with mvtrack.sim (sim)")
    ap.add_argument("--scores", action="store_true",
                    help="give every detection a uniform random score in [0, 1] (the score "
                         "stages' worst case: half the boxes low)")
    ap.add_argument("--birth-iou", default=None,
                    help="TrackerConfig.birth_iou (a number, or 'none')")
    ap.add_argument("--variants", action="store_true",
                    help="one run of each variant of the default (Markdown rows)")
    args = ap.parse_args(argv)
    if args.variants:
        print("| N | variant | CPU ms | MOTA | IDF1 | IDSW | FP | FN |")
        print("|---|---|---|---|---|---|---|---|")
        for n in args.n:
            rng = np.random.default_rng(args.seed + n)
            xy, wh = crowd_scene(n, args.frames, rng)
            frames = crowd_detections(xy, wh, rng)
            for name, cfg in variants():
                cpu, _, log = run_tracker(cfg, frames)
                a = accuracy(xy, wh, log)
                print(f"| {n} | {name} | {1000 * cpu / args.frames:.3f} | {a['MOTA']:.3f} | "
                      f"{a['IDF1']:.3f} | {a['IDSW']} | {a['FP']} | {a['FN']} |", flush=True)
        return 0

    changes = {
        k: v
        for k, v in (
            ("predictor", args.predictor), ("distance", args.distance),
            ("assign", args.assign), ("gate", args.gate),
            ("confirm_hits", args.confirm_hits), ("max_misses", args.max_misses),
        )
        if v is not None
    }
    if args.birth_iou is not None:
        lb = args.birth_iou.lower()
        changes["birth_iou"] = None if lb == "none" else float(lb)
    config = TrackerConfig(**changes)
    print(
        f"config: predictor={config.predictor} distance={config.distance} "
        f"assign={config.assign} gate={config.gate} confirm_hits={config.confirm_hits} "
        f"max_misses={config.max_misses} fps={config.fps} birth_iou={config.birth_iou}"
        + (" (uniform random scores)" if args.scores else "")
    )
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average {load:.1f}; one tiny NumPy op {small_op_us():.2f} µs")
    print(f"{'N':>6} {'CPU ms/frame':>12} {'wall ms/frame':>13} {'CPU runs':>24} {'MOTA':>6} "
          f"{'IDF1':>6} {'IDSW':>5} {'FP':>6} {'FN':>7}")
    results = []
    for n in args.n:
        if args.scene == "sim":
            xy, wh, frames = sim_scene(n, args.frames, args.seed + n)
        else:
            rng = np.random.default_rng(args.seed + n)
            xy, wh = crowd_scene(n, args.frames, rng)
            frames = crowd_detections(xy, wh, rng)
        if args.scores:
            srng = np.random.default_rng(args.seed + n + 1)
            frames = [Detections(d.frame, d.xy, d.wh, srng.uniform(0.0, 1.0, len(d)))
                      for d in frames]
        times, walls = [], []
        log = None
        for _ in range(args.repeats):
            cpu, wall, log = run_tracker(config, frames)
            times.append(1000.0 * cpu / args.frames)
            walls.append(1000.0 * wall / args.frames)
        med, wmed = statistics.median(times), statistics.median(walls)
        acc = accuracy(xy, wh, log) if n <= args.accuracy_max_n else {}
        results.append({"n": n, "cpu_ms_per_frame": med, "wall_ms_per_frame": wmed,
                        "cpu_runs_ms": times, "wall_runs_ms": walls, **acc})
        runs = " ".join(f"{t:.3f}" for t in times)
        if acc:
            tail = (f"{acc['MOTA']:6.3f} {acc['IDF1']:6.3f} {acc['IDSW']:5d} {acc['FP']:6d} "
                    f"{acc['FN']:7d}")
        else:
            tail = f"{'-':>6} {'-':>6}"
        print(f"{n:6d} {med:12.3f} {wmed:13.3f} {runs:>24} {tail}", flush=True)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump({"config": repr(config), "results": results}, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
