"""MOT15 public detections: mvtrack online and offline beside ten open trackers (peerbench).

For each development sequence of ``../shared/data/real`` (MOTChallenge 2D MOT 2015 train: DPM
detections and ground truth) this runs

* **mvtrack online** — a :class:`mvtrack.tracking.Tracker` stepped over the frames (frame
  rate given), writing the rows each step returns;
* **mvtrack offline** — :func:`mvtrack.tracking.track_detections`, what
  ``mvtrack track-detections DET --fps F`` writes;
* **the peers** — through ``../shared/peerbench`` with its own interpreter (the peers need
  NumPy < 2): ``run_peers.py`` for its table and its timing, and this script in
  ``--dump-peer-outputs`` mode for the peers' boxes, so that they get HOTA too. Without the
  peers' interpreter the recorded table ``benchmarks/data/mot15_peers.json`` is used.

Everything is scored by :mod:`mvtrack.eval` with ``ignore="drop"``, the code path that
equals peerbench's ``metrics.py`` to the last digit (checked here again on every peer whose
output is deterministic): IoU ≥ 0.5, the 0-marked rows of KITTI-17 dropped. Point trackers
(centroid rule) appear with peerbench's figures, marked; they are not like-for-like.

Speed: peerbench times only the tracker's per-frame call, median of its runs. mvtrack's
online time is measured the same way (``Tracker.step`` only, after a warm-up on a throw-away
instance). With the peers installed, ``--speed-rounds R`` interleaves R rounds of
(Rust SORT, C++ SORT, mvtrack online) per sequence and quotes the median ratio.

Usage::

    python benchmarks/bench_mot15.py --peers-python /work/peers-venv/bin/python \\
        --record --out docs/bench/mot15.md
    python benchmarks/bench_mot15.py                 # recorded peer table, mvtrack re-run
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
DATA = REPO.parent / "shared" / "data" / "real"
PEERBENCH = REPO.parent / "shared" / "peerbench"
RECORDED = HERE / "data" / "mot15_peers.json"

#: Development sequences and their frame rates (MOT15 seqinfo).
SEQUENCES: dict[str, float] = {
    "TUD-Campus": 25.0, "TUD-Stadtmitte": 25.0, "ADL-Rundle-6": 30.0, "KITTI-17": 10.0,
}
#: The table's metrics: (key, header, format).
COLUMNS = (("MOTA", "MOTA", ".3f"), ("IDF1", "IDF1", ".3f"), ("HOTA", "HOTA", ".3f"),
           ("IDSW", "IDsw", "d"), ("FP", "FP", "d"), ("FN", "FN", "d"),
           ("ms_per_frame", "ms/frame", ".3f"))
#: peerbench metric → our key (the figures checked for equality).
PEERBENCH_KEYS = {"mota": "MOTA", "idf1": "IDF1", "num_switches": "IDSW",
                  "num_false_positives": "FP", "num_misses": "FN"}
#: Reference trackers of the speed target.
SPEED_PEERS = ("ioutrack-sort", "sort-cpp")


# --------------------------------------------------------------------------- peers' side
# (runs under the peers' interpreter: NumPy only, no mvtrack)


def dump_peer_outputs(det: str, gt: str, fps: float, out_dir: str) -> None:
    """Run every installed box peer as peerbench does and write its MOTChallenge results."""
    import numpy as np

    sys.path.insert(0, str(PEERBENCH))
    import peers  # type: ignore[import-not-found]
    import run_peers  # type: ignore[import-not-found]

    n = max(run_peers.last_frame(gt), run_peers.last_frame(det))
    dets, _ = run_peers.read_dets(det, n)
    gts = run_peers.read_gt(gt, n)
    boxes = np.vstack([d[:, :4] for d in dets] + [b for _, b in gts])
    w, h = int(np.ceil(boxes[:, 2].max())), int(np.ceil(boxes[:, 3].max()))
    os.makedirs(out_dir, exist_ok=True)
    for name, version in peers.available().items():
        cls = peers.ALL_PEERS[name]
        if version.startswith("unavailable") or cls.kind != "box":
            continue
        tracker = cls(fps, w, h)
        rows = []
        for f, d in enumerate(dets, start=1):
            ids, geom = tracker.step(d)
            geom = np.asarray(geom, np.float64).reshape(-1, 4)
            for i, g in zip(np.asarray(ids, np.int64).tolist(), geom, strict=True):
                rows.append(f"{f},{i},{g[0]:.4f},{g[1]:.4f},{g[2] - g[0]:.4f},"
                            f"{g[3] - g[1]:.4f},1,-1,-1,-1")
        with open(os.path.join(out_dir, f"{name}.txt"), "w") as fh:
            fh.write("".join(r + "\n" for r in rows))


# --------------------------------------------------------------------------- mvtrack's side


def run_mvtrack(det: Path, fps: float, out_dir: Path) -> dict[str, dict[str, Any]]:
    """mvtrack online and offline on one sequence; results files and ms per frame."""
    from mvtrack.io.mot import read_detections, write_results
    from mvtrack.tracking import Tracker, TrackLog, preset, track_detections

    frames = read_detections(det)
    config = preset("default", fps=fps)
    warm = Tracker(config)  # warm-up: imports, first-call costs
    for d in frames[:5]:
        warm.step(d)
    runs = {}
    online_ms, offline_ms = [], []
    for _ in range(3):
        tracker, log, total = Tracker(config), TrackLog(), 0.0
        for d in frames:
            t0 = time.perf_counter()
            tf = tracker.step(d)
            total += time.perf_counter() - t0
            log.append(tf)
        online_ms.append(1000.0 * total / len(frames))
        t0 = time.perf_counter()
        offline = track_detections(frames, config)
        offline_ms.append(1000.0 * (time.perf_counter() - t0) / len(frames))
    runs["mvtrack online"] = {
        "file": write_results(out_dir / "online.txt", log.to_mot(include_coasting=True)),
        "ms_per_frame": statistics.median(online_ms), "ms_runs": online_ms,
    }
    runs["mvtrack offline"] = {
        "file": write_results(out_dir / "offline.txt", offline.to_mot(include_coasting=True)),
        "ms_per_frame": statistics.median(offline_ms), "ms_runs": offline_ms,
    }
    return runs


def online_ms(det: Path, fps: float) -> float:
    """Median ms per frame of ``Tracker.step`` over the sequence (3 runs, after a warm-up)."""
    from mvtrack.io.mot import read_detections
    from mvtrack.tracking import Tracker, preset

    frames = read_detections(det)
    config = preset("default", fps=fps)
    per = []
    for run in range(4):
        tracker, total = Tracker(config), 0.0
        for d in frames:
            t0 = time.perf_counter()
            tracker.step(d)
            total += time.perf_counter() - t0
        if run:  # the first run warms up
            per.append(1000.0 * total / len(frames))
    return statistics.median(per)


def score(gt: Path, results: Path, as_given: bool = False) -> dict[str, Any]:
    """The figures of the table, by mvtrack.eval with peerbench's rules (ignore="drop").

    ``as_given``: the boxes are taken as the file has them, without the reader's checks (a
    peer may output inverted boxes, which peerbench scores as they are).
    """
    import numpy as np

    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.mot import MotTable

    pred: Any = results
    if as_given:
        pred = MotTable.from_rows(np.loadtxt(results, delimiter=",", ndmin=2))
    s = evaluate(gt, pred, 0.5, ignore="drop")
    out = {k: s[k] for k in ("MOTA", "IDF1", "HOTA", "DetA", "AssA", "IDSW", "FP", "FN",
                             "num_pred_ids")}
    if s["num_ignored_gt"]:  # the other readings of the ignore flag, for the report
        out["ignore_modes"] = {}
        for mode in ("distractor", "none"):
            m = evaluate(gt, pred, 0.5, ignore=mode, with_hota=False)
            out["ignore_modes"][mode] = {k: m[k] for k in ("MOTA", "IDF1", "FP", "FN")}
    return out


# --------------------------------------------------------------------------- peers, run or recorded


def peers_python(arg: str | None) -> str | None:
    """The peers' interpreter: ``--peers-python``, ``$MVTRACK_PEERS_PYTHON`` or peerbench's
    default location; None when none exists."""
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    for candidate in (arg, os.environ.get("MVTRACK_PEERS_PYTHON"),
                      str(cache / "mvtrack-peers" / "bin" / "python")):
        if candidate and Path(candidate).exists():
            return candidate
    return None


def run_peers(python: str, seq: str, fps: float, work: Path) -> dict[str, Any]:
    """peerbench's table for one sequence, and our scores of the box peers' outputs."""
    det, gt = DATA / seq / "det.txt", DATA / seq / "gt.txt"
    table = work / f"{seq}-peerbench.json"
    cmd = [python, str(PEERBENCH / "run_peers.py"), "--det", str(det), "--gt", str(gt),
           "--fps", str(fps), "--json", str(table)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
    outputs = work / f"{seq}-peers"
    subprocess.run([python, __file__, "--dump-peer-outputs", str(det), str(gt), str(fps),
                    str(outputs)], check=True)
    rows = {}
    for r in json.loads(table.read_text())["rows"]:
        if r.get("error"):
            rows[r["tracker"]] = {"error": r["error"]}
            continue
        acc = r["accuracy"][r["match"]]
        row: dict[str, Any] = {
            "match": r["match"], "ms_per_frame": r["ms_per_frame"],
            "peerbench": {k: acc[k] for k in PEERBENCH_KEYS},
        }
        if r["kind"] == "box":
            ours = score(gt, outputs / f"{r['tracker']}.txt", as_given=True)
            row.update(ours)
            row["same_as_peerbench"] = all(
                ours[v] == acc[k] for k, v in PEERBENCH_KEYS.items()
            )
        else:  # centroid rule: peerbench's figures, no HOTA
            row.update({v: acc[k] for k, v in PEERBENCH_KEYS.items()}, HOTA=None)
        rows[r["tracker"]] = row
    return {"rows": rows, "peerbench_stdout": proc.stdout}


def paired_speed(python: str, rounds: int) -> dict[str, Any]:
    """Interleaved rounds of (each speed peer, mvtrack online) per sequence: ms and ratios."""
    out: dict[str, Any] = {seq: {"mvtrack": [], **{p: [] for p in SPEED_PEERS}}
                           for seq in SEQUENCES}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(rounds):
            for seq, fps in SEQUENCES.items():
                det, gt = DATA / seq / "det.txt", DATA / seq / "gt.txt"
                table = Path(tmp) / "t.json"
                subprocess.run(
                    [python, str(PEERBENCH / "run_peers.py"), "--det", str(det), "--gt",
                     str(gt), "--fps", str(fps), "--trackers", *SPEED_PEERS, "--repeats", "3",
                     "--json", str(table)], capture_output=True, check=True)
                for r in json.loads(table.read_text())["rows"]:
                    out[seq][r["tracker"]].append(r["ms_per_frame"])
                out[seq]["mvtrack"].append(online_ms(det, fps))
    for seq in SEQUENCES:
        m = out[seq]
        for p in SPEED_PEERS:
            ratios = [a / b for a, b in zip(m["mvtrack"], m[p], strict=True)]
            m[f"ratio_vs_{p}"] = statistics.median(ratios)
    return out


# --------------------------------------------------------------------------- eval at scale


def eval_crowd(n: int, work: Path, baseline: Path | None) -> dict[str, Any]:
    """``mvtrack eval`` on the crowd scene with ``n`` targets: wall and CPU seconds, peak RSS.

    The scene and its tracking come from the command line (``mvtrack simulate crowd --n N
    --detections``, ``mvtrack track-detections``); the evaluation runs in a child process,
    measured by the kernel's accounting of that child. With ``baseline`` (a ``src`` folder of
    another checkout) the same command runs on that code too, interleaved.
    """
    import resource

    def run(cmd: list[str], env: dict[str, str] | None = None) -> dict[str, float]:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, env=env)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        return {"wall_s": wall, "cpu_s": cpu, "max_rss_mb": after.ru_maxrss / 1024}

    scene = work / f"crowd{n}"
    exe = [sys.executable, "-m", "mvtrack"]
    subprocess.run([*exe, "simulate", "crowd", "--n", str(n), "--detections", "--out",
                    str(scene)], check=True, capture_output=True)
    subprocess.run([*exe, "track-detections", str(scene / "det.txt"), "--fps", "30", "--out",
                    str(scene / "trk")], check=True, capture_output=True)
    cmd = [*exe, "eval", "--gt", str(scene / "gt.txt"), "--pred", str(scene / "trk" / "det.txt")]
    out: dict[str, Any] = {"n": n, "rows": sum(1 for _ in open(scene / "gt.txt")),
                           "command": "mvtrack eval --gt gt.txt --pred trk/det.txt"}
    # ru_maxrss of RUSAGE_CHILDREN is the largest child so far: the baseline runs last.
    out["after"] = run(cmd)
    if baseline is not None:
        env = {**os.environ, "PYTHONPATH": str(baseline)}
        out["before"] = run(cmd, env)
        rev = subprocess.run(["git", "-C", str(baseline), "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True, check=False)
        out["before"]["commit"] = rev.stdout.strip() or "?"
    return out


# --------------------------------------------------------------------------- report


def _fmt(v: Any, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def table(rows: dict[str, dict[str, Any]]) -> list[str]:
    """Markdown rows: tracker | match | MOTA | IDF1 | HOTA | IDsw | FP | FN | ms/frame."""
    lines = ["| tracker | match | " + " | ".join(h for _, h, _ in COLUMNS) + " |",
             "|---|---|" + "---:|" * len(COLUMNS)]
    for name, r in rows.items():
        if "error" in r:
            lines.append(f"| {name} | error: {r['error']} |" + " |" * len(COLUMNS))
            continue
        match = "*centroid*" if r.get("match") == "centroid" else "iou"
        cells = [_fmt(r.get(k), f) for k, _, f in COLUMNS]
        bold = name.startswith("mvtrack")
        label = f"**{name}**" if bold else name
        lines.append(f"| {label} | {match} | " + " | ".join(cells) + " |")
    return lines


def mean_rows(per_seq: dict[str, dict[str, dict[str, Any]]]) -> dict[str, dict[str, Any]]:
    """Per tracker, the mean over the sequences of each figure (counts as means too)."""
    names = [n for n in next(iter(per_seq.values())) if all(
        n in rows and "error" not in rows[n] for rows in per_seq.values())]
    out = {}
    for n in names:
        rows = [per_seq[s][n] for s in per_seq]
        row: dict[str, Any] = {"match": rows[0].get("match", "iou")}
        for k, _, _ in COLUMNS:
            vals = [r.get(k) for r in rows]
            row[k] = None if any(v is None for v in vals) else statistics.fmean(vals)
        for k in ("IDSW", "FP", "FN"):
            row[k] = None if row[k] is None else round(row[k])
        out[n] = row
    return out


def targets(per_seq: dict[str, dict[str, dict[str, Any]]],
            mean: dict[str, dict[str, Any]]) -> list[str]:
    """Best IoU-scored peer per sequence and on the mean, against mvtrack online/offline."""
    lines = ["| sequence | best peer MOTA | best peer IDF1 | online MOTA | online IDF1 | "
             "offline MOTA | offline IDF1 |", "|---|---|---|---:|---:|---:|---:|"]
    for seq, rows in [*per_seq.items(), ("mean", mean)]:
        peers = {n: r for n, r in rows.items() if not n.startswith("mvtrack")
                 and r.get("match") == "iou" and "error" not in r}
        best = {k: max(peers.items(), key=lambda kv: kv[1][k]) for k in ("MOTA", "IDF1")}
        need = 0.03 if seq == "mean" else 0.0
        cells = [f"{best[k][1][k]:.3f} ({best[k][0]})" for k in ("MOTA", "IDF1")]
        for mode in ("online", "offline"):
            r = rows[f"mvtrack {mode}"]
            for k in ("MOTA", "IDF1"):
                ok = r[k] >= best[k][1][k] + need
                cells.append(f"{r[k]:.3f} {'✓' if ok else '✗'}")
        lines.append(f"| {seq} | " + " | ".join(cells) + " |")
    return lines


def report(result: dict[str, Any], command: str) -> str:
    per_seq, mean = result["per_sequence"], result["mean"]
    env = result["environment"]
    out = [
        "# MOT15 public detections: mvtrack beside the peers", "",
        f"Command: `{command}`", "",
        f"Peers: {result['peers_source']}. Scoring: `mvtrack.eval`, `ignore=\"drop\"` "
        "(MOT15's 0-marked gt rows removed, as the MOT15 devkit, TrackEval and peerbench), "
        "IoU ≥ 0.5; for every deterministic box peer our figures equal peerbench's own "
        f"({result['peerbench_agreement']}). *centroid*: point trackers scored by peerbench's "
        "centroid rule, not like-for-like. ms/frame: the tracker's per-frame call only, median "
        "of 3 runs (peerbench's protocol; mvtrack: `Tracker.step` after a warm-up); offline: "
        "the whole `track_detections` call per frame. mvtrack: preset `default`, only the "
        "frame rate given.", "",
        f"Machine: {env['cpus']} cores shared with other jobs; Python {env['python']}, "
        f"NumPy {env['numpy']}.", "",
    ]
    for seq, rows in per_seq.items():
        out += [f"## {seq} ({SEQUENCES[seq]:g} fps)", "", *table(rows), ""]
    out += ["## Mean over the four sequences", "", *table(mean), "",
            "## Targets (MOTA and IDF1 ≥ the best IoU-scored peer per sequence; ≥ best + 0.03 "
            "on the mean)", "", *targets(per_seq, mean), ""]
    flagged = {seq: rows for seq, rows in per_seq.items()
               if any("ignore_modes" in r for r in rows.values())}
    for seq, rows in flagged.items():
        out += [f"## The ignore flag on {seq} (MOTA / IDF1 / FP under each `--ignore`)", "",
                "| tracker | drop (default) | distractor | none |", "|---|---|---|---|"]
        for name, r in rows.items():
            if "ignore_modes" not in r:
                continue
            cells = [f"{r['MOTA']:.3f} / {r['IDF1']:.3f} / {r['FP']}"] + [
                f"{m['MOTA']:.3f} / {m['IDF1']:.3f} / {m['FP']}"
                for m in r["ignore_modes"].values()]
            out.append(f"| {name} | " + " | ".join(cells) + " |")
        out.append("")
    crowd = result.get("eval_crowd")
    if crowd:
        a = crowd["after"]
        out += [f"## `mvtrack eval` on the crowd scene ({crowd['n']} targets, {crowd['rows']} gt "
                "rows, 300 frames)", "",
                f"`mvtrack simulate crowd --n {crowd['n']} --detections`, then "
                f"`mvtrack track-detections det.txt --fps 30`, then `{crowd['command']}` in a "
                "child process (kernel accounting of the child: CPU = user + system).", "",
                "| code | wall s | CPU s | peak RSS MB |", "|---|---:|---:|---:|",
                f"| this | {a['wall_s']:.1f} | {a['cpu_s']:.1f} | {a['max_rss_mb']:.0f} |"]
        if "before" in crowd:
            b = crowd["before"]
            out.append(f"| before (`--baseline`, commit {b.get('commit', '?')}) | "
                       f"{b['wall_s']:.1f} | {b['cpu_s']:.1f} | {b['max_rss_mb']:.0f} |")
        out.append("")
    speed = result.get("speed")
    if speed:
        out += [f"## Speed, paired ({speed['rounds']} interleaved rounds)", "",
                "| sequence | mvtrack online ms | " + " | ".join(
                    f"{p} ms | ratio vs {p}" for p in SPEED_PEERS) + " |",
                "|---|---:|" + "---:|---:|" * len(SPEED_PEERS)]
        for seq in SEQUENCES:
            m = speed["sequences"][seq]
            cells = [f"{statistics.median(m['mvtrack']):.3f}"]
            for p in SPEED_PEERS:
                cells += [f"{statistics.median(m[p]):.3f}", f"×{m[f'ratio_vs_{p}']:.2f}"]
            out.append(f"| {seq} | " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--peers-python", help="interpreter of the peers' virtualenv")
    ap.add_argument("--record", action="store_true",
                    help=f"write the peers' rows to {RECORDED.relative_to(REPO)}")
    ap.add_argument("--speed-rounds", type=int, default=0,
                    help="interleaved speed rounds against the Rust and C++ SORT (peers needed)")
    ap.add_argument("--eval-crowd", type=int, default=0, metavar="N",
                    help="also time `mvtrack eval` on the crowd scene with N targets")
    ap.add_argument("--baseline", type=Path,
                    help="with --eval-crowd: a src/ folder of older code, timed the same way")
    ap.add_argument("--skip-trackers", action="store_true",
                    help="only the --eval-crowd measurement")
    ap.add_argument("--out", type=Path, help="write the Markdown report here")
    ap.add_argument("--json", type=Path, help="write every figure here")
    ap.add_argument("--dump-peer-outputs", nargs=4, metavar=("DET", "GT", "FPS", "DIR"),
                    help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.dump_peer_outputs:
        det, gt, fps, out_dir = args.dump_peer_outputs
        dump_peer_outputs(det, gt, float(fps), out_dir)
        return 0

    import platform

    import numpy as np

    if args.skip_trackers:
        with tempfile.TemporaryDirectory() as tmp:
            crowd = eval_crowd(args.eval_crowd or 1000, Path(tmp), args.baseline)
        print(json.dumps(crowd, indent=1))
        return 0
    python = peers_python(args.peers_python)
    per_seq: dict[str, dict[str, dict[str, Any]]] = {}
    recorded = json.loads(RECORDED.read_text()) if RECORDED.exists() else None
    peer_rows: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for seq, fps in SEQUENCES.items():
            if python:
                peer_rows[seq] = run_peers(python, seq, fps, work)
                print(peer_rows[seq]["peerbench_stdout"])
            elif recorded:
                peer_rows[seq] = recorded["sequences"][seq]
            else:
                raise SystemExit("no peers' interpreter and no recorded peer table")
            rows = dict(peer_rows[seq]["rows"])
            runs = run_mvtrack(DATA / seq / "det.txt", fps, work / seq)
            for name, run in runs.items():
                rows[name] = {"match": "iou", **score(DATA / seq / "gt.txt", run["file"]),
                              "ms_per_frame": run["ms_per_frame"], "ms_runs": run["ms_runs"]}
            per_seq[seq] = rows
            print(f"{seq}: " + ", ".join(
                f"{n} {r['MOTA']:.3f}/{r['IDF1']:.3f}" for n, r in rows.items()
                if n.startswith("mvtrack")), file=sys.stderr)
    same = [r["same_as_peerbench"] for rows in peer_rows.values()
            for n, r in rows["rows"].items() if "same_as_peerbench" in r and n != "trackpy"]
    result: dict[str, Any] = {
        "per_sequence": per_seq, "mean": mean_rows(per_seq),
        "peers_source": ("run now through ../shared/peerbench" if python else
                         f"recorded table {RECORDED.relative_to(REPO)} "
                         f"({recorded['recorded'] if recorded else '?'})"),
        "peerbench_agreement": f"{sum(same)} of {len(same)} peer rows identical, trackpy "
                               "excluded: its linking varies between runs",
        "environment": {"python": platform.python_version(), "numpy": np.__version__,
                        "cpus": os.cpu_count()},
    }
    if args.eval_crowd:
        with tempfile.TemporaryDirectory() as tmp:
            result["eval_crowd"] = eval_crowd(args.eval_crowd, Path(tmp), args.baseline)
    if python and args.speed_rounds:
        result["speed"] = {"rounds": args.speed_rounds,
                           "sequences": paired_speed(python, args.speed_rounds)}
    if python and args.record:
        RECORDED.parent.mkdir(parents=True, exist_ok=True)
        slim = {seq: {"rows": v["rows"]} for seq, v in peer_rows.items()}
        RECORDED.write_text(json.dumps(
            {"recorded": time.strftime("%Y-%m-%d"), "sequences": slim}, indent=1) + "\n")
    command = "python benchmarks/bench_mot15.py " + " ".join(
        a for a in (argv if argv is not None else sys.argv[1:]))
    text = report(result, command.strip())
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    if args.json:
        args.json.write_text(json.dumps(result, indent=1, default=str) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
