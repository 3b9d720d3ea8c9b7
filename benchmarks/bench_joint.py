"""All principal settings tuned at once, and whether that holds on a held-out sequence.

``bench_framerate.py --loo`` chooses each setting alone, the others at their defaults. This
benchmark moves all of them together: a coordinate descent over :data:`JOINT_GRID` (the
leave-one-out grid plus the life cycle's and the association's counts and thresholds), from
the defaults, keeping a move while the objective on the training cells (the mean of MOTA and
IDF1, online and offline) rises by more than :data:`MIN_GAIN`, until no move helps. It is run
on all 16 sweep cells and in each of the eight leave-one-out folds (a sequence at all ``k``, or
a ``k`` on all sequences, held out); each fold's choice is scored on its held-out cells
beside the defaults.

    python benchmarks/bench_joint.py --out docs/bench/joint.md --json benchmarks/data/joint.json
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import tempfile
from pathlib import Path
from typing import Any

import bench_framerate as bf

#: the settings moved together and the values tried (the default among them)
JOINT_GRID: dict[str, tuple[Any, ...]] = {
    **{k: v for k, v in bf.GRID.items() if k != "manoeuvre_noise"},
    "manoeuvre_noise": (10.0, 15.0, 25.0),
    "confirm_hits": (1, 2, 3),
    "min_misses": (2, 3, 4),
    "max_misses": (6, 10, 15),
    "coast_std": (0.0, 0.05, 0.1),
    "gate": (6.0, 9.21, 13.8),
    "min_score": (0.05, 0.1, 0.15),
    "score_high": (0.4, 0.5, 0.6),
    "config.SIZE_SMOOTHING": (0.3, 0.5, 0.7),
}
#: the least rise of the training objective that moves a setting
MIN_GAIN = 1e-4


def defaults() -> dict[str, Any]:
    """Each setting of :data:`JOINT_GRID` at its default (the default ``gate`` is the
    Mahalanobis distance's 9.21)."""
    d = {n: bf.default_value(n) for n in JOINT_GRID if n != "gate"}
    d["gate"] = 9.21
    return d


def descend(cells: list[dict[str, Any]], train: list[int],
            cache: dict[str, list[dict[str, dict[str, float]]]]) -> tuple[dict[str, Any],
                                                                           float, list[str]]:
    """The coordinate descent on the cells ``train`` (indices into ``cells``): the settings
    reached, their training objective and the moves in order."""

    def runs(cfg: dict[str, Any]) -> list[dict[str, dict[str, float]]]:
        key = json.dumps(cfg, sort_keys=True)
        if key not in cache:
            cache[key] = [bf.run_mvtrack(c, dict(cfg)) for c in cells]
        return cache[key]

    cur = defaults()
    best = bf._objective([runs(cur)[i] for i in train])
    moves = []
    moved = True
    while moved:
        moved = False
        for name, values in JOINT_GRID.items():
            for v in values:
                if v == cur[name]:
                    continue
                cfg = dict(cur, **{name: v})
                o = bf._objective([runs(cfg)[i] for i in train])
                if o > best + MIN_GAIN:
                    best, cur, moved = o, cfg, True
                    moves.append(f"{name} {v}")
    return cur, best, moves


def joint(work: Path) -> dict[str, Any]:
    """The descent on all cells and in each leave-one-out fold."""
    cells = bf.cells(work)
    cache: dict[str, list[dict[str, dict[str, float]]]] = {}
    base = [bf.run_mvtrack(c, defaults()) for c in cells]
    best_peer = bf.recorded_best()
    out: dict[str, Any] = {"default": defaults(), "folds": {}}
    folds = [("all", None, None)] + [("seq", s, s) for s in bf.SEQUENCES] + [
        ("k", k, f"k = {k}") for k in bf.KS]
    for key, held, label in folds:
        test = [i for i, c in enumerate(cells) if key != "all" and c[key] == held]
        train = [i for i in range(len(cells)) if i not in test]
        cfg, obj, moves = descend(cells, train, cache)
        chosen = cache[json.dumps(cfg, sort_keys=True)]
        row: dict[str, Any] = {"moves": moves, "train_objective": obj,
                               "choice": {n: v for n, v in cfg.items() if v != defaults()[n]}}
        if test:
            row["held_out_choice"] = bf._objective([chosen[i] for i in test])
            row["held_out_default"] = bf._objective([base[i] for i in test])
        else:
            row["means"] = {m: bf.means(chosen, m) for m in bf.MODES}
            row["means_default"] = {m: bf.means(base, m) for m in bf.MODES}
            row["behind"] = {
                m: [f"{c['seq']} k = {c['k']}" for c, r in zip(cells, chosen, strict=True)
                    if r[m]["MOTA"] < best_peer[(c["seq"], c["k"])]["MOTA"]
                    or r[m]["IDF1"] < best_peer[(c["seq"], c["k"])]["IDF1"]]
                for m in bf.MODES}
        out["folds"][label or "all 16 cells"] = row
        print(label or "all 16 cells", row["choice"], flush=True)
    return out


def report(res: dict[str, Any], command: str) -> str:
    """The Markdown page."""
    a = res["folds"]["all 16 cells"]
    fmt = "{:.3f} / {:.3f}".format
    lines = [
        "## All principal settings tuned at once", "", f"Command: `{command}`", "",
        "A coordinate descent over the settings below (three or four values each, from the "
        "defaults; a move kept while the objective — the mean of MOTA and IDF1, online and "
        f"offline — rises by more than {MIN_GAIN} on the training cells), on all 16 sweep "
        "cells and in each leave-one-out fold.", "",
        "| setting | values tried | default |", "|---|---|---|",
        *[f"| `{n}` | {', '.join(map(str, v))} | {res['default'][n]} |"
          for n, v in JOINT_GRID.items()],
        "", f"**On all 16 cells**: moves {', '.join(a['moves']) or 'none'}; objective "
        f"{a['train_objective']:.4f}; online {fmt(*a['means']['online'])} (default "
        f"{fmt(*a['means_default']['online'])}), offline {fmt(*a['means']['offline'])} (default "
        f"{fmt(*a['means_default']['offline'])}); cells behind the best peer: online "
        f"{', '.join(a['behind']['online']) or 'none'}, offline "
        f"{', '.join(a['behind']['offline']) or 'none'}.", "",
        "| held out | the fold's moves | held-out objective, fold's choice | default |",
        "|---|---|---|---|",
    ]
    for label, f in res["folds"].items():
        if "held_out_choice" in f:
            lines.append(f"| {label} | {', '.join(f['moves']) or 'none'} | "
                         f"{f['held_out_choice']:.4f} | {f['held_out_default']:.4f} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    args = bf.parse_args(ap, argv)
    if args is None:
        return 2
    command = "python benchmarks/bench_joint.py " + shlex.join(argv or sys.argv[1:])
    with tempfile.TemporaryDirectory() as tmp:
        res = joint(Path(tmp))
    text = report(res, command)
    bf.emit(text, res, args.out, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
