"""Offline video runs: ``mvtrack track CLIP`` online and with ``--offline``, end to end, on the
cars of the four US-101 clips and the people of KITTI-17, at their own frame rate and with
every 2nd, 3rd and 4th frame kept.

For each clip and ``k`` the frames 1, 1+k, 1+2k, … (a folder of links) are tracked with every
default at ``fps / k`` (US-101: 3 fps, KITTI-17: 10 fps), once online and once with
``--offline`` (``mvtrack.video.offline``: confirmed tracks written from their first detection,
every row smoothed), and the boxes or ground truth of the same frames score them:

* US-101 — F1 at IoU 0.5 by ``../shared/data/vehicles/score_boxes.py`` itself (the boxes have no
  identities);
* KITTI-17 — MOTA / IDF1 by :mod:`mvtrack.eval` (peerbench's rules: IoU ≥ 0.5, the ground
  truth's 0-flagged rows dropped).

The time of each run (``summary.json``'s ``seconds``, the loop; offline adds the revision and,
with a video, a second pass to draw it; here ``--no-video``) is printed beside it.

    python benchmarks/bench_offline_video.py [--k 1 2 3 4] [--out docs/bench/offline-video.md]
        [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_framerate as bf

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
VEHICLES = DATA / "vehicles"
KITTI = DATA / "real" / "KITTI-17"
CLIPS = {"US101-1": 3.0, "US101-2": 3.0, "US101-3": 3.0, "US101-4": 3.0}


def frames_folder(images: Path, k: int, dest: Path) -> Path:
    """A folder of links to every k-th image of ``images`` (sorted), renumbered from 1."""
    dest.mkdir(parents=True, exist_ok=True)
    files = sorted(p for p in images.iterdir() if p.suffix.lower() in (".jpg", ".png"))
    for i, p in enumerate(files[::k]):
        os.symlink(p, dest / f"{i + 1:06d}{p.suffix.lower()}")
    return dest


def track(images: Path, fps: float, out: Path, offline: bool) -> dict[str, Any]:
    """``mvtrack track`` with every default (``--no-video``); its summary."""
    cmd = [sys.executable, "-m", "mvtrack", "track", str(images), "--out", str(out),
           "--fps", f"{fps:g}", "--no-video", "--offline" if offline else "--online"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads((out / "summary.json").read_text())


def score_cars(clip: str, k: int, results: Path, work: Path) -> float:
    """F1 at IoU 0.5 by the clip's own scorer on the same frames."""
    seq = work / f"{clip}-seq-{k}"
    seq.mkdir(exist_ok=True)
    for name in ("boxes.txt", "static.txt", "still.txt"):
        bf.subsample(VEHICLES / clip / name, seq / name, k)
    out = subprocess.run([sys.executable, str(VEHICLES / "score_boxes.py"), str(seq),
                          str(results)], capture_output=True, text=True, check=True).stdout
    return float(out.splitlines()[0].split()[3])


def score_people(k: int, results: Path, work: Path) -> tuple[float, float]:
    """MOTA and IDF1 of KITTI-17 on the same frames (the sweep's rules)."""
    gt = work / f"kitti-gt-{k}.txt"
    bf.subsample(KITTI / "gt.txt", gt, k)
    s = bf.score(gt, results)
    return s["MOTA"], s["IDF1"]


def run(ks: list[int]) -> dict[str, Any]:
    res: dict[str, Any] = {"cells": []}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        cells = [(c, fps, VEHICLES / c / "img1") for c, fps in CLIPS.items()]
        cells.append(("KITTI-17", 10.0, KITTI / "img1"))
        for name, fps, images in cells:
            for k in ks:
                folder = frames_folder(images, k, work / f"{name}-img-{k}")
                cell: dict[str, Any] = {"clip": name, "k": k, "fps": fps / k}
                for mode in ("online", "offline"):
                    out = work / f"{name}-{k}-{mode}"
                    summary = track(folder, fps / k, out, mode == "offline")
                    results = out / "results.txt"
                    if name == "KITTI-17":
                        cell[mode] = dict(zip(("MOTA", "IDF1"), score_people(k, results, work),
                                              strict=True))
                    else:
                        cell[mode] = {"F1": score_cars(name, k, results, work)}
                    cell[mode]["seconds"] = summary["seconds"]
                print(json.dumps(cell), file=sys.stderr, flush=True)
                res["cells"].append(cell)
    return res


def markdown(res: dict[str, Any], argv: list[str]) -> str:
    cmd = "python benchmarks/bench_offline_video.py " + " ".join(argv)
    lines = ["# Offline video runs: `mvtrack track --offline` beside the online run", "",
             f"Made by `{cmd.strip()}` (every default; `--no-video`).", "",
             "| clip | k | fps | online | offline | gain | loop s online / offline |",
             "|---|---|---|---|---|---|---|"]
    gains: dict[str, list[float]] = {"cars": [], "MOTA": [], "IDF1": []}
    for c in res["cells"]:
        on, off = c["online"], c["offline"]
        t = f"{on['seconds']:.1f} / {off['seconds']:.1f}"
        if "F1" in on:
            g = off["F1"] - on["F1"]
            gains["cars"].append(g)
            lines.append(f"| {c['clip']} | {c['k']} | {c['fps']:g} | F1 {on['F1']:.3f} | "
                         f"F1 {off['F1']:.3f} | {g:+.3f} | {t} |")
        else:
            gm, gi = off["MOTA"] - on["MOTA"], off["IDF1"] - on["IDF1"]
            gains["MOTA"].append(gm)
            gains["IDF1"].append(gi)
            lines.append(f"| {c['clip']} | {c['k']} | {c['fps']:g} | "
                         f"{on['MOTA']:.3f} / {on['IDF1']:.3f} | "
                         f"{off['MOTA']:.3f} / {off['IDF1']:.3f} | {gm:+.3f} / {gi:+.3f} | {t} |")
    lines += ["", "Mean gain: cars F1 "
              f"{np.mean(gains['cars']):+.3f} over {len(gains['cars'])} cells; KITTI-17 MOTA "
              f"{np.mean(gains['MOTA']):+.3f}, IDF1 {np.mean(gains['IDF1']):+.3f} over "
              f"{len(gains['MOTA'])} cells.", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--k", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--out", default=None, help="write the Markdown page here")
    ap.add_argument("--json", default=None, help="write the figures here")
    args = ap.parse_args(argv)
    if not VEHICLES.is_dir() or not KITTI.is_dir():
        print(f"error: {VEHICLES} or {KITTI} not found", file=sys.stderr)
        return 2
    res = run(args.k)
    text = markdown(res, [a for a in argv if a not in (args.out, args.json, "--out", "--json")])
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
