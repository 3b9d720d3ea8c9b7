"""The self-contained HTML report of a run: ``report.html`` beside ``results.txt``.

One file, no external resource: the figures are PNGs inlined as ``data:`` URIs, the style
is inline. Sections: the run's metrics (``summary.json``), the movement matrix as a heat
map, counts per interval, a speed histogram, the trajectory picture (``trajectories.png``,
or drawn from the tracks), a frame of the video with the lines and zones drawn on it, and a
link to the annotated video ``tracks.mp4``.

The video is *linked*, not embedded: ``mvtrack track`` writes MPEG-4 Part 2 (OpenCV's
``mp4v``), which browsers do not decode, and inlining a video as base64 would make the page
many megabytes; the inlined frame shows the scene's setup instead.
"""

from __future__ import annotations

import base64
import html
import io
import os
from pathlib import Path
from typing import Any

import numpy as np

from mvtrack.analytics.run import AnalyticsResult
from mvtrack.io.atomic import atomic_path


def _png(fig: Any) -> str:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _img_png(img: np.ndarray) -> str:
    import cv2

    ok, data = cv2.imencode(".png", img)
    if not ok:  # pragma: no cover - OpenCV always encodes PNG
        raise OSError("cannot encode PNG")
    return base64.b64encode(data.tobytes()).decode("ascii")


def od_figure(result: AnalyticsResult) -> Any:
    """Heat map of the origin × destination counts (all intervals)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names, m = result.od_matrix()
    fig, ax = plt.subplots(figsize=(4.6, 3.8))
    im = ax.imshow(m, cmap="viridis", vmin=0)
    ax.set_xticks(range(len(names)), names)
    ax.set_yticks(range(len(names)), names)
    ax.set_xlabel("destination")
    ax.set_ylabel("origin")
    for i in range(m.shape[0]):
        for j in range(m.shape[1]):
            ax.text(j, i, str(m[i, j]), ha="center", va="center",
                    color="white" if m[i, j] < m.max() / 2 else "black")
    fig.colorbar(im, ax=ax, label=_objects(result))
    ax.set_title("turning movements (complete + completed)")
    return fig


def _objects(result: AnalyticsResult) -> str:
    """What the counted tracks are, for a label: ``tracks``, or ``tracks of class 2`` when
    every counted track has that class (people, vehicles or anything else alike)."""
    t = result.tracks
    counted = t["counted"].astype(bool) if t["counted"].size else np.zeros(0, bool)
    classes = {str(c) for c in t["class"][counted]}
    return f"tracks of class {classes.pop()}" if len(classes) == 1 and "" not in classes \
        else "tracks"


def counts_figure(result: AnalyticsResult) -> Any:
    """Counts per interval of every line and direction (grouped bars)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = result.counts
    sel = c["element"] == "line" if c["element"].size else np.zeros(0, bool)
    keys = sorted({(n, d) for n, d in zip(c["name"][sel], c["direction"][sel], strict=True)})
    n_int = result.n_intervals
    fig, ax = plt.subplots(figsize=(6.4, 3.4))
    width = 0.8 / max(len(keys), 1)
    for k, (name, direction) in enumerate(keys):
        s = sel & (c["name"] == name) & (c["direction"] == direction)
        per = np.bincount(c["interval"][s].astype(int), c["count"][s].astype(float), n_int)
        ax.bar(np.arange(n_int) + k * width - 0.4 + width / 2, per, width,
               label=f"{name} {direction}")
    starts = [i * result.interval for i in range(n_int)]
    ax.set_xticks(range(n_int), [f"{int(t // 60)}:{int(t % 60):02d}" for t in starts])
    ax.set_xlabel(f"interval start (min:s; {result.interval:g} s each)")
    ax.set_ylabel("crossings")
    if keys:
        ax.legend(fontsize=8)
    ax.set_title("counts per interval")
    return fig


def speed_figure(result: AnalyticsResult) -> Any:
    """Histogram of the per-track mean speeds and of the moving rows' speeds."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 3.4))
    rs = result.row_speeds
    if rs is not None:
        v = rs.speed[~rs.stopped & np.isfinite(rs.speed)]
        per = result.tracks.get("mean_kmh", np.zeros(0))
        per = per[np.isfinite(per)]
        hi = float(max(np.max(v, initial=10.0), 10.0))
        bins = np.linspace(0, hi * 1.05, 30)
        ax.hist(v, bins, density=True, alpha=0.5, label=f"rows ({v.size})")
        ax.hist(per, bins, density=True, histtype="step", lw=2,
                label=f"track means ({per.size})")
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no calibration: no speeds", ha="center", transform=ax.transAxes)
    ax.set_xlabel("speed (km/h)")
    ax.set_ylabel("density")
    ax.set_title("speeds (moving rows)")
    return fig


def trajectory_image(folder: Path, result: AnalyticsResult, frame: np.ndarray | None) -> str:
    """``trajectories.png`` of the folder (base64), or the tracks drawn on ``frame``."""
    path = folder / "trajectories.png"
    if path.exists():
        return base64.b64encode(path.read_bytes()).decode("ascii")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    if frame is not None:
        ax.imshow(frame[..., ::-1])
    rs = result.row_speeds
    pts = result.extra.get("points")
    if pts is not None:
        for a, b in zip(pts.starts[:-1], pts.starts[1:], strict=True):  # drawing only
            ax.plot(pts.xy[a:b, 0], pts.xy[a:b, 1], lw=1)
    if frame is None and pts is not None:
        ax.invert_yaxis()
    ax.set_title("trajectories")
    del rs
    return _png(fig)


def first_frame(folder: Path) -> np.ndarray | None:
    """A frame of the run's video (``tracks.mp4``), or None."""
    import cv2

    video = folder / "tracks.mp4"
    if not video.exists():
        return None
    cap = cv2.VideoCapture(str(video))
    try:
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        if n > 2:
            cap.set(cv2.CAP_PROP_POS_FRAMES, n // 2)
        ok, img = cap.read()
    finally:
        cap.release()
    return img if ok else None


def _metrics_table(summary: dict[str, Any]) -> str:
    keys = ("source", "frames", "video_fps", "size", "tracks", "detections", "fps", "seconds")
    rows = [(k, summary[k]) for k in keys if k in summary]
    for k, v in summary.get("metrics", {}).items() if isinstance(summary.get("metrics"),
                                                                 dict) else ():
        rows.append((k, v))
    if not rows:
        return "<p>No <code>summary.json</code> in this folder.</p>"
    body = "".join(f"<tr><th>{html.escape(str(k))}</th><td>{html.escape(str(v))}</td></tr>"
                   for k, v in rows)
    return f"<table>{body}</table>"


def _table(table: dict[str, np.ndarray], columns: list[str], limit: int = 40) -> str:
    n = len(next(iter(table.values()))) if table else 0
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = []
    for i in range(min(n, limit)):  # a page of rows for the reader
        cells = []
        for c in columns:
            v = table[c][i]
            if isinstance(v, (float, np.floating)):
                v = "" if not np.isfinite(v) else f"{float(v):.1f}"
            cells.append(f"<td>{html.escape(str(v))}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    more = f"<p>… {n - limit} more rows in the CSV file.</p>" if n > limit else ""
    return f"<table><tr>{head}</tr>{''.join(body)}</table>{more}"


_CSS = """body{font-family:sans-serif;margin:2em;max-width:72em;color:#222}
h1{font-size:1.5em}h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;font-size:.85em}td,th{border:1px solid #ddd;padding:2px 8px;
text-align:left}img{max-width:100%;border:1px solid #eee}.grid{display:flex;flex-wrap:wrap;
gap:1em}.grid figure{margin:0}figcaption{font-size:.8em;color:#555}"""

_SCRIPT = """window.addEventListener('load', function () {
  var bad = Array.prototype.filter.call(document.images, function (im) {
    return !(im.complete && im.naturalWidth > 0);
  });
  bad.forEach(function (im) { console.error('image did not load: ' + im.alt); });
  document.body.setAttribute('data-images', String(document.images.length));
  document.body.setAttribute('data-ready', bad.length ? 'broken' : 'ok');
});"""


def render_report(result: AnalyticsResult, folder: str | os.PathLike[str],
                  title: str | None = None) -> str:
    """The HTML text of the report (module docstring)."""
    from mvtrack.viz.scene import draw_scene

    folder = Path(folder)
    summary = result.extra.get("summary", {})
    frame = first_frame(folder)
    figs: list[tuple[str, str, str]] = []
    if result.settings.approaches:
        figs.append(("movements", _png(od_figure(result)), "origin × destination"))
    if result.settings.lines:
        figs.append(("counts", _png(counts_figure(result)), "crossings per interval"))
    figs.append(("speeds", _png(speed_figure(result)), "speed histogram"))
    figs.append(("trajectories", trajectory_image(folder, result, frame), "trajectories"))
    if frame is not None:
        scene = draw_scene(frame.copy(), result.settings)
        figs.append(("scene", _img_png(scene), "a frame of the video with lines and zones"))
    video = folder / "tracks.mp4"
    name = title or summary.get("source") or folder.name
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             f"<title>mvtrack report: {html.escape(str(name))}</title>"
             f"<style>{_CSS}</style><script>{_SCRIPT}</script></head><body>",
             f"<h1>mvtrack report: {html.escape(str(name))}</h1>",
             "<h2>Run</h2>", _metrics_table(summary),
             f"<p>{result.n_frames} frames at {result.fps:g} fps, "
             f"{len(result.tracks['track_id'])} tracks "
             f"({int(np.sum(result.tracks['counted']))} counted), intervals of "
             f"{result.interval:g} s.</p>",
             "<h2>Figures</h2><div class='grid'>"]
    for key, data, caption in figs:
        parts.append(f"<figure id='fig-{key}'><img alt='{key}' src='data:image/png;base64,"
                     f"{data}'><figcaption>{html.escape(caption)}</figcaption></figure>")
    parts.append("</div>")
    if video.exists():
        parts.append("<h2>Video</h2><p><a href='tracks.mp4'>tracks.mp4</a> (the annotated "
                     "video, beside this file; MPEG-4 Part 2, for a desktop player).</p>")
    if result.settings.lines or result.settings.zones:
        cols = ["interval_start_s", "element", "name", "direction", "class", "count",
                "mean_speed_kmh", "mean_occupancy", "mean_dwell_s"]
        parts += ["<h2>Counts</h2>", _table(result.counts, cols)]
    if result.settings.approaches:
        m = result.movements
        keep = m["count"] > 0 if m["count"].size else np.zeros(0, bool)
        parts += ["<h2>Movements</h2>",
                  _table({k: v[keep] for k, v in m.items()},
                         ["interval_start_s", "origin", "destination", "movement", "count",
                          "completed"])]
    if result.speeds["interval"].size:
        parts += ["<h2>Speeds per interval</h2>",
                  _table(result.speeds, ["interval_start_s", "class", "tracks", "mean_kmh",
                                         "median_kmh", "p85_kmh", "max_kmh",
                                         "stopped_share"])]
    parts.append("</body></html>\n")
    return "".join(parts)


def write_report(result: AnalyticsResult, folder: str | os.PathLike[str],
                 dest: str | os.PathLike[str] | None = None) -> Path:
    """Write ``report.html`` into ``folder`` (or to ``dest``) atomically; returns its path."""
    out = Path(dest) if dest is not None else Path(folder) / "report.html"
    text = render_report(result, folder)
    with atomic_path(out) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return out
