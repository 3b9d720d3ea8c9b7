"""Whole-pipeline speed: decode → detect (disturbance map) → track, frames per second, one core.

Sequences:

* ``vtest.avi`` — the real 768×576 campus recording (795 frames, XVID/MPEG-4 in AVI), read from
  ``../shared/data/vtest.avi`` beside the checkout (or ``--vtest``);
* ``x5`` — paper 1's synthetic intersection (SPEC X5) rendered at 320×240 by
  :mod:`mvtrack.sim.render` and written to a temporary MP4 (``mp4v``), so decoding is measured
  too. If the renderer is unavailable, a simple scene of textured rectangles on noisy grey is
  rendered here instead (the table says which).

Stages, each timed over the whole sequence, built exactly as ``mvtrack track --no-video`` builds
them (:func:`mvtrack.video.resolve_settings` for the video's size, then
:func:`~mvtrack.video.build_detector`, :func:`~mvtrack.video.build_tracker`,
:func:`~mvtrack.video.build_rescuer`, run by :func:`~mvtrack.video.run_frames`):
``decode`` (``open_source`` only), ``+ detect`` (decode and the disturbance map with the
pipeline's size-dependent defaults), ``+ track`` (also the ``default`` tracker preset at the
source's frame rate, ``templates.enabled = false``) and ``+ track + templates`` (also template
matching of stopped vehicles, the default). No video is written; rendering the synthetic video
is not timed.

Time is the CPU time of the process (``time.process_time``), what one dedicated core takes;
wall-clock time is printed beside it because the machine may be shared. OpenCV runs on one
thread (``cv2.setNumThreads(1)``), the decoder too (``open_source(..., threads=1)``; FFmpeg
otherwise decodes with several) and BLAS is pinned to one thread before NumPy loads. After an
untimed 50-frame warm-up per stage, each figure is the median of ``--repeats`` interleaved runs
(the least CPU time, "best", is printed too: what the stage takes when other work on a shared
machine slows it least); the decode share is the median decode CPU time over the median CPU
time of the stage.

Usage::

    python benchmarks/bench_pipeline.py                 # both sequences, 5 repeats
    python benchmarks/bench_pipeline.py --repeats 3 --detector frame-diff
    python benchmarks/bench_pipeline.py --markdown      # also print the Markdown table
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from mvtrack.io.video import open_source  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
VTEST = ROOT.parent / "shared" / "data" / "vtest.avi"

#: paper 1 (SPEC §1.4): 30 fps at 320×240 on a Pentium Pro 200 MHz; the targets of each size
PAPER_FPS = 30.0
TARGETS = {(320, 240): 1000.0, (768, 576): 150.0}


def _write(frames: list[np.ndarray], path: Path, fps: float) -> None:
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (w, h))
    if not writer.isOpened():
        raise OSError(f"cannot write {path} with OpenCV (mp4v)")
    for f in frames:
        writer.write(f)
    writer.release()


def simple_scene(n: int = 360, size: tuple[int, int] = (320, 240), seed: int = 0) -> list:
    """Fallback: 8 two-tone rectangles crossing a noisy grey road, ``n`` frames."""
    rng = np.random.default_rng(seed)
    w, h = size
    bg = np.clip(rng.normal(100, 8, (h, w)), 0, 255).astype(np.uint8)
    start = rng.uniform([0, 20], [w, h - 20], (8, 2))
    vel = rng.uniform(-3, 3, (8, 2))
    out = []
    for k in range(n):
        img = bg.copy()
        xy = (start + k * vel) % [w, h]
        for i, (x, y) in enumerate(xy.astype(int)):
            img[y : y + 8, x : x + 14] = 40 + 20 * i
            img[y : y + 8, x + 7 : x + 14] = 200
        noisy = img.astype(np.int16) + rng.integers(-4, 5, img.shape, dtype=np.int16)
        out.append(cv2.cvtColor(np.clip(noisy, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR))
    return out


def synthetic_video(folder: Path) -> tuple[Path, str]:
    """X5 at 320×240 as an MP4 (or the fallback scene); returns (path, description)."""
    path = folder / "x5.mp4"
    try:
        from mvtrack.sim.intersection import x5_intersection
        from mvtrack.sim.render import write_video

        scene = x5_intersection(0)
        write_video(scene, path, seed=0, size=(320, 240), progress=False)
        return path, f"X5 intersection, 320×240, {scene.n_frames} frames (mp4v)"
    except ImportError:
        frames = simple_scene()
        _write(frames, path, 30.0)
        return path, f"moving rectangles, 320×240, {len(frames)} frames (mp4v)"


def run_stage(
    video: Path, stage: str, detector: str, max_frames: int | None = None
) -> tuple[int, float, float]:
    """Frames processed, CPU seconds and wall seconds for one pass of ``stage`` over ``video``."""
    from mvtrack.config import RunSettings
    from mvtrack.video import (
        build_detector,
        build_rescuer,
        build_tracker,
        resolve_settings,
        run_frames,
    )

    with open_source(video, threads=1) as src:
        frames = (frame for _, frame in src)
        settings = resolve_settings(RunSettings(detector=detector, video=False), src.size)
        det = build_detector(settings) if stage != "decode" else None
        tracker = build_tracker(settings, src.fps) if stage in ("track", "track+tm") else None
        rescuer = build_rescuer(settings, tracker, det) if stage == "track+tm" else None
        c0, t0 = time.process_time(), time.perf_counter()
        if tracker is None:
            n = 0
            for frame in frames:
                if max_frames is not None and n >= max_frames:
                    break
                if det is not None:
                    det(frame)
                n += 1
        else:
            n = run_frames(
                frames, det, tracker, rescuer=rescuer, max_frames=max_frames, progress=False
            ).n_frames
        return n, time.process_time() - c0, time.perf_counter() - t0


def bench(
    video: Path, stages: list[str], repeats: int, detector: str
) -> dict[str, tuple[float, float, float]]:
    """Median CPU, median wall and least CPU seconds per stage; repeats interleave the stages
    so that changes of load on the shared machine hit all stages alike."""
    cpu: dict[str, list[float]] = {s: [] for s in stages}
    wall: dict[str, list[float]] = {s: [] for s in stages}
    n_frames = 0
    for s in stages:  # warm-up: lazy imports (SciPy) and first-call costs are not timed
        run_stage(video, s, detector, max_frames=50)
    for _ in range(repeats):
        for s in stages:
            n_frames, c, w = run_stage(video, s, detector)
            cpu[s].append(c)
            wall[s].append(w)
    med = {s: (statistics.median(cpu[s]), statistics.median(wall[s]), min(cpu[s])) for s in stages}
    med["frames"] = (float(n_frames),) * 3
    return med


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--vtest", type=Path, default=VTEST, help="path of vtest.avi")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--detector", default="disturbance-map")
    ap.add_argument("--no-track", action="store_true", help="skip the tracking stage")
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table too")
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)

    stages = ["decode", "detect"]
    if not args.no_track:
        try:
            import mvtrack.tracking  # noqa: F401
        except ImportError:
            print("tracker not available: timing decode + detect only", file=sys.stderr)
        else:
            stages += ["track", "track+tm"]

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        videos = []
        synth, desc = synthetic_video(Path(tmp))
        videos.append((synth, desc))
        if args.vtest.exists():
            videos.append((args.vtest, "vtest.avi, 768×576, 795 frames (XVID)"))
        else:
            print(f"{args.vtest} not found: skipping the real video", file=sys.stderr)
        for video, desc in videos:
            with open_source(video) as src:
                size = src.size
            med = bench(video, stages, args.repeats, args.detector)
            n = med["frames"][0]
            for s in stages:
                speed = n / med[s][0]
                wall_speed = n / med[s][1]
                best = n / med[s][2]
                share = med["decode"][0] / med[s][0]
                rows.append((desc, size, s, speed, wall_speed, share, best))
                target = TARGETS.get(size)
                mark = (
                    ""
                    if target is None or s == "decode"
                    else f"  (target ≥ {target:g}: {'met' if speed >= target else 'NOT met'})"
                )
                print(
                    f"{desc:44s} {s:7s} {speed:7.0f} frames/s CPU ({1e3 / speed:6.2f} ms/frame; "
                    f"best {best:5.0f}), {wall_speed:7.0f} frames/s wall, "
                    f"decode {100 * share:5.1f} %{mark}"
                )
    if args.markdown:
        names = {
            "decode": "decode",
            "detect": "decode + detect",
            "track": "decode + detect + track",
            "track+tm": "decode + detect + track + templates",
        }
        print()
        print(
            "| sequence | stage | frames/s (CPU, median) | ms/frame (CPU) "
            "| frames/s (CPU, best) | frames/s (wall) | decoding share | target |"
        )
        print("|---|---|---:|---:|---:|---:|---:|---:|")
        for desc, size, s, speed, wall_speed, share, best in rows:
            target = TARGETS.get(size)
            t = f"≥ {target:g}" if target and s != "decode" else ""
            print(
                f"| {desc} | {names[s]} | {speed:.0f} | {1e3 / speed:.2f} | {best:.0f} "
                f"| {wall_speed:.0f} | {100 * share:.0f} % | {t} |"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
