"""The frame-rate sweep: every development sequence at its own frame rate and with every 2nd,
3rd and 4th frame kept, mvtrack online and offline beside the peers, per cell and on the mean.

For each sequence of ``../shared/data/real`` (MOTChallenge 2D MOT 2015 train: DPM detections
and ground truth) and ``k = 1, 2, 3, 4`` the detection and ground-truth files keep frames
1, 1+k, 1+2k, … renumbered (``../shared/peerbench/subsample.py``), and the trackers get the
frame rate ``fps / k``:

* **mvtrack online** — :class:`mvtrack.tracking.Tracker` stepped over the frames, the rows each
  step returns;
* **mvtrack offline** — :func:`mvtrack.tracking.track_detections`, what ``mvtrack
  track-detections DET --fps F`` writes;
* **the peers** — ``run_peers.py`` of ``../shared/peerbench`` with its own interpreter
  (``--peers-python``; the six box trackers of ``sweep-best-peers.tsv``) on the same files;
  without it, the recorded best peer of ``sweep-best-peers.tsv``.

Everything is scored with peerbench's rules (IoU ≥ 0.5, the ground truth's 0-flagged rows
dropped), by :mod:`mvtrack.eval`, which equals peerbench's ``metrics.py``
(``benchmarks/bench_mot15.py`` checks it). Two more modes:

* ``--rules``: every rule of the tracker switched off (or to its plain alternative) one at a
  time, the change of the mean MOTA and IDF1 over the 16 cells, online and offline;
* ``--loo``: the principal settings chosen by leave-one-out over the sequences and over the
  frame rates: for each sequence held out (at all its ``k``) and each ``k`` held out (on every
  sequence), the value of each setting that does best on the other cells, and how the fold's
  choices score on the held-out cells.

``--ks 5 6 8`` runs the sweep at frame rates that no default was chosen on (a check of the
sweep itself; the peers are run, since ``sweep-best-peers.tsv`` records k = 1–4 only).

Usage::

    python benchmarks/bench_framerate.py --peers-python /work/peers/bin/python \\
        --out docs/bench/framerate.md --json benchmarks/data/framerate.json
    git worktree add /tmp/previous e15da75   # the engine before the rewrite
    python benchmarks/bench_framerate.py --peers-python /work/peers/bin/python \\
        --previous-src /tmp/previous --previous-label " (e15da75)" --out ... --json ...
    python benchmarks/bench_framerate.py --rules --out docs/bench/rules.md
    python benchmarks/bench_framerate.py --loo --out docs/bench/defaults.md
    python benchmarks/bench_framerate.py --ks 5 6 8 --peers-python /work/peers/bin/python \\
        --out docs/bench/heldout.md --json benchmarks/data/heldout.json   # frame rates held out
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
SHARED = REPO.parent / "shared"
DATA = SHARED / "data" / "real"
PEERBENCH = SHARED / "peerbench"
#: the development sequences and their frame rates (MOT15 seqinfo)
SEQUENCES = {"TUD-Campus": 25.0, "TUD-Stadtmitte": 25.0, "ADL-Rundle-6": 30.0, "KITTI-17": 10.0}
KS = (1, 2, 3, 4)
#: the peers of sweep-best-peers.tsv (box trackers, IoU-scored)
PEERS = ("sort-py", "ioutrack-sort", "ioutrack-bytetrack", "sv-bytetrack", "norfair-iou",
         "motpy")
MODES = ("online", "offline")


def subsample(src: Path, dst: Path, k: int) -> None:
    """Keep frames 1, 1+k, 1+2k, … of a MOTChallenge file, renumbered (as subsample.py)."""
    with open(src) as fi, open(dst, "w") as fo:
        for line in fi:
            if not line.strip():
                continue
            f, rest = line.split(",", 1)
            f = int(float(f))
            if (f - 1) % k == 0:
                fo.write(f"{(f - 1) // k + 1},{rest}")


def cells(work: Path, seqs: dict[str, float] | None = None,
          ks: tuple[int, ...] = KS) -> list[dict[str, Any]]:
    """The sweep's cells: sequence, k, frame rate and the subsampled files."""
    out = []
    for seq, fps in (seqs or SEQUENCES).items():
        for k in ks:
            d = work / f"{seq}-{k}"
            d.mkdir(parents=True, exist_ok=True)
            subsample(DATA / seq / "det.txt", d / "det.txt", k)
            subsample(DATA / seq / "gt.txt", d / "gt.txt", k)
            out.append({"seq": seq, "k": k, "fps": fps / k, "dir": d})
    return out


def score(gt: Path, results: Any) -> dict[str, float]:
    """MOTA, IDF1 and counts with peerbench's rules."""
    from mvtrack.eval.metrics import evaluate

    s = evaluate(gt, results, 0.5, ignore="drop", with_hota=False)
    return {k: float(s[k]) for k in ("MOTA", "IDF1", "IDSW", "FP", "FN")}


def best_peer(peers: dict[str, dict[str, float]]) -> dict[str, float]:
    """The best peer's figure per metric (not necessarily one peer)."""
    return {m: max(v[m] for v in peers.values()) for m in ("MOTA", "IDF1")}


def run_mvtrack(cell: dict[str, Any], changes: dict[str, Any] | None = None,
                offline: dict[str, bool] | None = None) -> dict[str, dict[str, float]]:
    """mvtrack online and offline on one cell, scored. ``changes`` are fields of
    ``TrackerConfig`` and, named ``module.NAME``, constants of ``mvtrack.tracking.module``
    (set for this run only)."""
    changes = dict(changes or {})
    constants = {k: changes.pop(k) for k in list(changes) if "." in k}
    if constants:
        old = {k: default_value(k) for k in constants}
        try:
            for k, v in constants.items():
                module, attr = k.split(".")
                setattr(importlib.import_module(f"mvtrack.tracking.{module}"), attr, v)
            return run_mvtrack(cell, changes, offline)
        finally:
            for k, v in old.items():
                module, attr = k.split(".")
                setattr(importlib.import_module(f"mvtrack.tracking.{module}"), attr, v)
    from mvtrack.io.mot import MotTable, read_detections
    from mvtrack.tracking import Tracker, TrackLog, preset, track_detections

    frames = read_detections(cell["dir"] / "det.txt")
    config = preset("default", fps=cell["fps"], **changes)
    tracker, log = Tracker(config), TrackLog()
    for d in frames:
        log.append(tracker.step(d))
    online = MotTable.from_rows(log.to_mot())
    off = track_detections(frames, config, **(offline or {}))
    offline_rows = MotTable.from_rows(off.to_mot())
    gt = cell["dir"] / "gt.txt"
    return {"online": score(gt, online), "offline": score(gt, offline_rows)}


def run_peers(python: str, cell: dict[str, Any]) -> dict[str, dict[str, float]]:
    """The six peers on one cell through peerbench (its interpreter, its scoring)."""
    out = cell["dir"] / "peers.json"
    cmd = [python, str(PEERBENCH / "run_peers.py"), "--det", str(cell["dir"] / "det.txt"),
           "--gt", str(cell["dir"] / "gt.txt"), "--fps", str(cell["fps"]), "--repeats", "1",
           "--trackers", *PEERS, "--json", str(out)]
    subprocess.run(cmd, check=True, capture_output=True, timeout=1800)
    rows = json.loads(out.read_text())["rows"]
    return {r["tracker"]: {"MOTA": r["accuracy"]["iou"]["mota"],
                           "IDF1": r["accuracy"]["iou"]["idf1"]}
            for r in rows if "iou" in r.get("accuracy", {})}


def run_previous(src: Path, cell: dict[str, Any]) -> dict[str, float]:
    """An earlier mvtrack's default offline run on one cell: ``python -m mvtrack
    track-detections`` with that checkout's ``src`` first on the path, scored here."""
    out = cell["dir"] / "previous"
    env = {**os.environ, "PYTHONPATH": str(src / "src")}
    cmd = [sys.executable, "-m", "mvtrack", "track-detections", str(cell["dir"] / "det.txt"),
           "--fps", str(cell["fps"]), "--out", str(out)]
    subprocess.run(cmd, check=True, capture_output=True, timeout=1800, env=env)
    (results,) = out.glob("*.txt")
    return score(cell["dir"] / "gt.txt", results)


def recorded_best() -> dict[tuple[str, int], dict[str, float]]:
    """The best peer per cell recorded in ``sweep-best-peers.tsv``."""
    best = {}
    for line in (PEERBENCH / "sweep-best-peers.tsv").read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        seq, k, _, m, i = line.split()
        best[(seq, int(k))] = {"MOTA": float(m), "IDF1": float(i)}
    return best


def sweep(work: Path, python: str | None, previous: Path | None = None,
          previous_recorded: Path | None = None, ks: tuple[int, ...] = KS) -> dict[str, Any]:
    """Every cell: mvtrack online and offline, the peers, the best peer per metric, and an
    earlier version's offline run (run from its checkout ``previous``, or as recorded in the
    JSON ``previous_recorded``). ``ks`` other than the sweep's (frame rates held out from the
    choice of the defaults) need the peers run (``python``)."""
    recorded = recorded_best()
    prev_rec = {}
    if previous_recorded is not None:
        prev_rec = {(r["seq"], r["k"]): r["previous"]
                    for r in json.loads(previous_recorded.read_text())["cells"]}
    result = []
    for cell in cells(work, ks=ks):
        row: dict[str, Any] = {"seq": cell["seq"], "k": cell["k"], "fps": cell["fps"]}
        t0 = time.perf_counter()
        row.update(run_mvtrack(cell))
        row["mvtrack_seconds"] = time.perf_counter() - t0
        if python:
            peers = run_peers(python, cell)
            row["peers"] = peers
            row["best"] = best_peer(peers)
            row["best_of"] = {m: max(peers, key=lambda n, m=m: peers[n][m])
                              for m in ("MOTA", "IDF1")}
        else:
            row["best"] = recorded[(cell["seq"], cell["k"])]
            row["best_of"] = {"MOTA": "recorded", "IDF1": "recorded"}
        if previous is not None:
            row["previous"] = run_previous(previous, cell)
        elif prev_rec:
            row["previous"] = prev_rec[(cell["seq"], cell["k"])]
        result.append(row)
        print(f"{cell['seq']:15s} k={cell['k']} " + " ".join(
            f"{m} {row[m]['MOTA']:.3f}/{row[m]['IDF1']:.3f}" for m in MODES)
            + f"  best peer {row['best']['MOTA']:.3f}/{row['best']['IDF1']:.3f}", flush=True)
    return {"cells": result}


def means(rows: list[dict[str, Any]], key: str) -> tuple[float, float]:
    return (float(np.mean([r[key]["MOTA"] for r in rows])),
            float(np.mean([r[key]["IDF1"] for r in rows])))


def report(res: dict[str, Any], command: str, previous_label: str = "") -> str:
    """The sweep as Markdown."""
    rows = res["cells"]
    prev = all("previous" in r for r in rows)
    held = sorted({r["k"] for r in rows} - set(KS))
    title = ("## The frame-rate sweep: mvtrack beside the peers" if not held else
             "## Frame rates held out: mvtrack beside the peers at k = "
             + ", ".join(map(str, held)))
    lines = [title, "",
             f"Command: `{command}`", "",
             "Each development sequence with every k-th frame kept (frames renumbered, "
             "`--fps fps/k`), the same files for every tracker, scored with peerbench's rules "
             "(IoU ≥ 0.5, the ground truth's 0-flagged rows dropped). Best peer: the best of "
             f"{', '.join(PEERS)} per metric (it may be two different peers). **Bold**: below "
             "the best peer.", "",
             "| sequence | k | fps | online MOTA / IDF1 | offline MOTA / IDF1 | best peer MOTA "
             "/ IDF1 |", "|---|---:|---:|---|---|---|"]
    behind = {m: 0 for m in MODES}

    def fmt(v: dict[str, float], best: dict[str, float], mode: str) -> str:
        parts = []
        lost = False
        for m in ("MOTA", "IDF1"):
            s = f"{v[m]:.3f}"
            if v[m] < best[m] - 1e-4:
                s, lost = f"**{s}**", True
            parts.append(s)
        behind[mode] += lost
        return " / ".join(parts)

    for r in rows:
        best = r["best"]
        names = r.get("best_of", {})
        who = "" if names.get("MOTA") == "recorded" else \
            f" ({names.get('MOTA')}, {names.get('IDF1')})"
        lines.append(f"| {r['seq']} | {r['k']} | {r['fps']:.3g} | "
                     f"{fmt(r['online'], best, 'online')} | "
                     f"{fmt(r['offline'], best, 'offline')} | "
                     f"{best['MOTA']:.3f} / {best['IDF1']:.3f}{who} |")
    on, off, bp = means(rows, "online"), means(rows, "offline"), means(rows, "best")
    lines += [f"| **mean of {len(rows)}** | | | {on[0]:.3f} / {on[1]:.3f} | "
              f"{off[0]:.3f} / {off[1]:.3f} | {bp[0]:.3f} / {bp[1]:.3f} |", "",
              f"Cells behind the best peer on MOTA or IDF1: online {behind['online']}, "
              f"offline {behind['offline']} of {len(rows)}. Mean lead over the best peer: "
              f"online {on[0] - bp[0]:+.3f} / {on[1] - bp[1]:+.3f}, offline "
              f"{off[0] - bp[0]:+.3f} / {off[1] - bp[1]:+.3f}.", ""]
    keys = ["online", "offline", *(["previous"] if prev else []), "best"]
    head = {"online": "online", "offline": "offline",
            "previous": f"previous engine{previous_label}, offline", "best": "best peer"}
    lines += ["Means over the four sequences per frame rate (MOTA / IDF1):", "",
              "| k | " + " | ".join(head[k] for k in keys) + " |",
              "|---:|" + "---|" * len(keys)]
    for k in sorted({r["k"] for r in rows}):
        sub = [r for r in rows if r["k"] == k]
        lines.append(f"| {k} | " + " | ".join(
            "{:.3f} / {:.3f}".format(*means(sub, key)) for key in keys) + " |")
    lines.append("| all | " + " | ".join(
        "{:.3f} / {:.3f}".format(*means(rows, key)) for key in keys) + " |")
    if prev:
        lines += ["", "Previous engine per cell (offline MOTA / IDF1): " + "; ".join(
            f"{r['seq']} k = {r['k']} {r['previous']['MOTA']:.3f} / "
            f"{r['previous']['IDF1']:.3f}" for r in rows) + "."]
    lines.append("")
    return "\n".join(lines)


# --------------------------------------------------------------------------- rules, on / off

#: each rule of the tracker and the configuration without it (one change at a time)
RULES: dict[str, tuple[dict[str, Any], dict[str, bool]]] = {
    "IMM (kalman-imm; off: kalman-cv, the steady model alone)": ({"predictor": "kalman-cv"},
                                                                {}),
    "size term of the gate (size_noise; off: position only)": ({"size_noise": None}, {}),
    "two stages by score (score_high; off: every detection high)": ({"score_high": None}, {}),
    "dropped weak boxes (min_score 0.1; off: 0)": ({"min_score": 0.0}, {}),
    "no birth on a tracked object (birth_iou; off: None)": ({"birth_iou": None}, {}),
    "a weak box shared with another track weighed less (shared_iou 0.4; off: None)": (
        {"shared_iou": None}, {}),
    "confirmation by score (confirm_score 1; off: 0)": ({"confirm_score": 0.0}, {}),
    "loss by uncertainty (lost_std; off: max_misses only)": ({"lost_std": None}, {}),
    "lives through min_misses (3; off: 0)": ({"min_misses": 0}, {}),
    "coasting rows while certain (coast_std 0.05; off: None)": ({"coast_std": None}, {}),
    "backfill (offline)": ({}, {"backfill_rows": False}),
    "interpolation (offline)": ({}, {"interpolate": False}),
    "relinking (offline)": ({}, {"relink": False}),
    "tracks of the weakest boxes left out (offline)": ({}, {"drop_weak_tracks": False}),
    "smoothing (offline)": ({}, {"smooth": False}),
}


#: where a rule under the bar on these cells earns its place (judged where it serves)
SERVES = {
    "IMM (kalman-imm; off: kalman-cv, the steady model alone)": (
        "Vehicles that turn and brake: the paper's intersection X5 end to end (`mvtrack "
        "simulate x5`, `mvtrack track`, `mvtrack eval`) 0.968 / 0.952 with it, 0.757 / 0.685 "
        "with the steady filter alone; `tests/tracking/test_tracker.py::"
        "test_a_turning_vehicle_keeps_its_id_with_the_imm_and_not_with_one_cv_filter`."),
    "lives through min_misses (3; off: 0)": (
        "A detector misses frames, not seconds: without it a walker missed for 3 frames at "
        "5 fps loses its ID (`tests/tracking/test_tracker.py::"
        "test_the_same_motion_keeps_the_same_identities_at_5_10_and_30_fps[5.0]` fails at "
        "`min_misses` 0 and passes at 10 and 30 fps)."),
    "coasting rows while certain (coast_std 0.05; off: None)": (
        "Missed frames of a walker in a group: on TUD-Campus with the boxes of `test.txt` "
        "(`benchmarks/bench_tud.py`, `docs/bench/tud.md`) 0.602 / 0.692 with it, 0.591 / "
        "0.683 without coasting rows and 0.560 / 0.690 with every coasting row."),
}


def rules(work: Path) -> dict[str, Any]:
    """The mean MOTA and IDF1 over the cells with each rule off, against the default."""
    cs = cells(work)
    base = [run_mvtrack(c) for c in cs]
    out = {"default": {m: means(base, m) for m in MODES}, "rules": {}}
    for name, (changes, offline) in RULES.items():
        runs = [run_mvtrack(c, changes, offline) for c in cs]
        out["rules"][name] = {m: means(runs, m) for m in MODES}
        d = {m: np.subtract(out["default"][m], out["rules"][name][m]) for m in MODES}
        print(f"{name}: gain online {d['online'][0]:+.4f}/{d['online'][1]:+.4f} offline "
              f"{d['offline'][0]:+.4f}/{d['offline'][1]:+.4f}", flush=True)
    return out


def rules_report(res: dict[str, Any], command: str) -> str:
    base = res["default"]
    lines = ["## The gain of every rule on the frame-rate sweep", "",
             f"Command: `{command}`", "",
             "Each rule switched off alone (the rest at the default), the mean MOTA and IDF1 "
             "over the 16 cells (4 sequences × every 1st–4th frame). Gain = default minus "
             "without the rule; a rule whose gain is under 0.005 on both metrics in both modes "
             "does not earn its place on these data.", "",
             f"Default: online {base['online'][0]:.3f} / {base['online'][1]:.3f}, offline "
             f"{base['offline'][0]:.3f} / {base['offline'][1]:.3f}.", "",
             "| rule | online gain MOTA / IDF1 | offline gain MOTA / IDF1 |", "|---|---|---|"]
    for name, r in res["rules"].items():
        g = {m: np.subtract(base[m], r[m]) for m in MODES}
        lines.append(f"| {name} | {g['online'][0]:+.3f} / {g['online'][1]:+.3f} | "
                     f"{g['offline'][0]:+.3f} / {g['offline'][1]:+.3f} |")
    under = [name for name, r in res["rules"].items()
             if max(max(np.subtract(base[m], r[m])) for m in MODES) < 0.005]
    lines += ["", "Under the bar here: " + (", ".join(f"*{n}*" for n in under) or "none")
              + ". Where each rule that was under it in a run serves:", ""]
    lines += [f"- *{name}*{' (under the bar in this run)' if name in under else ''}: {why}"
              for name, why in SERVES.items()]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- leave one out

#: how a default was settled beyond the people of the sweep
NOTES = {
    "manoeuvre_noise": (
        "15 since the folds chose it unanimously (it was 25). The video runs were checked "
        "too (`docs/bench/framerate.md`): the paper's intersection is indifferent (83 against "
        "84 of its 90 moving vehicles followed over 5 runs), KITTI-17 end to end and the "
        "US-101 clips' box F1 lose up to 0.016, while the share of track steps that jump "
        "across the road falls (US101-2: 12.5 % to 9.5 %)."),
    "relink.SPEED_STD": (
        "`relink.SPEED_STD` and `relink.MAX_STD` are constants of the offline relinking "
        "(`tracking/relink.py`), not user settings; four designs of it, each judged by a "
        "leave-one-out over a joint grid of the two, are in `docs/bench/framerate.md`."),
    "offline.MIN_MEAN_SCORE": (
        "`offline.MIN_MEAN_SCORE` leaves out the tracks of the weakest boxes in offline runs "
        "(`tracking/offline.py: drop_weak`); the folds choose 0.275 against the other values, "
        "but held out TUD-Stadtmitte is better without the rule at all (0.684 / 0.762 "
        "offline against 0.674 / 0.753 with the offline smoothing): "
        "`docs/bench/framerate.md`."),
    "smooth.SIZE_DRIFT": (
        "`smooth.SIZE_DRIFT` is the random walk of the log box size in the offline smoother "
        "(`tracking/smooth.py`), per √s; the smoother's other noise is the tracker's "
        "`measurement_noise` and `accel_noise`."),
}

#: the principal settings and the values tried (the default among them)
GRID: dict[str, tuple[Any, ...]] = {
    "measurement_noise": (0.07, 0.1, 0.14),
    "accel_noise": (0.5, 1.0, 2.0),
    "manoeuvre_noise": (10.0, 15.0, 25.0, 50.0),
    "velocity_prior": (1.0, 1.5, 3.0),
    "size_noise": (0.15, 0.25, 0.4),
    "lost_std": (0.2, 0.3, 0.5),
    "birth_iou": (0.2, 0.3, 0.5),
    "shared_iou": (0.3, 0.4, 0.5, None),
    "confirm_score": (0.8, 1.0, 1.3),
    "relink.SPEED_STD": (0.2, 0.4, 0.8),
    "relink.MAX_STD": (0.5, 0.7, 1.0),
    "offline.MIN_MEAN_SCORE": (0.2, 0.275, 0.35),
    "smooth.SIZE_DRIFT": (0.05, 0.1, 0.2),
}


def default_value(name: str) -> Any:
    """A setting's default: a field of ``TrackerConfig`` or, named ``module.NAME``, a constant
    of ``mvtrack.tracking.module``."""
    from mvtrack.tracking import TrackerConfig

    if "." in name:
        module, attr = name.split(".")
        return getattr(importlib.import_module(f"mvtrack.tracking.{module}"), attr)
    return getattr(TrackerConfig(), name)


def _objective(runs: list[dict[str, dict[str, float]]]) -> float:
    """The mean of MOTA and IDF1, online and offline."""
    return float(np.mean([r[m][k] for r in runs for m in MODES for k in ("MOTA", "IDF1")]))


def loo(work: Path) -> dict[str, Any]:
    """Leave one out, over the sequences and over the frame rates: for each sequence held out
    (at all its ``k``) and for each ``k`` held out (on every sequence), each setting's best
    value on the other cells (one setting at a time, the others at the default), and how the
    fold's choices together score on the held-out cells beside the default."""
    cs = cells(work)
    cache: dict[tuple[str, Any], list[dict[str, dict[str, float]]]] = {}
    for name, values in GRID.items():
        for v in values:
            cache[(name, v)] = [run_mvtrack(c, {name: v}) for c in cs]
        print(f"grid {name} done", flush=True)
    first = next(iter(GRID))
    base_runs = cache[(first, default_value(first))]
    fold_keys = [("seq", s) for s in SEQUENCES] + [("k", k) for k in KS]
    folds = {}
    for key, held in fold_keys:
        train = [i for i, c in enumerate(cs) if c[key] != held]
        test = [i for i, c in enumerate(cs) if c[key] == held]
        choice = {}
        for name, values in GRID.items():
            scored = {v: _objective([cache[(name, v)][i] for i in train]) for v in values}
            choice[name] = max(scored, key=scored.get)
        chosen = [run_mvtrack(cs[i], choice) for i in test]
        base = [base_runs[i] for i in test]
        label = held if key == "seq" else f"k = {held}"
        folds[label] = {"choice": choice, "held_out_choice": _objective(chosen),
                        "held_out_default": _objective(base),
                        "means_choice": {m: means(chosen, m) for m in MODES},
                        "means_default": {m: means(base, m) for m in MODES},
                        "cells_choice": [{m: r[m] for m in MODES} for r in chosen]}
        print(label, choice, f"{folds[label]['held_out_choice']:.4f} vs default "
              f"{folds[label]['held_out_default']:.4f}", flush=True)
    votes: dict[str, dict[Any, int]] = {name: {} for name in GRID}
    for f in folds.values():
        for name, v in f["choice"].items():
            votes[name][v] = votes[name].get(v, 0) + 1
    return {"folds": folds, "votes": {n: {str(k): c for k, c in v.items()}
                                      for n, v in votes.items()},
            "default": {n: default_value(n) for n in GRID}}


def loo_report(res: dict[str, Any], command: str) -> str:
    n = len(res["folds"])
    lines = ["## Defaults by leave-one-out over the sequences and the frame rates", "",
             f"Command: `{command}`", "",
             "Eight folds: each sequence held out at all four frame rates, and each k held out "
             "on all four sequences. In each fold every principal setting is chosen among the "
             "values below on the other cells (12 of the 16; one setting at a time, the others "
             "at the default; objective: the mean of MOTA and IDF1, online and offline), and "
             "the fold's choices together are scored on the held-out cells beside the "
             "default.", "",
             f"| setting | values tried | default | chosen in the {n} folds |", "|---|---|---|---|"]
    for name, values in GRID.items():
        lines.append(f"| `{name}` | {', '.join(map(str, values))} | {res['default'][name]} | "
                     + ", ".join(f"{v} ×{c}" for v, c in res["votes"][name].items()) + " |")
    lines += ["", "Held-out cells, mean MOTA / IDF1 (objective: the mean of the four):", "",
              "| held out | the fold's choices (those that differ from the default) | "
              "fold's choice: online, offline (objective) | default: online, offline "
              "(objective) |", "|---|---|---|---|"]

    def fmt(means: dict[str, list[float]], obj: float) -> str:
        return (f"{means['online'][0]:.3f} / {means['online'][1]:.3f}, "
                f"{means['offline'][0]:.3f} / {means['offline'][1]:.3f} ({obj:.4f})")

    wins = 0
    for held, f in res["folds"].items():
        diff = {k: v for k, v in f["choice"].items() if v != res["default"][k]}
        wins += f["held_out_default"] >= f["held_out_choice"]
        lines.append(f"| {held} | {diff or 'the default'} | "
                     f"{fmt(f['means_choice'], f['held_out_choice'])} | "
                     f"{fmt(f['means_default'], f['held_out_default'])} |")
    lines += ["", f"The default scores at least as well as the fold's choice on the held-out "
              f"cells in {wins} of the {n} folds."]
    for name, why in NOTES.items():
        lines += ["", f"**`{name}`.** {why}"]
    return "\n".join(lines) + "\n"


def emit(text: str, res: dict[str, Any], out: str | None, json_path: str | None) -> None:
    """Print the Markdown page and write it to ``out`` and the figures to ``json_path``."""
    print(text)
    if out:
        Path(out).write_text(text)
    if json_path:
        Path(json_path).write_text(json.dumps(res, indent=1, default=str))


def parse_args(ap: argparse.ArgumentParser, argv: list[str] | None
               ) -> argparse.Namespace | None:
    """Add ``--out`` and ``--json`` to a benchmark's parser and parse ``argv``; None (after a
    one-line error) when the development sequences are missing."""
    ap.add_argument("--out", default=None, help="write the Markdown page here")
    ap.add_argument("--json", default=None, help="write the figures here")
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        print(f"error: {DATA} not found (the development sequences)", file=sys.stderr)
        return None
    return args


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--peers-python", default=None,
                    help="the peers' interpreter (peerbench's setup.sh); without it the "
                    "recorded best peers of sweep-best-peers.tsv are used")
    ap.add_argument("--rules", action="store_true", help="each rule on / off instead")
    ap.add_argument("--loo", action="store_true",
                    help="leave-one-out over sequences and frame rates instead")
    ap.add_argument("--previous-src", default=None, type=Path,
                    help="a checkout of an earlier mvtrack: its default offline run beside "
                    "today's on every cell")
    ap.add_argument("--previous", default=None, type=Path,
                    help="a JSON of an earlier --previous-src run (its figures reused)")
    ap.add_argument("--previous-label", default="",
                    help="how the earlier version is named in the table, e.g. ' (e15da75)'")
    ap.add_argument("--ks", type=int, nargs="+", default=list(KS),
                    help="keep every k-th frame for each k given (default 1 2 3 4, the sweep; "
                    "others are frame rates held out from the defaults' choice and need "
                    "--peers-python)")
    args = parse_args(ap, argv)
    if args is None:
        return 2
    ks = tuple(args.ks)
    if min(ks) < 1:
        print(f"error: --ks must be positive frame steps, got {min(ks)}", file=sys.stderr)
        return 2
    if ks != KS and (args.rules or args.loo):
        print("error: --ks applies to the sweep, not to --rules or --loo (they use k = 1 2 3 4)",
              file=sys.stderr)
        return 2
    if not set(ks) <= set(KS) and not args.peers_python:
        print("error: --ks beyond 1 2 3 4 has no recorded peers: give --peers-python",
              file=sys.stderr)
        return 2
    command = "python benchmarks/bench_framerate.py " + shlex.join(argv or sys.argv[1:])
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if args.rules:
            res = rules(work)
            text = rules_report(res, command)
        elif args.loo:
            res = loo(work)
            text = loo_report(res, command)
        else:
            res = sweep(work, args.peers_python, args.previous_src, args.previous, ks)
            text = report(res, command, args.previous_label)
    emit(text, res, args.out, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
