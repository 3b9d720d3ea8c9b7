"""The experiments' figures, checked by what they show: bar heights and error bars equal the
reported figures, legends name every series in its colour, labels do not overlap, colours
read on the scene, truth is drawn beside the estimates."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.text import Text

from mvtrack.experiments import complexity as x2
from mvtrack.experiments import timing as x3
from mvtrack.experiments.stats import binomial_ci
from mvtrack.sim.nine_vehicles import x4_nine_vehicles
from mvtrack.types import TrackFrame
from mvtrack.viz.colors import PALETTE, contrast_ratio
from mvtrack.viz.labels import crowd_labels, place_labels
from mvtrack.viz.plots import TrackRows, grouped_bars, trajectory_figure


def rendered(fig: Figure) -> np.ndarray:
    """The figure as an (H, W, 3) float RGB image in [0, 1]."""
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3] / 255.0


def pixels_near(img: np.ndarray, color: object, box=None, tol: float = 0.08) -> int:
    """Pixels of ``img`` (inside the display box ``box``, if given) within ``tol`` of ``color``."""
    if box is not None:
        h = img.shape[0]
        x0, x1 = int(max(box.x0, 0)), int(min(box.x1, img.shape[1]))
        y0, y1 = int(max(h - box.y1, 0)), int(min(h - box.y0, h))
        img = img[y0:y1, x0:x1]
    return int((np.abs(img - np.asarray(to_rgb(color))).max(axis=-1) < tol).sum())


def legend_entries(ax) -> dict[str, object]:
    """Legend label -> the colour of its handle."""
    leg = ax.get_legend()
    assert leg is not None, "the axes have no legend"
    out = {}
    for handle, text in zip(leg.legend_handles, leg.get_texts(), strict=True):
        color = handle.get_facecolor() if hasattr(handle, "get_facecolor") else None
        if hasattr(handle, "get_color") and not hasattr(handle, "get_hatch"):
            color = handle.get_color()
        out[text.get_text()] = color
    return out


def bar_heights(ax) -> dict[str, list[float]]:
    """Heights of the bars of each labelled bar container."""
    return {c.get_label(): [p.get_height() for p in c.patches] for c in ax.containers
            if hasattr(c, "patches") and not c.get_label().startswith("_")}


def error_bars(ax) -> list[tuple[float, float, float]]:
    """(x, low, high) of every vertical error bar segment drawn on the axes."""
    out = []
    for coll in ax.collections:
        for seg in getattr(coll, "get_segments", lambda: [])():
            seg = np.asarray(seg)
            if seg.shape == (2, 2) and seg[0, 0] == seg[1, 0]:
                out.append((float(seg[0, 0]), float(min(seg[:, 1])), float(max(seg[:, 1]))))
    return out


# ------------------------------------------------------------------------------- helpers


def test_grouped_bars_draw_heights_intervals_and_a_legend_in_their_colours() -> None:
    fig = Figure(figsize=(5, 3))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    k, n = [3, 9], [10, 10]
    rates = [a / b for a, b in zip(k, n, strict=True)]
    ci = [binomial_ci(a, b) for a, b in zip(k, n, strict=True)]
    grouped_bars(ax, ["A", "B"], {"ours": rates, "paper": [0.5, np.nan]},
                 errors={"ours": ci}, colors={"ours": PALETTE[0], "paper": PALETTE[1]})
    ax.legend()
    assert bar_heights(ax) == {"ours": pytest.approx(rates), "paper": [0.5, 0.0]}
    bars = error_bars(ax)
    assert len(bars) == 2
    for (_, lo, hi), (elo, ehi) in zip(sorted(bars), ci, strict=True):
        assert lo == pytest.approx(elo) and hi == pytest.approx(ehi)
    texts = [t.get_text() for t in ax.texts]
    assert "n/a" in texts and "0.3" in texts  # the missing paper value is written, not drawn
    img = rendered(fig)
    leg = ax.get_legend().get_window_extent()
    assert pixels_near(img, PALETTE[0], leg) > 20 and pixels_near(img, PALETTE[1], leg) > 20


def test_place_labels_never_overlap_and_stay_inside_the_axes() -> None:
    fig = Figure(figsize=(4, 3))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set(xlim=(0, 100), ylim=(0, 100))
    anchors = np.array([[50.0, 50.0]] * 6 + [[99.0, 99.0]])  # six labels on one point
    placed = place_labels(ax, anchors, [f"track {i}" for i in range(7)])
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    boxes = [Text.get_window_extent(t, renderer) for t in placed]  # the text, not its leader
    inside = ax.get_window_extent(renderer)
    assert len(placed) >= 6
    for i, a in enumerate(boxes):
        assert inside.x0 <= a.x0 and a.x1 <= inside.x1 and inside.y0 <= a.y0 and a.y1 <= inside.y1
        assert not any(a.overlaps(b) for b in boxes[i + 1 :])


def test_place_labels_on_an_image_axes_do_not_overlap_once_drawn() -> None:
    # imshow fixes the aspect: the axes box shrinks when the figure is drawn, and labels
    # placed in the box before that would move relative to each other
    fig = Figure(figsize=(8, 4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.imshow(np.zeros((240, 320)), extent=(0, 320, 240, 0), cmap="gray")
    rng = np.random.default_rng(0)
    anchors = np.array([150.0, 80.0]) + rng.normal(0, 6, (30, 2))  # a crowded spot
    placed = place_labels(ax, anchors, [str(i) for i in range(30)])
    for dpi in (100, 110):
        fig.set_dpi(dpi)
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        boxes = [Text.get_window_extent(t, renderer) for t in placed]
        assert len(boxes) >= 20
        assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])
    assert all(t.get_zorder() > 5 for t in placed)  # over the paths (zorder 4–5)


def test_crowd_labels_join_four_or_more_ends_at_one_spot_and_keep_the_rest() -> None:
    anchors = np.array([[10.0, 10.0], [11.0, 10.0], [10.0, 12.0], [12.0, 11.0], [10.5, 10.5],
                        [50.0, 50.0], [51.0, 50.0], [80.0, 20.0]])
    texts = [str(i) for i in range(8)]
    colors = ["red"] * 5 + ["blue", "green", "red"]
    xy, out, cols = crowd_labels(anchors, texts, colors, radius=3.0)
    assert out == ["5 tracks: 0, 1, 2, …", "5", "6", "7"]
    np.testing.assert_allclose(xy[0], anchors[:5].mean(axis=0))
    np.testing.assert_array_equal(xy[1:], anchors[5:])
    assert cols == ["red", "blue", "green", "red"]  # the crowd's shared colour
    _, out, cols = crowd_labels(anchors, texts, ["red"] * 4 + ["blue"] * 4, 3.0, mixed="k")
    assert out[0].startswith("5 tracks") and cols[0] == "k"  # colours differ: ``mixed``
    _, out, _ = crowd_labels(anchors[:3], texts[:3], colors[:3], radius=3.0)
    assert out == ["0", "1", "2"]  # three are not a crowd


def test_a_trajectory_figure_labels_a_crowd_of_ends_once() -> None:
    paths = {i: np.column_stack([np.linspace(0, 100, 5), np.full(5, 50.0 + 0.1 * i)])
             for i in range(1, 9)}  # eight tracks that end at one spot
    paths[9] = np.array([[10.0, 10.0], [60.0, 20.0]])
    fig = trajectory_figure(_rows(paths), (200, 100))
    texts = sorted(t.get_text() for t in fig.axes[0].texts)
    assert texts == ["8 tracks: 1, 2, 3, …", "9"]


def _rows(paths: dict[int, np.ndarray]) -> TrackRows:
    frames = []
    n = max(len(p) for p in paths.values())
    for k in range(n):
        ids = [i for i, p in paths.items() if k < len(p)]
        xy = np.array([paths[i][k] for i in ids], float).reshape(-1, 2)
        z = np.zeros(len(ids), np.int64)
        frames.append(TrackFrame(k, np.array(ids, np.int64), z + 1, z, xy, xy, xy,
                                 np.full((len(ids), 2), 8.0), np.zeros((len(ids), 2))))
    return TrackRows.from_frames(frames)


def test_trajectories_read_on_the_x4_road_with_truth_and_a_legend() -> None:
    from mvtrack.sim.backgrounds import render_background

    scene = x4_nine_vehicles()
    _, xy = scene.trajectory(9)  # V9, the fast curving vehicle
    rows = _rows({1: xy[:30], 2: xy[30:]})
    fig = trajectory_figure(rows, scene.size, render_background(scene), groups={1: "V9", 2: "V9"},
                            truth={"V9": xy}, legend_title="vehicle")
    img = rendered(fig)
    ax = fig.axes[0]
    legend = legend_entries(ax)
    assert set(legend) == {"truth (dashed)", "V9"}
    color = legend["V9"]
    # the road as drawn, and the track colour on it: a WCAG contrast of at least 3:1
    road = img[img.shape[0] // 2, img.shape[1] // 3]
    assert contrast_ratio(color, road) >= 3.0
    # V9's colour is drawn where V9 drove, and its truth (black, dashed) beside it
    trans = ax.transData
    h = img.shape[0]
    on_path = 0
    for p in xy[5:60:5]:
        x, y = trans.transform(p)
        patch = img[int(h - y) - 3 : int(h - y) + 4, int(x) - 3 : int(x) + 4]
        on_path += (np.abs(patch - to_rgb(color)).max(axis=-1) < 0.1).any()
    assert on_path >= 10
    assert pixels_near(img, "black", ax.get_window_extent()) > 100
    labels = [t for t in ax.texts if t.get_text() in ("1", "2")]
    assert len(labels) == 2


def test_every_palette_colour_reads_on_the_light_scene() -> None:
    for c in PALETTE:
        assert contrast_ratio(c, (200 / 255,) * 3) >= 3.0


# ------------------------------------------------------------------------------- X2, X3


def test_table1_bars_are_the_paper_and_our_counts() -> None:
    report = x2.run()
    fig = report.plots["table1"]
    kf_ax, rls_ax = fig.axes[:2]
    kf, rls = report.figures["kf"], report.figures["rls"]
    paper = "paper (divisions not counted)"
    ours = "ours, dense eqs. as printed"
    assert bar_heights(kf_ax)[paper] == [120, 0.0, 93]
    assert bar_heights(kf_ax)[ours] == [kf["mul"], kf["div"], kf["add"]]
    assert bar_heights(rls_ax)[paper] == [37, 0.0, 24]
    assert bar_heights(rls_ax)[ours] == [rls["mul"], rls["div"], rls["add"]]
    assert all(p.get_hatch() == "//" for c in kf_ax.containers if c.get_label() == paper
               for p in c.patches)
    assert set(legend_entries(kf_ax)) == {paper, ours, "ours, the tracker's kernel"}


def test_table2_ratio_bars_are_the_measured_ratios(monkeypatch) -> None:
    monkeypatch.setattr(x3, "ITERATIONS", [100, 200])
    monkeypatch.setattr(x3, "BATCH", 50)
    report = x3.run(runs=1)
    fig = report.plots["table2"]
    ax = fig.axes[0]
    rows = report.figures["rows"]
    h = bar_heights(ax)
    assert h["paper (1999, Pentium Pro)"] == pytest.approx([0.42 / 5.86, 1.78 / 13.1])
    assert h["ours, pure Python"] == pytest.approx([r["python_ratio"] for r in rows])
    assert h["ours, NumPy (one target)"] == pytest.approx([r["numpy_ratio"] for r in rows])
    assert [t.get_text() for t in ax.get_xticklabels()] == ["100", "200"]


# ------------------------------------------------------------------------------- X6, X7


def test_fig1_regions_fit_in_the_axes_and_titles_do_not_overlap() -> None:
    from mvtrack.experiments import coupled_gate as x6

    fig = x6.run().plots["regions"]
    rendered(fig)
    renderer = fig.canvas.get_renderer()
    a, b = fig.axes[:2]
    assert not a.title.get_window_extent(renderer).overlaps(b.title.get_window_extent(renderer))
    for ax in (a, b):
        x0, x1 = sorted(ax.get_xlim())
        y0, y1 = sorted(ax.get_ylim())
        n_closed = 0
        for coll in ax.collections:  # every contour (iso-r² and gate) lies inside the view
            for path in getattr(coll, "get_paths", lambda: [])():
                v = path.vertices
                if len(v) < 3:
                    continue
                assert v[:, 0].min() > x0 and v[:, 0].max() < x1
                assert v[:, 1].min() > y0 and v[:, 1].max() < y1
                n_closed += 1
        assert n_closed >= 4  # two targets × (iso-r² through z, gate)
        labels = list(legend_entries(ax))
        assert any("(wins)" in t for t in labels)
    assert "target 2: r² = 18 (wins)" in legend_entries(b)
    assert "target 1: r² = 32 (wins)" in legend_entries(a)


def test_crossing_bars_show_the_literal_eq10_as_a_failure(monkeypatch) -> None:
    from mvtrack.experiments import crossing as x7
    from mvtrack.experiments import crossing_measure

    monkeypatch.setattr(crossing_measure, "RHO_SWEEP", (1.0,))
    report = x7.run(runs=6, seed=0)
    fig = report.plots["swap_rates"]
    head = fig.axes[0]
    assert head.get_title().startswith("headline")
    h = bar_heights(head)
    names = [t.get_text() for t in head.get_xticklabels()]
    lit = names.index("coupled-literal")
    swap, fail = "track 1 ends on T2 (the paper's measure)", "any failure"
    rows = report.figures["headline"]
    assert h[swap] == pytest.approx([rows[d]["swap"]["rate"] for d in names])
    assert h[fail] == pytest.approx([rows[d]["failure"]["rate"] for d in names])
    assert h[swap][lit] == 0.0 and h[fail][lit] == 1.0  # no swap, because both tracks merge
    # a Wilson interval on every bar, and the 0/6 bar's interval is not empty
    bars = error_bars(head)
    assert len(bars) == 2 * len(names)
    lo, hi = binomial_ci(0, 6)
    assert any(b[1] == pytest.approx(lo) and b[2] == pytest.approx(hi) for b in bars)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend[1].startswith("any failure")
