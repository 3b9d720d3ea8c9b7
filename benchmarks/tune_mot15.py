"""How the score-aware defaults were chosen: a grid, leave-one-sequence-out, sensitivity.

Every configuration of the grid runs online (:meth:`mvtrack.tracking.Tracker.step` over the
frames, the rows each step returns) and offline (:func:`mvtrack.tracking.track_detections`) on
the four MOT15 development sequences of ``../shared/data/real``, only the frame rate given, and
is scored as ``benchmarks/bench_mot15.py`` scores (``mvtrack.eval``, IoU ≥ 0.5, MOT15 ignore
rows dropped). The objective of a configuration on a set of sequences is the mean over those
sequences and both modes of ``(MOTA + IDF1) / 2``.

* **Leave one sequence out**: for each sequence, the configuration best on the other three,
  and its figures on the held-out one.
* **Sensitivity**: from the configuration best on all four, each parameter moved alone over its
  grid values; mean MOTA and IDF1 of both modes.

Usage::

    python benchmarks/tune_mot15.py --json out.json --out docs/bench/mot15-defaults.md
"""

from __future__ import annotations

import argparse
import itertools
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data" / "real"
SEQUENCES = {"TUD-Campus": 25.0, "TUD-Stadtmitte": 25.0, "ADL-Rundle-6": 30.0, "KITTI-17": 10.0}
MODES = ("online", "offline")
#: The grid: every TrackerConfig field named here, over these values.
GRID: dict[str, list[Any]] = {
    "score_high": [None, 0.3, 0.4, 0.5],
    "min_score": [0.0, 0.1, 0.2],
    "confirm_hits": [2, 3],
    "max_coast": [0.3, 0.6],
    "min_track_length": [None, 0.3, 0.6],
}


#: Each tried from the best configuration of the grid, one at a time (not part of the grid).
VARIANTS: dict[str, list[Any]] = {"nms_iou": [0.5, 0.7], "score_scale": ["prob"]}
#: Parameters outside the grid, each moved alone from the defaults (``TrackerConfig()``) over
#: these values, with its own leave-one-sequence-out choice.
FROM_DEFAULTS: dict[str, list[Any]] = {"coast_output": [0.0, 0.04, 0.08, 0.12, 0.2, None]}
#: fields that change only what an offline run writes
OFFLINE_ONLY = ("min_track_length",)


def run_one(overrides: dict[str, Any], work: Path,
            modes: tuple[str, ...] = MODES) -> dict[str, dict[str, float]]:
    """Figures of one configuration: ``{"SEQ|mode": {MOTA, IDF1, IDSW, FP, FN}}``."""
    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.mot import read_detections, write_results
    from mvtrack.tracking import Tracker, TrackLog, preset, track_detections

    out = {}
    for seq, fps in SEQUENCES.items():
        frames = read_detections(DATA / seq / "det.txt")
        config = preset("default", fps=fps, **overrides)
        for mode in modes:
            if mode == "online":
                tracker, log = Tracker(config), TrackLog()
                for d in frames:
                    log.append(tracker.step(d))
            else:
                log = track_detections(frames, config)
            path = write_results(work / f"{seq}-{mode}.txt", log.to_mot(include_coasting=True))
            m = evaluate(DATA / seq / "gt.txt", path, 0.5, ignore="drop", with_hota=False)
            out[f"{seq}|{mode}"] = {k: float(m[k]) for k in ("MOTA", "IDF1", "IDSW", "FP", "FN")}
    return out


def objective(res: dict[str, dict[str, float]], seqs: list[str]) -> float:
    """Mean of (MOTA + IDF1) / 2 over ``seqs`` and both modes."""
    return statistics.fmean(
        (res[f"{s}|{m}"]["MOTA"] + res[f"{s}|{m}"]["IDF1"]) / 2 for s in seqs for m in MODES)


def _valid(cfg: dict[str, Any]) -> bool:
    high = cfg.get("score_high")
    return (high is None and cfg.get("min_score", 0.0) == 0.0) or (
        high is not None and cfg.get("min_score", 0.0) < high)


def grid_configs() -> list[dict[str, Any]]:
    keys = list(GRID)
    configs = [dict(zip(keys, v, strict=True)) for v in itertools.product(*GRID.values())]
    for c in configs:
        c["recover_window"] = c["max_coast"]  # a lost track can be recovered while alive
    return [c for c in configs if _valid(c)]


def _fmt(cfg: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in cfg.items() if k != "recover_window")


def _mean(res: dict[str, dict[str, float]], mode: str, key: str) -> float:
    return statistics.fmean(res[f"{s}|{mode}"][key] for s in SEQUENCES)


def report(entries: list[dict[str, Any]], command: str, seconds: float,
           variants: list[dict[str, Any]] | None = None,
           moved: dict[str, list[dict[str, Any]]] | None = None) -> str:
    seqs = list(SEQUENCES)
    best = max(entries, key=lambda e: objective(e["res"], seqs))
    lines = ["# MOT15: choosing the score-aware defaults", "", f"Command: `{command}` "
             f"({len(entries)} configurations, {seconds:.0f} s). With `--from-json` the grid's "
             "figures are those an earlier `--json` run wrote (the grid takes about 11 minutes "
             "here) and only the variants run again.", "",
             "Objective: mean over the sequences and both modes (online, offline) of "
             "(MOTA + IDF1) / 2; scoring as `benchmarks/bench_mot15.py` (IoU ≥ 0.5, ignore rows "
             "dropped). Grid: " + "; ".join(f"`{k}` ∈ {v}" for k, v in GRID.items())
             + " (`recover_window` = `max_coast`).", "",
             "## Leave one sequence out", "",
             "| held out | chosen on the other three | online MOTA / IDF1 | "
             "offline MOTA / IDF1 |", "|---|---|---|---|"]
    for held in seqs:
        train = [s for s in seqs if s != held]
        pick = max(entries, key=lambda e: objective(e["res"], train))
        r = pick["res"]
        lines.append(f"| {held} | {_fmt(pick['cfg'])} | {r[f'{held}|online']['MOTA']:.3f} / "
                     f"{r[f'{held}|online']['IDF1']:.3f} | {r[f'{held}|offline']['MOTA']:.3f} / "
                     f"{r[f'{held}|offline']['IDF1']:.3f} |")
    from mvtrack.tracking import TrackerConfig

    defaults = TrackerConfig()
    ranked = sorted(entries, key=lambda e: -objective(e["res"], seqs))
    mine = [i for i, e in enumerate(ranked)
            if all(getattr(defaults, k) == v for k, v in e["cfg"].items())]
    lines += ["", f"Best on all four: {_fmt(best['cfg'])} (objective "
              f"{objective(best['res'], seqs):.4f}).", ""]
    if mine:
        e = ranked[mine[0]]
        lines += [f"The defaults (`TrackerConfig()`): {_fmt(e['cfg'])}, objective "
                  f"{objective(e['res'], seqs):.4f}, rank {mine[0] + 1} of {len(ranked)}; "
                  "online MOTA / IDF1 "
                  f"{_mean(e['res'], 'online', 'MOTA'):.3f} / "
                  f"{_mean(e['res'], 'online', 'IDF1'):.3f}, offline "
                  f"{_mean(e['res'], 'offline', 'MOTA'):.3f} / "
                  f"{_mean(e['res'], 'offline', 'IDF1'):.3f}. Where they differ from the best, "
                  "`docs/association.md` says why.", ""]
    lines += ["",
              "## Sensitivity (one parameter moved from the best on all four)", "",
              "| parameter | value | online MOTA | online IDF1 | offline MOTA | offline IDF1 |",
              "|---|---|---:|---:|---:|---:|"]
    for key, values in GRID.items():
        for v in values:
            want = dict(best["cfg"], **{key: v})
            if key == "max_coast":
                want["recover_window"] = v
            hit = [e for e in entries if e["cfg"] == want]
            if not hit:
                continue
            r = hit[0]["res"]
            mark = " (best)" if v == best["cfg"][key] else ""
            lines.append(f"| `{key}` | {v}{mark} | " + " | ".join(
                f"{_mean(r, m, k):.3f}" for m in MODES for k in ("MOTA", "IDF1")) + " |")
    if variants:
        lines += ["", "## Variants of the best (one setting added)", "",
                  "| setting | online MOTA | online IDF1 | offline MOTA | offline IDF1 |",
                  "|---|---:|---:|---:|---:|",
                  "| (none) | " + " | ".join(f"{_mean(best['res'], m, k):.3f}" for m in MODES
                                        for k in ("MOTA", "IDF1")) + " |"]
        for v in variants:
            lines.append(f"| `{v['setting']}` | " + " | ".join(
                f"{_mean(v['res'], m, k):.3f}" for m in MODES for k in ("MOTA", "IDF1")) + " |")
        lines += ["", "`score_scale=prob` reads the raw DPM scores as probabilities (clipped to "
                  "[0, 1]): the scale the automatic calibration exists for."]
    for key, runs in (moved or {}).items():
        from mvtrack.tracking import TrackerConfig as _Config

        now = getattr(_Config(), key)
        lines += ["", f"## `{key}` from the defaults (outside the grid)", "",
                  f"Each value with every other parameter at its default (`{key}` = {now}); "
                  "objective as above.", "",
                  "| value | objective (all four) | online MOTA | online IDF1 | offline MOTA | "
                  "offline IDF1 |", "|---|---:|---:|---:|---:|---:|"]
        for run in runs:
            mark = " (default)" if run["value"] == now else ""
            lines.append(f"| {run['value']}{mark} | {objective(run['res'], seqs):.4f} | "
                         + " | ".join(f"{_mean(run['res'], m, k):.3f}" for m in MODES
                                      for k in ("MOTA", "IDF1")) + " |")
        lines += ["", "| held out | chosen on the other three | held-out online MOTA / IDF1 | "
                  "offline MOTA / IDF1 |", "|---|---|---|---|"]
        picks = []
        for held in seqs:
            train = [x for x in seqs if x != held]
            pick = max(runs, key=lambda r: objective(r["res"], train))
            picks.append(pick["value"])
            r = pick["res"]
            lines.append(f"| {held} | {pick['value']} | {r[f'{held}|online']['MOTA']:.3f} / "
                         f"{r[f'{held}|online']['IDF1']:.3f} | "
                         f"{r[f'{held}|offline']['MOTA']:.3f} / "
                         f"{r[f'{held}|offline']['IDF1']:.3f} |")
        top = max(set(picks), key=picks.count)
        lines += ["", f"Leave-one-out picks {top} in {picks.count(top)} of {len(picks)} folds "
                  f"(the default: {now})."]
    lines += ["", "## Top ten on all four", "",
              "| configuration | objective | online MOTA / IDF1 | offline MOTA / IDF1 |",
              "|---|---:|---|---|"]
    for e in sorted(entries, key=lambda e: -objective(e["res"], seqs))[:10]:
        r = e["res"]
        lines.append(f"| {_fmt(e['cfg'])} | {objective(r, seqs):.4f} | "
                     f"{_mean(r, 'online', 'MOTA'):.3f} / {_mean(r, 'online', 'IDF1'):.3f} | "
                     f"{_mean(r, 'offline', 'MOTA'):.3f} / {_mean(r, 'offline', 'IDF1'):.3f} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", type=Path, help="Write every configuration's figures here.")
    ap.add_argument("--out", type=Path, help="Write the Markdown report here.")
    ap.add_argument("--from-json", type=Path,
                    help="Reuse the grid's figures from an earlier --json; run the variants only.")
    ap.add_argument("--work", type=Path, default=Path("out/tune_mot15"),
                    help="Folder for the results files.")
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        print(f"error: {DATA} not found (the MOT15 development sequences)", file=sys.stderr)
        return 2
    args.work.mkdir(parents=True, exist_ok=True)
    t0, entries = time.perf_counter(), []
    configs = grid_configs()
    if args.from_json:
        entries = json.loads(args.from_json.read_text())
        configs = []
    online: dict[tuple, dict[str, dict[str, float]]] = {}  # online runs ignore OFFLINE_ONLY
    for i, cfg in enumerate(configs, 1):
        key = tuple((k, v) for k, v in cfg.items() if k not in OFFLINE_ONLY)
        if key in online:
            res = {**online[key], **run_one(cfg, args.work, ("offline",))}
        else:
            res = run_one(cfg, args.work)
            online[key] = {k: v for k, v in res.items() if k.endswith("|online")}
        entries.append({"cfg": cfg, "res": res})
        print(f"[{i}/{len(configs)}] {_fmt(cfg)}: objective "
              f"{objective(res, list(SEQUENCES)):.4f}", flush=True)
    best = max(entries, key=lambda e: objective(e["res"], list(SEQUENCES)))
    variants = []
    for key, values in VARIANTS.items():
        for v in values:
            res = run_one({**best["cfg"], key: v}, args.work)
            variants.append({"setting": f"{key}={v}", "res": res})
    moved: dict[str, list[dict[str, Any]]] = {}
    for key, values in FROM_DEFAULTS.items():
        moved[key] = [{"value": v, "res": run_one({key: v}, args.work)} for v in values]
    seconds = time.perf_counter() - t0
    if args.json:
        args.json.write_text(json.dumps(entries, indent=1))
    text = report(entries, "python benchmarks/tune_mot15.py " + " ".join(
        argv if argv is not None else sys.argv[1:]), seconds, variants, moved)
    if args.out:
        args.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
