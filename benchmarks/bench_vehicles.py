"""Vehicles: every front end on the four US-101 clips, beside the stock OpenCV pipeline.

Data: ``../shared/data/vehicles/US101-{1,2,3,4}`` (640×480, about 3 fps, every car boxed, no
identities; parked cars of ``static.txt`` ignored as the shared scorer ignores them) and, for
speed, ``../shared/data/vtest.avi`` (768×576).

For every front end of mvtrack (``--frontends``) and clip, ``mvtrack track CLIP/img1 --fps 3
--no-video`` is run in this process (the same parts: :func:`mvtrack.video.resolve_settings`,
``build_detector``, ``build_tracker``, :func:`mvtrack.video.track_to_folder`), and two things
are scored per frame against ``boxes.txt`` — recall, precision and F1 at IoU 0.5 and 0.3, one
to one per frame by the Hungarian method, the rules of ``score_boxes.py`` (re-checked here on
the default's ``results.txt`` with the shared scorer itself):

* **front end** — the detector's own boxes as the tracker received them (the front end runs
  beside the tracker, as in the pipeline: it gets the predicted boxes back);
* **end to end** — the rows of ``results.txt``, what the tracker wrote.

*Waiting cars*: the share of the boxes of ``still.txt`` that are not parked (not in
``static.txt``) matched at IoU 0.5 — cars queueing at the US101-1 surface street and waiting
at the US101-4 intersection.

The **stock OpenCV pipeline**: ``cv2.createBackgroundSubtractorMOG2()`` with OpenCV's defaults
(shadows marked and dropped), a 3×3 opening, a 7×7 elliptic closing, connected components of at
least ``40 s²`` pixels (``s² = W H / 320·240``, mvtrack's blob stage), their bounding boxes,
tracked by peerbench's ``sort-py`` (the original SORT, ``max_age=1, min_hits=3,
iou_threshold=0.3``, run by ``../shared/peerbench/peers.py`` under the peers' interpreter, which
needs NumPy < 2: ``--peers-python``, ``$MVTRACK_PEERS_PYTHON``).

**Speed** (``--speed-rounds R``): decode to results, frames per second of process CPU time (one
OpenCV thread, one decoder thread; the machine is shared, CPU time is what one dedicated core
takes). mvtrack: the frame loop of ``mvtrack track --no-video`` (decode, front end, tracker,
template rescuer, relinking, the track log; the files written at the end are not timed).
Stock: decode (``cv2.imread``, ``cv2.VideoCapture``) + MOG2 + blobs in this process, plus
SORT's update calls in the peers' interpreter over the same detections; its ratio with the
frames decoded by mvtrack's reader (the same pixels) is given beside. The two alternate, R
rounds per sequence; the table gives the median of each and the median of the rounds' ratios.

Usage::

    python benchmarks/bench_vehicles.py --out /tmp/vehicles                # everything
    python benchmarks/bench_vehicles.py --out /tmp/vehicles --no-speed     # accuracy only
    python benchmarks/bench_vehicles.py --out /tmp/vehicles --pictures docs/images/vehicles
    python benchmarks/bench_vehicles.py --out /tmp/vehicles --loo          # constants, LOO
    python benchmarks/bench_vehicles.py --out /tmp/loo --no-accuracy --no-speed --loo-e2e
    python benchmarks/bench_vehicles.py --out /tmp/people --no-accuracy --no-speed --people

``--loo`` chooses the road-user front end's constants (one at a time, from a small grid each)
by leave-one-out over the four clips and KITTI-17 (people, scored on its own front-end boxes at
IoU 0.5 against ``gt.txt`` with flag-0 rows dropped): for each held-out sequence, the value
with the best mean front-end F1 on the others, and its F1 on the held-out one. ``--loo-e2e``
does the same for the constants of :data:`LOO_E2E_GRID`, scored on the end-to-end rows
(``results.txt``), since the travel a track needs before it is shown acts on them only
(``--grid NAME ...``: only those constants).
``--people``: KITTI-17 end to end with every default, as ``mvtrack track KITTI-17/img1 --fps
10`` and ``mvtrack eval --ignore drop`` score it (MOTA, IDF1).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
VEHICLES = SHARED / "data" / "vehicles"
PEERBENCH = SHARED / "peerbench"
KITTI = SHARED / "data" / "real" / "KITTI-17"
VTEST = SHARED / "data" / "vtest.avi"
CLIPS = ("US101-1", "US101-2", "US101-3", "US101-4")
FPS = 3.0
FRONTENDS = ("road-users", "disturbance-map", "mog2", "knn", "frame-diff", "scene", "hog")
SORT_SETTINGS = dict(max_age=1, min_hits=3, iou_threshold=0.3)

#: the frame drawn for each clip (1-based): mid-clip; on US101-4 while cars wait at the light
PICTURE_FRAME = {"US101-1": 90, "US101-2": 60, "US101-3": 75, "US101-4": 100}

#: the road-user front end's constants chosen by leave-one-out (``--loo``), their grids
LOO_GRID: dict[str, tuple[float, ...]] = {
    "valley": (0.35, 0.5, 0.65),
    "over": (1.3, 1.5, 1.8),
    "close_frac": (0.2, 0.3, 0.4),
    "max_z": (2.0, 2.5, 3.0),
}

#: the constants chosen by leave-one-out on the end-to-end rows (``--loo-e2e``): the
#: distance a track travels before it is shown, held and learnt from, the flat wings' height,
#: the clutter's share of the smallest kind, the smallest blob (``area``: pixels of the
#: 320×240 image, ``min_area = area s²``, :data:`mvtrack.video.settings.ROAD_USERS_AREA`)
LOO_E2E_GRID: dict[str, tuple[float, ...]] = {
    "travel": (0.25, 0.5, 1.0),
    "wings": (0.2, 0.3, 0.4),
    "small": (0.2, 0.35, 0.5),
    "area": (10.0, 20.0, 40.0, 60.0),
}


def e2e_params(name: str, value: float, frames: list[np.ndarray]) -> dict[str, Any]:
    """The road-user front end's parameters for ``name = value`` of :data:`LOO_E2E_GRID`
    (``area`` in pixels of the 320×240 image, given as ``min_area`` for the frame's size)."""
    if name != "area":
        return {name: value}
    h, w = frames[0].shape[:2]
    return {"min_area": float(round(value * w * h / (320 * 240)))}


# --------------------------------------------------------------------------- the peers' side
# (runs under the peers' interpreter: NumPy < 2, no mvtrack, no OpenCV)


def sort_side(dets_path: str, out_path: str) -> None:
    """SORT (peerbench's ``sort-py`` adapter) over per-frame detections; CPU seconds of the
    update calls and the tracks of each frame into ``out_path`` (JSON)."""
    sys.path.insert(0, str(PEERBENCH))
    import peers  # type: ignore[import-not-found]

    data = np.load(dets_path)
    frames = [data[f"f{k}"] for k in range(int(data["n"]))]
    peer = peers.SortPy(FPS, 0, 0)
    rows: list[list[float]] = []
    cpu = 0.0
    for k, dets in enumerate(frames):
        t0 = time.process_time()
        ids, boxes = peer.step(dets)
        cpu += time.process_time() - t0
        for i, b in zip(ids.tolist(), boxes.tolist(), strict=True):
            rows.append([k + 1, i, b[0], b[1], b[2] - b[0], b[3] - b[1]])
    Path(out_path).write_text(json.dumps({"cpu": cpu, "rows": rows}))


def run_sort(python: str, boxes: list[np.ndarray], work: Path) -> tuple[list[np.ndarray], float]:
    """SORT in the peers' interpreter over ``boxes`` (tlwh per frame): its boxes per frame and
    the CPU seconds of its update calls."""
    dets = {f"f{k}": np.column_stack([b[:, :2], b[:, :2] + b[:, 2:], np.ones(len(b))])
            if len(b) else np.zeros((0, 5)) for k, b in enumerate(boxes)}
    path = work / "dets.npz"
    np.savez(path, n=len(boxes), **dets)
    out = work / "sort.json"
    subprocess.run([python, __file__, "--sort-side", str(path), str(out)], check=True)
    got = json.loads(out.read_text())
    rows = np.array(got["rows"], np.float64).reshape(-1, 6)
    per = [rows[rows[:, 0] == k + 1, 2:6] for k in range(len(boxes))]
    return per, float(got["cpu"])


def peers_python(arg: str | None) -> str | None:
    """The peers' interpreter: ``--peers-python``, ``$MVTRACK_PEERS_PYTHON``, ``/work/peers``
    or peerbench's default location; None when none exists."""
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    for candidate in (arg, os.environ.get("MVTRACK_PEERS_PYTHON"),
                      str(ROOT.parent / "peers" / "bin" / "python"),
                      str(cache / "mvtrack-peers" / "bin" / "python")):
        if candidate and Path(candidate).exists():
            return candidate
    return None


# --------------------------------------------------------------------------- scoring


def _load(path: Path, static: bool = False) -> np.ndarray:
    if not path.exists() or path.stat().st_size == 0:
        return np.zeros((0, 6))
    a = np.loadtxt(path, delimiter=",", ndmin=2, usecols=range(5 if static else 6))
    return np.insert(a, 1, -1, axis=1) if static else a


def iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(M, N) IoU of tlwh boxes."""
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    inter = np.clip(hi - lo, 0.0, None).prod(axis=2)
    return inter / (a[:, 2:].prod(axis=1)[:, None] + b[:, 2:].prod(axis=1)[None, :] - inter)


class Truth:
    """A clip's boxes, parked cars and waiting cars, by frame (1-based)."""

    def __init__(self, seq: Path) -> None:
        self.seq = seq
        self.boxes = _load(seq / "boxes.txt")
        self.static = _load(seq / "static.txt", static=True)
        self.still = _load(seq / "still.txt", static=True)
        self.frames = np.unique(self.boxes[:, 0]).astype(int)

    def score(self, per_frame: list[np.ndarray], t: float) -> dict[str, float]:
        """score_boxes.py's rules: recall, precision, F1, and the waiting cars' recall."""
        from scipy.optimize import linear_sum_assignment

        tp = fp = fn = hit = waiting = 0
        for f in self.frames:
            g = self.boxes[self.boxes[:, 0] == f, 2:6]
            s = self.static[self.static[:, 0] == f, 2:6]
            w = self.still[self.still[:, 0] == f, 2:6]
            if len(s):
                g = g[~np.any(iou(g, s) > 0.99, axis=1)] if len(g) else g
                w = w[~np.any(iou(w, s) > 0.99, axis=1)] if len(w) else w
            r = per_frame[f - 1] if f - 1 < len(per_frame) else np.zeros((0, 4))
            matched = np.zeros(len(r), bool)
            if len(g) and len(r):
                c = iou(g, r)
                i, j = linear_sum_assignment(-c)
                ok = c[i, j] >= t
                tp += int(ok.sum())
                matched[j[ok]] = True
            fn += len(g) - int(matched.sum())
            rest = r[~matched]
            if len(s) and len(rest):
                rest = rest[~np.any(iou(rest, s) >= t, axis=1)]
            fp += len(rest)
            waiting += len(w)
            if len(w) and len(r):
                c = iou(w, r)
                i, j = linear_sum_assignment(-c)
                hit += int((c[i, j] >= t).sum())
        rec, pre = tp / max(tp + fn, 1), tp / max(tp + fp, 1)
        return {"recall": rec, "precision": pre,
                "f1": 2 * rec * pre / max(rec + pre, 1e-12),
                "waiting": hit / waiting if waiting else float("nan")}


def score_all(truth: Truth, per_frame: list[np.ndarray]) -> dict[str, Any]:
    """Scores at IoU 0.5 and 0.3."""
    return {"0.5": truth.score(per_frame, 0.5), "0.3": truth.score(per_frame, 0.3)}


def shared_scorer_f1(seq: Path, results: Path) -> list[float]:
    """F1 at 0.5 and 0.3 from ``score_boxes.py`` itself (the cross-check)."""
    out = subprocess.run([sys.executable, str(VEHICLES / "score_boxes.py"), str(seq),
                          str(results)], capture_output=True, text=True, check=True).stdout
    return [float(line.split()[3]) for line in out.splitlines() if line.strip()]


# --------------------------------------------------------------------------- runs


def lateral_jumps(results: Path) -> dict[str, float]:
    """An identity check that needs no identities: the share of a run's track steps (one
    track, consecutive frames) that move across the road by more than the box's height.

    The road's direction is the principal direction of the steps that move more than a box
    height (sign-free, the mean of the doubled angles); a car changes lanes over seconds, so
    a step across that direction longer than a box height is nearly always a track handed
    from one car to another (the boxes' F1 cannot see it: the box is on a car either way).
    """
    rows = np.loadtxt(results, delimiter=",", ndmin=2)
    if rows.size == 0:
        return {"steps": 0, "jumps": 0, "share": 0.0}
    rows = rows[np.lexsort((rows[:, 0], rows[:, 1]))]  # by track, then frame
    centre = rows[:, 2:4] + rows[:, 4:6] / 2
    same = (np.diff(rows[:, 1]) == 0) & (np.diff(rows[:, 0]) == 1)
    d = np.diff(centre, axis=0)[same]
    h = rows[1:, 5][same]
    moving = np.hypot(d[:, 0], d[:, 1]) > h
    a = 2.0 * np.arctan2(d[moving, 1], d[moving, 0])
    theta = 0.5 * np.arctan2(np.sin(a).mean(), np.cos(a).mean()) if moving.any() else 0.0
    across = np.abs(-d[:, 0] * np.sin(theta) + d[:, 1] * np.cos(theta))
    jumps = int((across > h).sum())
    return {"steps": int(d.shape[0]), "jumps": jumps,
            "share": jumps / d.shape[0] if d.shape[0] else 0.0}


def read_frames(path: Path) -> list[np.ndarray]:
    """Every frame of an image folder or video, decoded once."""
    from mvtrack.io.video import open_source

    with open_source(str(path), fps=FPS, threads=1) as src:
        return [frame for _, frame in src]


class Recorder:
    """A front end whose boxes of every frame are kept (its other hooks pass through)."""

    def __init__(self, inner: Any) -> None:
        self.__dict__["inner"] = inner
        self.__dict__["boxes"] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self.__dict__["inner"], name)

    def __call__(self, frame: np.ndarray, index: int | None = None) -> Any:
        dets = self.inner(frame)
        self.boxes.append(dets.tlwh.copy())
        return dets


def run_mvtrack(frames: list[np.ndarray], detector: str, out: Path,
                params: dict[str, Any] | None = None, fps: float = FPS) -> dict[str, Any]:
    """``mvtrack track`` over decoded frames: the front end's boxes, the results rows."""
    from mvtrack.config import RunSettings
    from mvtrack.video.build import build_detector, build_tracker
    from mvtrack.video.run import track_to_folder
    from mvtrack.video.settings import resolve_settings

    h, w = frames[0].shape[:2]
    settings = resolve_settings(RunSettings(detector=detector, detector_params=params or {},
                                            video=False), (w, h), fps)
    det = Recorder(build_detector(settings))
    tracker = build_tracker(settings, fps)
    run = track_to_folder(iter(frames), fps=fps, size=(w, h), settings=settings, out=out,
                          parts=(det, tracker), progress=False)
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    rows = rows if rows.size else np.zeros((0, 6))
    per = [rows[rows[:, 0] == k + 1, 2:6] for k in range(len(frames))]
    return {"frontend": det.boxes, "results": per, "loop_fps": run.summary["processing_speed"],
            "detector": det.inner}


def stock_frontend(frames: Any) -> list[np.ndarray]:
    """The stock MOG2 blobs of every frame (tlwh, bounding boxes), decoded as it goes."""
    out: list[np.ndarray] = []
    blobs = None
    for frame in frames:  # the stock pipeline, frame by frame, as a tutorial writes it
        blobs = blobs or _StockBlobs(frame.shape)
        out.append(blobs(frame))
    return out


def accuracy(args: argparse.Namespace, work: Path) -> dict[str, Any]:
    """Every front end and the stock pipeline on every clip."""
    python = peers_python(args.peers_python)
    table: dict[str, Any] = {}
    for clip in CLIPS:
        seq = VEHICLES / clip
        truth = Truth(seq)
        frames = read_frames(seq / "img1")
        table[clip] = {}
        for name in args.frontends:
            t0 = time.perf_counter()
            got = run_mvtrack(frames, name, work / clip / name)
            row = {"frontend": score_all(truth, got["frontend"]),
                   "end_to_end": score_all(truth, got["results"]),
                   "loop_fps": got["loop_fps"]}
            if name == args.frontends[0]:  # the shared scorer agrees with ours
                row["shared_scorer_f1"] = shared_scorer_f1(seq, work / clip / name /
                                                           "results.txt")
                row["lateral_jumps"] = lateral_jumps(work / clip / name / "results.txt")
                kinds = getattr(got["detector"], "kinds", None)
                if kinds is not None and kinds.ready:
                    row["kinds"] = {"sizes_at_centre": (kinds.sizes * kinds.scale(
                        320.0, 300.0)[..., None]).round(1).tolist(),
                        "share": kinds.share.round(3).tolist()}
            table[clip][name] = row
            print(f"{clip} {name:16s} FE F1 {row['frontend']['0.5']['f1']:.3f}/"
                  f"{row['frontend']['0.3']['f1']:.3f} waiting "
                  f"{row['frontend']['0.5']['waiting']:.3f} | E2E "
                  f"{row['end_to_end']['0.5']['f1']:.3f}/{row['end_to_end']['0.3']['f1']:.3f}"
                  f" waiting {row['end_to_end']['0.5']['waiting']:.3f}"
                  + (f" jumps {100 * row['lateral_jumps']['share']:.1f} %"
                     if "lateral_jumps" in row else "") + " | "
                  f"{row['loop_fps']} fps ({time.perf_counter() - t0:.0f} s)", flush=True)
        boxes = stock_frontend(frames)
        row = {"frontend": score_all(truth, boxes)}
        if python is not None:
            per, _ = run_sort(python, boxes, work)
            row["end_to_end"] = score_all(truth, per)
        table[clip]["stock"] = row
        print(f"{clip} stock MOG2+SORT  FE F1 {row['frontend']['0.5']['f1']:.3f}"
              + (f" | E2E {row['end_to_end']['0.5']['f1']:.3f}" if "end_to_end" in row else
                 " | (no peers' interpreter: no SORT)"), flush=True)
    return table


# --------------------------------------------------------------------------- speed


def mvtrack_cpu(path: Path, fps: float, detector: str | None = None) -> tuple[float, int]:
    """CPU seconds of ``mvtrack track --no-video``'s frame loop, decode to track log."""
    from mvtrack.config import RunSettings
    from mvtrack.io.video import open_source
    from mvtrack.tracking import TrackLog
    from mvtrack.video.build import build_detector, build_rescuer, build_tracker
    from mvtrack.video.loop import run_frames
    from mvtrack.video.relink import Relinker
    from mvtrack.video.settings import resolve_settings

    base = RunSettings(video=False) if detector is None else RunSettings(detector=detector,
                                                                        video=False)
    log = TrackLog()
    t0 = time.process_time()
    with open_source(str(path), fps=fps, threads=1) as src:
        settings = resolve_settings(base, src.size, src.fps)
        det, tracker = build_detector(settings), build_tracker(settings, src.fps)
        rescuer = build_rescuer(settings, tracker, det)
        relink = Relinker(src.fps, settings.relink)
        res = run_frames((f for _, f in src), det, tracker, rescuer=rescuer, relink=relink,
                         on_frame=lambda k, img, d, t: log.append(t), progress=False,
                         keep=False)
    return time.process_time() - t0, res.n_frames


def opencv_frames(path: Path) -> Any:
    """The frames as stock OpenCV reads them: ``cv2.imread`` of a folder's sorted files, or
    ``cv2.VideoCapture`` with one decoder thread."""
    import cv2

    from mvtrack.io.video import IMAGE_EXTENSIONS

    if path.is_dir():
        for f in sorted((p for p in path.iterdir() if p.suffix.lower() in IMAGE_EXTENSIONS),
                        key=lambda p: p.name):
            yield cv2.imread(str(f), cv2.IMREAD_COLOR)
        return
    cap = cv2.VideoCapture(str(path), cv2.CAP_ANY, [cv2.CAP_PROP_N_THREADS, 1])
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        yield frame
    cap.release()


def stock_cpu(path: Path, fps: float, python: str, work: Path,
              stock_decode: bool = True) -> tuple[float, int]:
    """CPU seconds of decode + MOG2 + blobs here, plus SORT's update calls there. The frames
    are decoded by OpenCV as a stock pipeline does (``stock_decode``), or by mvtrack's reader
    (:func:`mvtrack.io.video.open_source`, the same pixels)."""
    from mvtrack.io.video import open_source

    t0 = time.process_time()
    if stock_decode:
        boxes = stock_frontend(opencv_frames(path))
    else:
        with open_source(str(path), fps=fps, threads=1) as src:
            boxes = stock_frontend(f for _, f in src)
    front = time.process_time() - t0
    _, sort = run_sort(python, boxes, work)
    return front + sort, len(boxes)


class _StockBlobs:
    """MOG2 (OpenCV's defaults, shadows dropped), 3×3 opening, 7×7 closing, blobs of at
    least ``40 s²`` pixels, their bounding boxes."""

    def __init__(self, shape: tuple[int, ...]) -> None:
        import cv2

        self.cv2 = cv2
        self.mog = cv2.createBackgroundSubtractorMOG2()
        self.opening = np.ones((3, 3), np.uint8)
        self.closing = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (7, 7))
        self.min_area = 40.0 * shape[0] * shape[1] / (320 * 240)

    def __call__(self, frame: np.ndarray) -> np.ndarray:
        cv2 = self.cv2
        fg = cv2.threshold(self.mog.apply(frame), 127, 255, cv2.THRESH_BINARY)[1]
        fg = cv2.morphologyEx(fg, cv2.MORPH_OPEN, self.opening)
        fg = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, self.closing)
        _, _, st, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
        st = st[1:][st[1:, cv2.CC_STAT_AREA] >= self.min_area].astype(np.float64)
        return st[:, :4] - np.array([0.5, 0.5, 0.0, 0.0])


def speed(args: argparse.Namespace, work: Path) -> dict[str, Any]:
    """Paired rounds of mvtrack (defaults) and the stock pipeline on each sequence."""
    import cv2

    cv2.setNumThreads(1)
    python = peers_python(args.peers_python)
    if python is None:
        print("no peers' interpreter: no speed comparison", file=sys.stderr)
        return {}
    seqs = {clip: (VEHICLES / clip / "img1", FPS) for clip in CLIPS}
    if VTEST.exists():
        seqs["vtest.avi"] = (VTEST, 10.0)
    out: dict[str, Any] = {}
    for name, (path, fps) in seqs.items():
        ours, stock, ratio, same = [], [], [], []
        mvtrack_cpu(path, fps)  # warm-up: imports, numba's cache
        for _ in range(args.speed_rounds):
            a, n = mvtrack_cpu(path, fps)
            b, m = stock_cpu(path, fps, python, work)
            c, _ = stock_cpu(path, fps, python, work, stock_decode=False)
            ours.append(n / a)
            stock.append(m / b)
            ratio.append((n / a) / (m / b))
            same.append((n / a) / (m / c))
        out[name] = {"frames": n, "mvtrack_fps": statistics.median(ours),
                     "stock_fps": statistics.median(stock), "ratio": statistics.median(ratio),
                     "ratio_same_reader": statistics.median(same),
                     "rounds": {"mvtrack": ours, "stock": stock}}
        print(f"speed {name}: mvtrack {out[name]['mvtrack_fps']:.1f} fps, stock "
              f"{out[name]['stock_fps']:.1f} fps, ratio {out[name]['ratio']:.2f} (stock "
              f"decoding with mvtrack's reader: {out[name]['ratio_same_reader']:.2f})",
              flush=True)
    return out


# --------------------------------------------------------------------------- leave-one-out


def kitti_f1(per_frame: list[np.ndarray]) -> float:
    """F1 at IoU 0.5 of boxes (tlwh per frame) on KITTI-17: flag-1 rows are the truth, and a
    box left unmatched that matches a flag-0 row (a person to ignore) is not counted, as
    ``mvtrack eval --ignore drop`` does."""
    from scipy.optimize import linear_sum_assignment

    gt = np.loadtxt(KITTI / "gt.txt", delimiter=",", ndmin=2)
    tp = fp = fn = 0
    for k, r in enumerate(per_frame):
        rows = gt[gt[:, 0] == k + 1]
        g, ignored = rows[rows[:, 6] != 0, 2:6], rows[rows[:, 6] == 0, 2:6]
        matched = np.zeros(len(r), bool)
        if len(g) and len(r):
            c = iou(g, r)
            i, j = linear_sum_assignment(-c)
            matched[j[c[i, j] >= 0.5]] = True
        rest = r[~matched]
        if len(ignored) and len(rest):
            rest = rest[~(iou(rest, ignored) >= 0.5).any(axis=1)]
        t = int(matched.sum())
        tp, fp, fn = tp + t, fp + len(rest), fn + len(g) - t
    rec, pre = tp / max(tp + fn, 1), tp / max(tp + fp, 1)
    return 2 * rec * pre / max(rec + pre, 1e-12)


def kitti_frontend_f1(frames: list[np.ndarray], params: dict[str, Any], work: Path) -> float:
    """F1 at IoU 0.5 of the road-user front end's own boxes on KITTI-17 (:func:`kitti_f1`)."""
    return kitti_f1(run_mvtrack(frames, "road-users", work, params, fps=10.0)["frontend"])


def kitti_end_to_end(frames: list[np.ndarray], work: Path,
                     params: dict[str, Any] | None = None) -> dict[str, float]:
    """``mvtrack track KITTI-17/img1 --fps 10`` (the default front end) scored as ``mvtrack
    eval --ignore drop``: MOTA, IDF1, precision, recall, and the F1 of :func:`kitti_f1` of
    its rows and of the front end's boxes."""
    from mvtrack.eval.metrics import score_sequence

    got = run_mvtrack(frames, "road-users", work, params, fps=10.0)
    s = score_sequence(KITTI / "gt.txt", work / "results.txt", 0.5, ignore="drop",
                       with_hota=False).as_dict()
    out = {k: float(s[k]) for k in ("MOTA", "IDF1", "precision", "recall")}
    out.update({k: int(s[k]) for k in ("FP", "FN", "IDSW")})
    out["f1"] = kitti_f1(got["results"])
    out["frontend_f1"] = kitti_f1(got["frontend"])
    return out


def _folds(label: str, grid: Any, f1: dict[Any, dict[str, float]], seqs: list[str]
           ) -> dict[str, Any]:
    """Leave one sequence out: for each held-out sequence the grid value with the best mean F1
    on the others, and its F1 on the held-out one (printed as ``label``)."""
    folds = {}
    for held in seqs:
        train = [s for s in seqs if s != held]
        best = max(grid, key=lambda v: np.mean([f1[v][s] for s in train]))
        folds[held] = {"chosen": best, "held_out_f1": f1[best][held]}
    print(f"{label}: " + ", ".join(f"{h}: {d['chosen']} ({d['held_out_f1']:.3f})"
                                    for h, d in folds.items()), flush=True)
    return {"grid": {str(v): f1[v] for v in grid}, "folds": folds}


def leave_one_out(args: argparse.Namespace, work: Path) -> dict[str, Any]:
    """Each constant of :data:`LOO_GRID` chosen with one sequence held out (module doc)."""
    seqs: dict[str, Any] = {clip: (read_frames(VEHICLES / clip / "img1"), Truth(VEHICLES / clip))
                            for clip in CLIPS}
    if KITTI.exists():
        seqs["KITTI-17"] = (read_kitti(), None)
    out: dict[str, Any] = {}
    for name, grid in LOO_GRID.items():
        f1: dict[float, dict[str, float]] = {}
        for value in grid:
            f1[value] = {}
            for seq, (frames, truth) in seqs.items():
                if truth is None:
                    f1[value][seq] = kitti_frontend_f1(frames, {name: value}, work / "k")
                else:
                    got = run_mvtrack(frames, "road-users", work / "l", {name: value})
                    f1[value][seq] = truth.score(got["frontend"], 0.5)["f1"]
            print(f"loo {name}={value}: " + " ".join(f"{s} {v:.3f}" for s, v in
                                                   f1[value].items()), flush=True)
        out[name] = _folds(f"loo {name}", grid, f1, list(seqs))
    return out


def leave_one_out_e2e(args: argparse.Namespace, work: Path) -> dict[str, Any]:
    """Each constant of :data:`LOO_E2E_GRID` chosen with one sequence held out, by the mean
    end-to-end F1 at IoU 0.5 (the ``results.txt`` rows) on the others: the four clips
    (``score_boxes.py``'s rules) and KITTI-17 (:func:`kitti_f1`); the other constants at
    their defaults."""
    seqs: dict[str, Any] = {clip: (read_frames(VEHICLES / clip / "img1"), Truth(VEHICLES / clip))
                            for clip in CLIPS}
    if KITTI.exists():
        seqs["KITTI-17"] = (read_kitti(), None)
    out: dict[str, Any] = {}
    names = args.grid or list(LOO_E2E_GRID)
    for name, grid in ((n, LOO_E2E_GRID[n]) for n in names):
        f1: dict[float, dict[str, float]] = {}
        for value in grid:
            f1[value] = {}
            for seq, (frames, truth) in seqs.items():
                params = e2e_params(name, value, frames)
                if truth is None:
                    got = run_mvtrack(frames, "road-users", work / "k", params, fps=10.0)
                    f1[value][seq] = kitti_f1(got["results"])
                else:
                    got = run_mvtrack(frames, "road-users", work / "l", params)
                    f1[value][seq] = truth.score(got["results"], 0.5)["f1"]
            print(f"loo-e2e {name}={value}: " + " ".join(f"{s} {v:.3f}" for s, v in
                                                       f1[value].items()), flush=True)
        out[name] = _folds(f"loo-e2e {name}", grid, f1, list(seqs))
    return out


def read_kitti() -> list[np.ndarray]:
    """The frames of KITTI-17 (10 fps)."""
    from mvtrack.io.video import open_source

    with open_source(str(KITTI / "img1"), fps=10.0, threads=1) as src:
        return [frame for _, frame in src]


# --------------------------------------------------------------------------- pictures


def pictures(folder: Path, work: Path) -> dict[str, str]:
    """One frame per clip: the default front end's boxes (orange) and the tracker's rows
    (cyan, with IDs) over the ground truth (thin green)."""
    import cv2

    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for clip in CLIPS:
        seq = VEHICLES / clip
        frames = read_frames(seq / "img1")
        got = run_mvtrack(frames, "road-users", work / "pic" / clip)
        k = PICTURE_FRAME[clip]
        img = frames[k - 1].copy()
        truth = Truth(seq)
        for x, y, w, h in truth.boxes[truth.boxes[:, 0] == k, 2:6]:
            cv2.rectangle(img, (int(x), int(y)), (int(x + w), int(y + h)), (0, 200, 0), 1)
        for x, y, w, h in got["frontend"][k - 1]:
            cv2.rectangle(img, (round(x), round(y)),
                          (round(x + w), round(y + h)), (0, 140, 255), 1)
        rows = np.loadtxt(work / "pic" / clip / "results.txt", delimiter=",", ndmin=2)
        for row in rows[rows[:, 0] == k]:
            x, y, w, h = row[2:6]
            cv2.rectangle(img, (round(x) - 1, round(y) - 1),
                          (round(x + w) + 1, round(y + h) + 1), (255, 255, 0), 1)
            cv2.putText(img, str(int(row[1])), (int(x), int(y) - 2), cv2.FONT_HERSHEY_PLAIN,
                        0.8, (255, 255, 0), 1)
        dest = folder / f"{clip}.png"
        cv2.imwrite(str(dest), img, [cv2.IMWRITE_PNG_COMPRESSION, 9])
        out[clip] = str(dest)
    return out


# --------------------------------------------------------------------------- table


def markdown(table: dict[str, Any], frontends: tuple[str, ...]) -> str:
    """The accuracy table: front end and end to end F1 at 0.5 / 0.3, waiting cars."""
    head = ("| front end | " + " | ".join(CLIPS) + " | waiting cars US101-1 / US101-4 |\n"
            "|---|" + "---|" * (len(CLIPS) + 1) + "\n")
    lines = []
    for name in (*frontends, "stock"):
        for part in ("frontend", "end_to_end"):
            if not all(part in table[c].get(name, {}) for c in CLIPS):
                continue
            label = "stock MOG2 + SORT" if name == "stock" else f"`{name}`"
            if name == frontends[0]:
                label += " (default)"
            cells = [f"{table[c][name][part]['0.5']['f1']:.3f} / "
                     f"{table[c][name][part]['0.3']['f1']:.3f}" for c in CLIPS]
            wait = " / ".join(f"{table[c][name][part]['0.5']['waiting']:.3f}"
                              for c in ("US101-1", "US101-4"))
            kind = "front end" if part == "frontend" else "end to end"
            lines.append(f"| {label}, {kind} | " + " | ".join(cells) + f" | {wait} |")
    jumps = [table[c][frontends[0]].get("lateral_jumps") for c in CLIPS]
    tail = ""
    if all(jumps):
        tail = ("\nTrack steps across the road (`lateral_jumps`: more than a box height across "
                "the road's direction in one frame, a track handed to another car), "
                f"`{frontends[0]}` end to end: " + ", ".join(
                    f"{c} {j['jumps']} of {j['steps']} ({100 * j['share']:.1f} %)"
                    for c, j in zip(CLIPS, jumps, strict=True)) + ".\n")
    return head + "\n".join(lines) + "\n" + tail


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=Path("bench-vehicles"))
    ap.add_argument("--frontends", nargs="+", default=list(FRONTENDS))
    ap.add_argument("--peers-python", default=None)
    ap.add_argument("--speed-rounds", type=int, default=3)
    ap.add_argument("--no-speed", action="store_true")
    ap.add_argument("--no-accuracy", action="store_true")
    ap.add_argument("--pictures", type=Path, default=None)
    ap.add_argument("--loo", action="store_true")
    ap.add_argument("--loo-e2e", action="store_true")
    ap.add_argument("--grid", nargs="+", choices=sorted(LOO_E2E_GRID), default=None,
                    help="with --loo-e2e: only these constants")
    ap.add_argument("--people", action="store_true",
                    help="KITTI-17 end to end with the default front end (MOTA, IDF1)")
    ap.add_argument("--sort-side", nargs=2, metavar=("DETS", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.sort_side:
        sort_side(*args.sort_side)
        return
    args.frontends = tuple(args.frontends)
    args.out.mkdir(parents=True, exist_ok=True)
    report: dict[str, Any] = {"command": " ".join(sys.argv)}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if not args.no_accuracy:
            report["accuracy"] = accuracy(args, work)
            text = markdown(report["accuracy"], args.frontends)
            (args.out / "vehicles.md").write_text(text)
            print(text)
        if not args.no_speed:
            report["speed"] = speed(args, work)
        if args.pictures is not None:
            report["pictures"] = pictures(args.pictures, work)
        if args.loo:
            report["loo"] = leave_one_out(args, work)
        if args.loo_e2e:
            report["loo_e2e"] = leave_one_out_e2e(args, work)
        if args.people and KITTI.exists():
            report["kitti"] = kitti_end_to_end(read_kitti(), work / "kitti")
            print("KITTI-17 end to end: " + ", ".join(
                f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                for k, v in report["kitti"].items()), flush=True)
    (args.out / "vehicles.json").write_text(json.dumps(report, indent=1, default=float))


if __name__ == "__main__":
    main()
