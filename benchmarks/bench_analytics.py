"""Time the analytics against the pipeline on vtest.avi, in paired runs.

Each run: ``mvtrack track vtest.avi --no-video`` (its own ``summary.json`` "seconds": detect
and track), then, on its output, the analytics of ``docs/analytics-example.toml``
(read results.txt, estimate velocities, lines, zones, movements, speeds, write the CSV
files). Prints both times and their ratio per run.

    python benchmarks/bench_analytics.py [--runs 3] [--video ../shared/data/vtest.avi]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--video", default=str(ROOT.parent / "shared" / "data" / "vtest.avi"))
    args = ap.parse_args()
    from mvtrack.analytics import analyse_folder, load_settings
    from mvtrack.analytics.outputs import write_outputs

    settings = load_settings(ROOT / "docs" / "analytics-example.toml")
    ratios = []
    for r in range(args.runs):
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run([sys.executable, "-m", "mvtrack", "track", args.video, "--out", tmp,
                            "--no-video"], check=True, capture_output=True)
            pipe = json.loads((Path(tmp) / "summary.json").read_text())["seconds"]
            t0 = time.perf_counter()
            res = analyse_folder(tmp, settings)
            write_outputs(res, tmp)
            ana = time.perf_counter() - t0
        ratios.append(ana / pipe)
        print(f"run {r}: pipeline {pipe:.2f} s, analytics {ana:.3f} s, ratio {ana / pipe:.3f}")
    print(f"median ratio {sorted(ratios)[len(ratios) // 2]:.3f}")


if __name__ == "__main__":
    main()
