"""Real data: TUD-Campus and TUD-Stadtmitte (the MOTChallenge files shipped inside motmetrics).

Two kinds of detections, tracked offline (:func:`mvtrack.tracking.track_detections`, backfill
and interpolation on) at the sequences' 25 fps and scored against ``gt.txt`` with
:func:`mvtrack.eval.metrics.evaluate` (MOTA and IDF1 by motmetrics at IoU 0.5, HOTA):

* ``test``  — the boxes of motmetrics' ``test.txt`` (an old tracker's output) with the IDs
  dropped and the confidence set to 1;
* ``noisy`` — the ground-truth boxes with 10 % of them dropped and Gaussian noise of 5 % of
  the box size added (σ = 0.05·w on left and width, σ = 0.05·h on top and height), seeded.

Three parts:

* **the grid** — every predictor × distance × assignment rule on top of the default
  configuration (:func:`mvtrack.tracking.default`); a distance other than the default's gets
  its own default gate;
* **the variants** — the default with one change at a time: each setting of
  ``docs/settings.md`` moved up and down, the IMM against its steady filter alone
  (``kalman-cv``), the offline rows (backfill, interpolation, coasting rows), and the papers'
  presets (``paper1``, ``paper2``);
* **the peers** (``--peers-python``) — peerbench's trackers (``../shared/peerbench``, their own
  interpreter) on the same detection files, scored by peerbench (box trackers only).

``--previous FILE`` puts the figures of an earlier version beside today's: the JSON that
version's ``bench_tud.py --json`` wrote (``benchmarks/data/tud-previous.json``: the engine
before the rework, whose default was ``kalman-cv / euclidean / optimal`` with pixel gates).

Usage::

    python benchmarks/bench_tud.py --peers-python /work/peers/bin/python \\
        --previous benchmarks/data/tud-previous.json --out docs/bench/tud.md \\
        --json benchmarks/data/tud.json
    python benchmarks/bench_tud.py --quick          # the default only, to check the wiring

Prints one line per run and writes a Markdown report with every table.
"""

from __future__ import annotations

import argparse
import itertools
import json
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mvtrack.eval.metrics import evaluate
from mvtrack.io.atomic import write_json, write_text
from mvtrack.io.mot import MotTable, read_tracks, write_detections, write_results
from mvtrack.tracking import TrackerConfig, default, preset, track_detections
from mvtrack.types import Detections

SEQUENCES = ("TUD-Campus", "TUD-Stadtmitte")
FPS = 25.0  # both sequences (MOT15 seqinfo)
DET_KINDS = ("test", "noisy")
NOISE = 0.05
DROP = 0.10
ROOT = Path(__file__).resolve().parents[1]
PEERBENCH = ROOT.parent / "shared" / "peerbench"
METRICS = ("MOTA", "IDF1", "HOTA", "IDSW", "FP", "FN")

#: The best peers recorded earlier on this machine on the same detections (MOTA, IDF1); how
#: they were configured was not recorded. ``--peers-python`` measures peerbench's peers now.
RECORDED_PEERS: dict[tuple[str, str], tuple[str, float, float]] = {
    ("TUD-Campus", "test"): ("Stone Soup", 0.599, 0.617),
    ("TUD-Stadtmitte", "test"): ("Stone Soup", 0.587, 0.660),
    ("TUD-Campus", "noisy"): ("supervision ByteTrack", 0.891, 0.943),
    ("TUD-Stadtmitte", "noisy"): ("motpy", 0.937, 0.969),
}


def data_dir() -> Path:
    """motmetrics' shipped data folder."""
    import motmetrics

    return Path(motmetrics.__file__).parent / "data"


def test_table(seq: str) -> MotTable:
    """The boxes of ``test.txt`` (IDs dropped, confidence 1)."""
    table = read_tracks(data_dir() / seq / "test.txt")
    return MotTable(
        table.frame, np.full(len(table), -1), table.tlwh, np.ones(len(table)), table.cls,
        table.visibility,
    )


def noisy_table(gt: MotTable, rng: np.random.Generator) -> MotTable:
    """Ground-truth rows (IDs kept), ``DROP`` of them removed, noise of ``NOISE`` × box size.

    Rows are shuffled within each frame, as a detector would give them.
    """
    keep = rng.random(len(gt)) >= DROP
    g = gt.take(keep)
    wh = g.tlwh[:, 2:]
    scale = np.hstack([wh, wh])  # σ for (left, top, w, h) = NOISE × (w, h, w, h)
    tlwh = g.tlwh + rng.normal(0.0, 1.0, g.tlwh.shape) * NOISE * scale
    tlwh[:, 2:] = np.maximum(tlwh[:, 2:], 1.0)
    order = np.lexsort((rng.random(len(g)), g.frame))
    return MotTable(g.frame[order], g.id[order], tlwh[order], np.ones(len(g)), g.cls[order],
                    g.visibility[order])


def inputs(gts: dict[str, MotTable], seeds: int) -> dict[str, list[list[Detections]]]:
    """The detections of every column (``"seq|kind"``): one run for test.txt, one per seed
    for the noisy ground truth."""
    out: dict[str, list[list[Detections]]] = {}
    for s in SEQUENCES:
        n = gts[s].num_frames
        out[f"{s}|test"] = [test_table(s).to_detections(n)]
        noisy = [noisy_table(gts[s], np.random.default_rng(seed)) for seed in range(seeds)]
        out[f"{s}|noisy"] = [t.to_detections(n) for t in noisy]
    return out


def oracle(seq: str, gt: MotTable, seeds: int) -> dict[str, dict[str, float]]:
    """The detections scored with their true IDs and no tracking: what a tracker that only
    outputs detected boxes could reach at best (``test``: test.txt with its own IDs)."""
    test = evaluate(gt, read_tracks(data_dir() / seq / "test.txt"))
    noisy = [evaluate(gt, noisy_table(gt, np.random.default_rng(s))) for s in range(seeds)]
    return {
        "test": {k: test[k] for k in ("MOTA", "IDF1", "HOTA")},
        "noisy": {k: float(np.mean([n[k] for n in noisy])) for k in ("MOTA", "IDF1", "HOTA")},
    }


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of boxes ``a`` (n, 4) and ``b`` (m, 4), tlwh."""
    lt = np.maximum(a[:, None, :2], b[None, :, :2])
    rb = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    inter = np.prod(np.clip(rb - lt, 0.0, None), axis=2)
    union = np.prod(a[:, 2:], axis=1)[:, None] + np.prod(b[:, 2:], axis=1)[None] - inter
    return inter / union


def test_gaps(seq: str) -> dict[str, Any]:
    """Where test.txt misses ground-truth boxes: inside a target's first..last detected frame
    (a gap a tracker could bridge) or outside it, and the lengths of the inner gaps (frames).
    A ground-truth box counts as detected when a test.txt box overlaps it with IoU >= 0.5
    (one-to-one per frame, Hungarian)."""
    from scipy.optimize import linear_sum_assignment

    gt = read_tracks(data_dir() / seq / "gt.txt", kind="gt")
    test = read_tracks(data_dir() / seq / "test.txt")
    covered: dict[int, set[int]] = {}
    for f in np.unique(gt.frame):
        g, d = gt.frame == f, test.frame == f
        if not d.any():
            continue
        cost = 1.0 - _iou(gt.tlwh[g], test.tlwh[d])
        cost[cost > 0.5] = 9.0
        r, c = linear_sum_assignment(cost)
        for gid in gt.id[g][r[cost[r, c] < 9.0]]:
            covered.setdefault(int(gid), set()).add(int(f))
    inner = outer = 0
    gaps: list[int] = []
    for gid in np.unique(gt.id):
        frames = gt.frame[gt.id == gid]
        cov = sorted(covered.get(int(gid), set()))
        if not cov:
            outer += frames.size
            continue
        inside = (frames > cov[0]) & (frames < cov[-1])
        inner += int(np.sum(inside & ~np.isin(frames, cov)))
        outer += int(np.sum(~inside & ~np.isin(frames, cov)))
        gaps += [b - a - 1 for a, b in itertools.pairwise(cov) if b - a > 1]
    return {"gt": len(gt), "inner": inner, "outer": outer, "gaps": sorted(gaps)}


def missed_people(rows: np.ndarray, gt: MotTable, least: int = 5) -> list[dict[str, Any]]:
    """The ground-truth people that ``rows`` (MOTChallenge results) miss in ``least`` frames
    or more: their ID, first and last missed frame (1-based), and the median over those frames
    of the largest IoU of their box with another person's (are they missed while they overlap
    someone?). Matching one-to-one per frame at IoU >= 0.5, as :func:`test_gaps`."""
    from scipy.optimize import linear_sum_assignment

    pred = MotTable.from_rows(rows)
    missed: dict[int, list[tuple[int, float]]] = {}
    for f in np.unique(gt.frame):
        g, p = gt.frame == f, pred.frame == f
        ok = np.zeros(int(g.sum()), dtype=bool)
        if p.any():
            cost = 1.0 - _iou(gt.tlwh[g], pred.tlwh[p])
            cost[cost > 0.5] = 9.0
            r, c = linear_sum_assignment(cost)
            ok[r[cost[r, c] < 9.0]] = True
        others = _iou(gt.tlwh[g], gt.tlwh[g])
        np.fill_diagonal(others, 0.0)
        for i in np.flatnonzero(~ok):
            missed.setdefault(int(gt.id[g][i]), []).append((int(f) + 1, float(others[i].max())))
    return [{"id": k, "frames": len(v), "first": v[0][0], "last": v[-1][0],
             "overlap": float(np.median([o for _, o in v]))}
            for k, v in sorted(missed.items()) if len(v) >= least]


# ------------------------------------------------------------------------------ configurations


@dataclass(frozen=True)
class Combo:
    """One predictor / distance / assignment rule of the grid."""

    predictor: str
    distance: str
    assign: str

    @property
    def name(self) -> str:
        return f"{self.predictor} / {self.distance} / {self.assign}"


@dataclass(frozen=True)
class Variant:
    """One run of the variants table: a configuration and how its rows are written."""

    label: str
    config: Callable[[], TrackerConfig]
    offline: dict[str, bool] = field(default_factory=dict)
    coasting: bool = True


def default_config() -> TrackerConfig:
    """The tracker's default at the sequences' frame rate."""
    return default(fps=FPS)


def combo_config(combo: Combo) -> TrackerConfig:
    """``combo`` on top of the default; another distance gets its own default gate."""
    base = default_config()
    gate = {} if combo.distance == base.distance else {"gate": None}
    return base.replace(predictor=combo.predictor, distance=combo.distance,
                        assign=combo.assign, **gate)


def default_combo() -> Combo:
    """The tracker's default predictor, distance and assignment rule."""
    c = default_config()
    return Combo(c.predictor, c.distance, c.assign)


def grid() -> list[Combo]:
    """Every predictor × distance × assignment rule."""
    from mvtrack.association import ASSIGN_RULES, DISTANCES
    from mvtrack.filters.predictors import PREDICTORS

    return [Combo(*c) for c in itertools.product(PREDICTORS, DISTANCES, ASSIGN_RULES)]


def _changed(**changes: Any) -> Callable[[], TrackerConfig]:
    return lambda: default_config().replace(**changes)


def _preset(name: str, **kw: Any) -> Callable[[], TrackerConfig]:
    return lambda: preset(name, fps=FPS, **kw)


def variants() -> list[Variant]:
    """The default, then one change at a time (the settings of ``docs/settings.md`` but the
    score thresholds, which change nothing here: every box has the same score)."""
    d = default_config()
    v = [
        Variant("default", _changed()),
        Variant("coasting rows left out of the results", _changed(), coasting=False),
        Variant("no backfill (rows from confirmation on)", _changed(),
                {"backfill_rows": False}),
        Variant("no interpolation of bridged gaps", _changed(), {"interpolate": False}),
        Variant("no relinking of ended tracks", _changed(), {"relink": False}),
        Variant("neither (the online tracker's rows)", _changed(),
                {"backfill_rows": False, "interpolate": False}),
        Variant("predictor kalman-cv (the IMM's steady filter alone)",
                _changed(predictor="kalman-cv")),
        Variant("assign greedy", _changed(assign="greedy")),
        Variant("gate 5.99 (χ² 95 %)", _changed(gate=5.99)),
        Variant("gate 13.8 (χ² 99.9 %)", _changed(gate=13.8)),
    ]
    steps: tuple[tuple[str, tuple[Any, ...]], ...] = (
        ("measurement_noise", (0.05, 0.2)),
        ("accel_noise", (0.5, 2.0)),
        ("manoeuvre_noise", (10.0, 25.0)),
        ("velocity_prior", (0.75, 3.0)),
        ("size_noise", (None, 0.15, 0.4)),
        ("confirm_hits", (1, 3)),
        ("min_misses", (0, 6)),
        ("max_misses", (5, 20)),
        ("lost_std", (None, 0.2, 0.5)),
        ("coast_std", (None, float("inf"))),
        ("birth_iou", (None, 0.5)),
    )
    for name, values in steps:
        for value in values:
            if value == getattr(d, name):
                continue
            v.append(Variant(f"{name} {_value(value)} ({_value(getattr(d, name))})",
                             _changed(**{name: value})))
    v += [
        Variant("preset paper1 (kalman-ca, 20 px circle, nearest)", _preset("paper1")),
        Variant("preset paper1, rls", _preset("paper1", predictor="rls")),
        Variant("preset paper2 (kalman-ca, coupled region, nearest)", _preset("paper2")),
    ]
    return v


def _value(v: Any) -> str:
    if v is None:
        return "None"
    if isinstance(v, float) and v == float("inf"):
        return "inf"
    return f"{v:g}" if isinstance(v, float) else str(v)


# ------------------------------------------------------------------------------------ running


def run_one(config: TrackerConfig, frames: list[Detections], gt: MotTable,
            coasting: bool = True, offline: dict[str, bool] | None = None,
            keep: Path | None = None) -> dict[str, Any]:
    """Track ``frames`` offline with ``config`` and score the rows (``keep``: also write
    them there as a MOTChallenge results file)."""
    t0 = time.perf_counter()
    log = track_detections(frames, config, **(offline or {}))
    seconds = time.perf_counter() - t0
    rows = log.to_mot(include_coasting=coasting)
    if keep is not None:
        write_results(keep, rows)
    scores = evaluate(gt, MotTable.from_rows(rows), iou=0.5)
    return {**{k: scores[k] for k in METRICS},
            "ms_per_frame": 1000.0 * seconds / max(len(frames), 1)}


def _mean(runs: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key in runs[0]:
        values = [r[key] for r in runs if r[key] is not None]
        out[key] = float(np.mean(values)) if values else None
    out["ms_per_frame"] = float(np.median([r["ms_per_frame"] for r in runs]))
    return out


_FAILED = {**dict.fromkeys(METRICS), "ms_per_frame": float("nan")}


def run_column(config: TrackerConfig, runs: list[list[Detections]], gt: MotTable,
               label: str, **kw: Any) -> dict[str, Any]:
    """The mean over the runs of one column; a configuration that cannot run is reported,
    not fatal."""
    try:
        return _mean([run_one(config, frames, gt, **kw) for frames in runs])
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # a configuration that cannot run: "–" in the tables
        print(f"{label}: failed: {exc}", file=sys.stderr)
        return dict(_FAILED)


def run_peers(python: str, gts: dict[str, MotTable], data: dict[str, list[list[Detections]]],
              default_rows: dict[str, list[Path]], work: Path) -> dict[str, Any]:
    """peerbench's trackers on every run of every column (box trackers, IoU-scored); the
    default's results files are scored by peerbench too, as a check of the scoring."""
    out: dict[str, Any] = {}
    for key, runs in data.items():
        seq = key.split("|")[0]
        gt_path = data_dir() / seq / "gt.txt"
        per_run: list[dict[str, dict[str, float]]] = []
        for i, frames in enumerate(runs):
            det = work / f"{key.replace('|', '-')}-{i}.det.txt"
            write_detections(det, frames)
            res = work / f"{key.replace('|', '-')}-{i}.peers.json"
            cmd = [python, str(PEERBENCH / "run_peers.py"), "--det", str(det),
                   "--gt", str(gt_path), "--fps", f"{FPS:g}", "--repeats", "1",
                   "--results", f"mvtrack={default_rows[key][i]}", "--json", str(res)]
            subprocess.run(cmd, check=True, capture_output=True, timeout=3600)
            rows = json.loads(res.read_text())["rows"]
            per_run.append({r["tracker"]: {"MOTA": r["accuracy"]["iou"]["mota"],
                                           "IDF1": r["accuracy"]["iou"]["idf1"]}
                            for r in rows if "iou" in r.get("accuracy", {})})
        names = sorted(set.intersection(*(set(p) for p in per_run)))
        out[key] = {n: {m: float(np.mean([p[n][m] for p in per_run])) for m in ("MOTA", "IDF1")}
                    for n in names}
        print(f"peers {key}: " + ", ".join(
            f"{n} {v['MOTA']:.3f}/{v['IDF1']:.3f}" for n, v in out[key].items()), flush=True)
    return out


# ------------------------------------------------------------------------------------- report


def code_version() -> str:
    """The short commit of the checkout, noting uncommitted changes to the tracker."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--", "src/mvtrack"],
            cwd=ROOT, capture_output=True, text=True, check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return f"{head} (with uncommitted changes to src/mvtrack)" if dirty else head


def _score(r: dict[str, Any]) -> float:
    """Ranking key of one result: MOTA + IDF1 (a failed run ranks last)."""
    if r["MOTA"] is None or r["IDF1"] is None:
        return -np.inf
    return float(r["MOTA"] + r["IDF1"])


def _fmt(x: float | None) -> str:
    return "–" if x is None or not np.isfinite(x) else f"{x:.3f}"


def _pair(r: dict[str, Any] | None) -> str:
    return "–" if r is None else f"{_fmt(r.get('MOTA'))} / {_fmt(r.get('IDF1'))}"


def _diff(a: dict[str, Any] | None, b: dict[str, Any] | None) -> str:
    if a is None or b is None or a.get("MOTA") is None or b.get("MOTA") is None:
        return "–"
    return f"{a['MOTA'] - b['MOTA']:+.3f} / {a['IDF1'] - b['IDF1']:+.3f}"


@dataclass
class Results:
    """Everything one run of this script measured."""

    seeds: int
    grid: dict[str, dict[str, dict[str, Any]]]
    variants: dict[str, dict[str, dict[str, Any]]]
    oracles: dict[str, dict[str, dict[str, float]]]
    gaps: dict[str, dict[str, Any]]
    peers: dict[str, Any] | None
    previous: dict[str, Any] | None
    previous_path: str
    elapsed: float
    missed: dict[str, list[list[dict[str, Any]]]] = field(default_factory=dict)


COLUMNS = [f"{s}|{k}" for k in DET_KINDS for s in SEQUENCES]
LABEL = {f"{s}|{k}": f"{s.removeprefix('TUD-')} {'test.txt' if k == 'test' else 'noisy gt'}"
         for s in SEQUENCES for k in DET_KINDS}


def report(res: Results, combos: list[Combo], command: str) -> str:
    """The Markdown fragment ``docs/bench/tud.md``."""
    dflt = default_combo()
    new = res.grid[dflt.name]
    prev = res.previous or {}
    prev_name = prev.get("default", "")
    prev_default = prev.get("results", {}).get(prev_name)
    prev_code = prev.get("code", "an earlier version")
    lines = [
        "## Real data: TUD-Campus and TUD-Stadtmitte",
        "",
        "Ground truth and `test.txt` are the MOTChallenge files shipped in motmetrics "
        "(`motmetrics/data/`, the same ground truth as `../shared/data/real`). Two kinds of "
        "detections: **test.txt** — the boxes of `test.txt` (an old tracker's output: recall "
        "0.58 / 0.61) with IDs dropped; **noisy gt** — the ground-truth boxes with "
        f"{DROP:.0%} dropped and Gaussian noise of {NOISE:.0%} of the box size on "
        "left/top/width/height "
        f"({'mean of seeds 0..' + str(res.seeds - 1) if res.seeds > 1 else 'seed 0'}). Every "
        "box has the same score, so the score settings (`score_high`, `min_score`, "
        "`confirm_score`) change nothing here. Tracked offline (`track_detections`: backfill, "
        "relinking and interpolation), coasting rows included, at 25 fps; MOTA and IDF1 by "
        "motmetrics at IoU 0.5, HOTA by `mvtrack.eval` (`mvtrack.eval.metrics.evaluate`).",
        "",
        "Command:",
        "",
        "```",
        command,
        "```",
        "",
        f"Measured on a shared 2-core machine (Python {platform.python_version()}, code "
        f"{code_version()}); whole run {res.elapsed / 60:.1f} min.",
        "",
        "### The default beside the previous engine and the peers (MOTA / IDF1)",
        "",
    ]
    if prev_default is not None:
        lines += [
            f"*Previous engine*: the default of code {prev_code}, the last before the tracker "
            f"was rewritten (`{prev_name}` with pixel gates scaled by the box, a second gate, a "
            "recovery stage and a size gate), measured by that version of this script on the "
            f"same detections (`{res.previous_path}`). *Default*: today's "
            f"(`{dflt.name}`, `docs/settings.md`).",
            "",
        ]
    head = ("| sequence, detections | boxes with true IDs | previous engine | default "
            "| default − previous | default HOTA |")
    rule = "|---|---|---|---|---|---|"
    if res.peers:
        head += " best peer (peerbench, this run) | default − peer |"
        rule += "---|---|"
    head += " best peer recorded earlier |"
    rule += "---|"
    lines += [head, rule]
    for s in COLUMNS:
        seq, kind = s.split("|")
        orc = res.oracles[seq][kind]
        pv = None if prev_default is None else prev_default.get(s)
        cells = [LABEL[s], _pair(orc), _pair(pv), _pair(new[s]), _diff(new[s], pv),
                 _fmt(new[s]["HOTA"])]
        if res.peers:
            best = _best_peer(res.peers[s])
            cells += [f"{_pair(best)} ({best['name']})", _diff(new[s], best)]
        name, m, i = RECORDED_PEERS[(seq, kind)]
        cells.append(f"{name} {m:.3f} / {i:.3f}")
        lines.append("| " + " | ".join(cells) + " |")
    lines += [
        "",
        "*Boxes with true IDs*: the input boxes scored with their true identities and no "
        "tracking (for test.txt, its own IDs): what the boxes alone give. "
        + ("*Best peer*: the best of peerbench's box trackers per metric (it may be two "
           "peers), each with its settings of `../shared/peerbench/README.md`, scored by "
           "peerbench (the default's results files scored by peerbench too give "
           + _peer_check(res) + "). " if res.peers else "")
        + "*Recorded earlier*: the best peers of an earlier measurement on this machine, "
        "configuration not recorded.",
    ]
    lines += _findings(res, dflt)
    lines += _variants_table(res, prev)
    lines += _gap_text(res.gaps, res.variants)
    lines += _grid_table(res, combos, dflt, prev)
    return "\n".join(lines) + "\n"


def _best_peer(peers: dict[str, dict[str, float]]) -> dict[str, Any]:
    """The best peer per metric (the default's own results file, ``mvtrack``, left out)."""
    names = [n for n in peers if n != "mvtrack"]
    bm = max(names, key=lambda n: peers[n]["MOTA"])
    bi = max(names, key=lambda n: peers[n]["IDF1"])
    return {"MOTA": peers[bm]["MOTA"], "IDF1": peers[bi]["IDF1"],
            "name": bm if bm == bi else f"{bm}, {bi}"}


def _peer_check(res: Results) -> str:
    if not res.peers:
        return "–"
    same = all(
        abs(res.peers[s]["mvtrack"][m] - res.grid[default_combo().name][s][m]) < 5e-4
        for s in COLUMNS for m in ("MOTA", "IDF1") if "mvtrack" in res.peers[s]
    )
    return "the same MOTA and IDF1 as `mvtrack.eval`" if same else \
        "figures that differ from `mvtrack.eval`'s: see the JSON"


def _findings(res: Results, dflt: Combo) -> list[str]:
    """Where the default gained and lost against the previous engine and the peers, which
    single changes recover a loss, and whom the default misses on the noisy ground truth."""
    prev = res.previous or {}
    pd = prev.get("results", {}).get(prev.get("default", ""))
    new = res.grid[dflt.name]
    out = ["", "**In short.**"]
    worse: list[str] = []
    if pd is not None:
        worse = [s for s in COLUMNS if new[s]["MOTA"] < pd[s]["MOTA"] - 5e-4
                 or new[s]["IDF1"] < pd[s]["IDF1"] - 5e-4]
        better = [s for s in COLUMNS if s not in worse]
        if worse:
            out[-1] += " Against the previous engine the default is **worse** on " + "; ".join(
                f"{LABEL[s]} ({_diff(new[s], pd[s])})" for s in worse) + "."
        if better:
            out[-1] += " At or above it on " + "; ".join(
                f"{LABEL[s]} ({_diff(new[s], pd[s])})" for s in better) + "."
    if res.peers:
        below = [s for s in COLUMNS
                 if new[s]["MOTA"] < _best_peer(res.peers[s])["MOTA"]
                 or new[s]["IDF1"] < _best_peer(res.peers[s])["IDF1"]]
        if below:
            out[-1] += " Below peerbench's best peer on " + "; ".join(
                f"{LABEL[s]} ({_diff(new[s], _best_peer(res.peers[s]))})" for s in below) + "."
        else:
            out[-1] += " At or above peerbench's best peer on every column."
    cv = res.variants.get("predictor kalman-cv (the IMM's steady filter alone)")
    if cv is not None:
        out[-1] += (" The IMM against its steady filter alone (default − kalman-cv): "
                    + "; ".join(f"{LABEL[s]} {_diff(new[s], cv[s])}" for s in COLUMNS) + ".")
    for s in worse:
        fixes = [name for name, r in res.variants.items()
                 if r[s]["MOTA"] is not None and r[s]["MOTA"] >= pd[s]["MOTA"] - 5e-4
                 and r[s]["IDF1"] >= pd[s]["IDF1"] - 5e-4]
        out += ["", f"*{LABEL[s]}*: the single changes of the variants table that reach the "
                "previous engine's figure: " + ("; ".join(
                    f"{f} ({_pair(res.variants[f][s])}, elsewhere "
                    + ", ".join(f"{LABEL[o]} {_diff(res.variants[f][o], new[o])}"
                                for o in COLUMNS if o != s) + ")" for f in fixes)
                    if fixes else "none") + "."]
    for key, runs in res.missed.items():
        people: dict[int, list[dict[str, Any]]] = {}
        for run in runs:
            for m in run:
                people.setdefault(m["id"], []).append(m)
        if not people:
            continue
        out += ["", f"*Whom the default misses on {LABEL[key]}* (ground-truth people missed "
                f"in 5 frames or more of a run, of {len(runs)} runs; the median IoU of their box "
                "with another person's over the missed frames): " + "; ".join(
                    f"person {pid}, {len(ms)} run(s), frames "
                    + ", ".join(f"{m['first']}–{m['last']} ({m['frames']})" for m in ms)
                    + f", IoU {np.median([m['overlap'] for m in ms]):.2f}"
                    for pid, ms in sorted(people.items())) + "."]
        b = default_config().birth_iou
        if b is not None and any(np.median([m["overlap"] for m in ms]) >= b
                                 for ms in people.values()):
            out[-1] += (f" `birth_iou` ({b:g}) refuses a track to a detection left over whose "
                        "box overlaps a live track's by that IoU or more: a person who appears "
                        "overlapping a tracked one is missed until they separate (the "
                        "`birth_iou` rows of the variants table).")
    return out


def _variants_table(res: Results, prev: dict[str, Any]) -> list[str]:
    pd = prev.get("results", {}).get(prev.get("default", ""))
    lines = [
        "",
        "### The default with one change at a time (MOTA / IDF1)",
        "",
        "Each row changes one thing of the default (its value in brackets): the settings of "
        "`docs/settings.md` moved down and up, the IMM against its steady filter alone, the "
        "offline rows, and the papers' presets (their own settings throughout, "
        "`docs/settings.md`). The defaults were chosen on the frame-rate sweep "
        "(`docs/bench/defaults.md`), not on these sequences.",
        "",
        "| variant | " + " | ".join(LABEL[s] for s in COLUMNS) + " |",
        "|---|" + "---|" * len(COLUMNS),
    ]
    if pd is not None:
        lines.append(f"| previous engine ({prev.get('code', '')}) | "
                     + " | ".join(_pair(pd.get(s)) for s in COLUMNS) + " |")
    for name, r in res.variants.items():
        lines.append(f"| {name} | " + " | ".join(_pair(r[s]) for s in COLUMNS) + " |")
    return lines


def _gap_text(gaps: dict[str, dict[str, Any]],
              var: dict[str, dict[str, dict[str, Any]]]) -> list[str]:
    """What test.txt leaves to a tracker."""
    parts = []
    for seq, g in gaps.items():
        parts.append(
            f"{seq.removeprefix('TUD-')}: of {g['gt']} ground-truth boxes, test.txt misses "
            f"{g['inner'] + g['outer']}, {g['inner']} of them inside a target's detected span "
            f"(gaps of {', '.join(str(x) for x in g['gaps'])} frames) and {g['outer']} before "
            "its first or after its last detection"
        )
    return [
        "",
        "### What test.txt leaves to a tracker",
        "",
        "; ".join(parts) + ". Coasting and interpolation bridge the short gaps; the long ones "
        "only a track kept that long could (`max_misses` 20 instead of 10: "
        + ", ".join(f"{LABEL[s]} {_pair(var.get('max_misses 20 (10)', {}).get(s))}"
                    for s in COLUMNS if s.endswith("|test"))
        + "). test.txt's own tracks also drift from one person to the next, and a tracker that "
        "follows its boxes inherits the switch.",
    ]


def _grid_table(res: Results, combos: list[Combo], dflt: Combo,
                prev: dict[str, Any]) -> list[str]:
    old = prev.get("results", {})

    def mean_score(c: Combo) -> float:
        return float(np.mean([_score(res.grid[c.name][s]) for s in COLUMNS]))

    ranked = sorted(combos, key=mean_score, reverse=True)
    lines = [
        "",
        "### Every predictor / distance / assignment rule (MOTA / IDF1 / HOTA), sorted by "
        "mean MOTA + IDF1",
        "",
        "The rest of the configuration is the default; a distance other than `mahalanobis` "
        "has its own default gate (`docs/association.md`); `kalman-ca`, `kalman-coupled`, "
        "`rls` and `structured` keep their own noise in pixels (only `kalman-imm` and "
        "`kalman-cv` scale theirs with the box). *was*: the same combination in the previous "
        "engine (MOTA / IDF1; its other settings were that engine's defaults; `kalman-imm` "
        "did not exist).",
        "",
        "| predictor / distance / assignment | " + " | ".join(LABEL[s] for s in COLUMNS)
        + " | ms/frame |",
        "|---|" + "---|" * (len(COLUMNS) + 1),
    ]
    for c in ranked:
        cells = []
        for s in COLUMNS:
            r = res.grid[c.name][s]
            cell = f"{_fmt(r['MOTA'])} / {_fmt(r['IDF1'])} / {_fmt(r['HOTA'])}"
            was = old.get(c.name, {}).get(s)
            if was is not None:
                cell += f" (was {_pair(was)})"
            cells.append(cell)
        ms = np.nanmedian([res.grid[c.name][s]["ms_per_frame"] for s in COLUMNS])
        mark = " **(default)**" if c == dflt else ""
        lines.append(f"| {c.name}{mark} | " + " | ".join(cells) + f" | {ms:.2f} |")
    return lines


def _line(label: str, key: str, r: dict[str, Any]) -> str:
    return (f"{label:58s} {key:22s} MOTA {_fmt(r['MOTA'])} IDF1 {_fmt(r['IDF1'])} "
            f"HOTA {_fmt(r['HOTA'])} {r['ms_per_frame']:.2f} ms/frame")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="seeds of the noisy detections")
    parser.add_argument("--out", type=Path, default=Path("docs/bench/tud.md"))
    parser.add_argument("--json", type=Path, default=None, help="also write raw figures")
    parser.add_argument("--previous", type=Path, default=None,
                        help="JSON of an earlier version's run, shown beside today's")
    parser.add_argument("--peers-python", default=None,
                        help="the peers' interpreter (peerbench): run them on the same files")
    parser.add_argument("--quick", action="store_true", help="only the default combination")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be >= 1")
    previous = None
    if args.previous is not None:
        try:
            previous = json.loads(args.previous.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            parser.error(f"--previous {args.previous}: {exc}")
    if args.peers_python is not None and not Path(args.peers_python).exists():
        parser.error(f"--peers-python {args.peers_python}: no such interpreter")

    dflt = default_combo()
    combos = [dflt] if args.quick else grid()
    if dflt not in combos:
        combos.insert(0, dflt)
    gts = {s: read_tracks(data_dir() / s / "gt.txt", kind="gt") for s in SEQUENCES}
    data = inputs(gts, args.seeds)

    t0 = time.perf_counter()
    results: dict[str, dict[str, dict[str, Any]]] = {}
    for i, c in enumerate(combos, 1):
        config = combo_config(c)
        results[c.name] = {}
        for key, runs in data.items():
            r = run_column(config, runs, gts[key.split("|")[0]], f"{c.name} {key}")
            results[c.name][key] = r
            print(f"[{i}/{len(combos)}] " + _line(c.name, key, r), flush=True)
    var: dict[str, dict[str, dict[str, Any]]] = {}
    for v in [] if args.quick else variants():
        config = v.config()
        var[v.label] = {
            key: run_column(config, runs, gts[key.split("|")[0]], f"{v.label} {key}",
                            coasting=v.coasting, offline=v.offline)
            for key, runs in data.items()
        }
        print("variant " + v.label + ": " + "  ".join(
            f"{k} {_pair(r)}" for k, r in var[v.label].items()), flush=True)
    missed = {  # who the default misses on the noisy ground truth, run by run
        key: [missed_people(track_detections(frames, combo_config(dflt)).to_mot(),
                            gts[key.split("|")[0]]) for frames in runs]
        for key, runs in data.items() if key.endswith("|noisy")
    }
    peers = None
    if args.peers_python is not None:
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            rows: dict[str, list[Path]] = {}
            for key, runs in data.items():  # the default's results files, for peerbench
                rows[key] = []
                for j, frames in enumerate(runs):
                    path = work / f"{key.replace('|', '-')}-{j}.mvtrack.txt"
                    run_one(combo_config(dflt), frames, gts[key.split("|")[0]], keep=path)
                    rows[key].append(path)
            peers = run_peers(args.peers_python, gts, data, rows, work)
    res = Results(
        seeds=args.seeds, grid=results, variants=var,
        oracles={s: oracle(s, gts[s], args.seeds) for s in SEQUENCES},
        gaps={s: test_gaps(s) for s in SEQUENCES}, peers=peers, previous=previous,
        previous_path=str(args.previous), elapsed=time.perf_counter() - t0, missed=missed,
    )
    if args.json is not None:
        write_json(args.json, {"seeds": args.seeds, "code": code_version(),
                               "default": dflt.name, "results": results, "variants": var,
                               "peers": peers, "missed": missed})
    given = argv if argv is not None else sys.argv[1:]
    command = "python benchmarks/bench_tud.py " + " ".join(given)
    write_text(args.out, report(res, combos, command.strip()))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
