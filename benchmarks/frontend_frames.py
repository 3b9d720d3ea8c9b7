"""Annotated frames of the default real-video front end, and its track statistics.

Runs the scene front end offline (background from the clip's median, size prior from a first
pass; :func:`mvtrack.detection.feedback.two_pass`) with the default tracker as the video pipeline
sets it (:func:`bench_kitti.tracker_config`) on vtest.avi and KITTI-17, writes the chosen
frames with each box, its track ID and its blob flag (plain / merged / split) and the learnt
size prior drawn as a faint ruler (the expected height of a person standing at each of a few
rows), and prints the number of tracks and their median length.

Usage::

    python benchmarks/frontend_frames.py --out docs/images/frontend        # JPEG for the docs
    python benchmarks/frontend_frames.py --out /tmp/frames --ext png
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_kitti import SEQ, VTEST, load_frames, online_tracker, tracker_config
from mvtrack.detection.feedback import detect_with_tracker
from mvtrack.detection.scene_frontend import SceneFrontEnd
from mvtrack.tracking import track_detections

VTEST_FRAMES = (157, 185, 212, 300)
KITTI_FRAMES = (5, 40, 100, 130)
COLOURS = {0: (60, 220, 60), 1: (220, 60, 220), 2: (0, 160, 255)}  # plain, merged, split


def read_video(path: Path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        sys.exit(f"frontend_frames: cannot open {path}")
    frames = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(f)
    return frames


def draw(frame: np.ndarray, rows: np.ndarray, flags: np.ndarray, dets: np.ndarray,
         fe: SceneFrontEnd, label: str) -> np.ndarray:
    """Boxes (colour = flag of the detection they came from), IDs, and the prior's ruler."""
    out = frame.copy()
    w = out.shape[1]
    if fe.prior.ready:  # the ruler: expected height at five foot rows where people were seen
        overlay = out.copy()
        seen = fe.prior._buf[: fe.prior.n_samples, 0]
        for i, yw in enumerate(np.linspace(*np.percentile(seen, [10, 90]), 5)):
            foot = (yw + 0.5) / fe.scale - 0.5
            ph = float(fe.prior.expected([yw])[0, 1]) / fe.scale
            x = 14 + 18 * i
            cv2.line(overlay, (x, int(foot)), (x, int(foot - ph)), (255, 255, 255), 3)
            cv2.line(overlay, (x - 4, int(foot)), (x + 4, int(foot)), (255, 255, 255), 2)
        out = cv2.addWeighted(overlay, 0.45, out, 0.55, 0)
    for r in rows:
        x, y, bw, bh = r[2:6]
        colour = (200, 200, 200)
        if len(dets):
            c = dets[:, :2] + dets[:, 2:] / 2
            d = np.hypot(*(c - (np.array([x, y]) + np.array([bw, bh]) / 2)).T)
            j = int(np.argmin(d))
            if d[j] < 0.25 * max(bw, bh):
                colour = COLOURS[int(flags[j])]
        cv2.rectangle(out, (int(x), int(y)), (int(x + bw), int(y + bh)), colour, 2)
        cv2.putText(out, str(int(r[1])), (int(x), int(y) - 3), cv2.FONT_HERSHEY_SIMPLEX, 0.5,
                    colour, 2)
    cv2.putText(out, label, (w - 230, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 2)
    return out


def run(name: str, frames: list[np.ndarray], fps: float, keep: tuple[int, ...], out: Path,
        ext: str) -> dict:
    """Two passes as :func:`~mvtrack.detection.feedback.two_pass`, recording the second's flags."""
    size = (frames[0].shape[1], frames[0].shape[0])
    first = SceneFrontEnd()
    first.bootstrap(frames)
    detect_with_tracker(frames, first, online_tracker(size, fps))
    fe = SceneFrontEnd(prior=first.prior)
    fe.bootstrap(frames)
    flags: dict[int, np.ndarray] = {}

    def on_frame(k: int, image: np.ndarray, d: object, tf: object) -> None:
        if k in keep:
            flags[k] = fe.flags.copy()

    dets = detect_with_tracker(frames, fe, online_tracker(size, fps), on_frame=on_frame)
    mot = track_detections(dets, tracker_config(size, fps)).to_mot()
    out.mkdir(parents=True, exist_ok=True)
    for k in keep:
        img = draw(frames[k], mot[mot[:, 0] == k + 1], flags[k], dets[k].tlwh, fe,
                   f"{name} frame {k}")
        cv2.imwrite(str(out / f"{name}-{k:04d}.{ext}"), img)
    ids, counts = np.unique(mot[:, 1], return_counts=True)
    return {"sequence": name, "tracks": len(ids),
            "median_track_s": float(np.median(counts) / fps) if len(ids) else 0.0,
            "frames": len(frames)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("docs/images/frontend"))
    ap.add_argument("--ext", default="jpg", choices=("jpg", "png"))
    ap.add_argument("--only", choices=("vtest", "kitti"))
    args = ap.parse_args(argv)
    stats = []
    if args.only in (None, "vtest"):
        stats.append(run("vtest", read_video(VTEST), 10.0, VTEST_FRAMES, args.out, args.ext))
    if args.only in (None, "kitti"):
        stats.append(run("kitti17", load_frames(SEQ), 10.0, KITTI_FRAMES, args.out, args.ext))
    for s in stats:
        print(f"{s['sequence']}: {s['frames']} frames, {s['tracks']} tracks, median track "
              f"{s['median_track_s']:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
