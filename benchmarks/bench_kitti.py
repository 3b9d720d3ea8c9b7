"""KITTI-17 end to end: images → front end → the default tracker → MOTA / IDF1.

Each design is a front end; all feed the same tracker, the default preset at 10 fps as the
video pipeline builds it (the online tracker beside a front end knows the image's size), run
offline by
:func:`mvtrack.tracking.track_detections` (backfill and interpolation on). Designs whose
front end takes the tracker's predicted boxes run a first online :class:`Tracker` beside it
(:func:`mvtrack.detection.feedback.detect_with_tracker`); the detections it produced are then
tracked offline.

Scoring as peerbench scores a results file: ground-truth rows whose "consider" flag is 0 are
dropped (a box on such a person is a false positive), a box matches at IoU ≥ 0.5, MOTA and
IDF1 from motmetrics (:func:`mvtrack.eval.evaluate`). ``det R/P`` are the detections' own
recall and precision at IoU ≥ 0.5 (one-to-one), before the tracker.

Usage::

    python benchmarks/bench_kitti.py                       # every design, Markdown to stdout
    python benchmarks/bench_kitti.py --designs scene-two-pass --json out.json
    python benchmarks/bench_kitti.py --speed               # front-end speed, 768×576 and 320×240
    python benchmarks/bench_kitti.py --sensitivity         # one default changed at a time
    python benchmarks/bench_kitti.py --results-dir DIR     # also write each design's results
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from mvtrack.config import RunSettings
from mvtrack.detection import MOG2, DisturbanceMap
from mvtrack.detection.adaptive import GaussianBackground
from mvtrack.detection.feedback import detect_with_tracker, two_pass
from mvtrack.detection.scene_frontend import SceneFrontEnd
from mvtrack.eval import evaluate, iou_matrix
from mvtrack.io.mot import MotTable, read_tracks
from mvtrack.tracking import Tracker, TrackerConfig, track_detections
from mvtrack.types import Detections
from mvtrack.video import build_tracker_config, resolve_settings

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
SEQ = SHARED / "data" / "real" / "KITTI-17"
VTEST = SHARED / "data" / "vtest.avi"
FPS = 10.0
REFERENCE = 320 * 240

#: the figures of the issue, for the table (MOTA, IDF1)
TODAY = {"disturbance-map": (-1.097, 0.014), "mog2": (-0.469, 0.227)}


def tracker_config(size: tuple[int, int], fps: float = FPS) -> TrackerConfig:
    """The tracker configuration the video pipeline builds for a ``size`` video at ``fps``
    (:func:`mvtrack.video.resolve_settings`, :func:`mvtrack.video.build_tracker_config`: the
    default preset; the tracker's settings are in box sizes, the same for any image)."""
    settings = resolve_settings(RunSettings(detector="scene"), size, fps)
    return build_tracker_config(settings, fps)


def online_tracker(size: tuple[int, int], fps: float = FPS) -> Tracker:
    """The online tracker beside a front end, as the video pipeline builds it (it ends a track
    whose prediction leaves the ``size`` image)."""
    return Tracker(tracker_config(size, fps), frame_size=(float(size[0]), float(size[1])))


def load_frames(seq: Path) -> list[np.ndarray]:
    paths = sorted((seq / "img1").glob("*.jpg"))
    if not paths:
        sys.exit(f"bench_kitti: no images in {seq / 'img1'}")
    return [cv2.imread(str(p)) for p in paths]


def considered_gt(seq: Path) -> MotTable:
    """Ground truth without the rows flagged 0 (peerbench's rule)."""
    g = read_tracks(seq / "gt.txt", "gt")
    return g.take(g.conf > 0)


def detection_pr(dets: list[Detections], gt: MotTable) -> tuple[float, float]:
    """Recall and precision of the detections at IoU ≥ 0.5, one-to-one per frame."""
    idx = gt.frame_index(max(len(dets), gt.num_frames))
    tp = n = 0
    for d in dets:
        g = gt.tlwh[idx[d.frame]]
        n += len(d)
        if len(d) and len(g):
            iou = iou_matrix(g, d.tlwh)
            r, c = linear_sum_assignment(-iou)
            tp += int((iou[r, c] >= 0.5).sum())
    return tp / max(len(gt), 1), tp / max(n, 1)


# --------------------------------------------------------------------------- designs
def _plain(make: Callable[[], Any]) -> Callable[[list[np.ndarray], tuple[int, int]], Any]:
    def run(frames: list[np.ndarray], size: tuple[int, int]) -> list[Detections]:
        fe = make()
        return [fe(f, k) for k, f in enumerate(frames)]

    return run


def _scene(
    bootstrap: str, **kw: Any
) -> Callable[[list[np.ndarray], tuple[int, int]], list[Detections]]:
    def run(frames: list[np.ndarray], size: tuple[int, int]) -> list[Detections]:
        bg_kw = kw.get("bg")
        fe_kw = {k: v for k, v in kw.items() if k != "bg"}

        def make() -> SceneFrontEnd:
            bg = None if bg_kw is None else GaussianBackground(**bg_kw)
            return SceneFrontEnd(background=bg, **fe_kw)

        if bootstrap == "two-pass":
            dets, _ = two_pass(frames, make, lambda: online_tracker(size))
            return dets
        fe = make()
        if bootstrap == "clip":
            fe.bootstrap(frames)
        elif bootstrap == "start":
            fe.bootstrap(frames[:20])
        return detect_with_tracker(frames, fe, online_tracker(size))

    return run


def _pixels(size: tuple[int, int]) -> float:
    return size[0] * size[1] / REFERENCE


DESIGNS: dict[str, tuple[str, Callable[..., list[Detections]]]] = {
    "disturbance-map": (
        "paper 1's disturbance map, the pipeline's blob settings (area ≥ 40 s², closing 7)",
        lambda fr, sz: _plain(lambda: DisturbanceMap(min_area=round(40 * _pixels(sz)),
                                                     close_size=7))(fr, sz),
    ),
    "mog2": (
        "OpenCV MOG2 (shadows removed), open 3×3, close 7×7, area ≥ 150",
        _plain(lambda: MOG2(open_size=3, close_size=7, min_area=150)),
    ),
    "gaussian-only": (
        "per-pixel Gaussian, clip median bootstrap, blobs only (no split, no prior)",
        _scene("clip", split=False, reject=False),
    ),
    "scene-online": (
        "scene front end, online: first frame as background, prior learnt as it goes",
        _scene("none"),
    ),
    "scene-start-median": (
        "scene front end, online, median of the first 20 frames",
        _scene("start"),
    ),
    "scene-clip-median": (
        "scene front end, one pass, median of the whole clip",
        _scene("clip"),
    ),
    "scene-two-pass": (
        "scene front end, offline: clip median, prior from a first pass",
        _scene("two-pass"),
    ),
    "scene-two-pass-no-shadows": (
        "as scene-two-pass without shadow removal",
        _scene("two-pass", bg={"shadows": False}),
    ),
    "scene-two-pass-chroma-shadows": (
        "as scene-two-pass, shadows by chromaticity only (no texture test)",
        _scene("two-pass", bg={"shadow_texture": 2.0}),
    ),
    "scene-two-pass-no-jitter": (
        "as scene-two-pass, jitter 0 (each pixel against its own background)",
        _scene("two-pass", bg={"jitter": 0}),
    ),
    "scene-two-pass-no-split": (
        "as scene-two-pass without split/merge and prior rejection",
        _scene("two-pass", split=False, reject=False),
    ),
    "scene-two-pass-hog-verify": (
        "as scene-two-pass, split boxes kept only if HOG's margin ≥ 0",
        _scene("two-pass", verify=0.0),
    ),
}


#: one parameter of the default (scene-two-pass) changed at a time: (label, front-end kwargs)
SENSITIVITY: list[tuple[str, dict[str, Any]]] = [
    ("k_sigma 3.0 (3.5)", {"bg": {"k_sigma": 3.0}}),
    ("k_sigma 4.0", {"bg": {"k_sigma": 4.0}}),
    ("min_diff 12 (18)", {"bg": {"min_diff": 12.0}}),
    ("min_diff 25", {"bg": {"min_diff": 25.0}}),
    ("alpha 0.01 (0.02)", {"bg": {"alpha": 0.01}}),
    ("alpha 0.04", {"bg": {"alpha": 0.04}}),
    ("alpha_slow 0 (0.0005)", {"bg": {"alpha_slow": 0.0}}),
    ("alpha_slow 0.002", {"bg": {"alpha_slow": 0.002}}),
    ("guard on (off)", {"bg": {"guard": True}}),
    ("relative_floor off (on)", {"bg": {"relative_floor": False}}),
    ("trim 0.1 (0.2)", {"trim": 0.1}),
    ("trim 0.3", {"trim": 0.3}),
    ("close_frac 0.1 (0.15)", {"close_frac": 0.1}),
    ("close_frac 0.2", {"close_frac": 0.2}),
    ("wide 1.5 (1.8)", {"split_params": {"wide": 1.5}}),
    ("wide 2.2", {"split_params": {"wide": 2.2}}),
    ("complete 0.8 (0.85)", {"complete": 0.8}),
    ("complete 0.95", {"complete": 0.95}),
    ("complete off", {"complete": None}),
    ("work_pixels 60k (110k)", {"work_pixels": 60_000}),
    ("work_pixels 200k", {"work_pixels": 200_000}),
]


def sensitivity(frames: list[np.ndarray], gt: MotTable) -> list[dict]:
    """The default design with one parameter changed at a time."""
    rows = []
    for label, kw in SENSITIVITY:
        DESIGNS["_sens"] = (label, _scene("two-pass", **kw))
        r = run_design("_sens", frames, gt, None)
        r["design"] = label
        rows.append(r)
        print(f"| {label} | {r['MOTA']:.3f} | {r['IDF1']:.3f} | {r['IDSW']} | {r['FP']} | "
              f"{r['FN']} | {r['det_recall']:.3f} | {r['det_precision']:.3f} |", flush=True)
    del DESIGNS["_sens"]
    return rows


def run_design(name: str, frames: list[np.ndarray], gt: MotTable, out: Path | None) -> dict:
    size = (frames[0].shape[1], frames[0].shape[0])
    t0 = time.perf_counter()
    dets = DESIGNS[name][1](frames, size)
    t_front = time.perf_counter() - t0
    log = track_detections(dets, tracker_config(size))
    pred = MotTable.from_rows(log.to_mot())
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        log.write_mot(out / f"{name}.txt")
    m = evaluate(gt, pred, with_hota=False)
    rec, prec = detection_pr(dets, gt)
    return {
        "design": name,
        "MOTA": m["MOTA"],
        "IDF1": m["IDF1"],
        "IDSW": m["IDSW"],
        "FP": m["FP"],
        "FN": m["FN"],
        "ids": m["num_pred_ids"],
        "det_recall": rec,
        "det_precision": prec,
        "seconds": t_front,
    }


# --------------------------------------------------------------------------- speed
def speed(repeats: int = 3) -> list[dict]:
    """Front-end frames per second on vtest.avi at 768×576 and reduced to 320×240 (one core)."""
    cv2.setNumThreads(1)
    cap = cv2.VideoCapture(str(VTEST))
    raw = []
    t0 = time.perf_counter()
    while len(raw) < 300:
        ok, f = cap.read()
        if not ok:
            break
        raw.append(f)
    decode = (time.perf_counter() - t0) / max(len(raw), 1)
    rows = []
    for label, frames in (
        ("768x576", raw),
        ("320x240", [cv2.resize(f, (320, 240), interpolation=cv2.INTER_AREA) for f in raw]),
    ):
        for name, make in (
            ("scene (default)", lambda: SceneFrontEnd()),
            ("disturbance-map", lambda: DisturbanceMap(close_size=7)),
            ("mog2", lambda: MOG2(close_size=7)),
        ):
            best = math.inf
            for _ in range(repeats):
                fe = make()
                t = time.perf_counter()
                for k, f in enumerate(frames):
                    fe(f, k)
                best = min(best, (time.perf_counter() - t) / len(frames))
            rows.append({"size": label, "front end": name, "ms": 1e3 * best,
                         "frames_per_s": 1.0 / best,
                         "decode_ms": 1e3 * decode if label == "768x576" else None})
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seq", type=Path, default=SEQ)
    ap.add_argument("--designs", nargs="*", default=list(DESIGNS))
    ap.add_argument("--json", type=Path)
    ap.add_argument("--results-dir", type=Path)
    ap.add_argument("--speed", action="store_true", help="front-end speed instead of accuracy")
    ap.add_argument("--sensitivity", action="store_true",
                    help="the default design with one parameter changed at a time")
    args = ap.parse_args(argv)
    if args.sensitivity:
        frames = load_frames(args.seq)
        print("| change | MOTA | IDF1 | IDsw | FP | FN | det R | det P |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
        rows = sensitivity(frames, considered_gt(args.seq))
        if args.json:
            args.json.write_text(json.dumps(rows, indent=1))
        return 0
    if args.speed:
        rows = speed()
        print("| size | front end | ms / frame | frames/s | decode ms / frame |")
        print("|---|---|---:|---:|---:|")
        for r in rows:
            dec = "" if r["decode_ms"] is None else f"{r['decode_ms']:.2f}"
            print(f"| {r['size']} | {r['front end']} | {r['ms']:.2f} "
                  f"| {r['frames_per_s']:.0f} | {dec} |")
        if args.json:
            args.json.write_text(json.dumps(rows, indent=1))
        return 0
    unknown = sorted(set(args.designs) - set(DESIGNS))
    if unknown:
        sys.exit(
            f"bench_kitti: unknown design(s) {', '.join(unknown)}; known: {', '.join(DESIGNS)}"
        )
    frames = load_frames(args.seq)
    gt = considered_gt(args.seq)
    print(f"# KITTI-17 end to end ({len(frames)} frames, {len(gt)} considered gt boxes; "
          f"{platform.python_version()}, OpenCV {cv2.__version__})\n")
    print("| design | MOTA | IDF1 | IDsw | FP | FN | IDs | det R | det P | front end s | what |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    rows = []
    for name in args.designs:
        r = run_design(name, frames, gt, args.results_dir)
        rows.append(r)
        print(f"| {name} | {r['MOTA']:.3f} | {r['IDF1']:.3f} | {r['IDSW']} | {r['FP']} | "
              f"{r['FN']} | {r['ids']} | {r['det_recall']:.3f} | {r['det_precision']:.3f} | "
              f"{r['seconds']:.1f} | {DESIGNS[name][0]} |", flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
