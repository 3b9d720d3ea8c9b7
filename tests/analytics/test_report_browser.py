"""The HTML report in a real headless browser (Debian's chromium; skipped without it)."""

from __future__ import annotations

import os
import shutil
import subprocess

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _report(tmp_path):  # type: ignore[no-untyped-def]
    import cv2

    from mvtrack.analytics import analyse, settings_from_dict
    from mvtrack.analytics.accuracy import scene_points
    from mvtrack.analytics.report import write_report
    from mvtrack.sim.queue import queue_scene, queue_settings
    from mvtrack.sim.render import render_frames

    sc = queue_scene(0)
    # a short annotated video beside the results, as mvtrack track writes it
    w = cv2.VideoWriter(str(tmp_path / "tracks.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 30.0,
                        sc.size)
    for k, img in enumerate(render_frames(sc, 0)):
        if k >= 400:
            break
        if k >= 300:
            w.write(img)
    w.release()
    res = analyse(scene_points(sc), settings_from_dict(queue_settings()), sc.fps, sc.n_frames)
    res.extra["summary"] = {"source": "queue scene", "frames": sc.n_frames}
    return write_report(res, tmp_path)


def test_report_is_self_contained(tmp_path):
    text = _report(tmp_path).read_text()
    assert "src='http" not in text and 'src="http' not in text and "<link" not in text
    assert text.count("data:image/png;base64,") == 5
    assert "href='tracks.mp4'" in text


def test_report_loads_in_chromium_and_shows_the_figures(tmp_path):
    from PIL import Image

    if CHROMIUM is None:  # .ci/run installs it; a user's machine may not have it
        if os.environ.get("CI") == "true":
            pytest.fail("chromium is not installed, and CI=true requires it (.ci/run installs it)")
        pytest.skip("chromium is not installed")

    page = _report(tmp_path)
    url = page.resolve().as_uri()
    base = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
            "--enable-logging=stderr", "--v=0"]
    dom = subprocess.run([*base, "--virtual-time-budget=5000", "--dump-dom", url],
                         capture_output=True, text=True, timeout=120)
    assert dom.returncode == 0
    assert 'data-ready="ok"' in dom.stdout and 'data-images="5"' in dom.stdout
    console = [ln for ln in dom.stderr.splitlines() if "CONSOLE" in ln or "Uncaught" in ln]
    assert console == []
    shot = tmp_path / "shot.png"
    subprocess.run([*base, "--window-size=1280,1600", f"--screenshot={shot}", url],
                   capture_output=True, timeout=120, check=True)
    img = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    assert img.shape[:2] == (1600, 1280)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    # the heat map's viridis extremes (dark purple, yellow) and the bars' matplotlib blue
    purple = (r > 50) & (r < 90) & (g < 30) & (b > 70) & (b < 110)
    yellow = (r > 220) & (g > 200) & (b < 60)
    blue = (abs(r - 31) < 12) & (abs(g - 119) < 12) & (abs(b - 180) < 12)
    assert purple.sum() > 2000 and yellow.sum() > 200 and blue.sum() > 2000
