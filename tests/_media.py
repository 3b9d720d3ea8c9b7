"""Small synthetic media the tests share."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np


def box_video(path: Path, n: int = 30, speed: int = 2) -> Path:
    """A small MJPG video (96×64, 15 fps): grey, and from frame 5 one bright 10×8 box moving
    right at ``speed`` px per frame."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15, (96, 64))
    assert writer.isOpened()
    for k in range(n):
        img = np.full((64, 96, 3), 80, np.uint8)
        if k >= 5:
            x = 6 + speed * (k - 5)
            img[28:36, x : x + 10] = 230
        writer.write(img)
    writer.release()
    return path


def squares_video(
    n_frames: int = 60, size: tuple[int, int] = (160, 120), noise: float = 2.0, seed: int = 0
) -> tuple[list[np.ndarray], np.ndarray]:
    """Two 10×8 bright boxes moving across a textured grey background, and their centres.

    Box A (bright) moves right at 2 px/frame along y = 40, box B (dark) left at 1.5 px/frame
    along y = 85.
    Both appear at frame 15, after the disturbance map's background has settled on the empty
    road (boxes sliding in over the border give a biased centroid while partly visible).
    Returns the frames and the true centres (n_frames, 2, 2).
    """
    rng = np.random.default_rng(seed)
    w, h = size
    base = np.full((h, w, 3), 90, np.uint8)
    base[::8, :, :] = 100  # faint texture
    frames, centres = [], np.zeros((n_frames, 2, 2))
    for k in range(n_frames):
        img = base.astype(np.float64)
        for j, (x, y, color) in enumerate(
            [(2.0 * k - 10, 40.0, (40, 220, 230)), (w + 5 - 1.5 * k, 85.0, (30, 30, 30))]
        ):
            centres[k, j] = (x, y)
            if k < 15:
                continue
            x0, y0 = round(x - 5), round(y - 4)
            img[y0 : y0 + 8, x0 : x0 + 10] = color
        img += rng.normal(0, noise, img.shape)
        frames.append(np.clip(img, 0, 255).astype(np.uint8))
    return frames, centres


def default_signals() -> None:
    """``preexec_fn`` of a child that a test signals: SIGINT and SIGTERM at their defaults in
    the child, whatever the test process has set meanwhile (an ignored signal stays ignored
    across ``exec``, and Python then never turns SIGINT into ``KeyboardInterrupt``)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def batch_signalled(tmp_path: Path, sig: int, group: bool = False) -> tuple[Any, str, list[Any]]:
    """Start ``mvtrack batch`` on six short videos with two workers and send ``sig`` once one
    video is done: to the client alone (``kill PID``, ``timeout``) or, with ``group``, to its
    whole process group (a terminal's Ctrl-C). Returns (process, stderr, worker processes
    seen before the signal)."""
    import json
    import os
    import signal
    import subprocess
    import sys
    import time

    import psutil  # installed with distributed

    from mvtrack.sim.nine_vehicles import x4_nine_vehicles
    from mvtrack.sim.render import write_video

    folder = tmp_path / "in"
    folder.mkdir()
    full = write_video(x4_nine_vehicles(), folder / "v0.mp4", progress=False)
    for i in range(1, 6):
        (folder / f"v{i}.mp4").write_bytes(full.read_bytes())
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "mvtrack", "batch", str(folder), "--out", str(out),
         "--workers", "2"],
        start_new_session=True, preexec_fn=default_signals,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            time.sleep(0.1)
            try:
                if json.loads((out / "batch.json").read_text())["ok"] >= 1:
                    break
            except (OSError, ValueError):
                pass
        workers = psutil.Process(proc.pid).children(recursive=True)
        if group:
            os.killpg(proc.pid, sig)
        else:
            proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    return proc, err, workers


def stop_at_frame(monkeypatch: Any, n: int, stop: Any) -> None:
    """Make the detector of every video run call ``stop()`` when it is given its ``n``-th
    frame (send the process a signal, or raise ``KeyboardInterrupt`` as Ctrl-C does in the
    frame loop)."""
    import mvtrack.video.run as run

    real = run.build_detector

    class Stopping:
        """The front end, stopping at its ``n``-th frame; its other hooks (``prepare``,
        ``observe``, ``shown``, ``mask`` ...) pass through, so the run is the same until then."""

        def __init__(self, det: Any) -> None:
            self.__dict__["det"] = det
            self.__dict__["calls"] = 0

        def __getattr__(self, name: str) -> Any:
            return getattr(self.__dict__["det"], name)

        def __call__(self, frame: Any) -> Any:
            self.__dict__["calls"] += 1
            if self.__dict__["calls"] == n:
                stop()
            return self.__dict__["det"](frame)

    def build(settings: Any) -> Any:
        return Stopping(real(settings))

    monkeypatch.setattr(run, "build_detector", build)
