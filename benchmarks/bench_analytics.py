"""Time the analytics against the pipeline on vtest.avi, in paired runs.

Each run, two parts:

- ``mvtrack track vtest.avi`` (its own ``summary.json`` "seconds": detect, track and write
  the annotated video, the only case in which the analytics are drawn), then, on its output,
  the analytics of ``docs/analytics-example.toml`` (read
  results.txt, estimate velocities, lines, zones, movements, speeds, write the CSV files);
- the loop's cost of drawing them on the video: the same ``LiveAnalytics`` updated and drawn
  on every frame of the run's rows (what ``mvtrack track --config`` adds to writing
  ``tracks.mp4``), timed in the same process.

Prints the times and their ratios to the pipeline per run.

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
    ratios, totals = [], []
    for r in range(args.runs):
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run([sys.executable, "-m", "mvtrack", "track", args.video, "--out", tmp],
                           check=True, capture_output=True)
            summary = json.loads((Path(tmp) / "summary.json").read_text())
            pipe = summary["seconds"]
            t0 = time.perf_counter()
            res = analyse_folder(tmp, settings)
            write_outputs(res, tmp)
            ana = time.perf_counter() - t0
            draw = live_overlay_seconds(Path(tmp) / "results.txt", settings,
                                        summary["video_fps"], tuple(summary["size"]))
        ratios.append(ana / pipe)
        totals.append((ana + draw) / pipe)
        print(f"run {r}: pipeline {pipe:.2f} s, analytics {ana:.3f} s ({ana / pipe:.3f}), "
              f"drawn on every frame {draw:.2f} s; both {(ana + draw) / pipe:.3f} of the pipeline")
    print(f"median ratio: analytics {sorted(ratios)[len(ratios) // 2]:.3f}, with the drawing "
          f"{sorted(totals)[len(totals) // 2]:.3f}")


def live_overlay_seconds(results: Path, settings: object, fps: float,
                         size: tuple[int, int]) -> float:
    """Seconds to update and draw :class:`~mvtrack.viz.overlay.LiveAnalytics` on every frame
    of ``results`` (its rows replayed as the tracker's output, on a grey frame)."""
    import numpy as np

    from mvtrack.io.mot import read_tracks
    from mvtrack.types import TrackFrame, TrackState
    from mvtrack.viz.overlay import LiveAnalytics

    t = read_tracks(results, "results")
    xy = t.tlwh[:, :2] + t.tlwh[:, 2:] / 2
    frames = []
    for f in range(int(t.frame.max()) + 1 if len(t.frame) else 0):
        sel = t.frame == f
        m = int(sel.sum())
        frames.append(TrackFrame(f, t.id[sel].astype(np.int64),
                                 np.full(m, int(TrackState.CONFIRMED)), np.zeros(m, np.int64),
                                 xy[sel], xy[sel], xy[sel], t.tlwh[sel, 2:], np.zeros((m, 2))))
    live = LiveAnalytics(settings, fps)
    grey = np.full((size[1], size[0], 3), 128, np.uint8)
    t0 = time.perf_counter()
    for tf in frames:
        img = grey.copy()
        live.push(tf)
        live.draw(img)
    return time.perf_counter() - t0 - len(frames) * _copy_seconds(grey)


def _copy_seconds(img: object) -> float:
    t0 = time.perf_counter()
    for _ in range(50):
        img.copy()  # type: ignore[attr-defined]
    return (time.perf_counter() - t0) / 50


if __name__ == "__main__":
    main()
