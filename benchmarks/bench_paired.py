"""Two tracker configurations timed in paired, alternating runs on the MOT15 sequences.

Each round runs ``Tracker.step`` over every frame of a sequence once with configuration A and
once with B (the default preset with the JSON overrides given), in alternation, so that the
load of this noisy machine falls on both alike; the figures of each are the median and the
fastest of its rounds, and the ratios B / A are what to read. The detections are read before
the clock starts, and an untimed pass of each configuration loads its compiled kernels.

Usage::

    python benchmarks/bench_paired.py '{}' '{"size_noise": null}' --rounds 9
    python benchmarks/bench_paired.py '{}' '{"predictor": "kalman-cv"}' --rounds 9
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data" / "real"
SEQUENCES = {"TUD-Campus": 25.0, "TUD-Stadtmitte": 25.0, "ADL-Rundle-6": 30.0, "KITTI-17": 10.0}


def _run(config: Any, frames: list[Any]) -> float:
    """Ms per frame of ``Tracker.step`` over ``frames`` with a fresh tracker."""
    from mvtrack.tracking import Tracker

    tracker, total = Tracker(config), 0.0
    for dets in frames:
        t0 = time.perf_counter()
        tracker.step(dets)
        total += time.perf_counter() - t0
    return 1000.0 * total / len(frames)


def paired(frames: list[Any], configs: list[Any], rounds: int) -> list[list[float]]:
    """Ms per frame of each configuration in each of ``rounds`` alternating rounds."""
    for config in configs:  # an untimed pass: the compiled kernels loaded before the clock
        _run(config, frames)
    runs: list[list[float]] = [[] for _ in configs]
    for _ in range(rounds):
        for i, config in enumerate(configs):
            runs[i].append(_run(config, frames))
    return runs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a", help="JSON overrides of the default preset for configuration A")
    ap.add_argument("b", help="JSON overrides for configuration B")
    ap.add_argument("--rounds", type=int, default=9)
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        print(f"error: {DATA} not found (the MOT15 development sequences)", file=sys.stderr)
        return 2
    from mvtrack.io.mot import read_detections
    from mvtrack.tracking import preset

    try:
        over = [json.loads(args.a), json.loads(args.b)]
        if not all(isinstance(o, dict) for o in over):
            raise ValueError("each configuration must be a JSON object")
        configs = {seq: [preset("default", fps=fps, **o) for o in over]
                   for seq, fps in SEQUENCES.items()}
    except (ValueError, TypeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"A = default + {args.a}; B = default + {args.b}; {args.rounds} alternating rounds")
    print("| sequence | A ms/frame, median (fastest) | B ms/frame, median (fastest) | "
          "B / A, medians (fastest) |")
    print("|---|---:|---:|---:|")
    for seq in SEQUENCES:
        frames = list(read_detections(DATA / seq / "det.txt"))
        a, b = paired(frames, configs[seq], args.rounds)
        ma, mb = statistics.median(a), statistics.median(b)
        print(f"| {seq} | {ma:.3f} ({min(a):.3f}) | {mb:.3f} ({min(b):.3f}) | "
              f"{mb / ma:.2f} ({min(b) / min(a):.2f}) |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
