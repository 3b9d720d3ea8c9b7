"""The frame-rate sweep under detector dropout: is a cell's lead or deficit the tracker's, or
one decision's?

A cell of the sweep (``bench_framerate.py``) is one run on one file, and on a short sequence one
association decision moves IDF1 by several hundredths. Here every cell is run ``--runs`` times,
each on a copy of its detection file with every detection dropped independently with
probability ``--drop`` (run ``r`` draws with seed ``--seed + r``): the detector's
frame-to-frame variability, neutral to every tracker. mvtrack (online and offline, as in the
sweep) and the peers run on the identical copies and are scored with peerbench's rules. Per
cell the page gives each side's mean over the runs (the best peer taken per run and metric)
and in how many runs mvtrack is behind the best peer on MOTA or IDF1: a deficit in every run is
the tracker's; one in a few runs is within what a single decision moves.

Usage::

    python benchmarks/bench_dropout.py --peers-python /work/peers/bin/python \\
        --runs 5 --drop 0.02 --out docs/bench/dropout.md --json benchmarks/data/dropout.json
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_framerate as bf

METRICS = ("MOTA", "IDF1")


def drop_rows(src: Path, dst: Path, p: float, seed: int) -> None:
    """Copy a MOTChallenge detection file, each row dropped with probability ``p``."""
    lines = [line for line in src.read_text().splitlines(keepends=True) if line.strip()]
    keep = np.random.default_rng(seed).random(len(lines)) >= p
    dst.write_text("".join(line for line, k in zip(lines, keep, strict=True) if k))


def dropout(work: Path, python: str, runs: int, p: float, seed: int,
            changes: dict[str, Any] | None = None) -> dict[str, Any]:
    """Every sweep cell ``runs`` times with detections dropped; mvtrack and the peers."""
    out = []
    for cell in bf.cells(work / "cells"):
        for r in range(runs):
            d = work / f"{cell['seq']}-{cell['k']}-{r}"
            d.mkdir(parents=True, exist_ok=True)
            drop_rows(cell["dir"] / "det.txt", d / "det.txt", p, seed + r)
            (d / "gt.txt").write_text((cell["dir"] / "gt.txt").read_text())
            run = dict(cell, dir=d)
            ours = bf.run_mvtrack(run, changes)
            peers = bf.run_peers(python, run)
            out.append({"seq": cell["seq"], "k": cell["k"], "seed": seed + r, "ours": ours,
                        "peers": peers})
            print(f"{cell['seq']} k={cell['k']} seed {seed + r}: online "
                  f"{ours['online']['MOTA']:.3f} / {ours['online']['IDF1']:.3f}, best peer "
                  f"{bf.best_peer(peers)['MOTA']:.3f} / {bf.best_peer(peers)['IDF1']:.3f}",
                  file=sys.stderr, flush=True)
    return {"runs": runs, "drop": p, "seed": seed, "changes": changes or {}, "rows": out}


def summarise(res: dict[str, Any]) -> list[dict[str, Any]]:
    """Per cell: the means over the runs and the runs in which mvtrack is behind."""
    cells: dict[tuple[str, int], list[dict[str, Any]]] = {}
    for row in res["rows"]:
        cells.setdefault((row["seq"], row["k"]), []).append(row)
    out = []
    for (seq, k), rows in cells.items():
        best = [bf.best_peer(r["peers"]) for r in rows]
        entry: dict[str, Any] = {
            "seq": seq, "k": k, "peer": {m: float(np.mean([b[m] for b in best])) for m in METRICS}}
        for mode in bf.MODES:
            entry[mode] = {m: float(np.mean([r["ours"][mode][m] for r in rows])) for m in METRICS}
            behind = [any(r["ours"][mode][m] < b[m] for m in METRICS)
                      for r, b in zip(rows, best, strict=True)]
            entry[mode]["behind"] = int(sum(behind))
        out.append(entry)
    return out


def report(res: dict[str, Any], command: str) -> str:
    """The Markdown page."""
    cells = summarise(res)
    n = res["runs"]

    def fmt(v: dict[str, float], peer: dict[str, float]) -> str:
        parts = [f"**{v[m]:.3f}**" if v[m] < peer[m] else f"{v[m]:.3f}" for m in METRICS]
        return " / ".join(parts)

    lines = [
        "## The sweep under detector dropout",
        "",
        f"Every cell of the frame-rate sweep run {n} times, each detection dropped with "
        f"probability {res['drop']} (seeds {res['seed']}–{res['seed'] + n - 1}); mvtrack and the "
        "peers on the identical copies. Means over the runs (the best peer per run and metric; "
        "**bold**: below the best peer's mean) and the runs in which mvtrack is behind the best "
        "peer on MOTA or IDF1. Made by",
        "",
        f"    {command}",
        "",
        "| sequence | k | online MOTA / IDF1 | runs behind | offline MOTA / IDF1 | runs behind "
        "| best peer MOTA / IDF1 |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in cells:
        lines.append(
            f"| {c['seq']} | {c['k']} | {fmt(c['online'], c['peer'])} | "
            f"{c['online']['behind']} / {n} | {fmt(c['offline'], c['peer'])} | "
            f"{c['offline']['behind']} / {n} | {c['peer']['MOTA']:.3f} / {c['peer']['IDF1']:.3f} |")
    mean = {key: {m: float(np.mean([c[key][m] for c in cells])) for m in METRICS}
            for key in ("online", "offline", "peer")}
    behind = {mode: sum(c[mode]["behind"] for c in cells) for mode in bf.MODES}
    lines.append(
        f"| **mean of {len(cells)}** | | {mean['online']['MOTA']:.3f} / "
        f"{mean['online']['IDF1']:.3f} | {behind['online']} / {n * len(cells)} | "
        f"{mean['offline']['MOTA']:.3f} / {mean['offline']['IDF1']:.3f} | "
        f"{behind['offline']} / {n * len(cells)} | {mean['peer']['MOTA']:.3f} / "
        f"{mean['peer']['IDF1']:.3f} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--peers-python", required=True,
                    help="the peers' interpreter (peerbench's setup.sh)")
    ap.add_argument("--runs", type=int, default=5, help="runs per cell")
    ap.add_argument("--drop", type=float, default=0.02,
                    help="probability that a detection is dropped")
    ap.add_argument("--seed", type=int, default=1, help="seed of the first run")
    ap.add_argument("--changes", default="{}",
                    help="JSON of settings changed for mvtrack (as bench_framerate)")
    args = bf.parse_args(ap, argv)
    if args is None:
        return 2
    if args.runs < 1 or not 0.0 <= args.drop < 1.0:
        print("error: --runs must be at least 1 and --drop in [0, 1)", file=sys.stderr)
        return 2
    try:
        changes = json.loads(args.changes)
    except json.JSONDecodeError as exc:
        print(f"error: --changes is not JSON: {exc}", file=sys.stderr)
        return 2
    command = "python benchmarks/bench_dropout.py " + shlex.join(argv or sys.argv[1:])
    with tempfile.TemporaryDirectory() as tmp:
        res = dropout(Path(tmp), args.peers_python, args.runs, args.drop, args.seed, changes)
    bf.emit(report(res, command), res, args.out, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
