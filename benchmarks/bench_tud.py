"""Real data: TUD-Campus and TUD-Stadtmitte (the MOTChallenge files shipped inside motmetrics).

Runs the tracker for every predictor × distance × assignment rule on two kinds of detections:

* ``test``  — the boxes of motmetrics' ``test.txt`` (an old tracker's output) with the IDs
  dropped and the confidence set to 1;
* ``noisy`` — the ground-truth boxes with 10 % of them dropped and Gaussian noise of 5 % of
  the box size added (σ = 0.05·w on left and width, σ = 0.05·h on top and height), seeded.

and scores the results against ``gt.txt`` with :func:`mvtrack.eval.metrics.evaluate` (MOTA,
IDF1 via motmetrics at IoU 0.5, HOTA via TrackEval). Everything except predictor, distance,
assignment is the tracker's default configuration (:func:`mvtrack.tracking.default`) at the
sequences' 25 fps; a distance other than the default's gets its own default gate.

Usage::

    python benchmarks/bench_tud.py [--seeds 3] [--out docs/bench/tud.md] [--json tud.json]
    python benchmarks/bench_tud.py --quick          # defaults only, to check the wiring

Prints one line per run and writes a Markdown report with the full table.
"""

from __future__ import annotations

import argparse
import itertools
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mvtrack.eval.metrics import evaluate
from mvtrack.io.atomic import write_json, write_text
from mvtrack.io.mot import MotTable, read_tracks
from mvtrack.types import Detections

SEQUENCES = ("TUD-Campus", "TUD-Stadtmitte")
FPS = 25.0  # both sequences (MOT15 seqinfo)
DET_KINDS = ("test", "noisy")
NOISE = 0.05
DROP = 0.10

#: Best peers measured on this machine (MOTA, IDF1), from the project's issue.
PEERS: dict[tuple[str, str], tuple[str, float, float]] = {
    ("TUD-Campus", "test"): ("Stone Soup", 0.599, 0.617),
    ("TUD-Stadtmitte", "test"): ("Stone Soup", 0.587, 0.660),
    ("TUD-Campus", "noisy"): ("supervision ByteTrack", 0.891, 0.943),
    ("TUD-Stadtmitte", "noisy"): ("motpy", 0.937, 0.969),
}


def data_dir() -> Path:
    """motmetrics' shipped data folder."""
    import motmetrics

    return Path(motmetrics.__file__).parent / "data"


def test_detections(seq: str, num_frames: int) -> list[Detections]:
    """The boxes of ``test.txt`` as detections (IDs dropped, confidence 1)."""
    table = read_tracks(data_dir() / seq / "test.txt")
    table = MotTable(
        table.frame, np.full(len(table), -1), table.tlwh, np.ones(len(table)), table.cls,
        table.visibility,
    )
    return table.to_detections(num_frames)


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


def noisy_detections(gt: MotTable, rng: np.random.Generator) -> list[Detections]:
    """:func:`noisy_table` as per-frame detections (IDs dropped)."""
    return noisy_table(gt, rng).to_detections(gt.num_frames)


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


#: The defaults before box-size scaling, ``coast_output``, ``backfill``, the size gate and
#: interpolation (code 2a32458).
PREVIOUS_DEFAULT: dict[str, Any] = {
    "size_ref": None, "coast_output": None, "measurement_std": 2.0, "size_weight": 0.0,
    "backfill": False, "size_gate": None, "interpolate": False,
}

#: Sensitivity of the default combination: (label, config changes, coasting rows written).
SENSITIVITY: tuple[tuple[str, dict[str, Any], bool], ...] = (
    ("default", {}, True),
    ("default, coasting rows left out", {}, False),
    ("no interpolation (interpolate = False)", {"interpolate": False}, True),
    ("no backfill (rows from confirmation on, backfill = False)", {"backfill": False}, True),
    ("no size gate (size_gate = None)", {"size_gate": None}, True),
    ("size gate 1.4 (size_gate = 1.4)", {"size_gate": 1.4}, True),
    ("size gate 2 (size_gate = 2, the previous default)", {"size_gate": 2.0}, True),
    ("size gate 2.5 (size_gate = 2.5)", {"size_gate": 2.5}, True),
    ("no recovery stage (recover_speed = None)", {"recover_speed": None}, True),
    ("no recovery margin (recover_margin = 0)", {"recover_margin": 0.0}, True),
    ("recovery margin 1 px (recover_margin = 1)", {"recover_margin": 1.0}, True),
    ("tracks kept 0.5 s (max_coast = 0.5)", {"max_coast": 0.5}, True),
    ("tracks kept 0.8 s (max_coast = 0.8)", {"max_coast": 0.8}, True),
    ("second_gate = 15 px", {"second_gate": 15.0}, True),
    ("no box-size scaling (size_ref = None)", {"size_ref": None}, True),
    ("size_ref = 40 px", {"size_ref": 40.0}, True),
    ("every coasting row output (coast_output = None)", {"coast_output": None}, True),
    ("no box-size term in the cost (size_weight = 0)", {"size_weight": 0.0}, True),
    ("σ_z = 3 px (measurement_std)", {"measurement_std": 3.0}, True),
    ("previous default (σ_z 2 px, no size scaling, size term or size gate, every coasting "
     "row, no backfill or interpolation)", PREVIOUS_DEFAULT, True),
    ("coast 1 s, every coasting row output (filling test.txt's long gaps)",
     {"max_coast": 1.0, "coast_output": None}, True),
    # The best of a 108-point sweep (distance iou/mahalanobis × r × max_coast × coasting rows ×
    # confirm_hits) on these sequences, seed 0, on top of the previous default: tuned on the
    # test data itself (with the previous default it gave 0.521 / 0.542, 0.554 / 0.653,
    # 0.940 / 0.971, 0.982 / 0.991).
    ("iou distance, r = 400 px², confirm_hits 1, max_coast 0.2 s, every coasting row "
     "(the best of an earlier sweep on these sequences)",
     {"distance": "iou", "predictor_params": {"r": 400.0}, "confirm_hits": 1, "max_coast": 0.2,
      "coast_output": None, "interpolate": False}, True),
)


@dataclass(frozen=True)
class Combo:
    """One tracker configuration of the grid."""

    predictor: str
    distance: str
    assign: str

    @property
    def name(self) -> str:
        return f"{self.predictor} / {self.distance} / {self.assign}"


def default_combo() -> Combo:
    """The tracker's default predictor, distance and assignment rule."""
    from mvtrack.tracking import default

    c = default(fps=FPS)
    return Combo(c.predictor, c.distance, c.assign)


def grid() -> list[Combo]:
    """Every predictor × distance × assignment rule."""
    from mvtrack.association import ASSIGN_RULES, DISTANCES
    from mvtrack.filters.predictors import PREDICTORS

    return [Combo(*c) for c in itertools.product(PREDICTORS, DISTANCES, ASSIGN_RULES)]


def run_one(
    combo: Combo, frames: list[Detections], gt: MotTable, coasting: bool = True,
    changes: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Track ``frames`` with ``combo`` on top of the default configuration and score it.

    ``changes`` replaces further fields of the configuration (sensitivity runs).
    """
    from mvtrack.tracking import default, track_detections

    base = default(fps=FPS)
    fields: dict[str, Any] = {
        "predictor": combo.predictor, "distance": combo.distance, "assign": combo.assign,
    }
    if combo.distance != base.distance:
        fields["gate"] = None  # the gate is in the distance's units: use its default
    changes = changes or {}
    if changes.get("distance", base.distance) != base.distance and "gate" not in changes:
        changes = {**changes, "gate": None}
    config = base.replace(**{**fields, **changes})
    t0 = time.perf_counter()
    log = track_detections(frames, config)
    seconds = time.perf_counter() - t0
    rows = log.to_mot(include_coasting=coasting)
    pred = MotTable.from_rows(rows)
    scores = evaluate(gt, pred, iou=0.5)
    return {
        "MOTA": scores["MOTA"], "IDF1": scores["IDF1"], "HOTA": scores["HOTA"],
        "IDSW": scores["IDSW"], "FP": scores["FP"], "FN": scores["FN"],
        "ms_per_frame": 1000.0 * seconds / max(len(frames), 1),
    }


def _mean(runs: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key in runs[0]:
        values = [r[key] for r in runs if r[key] is not None]
        out[key] = float(np.mean(values)) if values else None
    out["ms_per_frame"] = float(np.median([r["ms_per_frame"] for r in runs]))
    return out


def code_version() -> str:
    """``git describe`` of the checkout, noting uncommitted changes to the tracking code."""
    import subprocess

    root = Path(__file__).resolve().parents[1]
    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--", "src/mvtrack/tracking",
             "src/mvtrack/association", "src/mvtrack/filters"],
            cwd=root, capture_output=True, text=True, check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return f"{head} (with uncommitted changes to the tracker)" if dirty else head


def _score(r: dict[str, Any]) -> float:
    """Ranking key of one result: MOTA + IDF1."""
    return float(r["MOTA"] + r["IDF1"])


def _fmt(x: float | None) -> str:
    return "–" if x is None or not np.isfinite(x) else f"{x:.3f}"


def report(
    results: dict[str, dict[str, dict[str, Any]]], combos: list[Combo], default: Combo,
    command: str, seeds: int, elapsed: float, coasting: bool = True,
    oracles: dict[str, dict[str, dict[str, float]]] | None = None,
    sensitivity: dict[str, dict[str, dict[str, Any]]] | None = None,
    gaps: dict[str, dict[str, Any]] | None = None,
) -> str:
    """The Markdown fragment docs/bench/tud.md."""
    settings = [f"{s}|{k}" for k in DET_KINDS for s in SEQUENCES]
    label = {f"{s}|{k}": f"{s.removeprefix('TUD-')} {'test.txt' if k == 'test' else 'noisy gt'}"
             for s in SEQUENCES for k in DET_KINDS}

    def mean_score(c: Combo) -> float:
        return float(np.mean([_score(results[c.name][s]) for s in settings]))

    ranked = sorted(combos, key=mean_score, reverse=True)
    best_overall = ranked[0]
    lines = [
        "## Real data: TUD-Campus and TUD-Stadtmitte",
        "",
        "Ground truth and `test.txt` are the MOTChallenge files shipped in motmetrics "
        "(`motmetrics/data/`). Two kinds of detections: **test.txt** — the boxes of `test.txt` "
        "(an old tracker's output: recall 0.58 / 0.61) with IDs dropped; **noisy gt** — the "
        f"ground-truth boxes with {DROP:.0%} dropped and Gaussian noise of {NOISE:.0%} of the "
        "box size on left/top/width/height "
        f"({'mean of seeds 0..' + str(seeds - 1) if seeds > 1 else 'seed 0'}). "
        "MOTA and IDF1 by motmetrics at IoU 0.5, HOTA by TrackEval "
        "(`mvtrack.eval.metrics.evaluate`). Everything but predictor, distance and assignment "
        "rule is the tracker's default configuration at 25 fps; where the distance differs "
        "from the default's, the gate is that distance's default. Rows of coasting (missed, "
        "predicted) tracks are "
        + ("included in" if coasting else "left out of")
        + " the results.",
        "",
        "Command:",
        "",
        "```",
        command,
        "```",
        "",
        f"Measured on a shared 2-core machine (Python {platform.python_version()}, code "
        f"{code_version()}); "
        f"whole grid {elapsed / 60:.1f} min. Peers: the best of several open-source trackers "
        "measured on this machine on the same detections.",
        "",
        "### Best peer, our default and our best combination (MOTA / IDF1)",
        "",
        "| sequence, detections | detections with true IDs | best peer | ours, default "
        f"({default.name}) | default − peer | ours, best for this column "
        f"| best overall ({best_overall.name}) |",
        "|---|---|---|---|---|---|---|",
    ]
    for s in settings:
        seq, kind = s.split("|")
        peer, p_mota, p_idf1 = PEERS[(seq, kind)]
        d = results[default.name][s]
        best = max(combos, key=lambda c, s=s: _score(results[c.name][s]))
        b = results[best.name][s]
        o = results[best_overall.name][s]
        orc = (oracles or {}).get(seq, {}).get(kind)
        orc_text = "–" if orc is None else f"{_fmt(orc['MOTA'])} / {_fmt(orc['IDF1'])}"
        lines.append(
            f"| {label[s]} | {orc_text} | {peer} {p_mota:.3f} / {p_idf1:.3f} "
            f"| {_fmt(d['MOTA'])} / {_fmt(d['IDF1'])} "
            f"| {d['MOTA'] - p_mota:+.3f} / {d['IDF1'] - p_idf1:+.3f} "
            f"| {_fmt(b['MOTA'])} / {_fmt(b['IDF1'])} ({best.name}) "
            f"| {_fmt(o['MOTA'])} / {_fmt(o['IDF1'])} |"
        )
    lines += [
        "",
        "*Detections with true IDs*: the input boxes scored with their true identities and no "
        "tracking (for test.txt, its own IDs) — a reference for what the boxes alone give.",
    ]
    lines += _summary(results[default.name], settings, label)
    lines += _chosen_text()
    if gaps:
        lines += _gap_text(gaps, sensitivity)
    if sensitivity:
        lines += [
            "",
            f"### Sensitivity of the default combination ({default.name})",
            "",
            "One change at a time to the default (MOTA / IDF1, same detections as above). The "
            "last row is the best of an earlier sweep on these very sequences (on top of the "
            "previous default, where it gave 0.521 / 0.542, 0.554 / 0.653, 0.940 / 0.971 and "
            "0.982 / 0.991), kept for reference.",
            "",
            "| setting | " + " | ".join(label[s] for s in settings) + " |",
            "|---|" + "---|" * len(settings),
        ]
        for name, res in sensitivity.items():
            cells = [f"{_fmt(res[s]['MOTA'])} / {_fmt(res[s]['IDF1'])}" for s in settings]
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "### Every combination (MOTA / IDF1 / HOTA), sorted by mean MOTA + IDF1",
        "",
        "| predictor / distance / assignment | " + " | ".join(label[s] for s in settings)
        + " | ms/frame |",
        "|---|" + "---|" * (len(settings) + 1),
    ]
    for c in ranked:
        cells = [
            f"{_fmt(results[c.name][s]['MOTA'])} / {_fmt(results[c.name][s]['IDF1'])} / "
            f"{_fmt(results[c.name][s]['HOTA'])}"
            for s in settings
        ]
        ms = np.median([results[c.name][s]["ms_per_frame"] for s in settings])
        mark = " **(default)**" if c == default else ""
        lines.append(f"| {c.name}{mark} | " + " | ".join(cells) + f" | {ms:.2f} |")
    return "\n".join(lines) + "\n"


def _summary(
    d: dict[str, dict[str, Any]], settings: list[str], label: dict[str, str]
) -> list[str]:
    """One paragraph: where the default beats the best peer and where it stays below."""
    above, below = [], []
    for s in settings:
        _, p_mota, p_idf1 = PEERS[tuple(s.split("|"))]  # type: ignore[index]
        dm, di = d[s]["MOTA"] - p_mota, d[s]["IDF1"] - p_idf1
        text = f"{label[s]} {dm:+.3f} / {di:+.3f}"
        (above if dm >= 0 and di >= 0 else below).append(text)
    out = ["", "**Against the best peer** (default − peer, MOTA / IDF1): "]
    if above:
        out[-1] += "at or above it on " + "; ".join(above) + ". "
    if below:
        out[-1] += "**Below it** on " + "; ".join(below) + " (see *test.txt: where the " \
            "peers' margin comes from* below)."
    return out


def _chosen_text() -> list[str]:
    """How the default was chosen (static text; the figures it relies on are in the tables)."""
    return [
        "",
        "### How the default was chosen",
        "",
        "The previous default (σ_z = 2 px, a 10 px Euclidean gate, a 20 px second stage, every "
        "coasting row output) was tuned on the crowd scene of docs/bench/tracker.md: 40 × 30 px "
        "boxes with 2 px noise. On TUD the boxes are 50–200 px and the noisy-gt detections carry "
        "noise of 5 % of the box (σ ≈ 4 px along x, ≈ 9 px along y for a 73 × 185 px person), so "
        "a 10 px gate loses the targets (see the *previous default* row below). The new default "
        "keeps every pixel value of the old one for boxes up to `size_ref` = 50 px wide and high "
        "and stretches them per axis for larger boxes: the gates become ellipses with semi-axes "
        "scaled by f_x = w / 50 and f_y = h / 50, the measurement variance is multiplied by "
        "max(f_x, f_y)² (one isotropic variance per track, covering the noisier axis) and the "
        "recovery margin by max(f_x, f_y) (`TrackerConfig.size_ref`) — a detector's localisation "
        "error grows with the box, as in DeepSORT, whose noise is proportional to the box height."
        " Motion parameters (σ_a, velocity prior, recovery speed) are not scaled. Second, the "
        "Euclidean assignment cost of a gated pair gets a box-size term, `size_weight` = 0.5 "
        "times the squared difference of the boxes' widths and heights (in the same stretched "
        "units, capped at the gate; the gate itself stays on the position): like the overlap in "
        "IoU association it separates people side by side at different depths. Third, "
        "`coast_output` = 0.08 s keeps a lost track alive for `max_coast` (0.3 s) but outputs its"
        " predicted rows only for the first two frames: a short gap is usually a missed detection"
        " of a target still there, a longer one more often a target that has left. On Campus "
        "test.txt the scaling costs accuracy (sensitivity table, *no box-size scaling*); it is"
        " kept for the noisy-gt columns, where the previous default fails. Fourth, `backfill`: "
        "an offline run (`track_detections`) writes a confirmed track from its first detection,"
        " as a multi-measurement initiator that hands over its whole tentative track does; the "
        "online tracker (crowd benchmark, video pipeline, `mvtrack demo`) cannot rewrite past "
        "frames and is unchanged by it.",
        "",
        "Two later defaults. `size_gate`: a track and a detection whose widths or heights "
        "differ by more than a factor ρ are never paired — a box much larger or smaller is "
        "another object (see *Identities* below). It was introduced here with ρ = 2; ρ = 1.5 "
        "is the MOT15 leave-one-sequence-out choice among the gates that keep this benchmark's "
        "figures (1.4 costs Campus noisy gt 0.002 MOTA and 0.001 IDF1, 0.011 and 0.006 "
        "before the width was gated at ρ²; "
        "`docs/bench/mot15-defaults.md`), and *size gate 2* in the sensitivity table is the "
        "earlier value. It is off in the video pipeline: the "
        "disturbance map's blobs merge and split, and on `mvtrack demo` the gate cost IDF1 "
        "0.876 → 0.860; on the crowd scene (boxes ±10 %) it changes no output. And "
        "`interpolate`: an offline run writes every row of a gap that a track bridged (lost "
        "for at most `max_coast`, then associated again), the box interpolated linearly "
        "between the measured rows on either side — the linear interpolation commonly applied "
        "to offline MOTChallenge results; it has no parameter of its own (see *no "
        "interpolation* in the sensitivity table).",

        "",
        "The principle (noise and gates proportional to the box) comes from the detector model, "
        "not from TUD. **Six choices were then made by looking at these TUD sequences** (noisy "
        "gt seeds 0–2 and test.txt) together with the crowd scene, and nothing else was tuned: "
        "per-axis factors rather than one factor √(w h) / size_ref (in the development sweep, "
        "with max_coast 0.1 s instead of coast_output, Campus noisy gt rose from 0.865 / 0.878 to"
        " 0.910 / 0.929); `size_ref` 50 px rather than 40 px (better Campus test.txt MOTA and "
        "Stadtmitte noisy-gt IDF1, within 0.001 elsewhere in the sensitivity table, and the crowd"
        " scene's boxes, at most ~47 px, stay unscaled); the variance factor max(f_x, f_y)² "
        "rather than f_x f_y (Stadtmitte noisy-gt IDF1 0.968 → 0.990; σ_z itself stays 2 px, the "
        "crowd scene's noise, which is better than 3 px at N = 10 and 100 on every crowd seed we "
        "ran; at N = 1 000 3 px gives IDF1 0.963 against 0.955); `size_weight` 0.5 (0.5 and 1 "
        "gave the same TUD figures; it must stay below 1, see `TrackerConfig`; on the crowd scene"
        " it changed nothing at N = 10 and 100 and cut the ID switches at N = 1 000 from 262 to "
        "223); `coast_output` two frames (three frames cost Campus noisy gt 0.016 MOTA in the"
        " sweep); and the size gate's factor 2 rather than 2.5 or 3 (the Campus event it "
        "prevents pairs boxes 2.5 times apart; *size gate 2.5* in the sensitivity table), since"
        " lowered to 1.5 on the MOT15 sequences. The "
        "crowd benchmark (docs/bench/tracker.md) and the video experiments (`mvtrack"
        " demo`, X4, X5) were re-checked with the same default. How the peers were configured is "
        "not recorded here; part of our margin on the noisy-gt columns is tuning on these "
        "sequences.",
    ]


def _gap_text(
    gaps: dict[str, dict[str, Any]], sensitivity: dict[str, dict[str, dict[str, Any]]] | None
) -> list[str]:
    """Why Stone Soup beats the test.txt boxes' own MOTA, as far as measured here."""
    parts = []
    for seq, g in gaps.items():
        parts.append(
            f"{seq.removeprefix('TUD-')}: of {g['gt']} ground-truth boxes, test.txt misses "
            f"{g['inner'] + g['outer']}, {g['inner']} of them inside a target's detected span "
            f"(gaps of {', '.join(str(x) for x in g['gaps'])} frames) and {g['outer']} before "
            "its first or after its last detection"
        )
    sens = sensitivity or {}

    def cell(row: str, key: str) -> str:
        r = sens.get(row, {}).get(key)
        return "–" if r is None else f"{_fmt(r['MOTA'])} / {_fmt(r['IDF1'])}"

    coast = "coast 1 s, every coasting row output (filling test.txt's long gaps)"
    lines = [
        "",
        "### test.txt: where the peers' margin comes from",
        "",
        "Stone Soup's MOTA on test.txt (0.599 / 0.587) is above what the boxes give with "
        "their own IDs (first table), so it outputs correct boxes where test.txt has none. "
        + "; ".join(parts) + ". Keeping tracks 1 s and writing every coasting row does not "
        f"fill the long gaps (Campus / Stadtmitte {cell(coast, 'TUD-Campus|test')} and "
        f"{cell(coast, 'TUD-Stadtmitte|test')}, sensitivity table): most predictions through "
        "16–51 frames miss the person (IoU < 0.5).",
        "",
        "**A plain Stone Soup tracker, rebuilt here.** To see *what* the peer does, we built "
        "a plain Stone Soup 1.9.1 GNN tracker on the same boxes, outside this repository, and "
        "scored it with the same `evaluate`: constant-velocity model on the box centre "
        "(noise coefficient q = 100 px²/s³), Kalman predictor and updater with R = 100 px² on "
        "the centre, Mahalanobis distance hypothesiser (missed distance 3), GNN with 2-D "
        "assignment, multi-measurement initiator (2 points, velocity prior 50 px/s), deletion "
        "5 steps after the last update; every state of every track written — the initiating "
        "detection, the updates with the *measured* box, the predictions through misses and the"
        " 5 before deletion with the last measured size. It gives Campus 0.571 / 0.634 (FP 28, "
        "FN 121, IDSW 5) and Stadtmitte 0.561 / 0.656 (FP 65, FN 437, IDSW 6); in a sweep of "
        "about 60 configurations (q 1–1000 px²/s³, R 4–1600 px², deletion 2–10 steps, box "
        "size in the state or measured, predictions written or not) none reached the recorded "
        "0.599 / 0.587 (best Campus MOTA 0.571, best Stadtmitte 0.575), so the recorded run had "
        "a configuration we did not find; the mechanisms below are those of the rebuilt one.",
        "",
        "**Frame by frame against our default without backfill** (measured before the size "
        "gate and interpolation became defaults; ground-truth boxes matched "
        "at IoU 0.5). Campus: the rebuilt tracker matches 33 ground-truth boxes that we miss, "
        "we match 5 that it misses. Of its 33: (a) 19 are *predicted* rows, most of them "
        "among the 5 "
        "written before a track is deleted — 25 of its 40 such rows hit the person, because "
        "test.txt ends tracks of people who keep walking on a straight line; our "
        "`coast_output` writes 2 and writing 5 costs us (coast_output 0.2 s: Campus 0.513 / "
        "0.534 before backfill, 16 of our 30 such rows hit); (b) 9 are among the first two "
        "rows of a track, which an initiator that hands over its tentative track writes: "
        "`backfill`, now our default, gains 4 of them (the other 5 we did not trace); (c) 5 "
        "are detected boxes where our row (filtered centre, "
        "smoothed size) has IoU < 0.5 and the measured box has it: writing the measured box "
        "gave Campus +0.028 MOTA but Stadtmitte −0.004 and Campus noisy gt −0.006 / −0.003, so "
        "it was not adopted. Stadtmitte: 24 against 9 (7 first rows of a track, 7 detected "
        "boxes, 10 predictions); with backfill 17 against 9.",
        "",
        "**Identities.** Without the size gate (Campus "
        f"{cell('no size gate (size_gate = None)', 'TUD-Campus|test')}) our tracks of large "
        "boxes take the detection of *another* person of half their size — the second gate "
        "(20 px stretched with the box, up to 50 × 114 px around a 126 × 285 px person) and the "
        "recovery stage reach it, and the size term of the cost only ranks pairs; e.g. Campus "
        "frames 49–52, a 126 × 285 px track takes the 50 × 115 px box of a farther person and "
        "writes 4 false positives before it is lost. The peer's gate (σ 10 px, not stretched) "
        "does not reach it; the size gate (factor 2, and the default 1.5) refuses it. What "
        "remains on "
        "Campus is one group of people walking side by side (frames 33–39): a track whose own "
        "detection is missed takes the neighbour's, through the second gate or the recovery "
        "stage (10 px + the 6 px margin stretched with the box). Each change that prevents "
        "that one "
        "event lifts Campus to the peer's level or above — no recovery stage "
        f"{cell('no recovery stage (recover_speed = None)', 'TUD-Campus|test')}, no recovery "
        f"margin {cell('no recovery margin (recover_margin = 0)', 'TUD-Campus|test')}, a 15 px "
        f"second gate {cell('second_gate = 15 px', 'TUD-Campus|test')} — but each is a knife "
        "edge (a 1 px margin gives "
        f"{cell('recovery margin 1 px (recover_margin = 1)', 'TUD-Campus|test')}; 16 px for the"
        " second gate loses the gain) or costs elsewhere (without the recovery stage the crowd "
        "scene's IDF1 falls from 0.992 to 0.859 at N = 10, docs/bench/tracker.md), so none was "
        "adopted. Keeping tracks 0.5 s "
        f"({cell('tracks kept 0.5 s (max_coast = 0.5)', 'TUD-Campus|test')}) bridges longer "
        "Campus gaps, which interpolation fills (without it 0.565 / 0.578), but 0.8 s already "
        "costs Campus noisy gt "
        f"({cell('tracks kept 0.8 s (max_coast = 0.8)', 'TUD-Campus|noisy')}).",
        "",
        "**Where the rest of the margin lies.** With the default, Campus test.txt is 0.02 MOTA "
        "and 0.04 IDF1 below the recorded peer, and above the rebuilt one on MOTA (0.571); the "
        "difference is the group event above and the predicted rows before deletion (a). On "
        "Stadtmitte the boxes themselves set the ceiling: the default is at the MOTA of "
        "test.txt with its own IDs, and 150 random configurations of σ_z, σ_a, velocity prior, "
        "gates, confirmation, size smoothing, size weight and max_coast (with the size gate, "
        "without the recovery stage) all gave MOTA ≤ 0.565; test.txt's own tracks drift from "
        "one person to the next (e.g. frames 44–53, a box slides from ground-truth person 5 "
        "onto person 4), and a tracker that follows the boxes inherits the switch. The "
        "recorded 0.587 is from a configuration we could not reproduce. Confirmation and "
        "box-size smoothing are not where the difference lies: confirm_hits 1 or 3, a "
        "tentative track surviving misses (tentative_max_coast 0.2 s), size_smoothing 1 and "
        "smoother filters (σ_a 20–50 px/s², σ_z 5 px) each moved the test.txt MOTA by at most "
        "0.025 and cost elsewhere in our sweeps.",
    ]
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="seeds of the noisy detections")
    parser.add_argument("--out", type=Path, default=Path("docs/bench/tud.md"))
    parser.add_argument("--json", type=Path, default=None, help="also write raw figures")
    parser.add_argument("--quick", action="store_true", help="only the default combination")
    parser.add_argument(
        "--no-coasting", action="store_true", help="leave coasting (missed) rows out of results"
    )
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be >= 1")

    default = default_combo()
    combos = [default] if args.quick else grid()
    if default not in combos:
        combos.insert(0, default)
    gts = {s: read_tracks(data_dir() / s / "gt.txt", kind="gt") for s in SEQUENCES}
    inputs: dict[str, list[list[Detections]]] = {}
    for s in SEQUENCES:
        inputs[f"{s}|test"] = [test_detections(s, gts[s].num_frames)]
        inputs[f"{s}|noisy"] = [
            noisy_detections(gts[s], np.random.default_rng(seed)) for seed in range(args.seeds)
        ]

    results: dict[str, dict[str, dict[str, Any]]] = {}
    t0 = time.perf_counter()
    for i, c in enumerate(combos, 1):
        results[c.name] = {}
        for key, variants in inputs.items():
            seq = key.split("|")[0]
            try:
                runs = [
                    run_one(c, frames, gts[seq], not args.no_coasting) for frames in variants
                ]
            except KeyboardInterrupt:
                raise
            except Exception as exc:  # a combination that cannot run is reported, not fatal
                print(f"[{i}/{len(combos)}] {c.name} {key}: failed: {exc}", file=sys.stderr)
                runs = [{"MOTA": None, "IDF1": None, "HOTA": None, "IDSW": None, "FP": None,
                         "FN": None, "ms_per_frame": float("nan")}]
            results[c.name][key] = _mean(runs)
            r = results[c.name][key]
            print(
                f"[{i}/{len(combos)}] {c.name:40s} {key:22s} MOTA {_fmt(r['MOTA'])} "
                f"IDF1 {_fmt(r['IDF1'])} HOTA {_fmt(r['HOTA'])} {r['ms_per_frame']:.2f} ms/frame",
                flush=True,
            )
    sensitivity: dict[str, dict[str, dict[str, Any]]] = {}
    if not args.quick:
        for name, changes, coast in SENSITIVITY:
            sensitivity[name] = {
                key: _mean([run_one(default, f, gts[key.split("|")[0]], coast, changes)
                            for f in variants])
                for key, variants in inputs.items()
            }
            print(f"sensitivity {name}: " + "  ".join(
                f"{k} {_fmt(v['MOTA'])}/{_fmt(v['IDF1'])}" for k, v in sensitivity[name].items()
            ), flush=True)
    elapsed = time.perf_counter() - t0
    if args.json is not None:
        write_json(args.json, {"seeds": args.seeds, "default": default.name, "results": results,
                               "sensitivity": sensitivity})
    for c in combos:  # failed runs rank last
        for r in results[c.name].values():
            for k in ("MOTA", "IDF1"):
                r[k] = -np.inf if r[k] is None else r[k]
    given = argv if argv is not None else sys.argv[1:]
    command = "python benchmarks/bench_tud.py " + " ".join(given)
    write_text(args.out, report(
        results, combos, default, command.strip(), args.seeds, elapsed, not args.no_coasting,
        {s: oracle(s, gts[s], args.seeds) for s in SEQUENCES}, sensitivity,
        {s: test_gaps(s) for s in SEQUENCES},
    ))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
