"""Small synthetic media the tests share."""

from __future__ import annotations

from pathlib import Path

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


def default_signals() -> None:
    """``preexec_fn`` of a child that a test signals: SIGINT and SIGTERM at their defaults in
    the child, whatever the test process has set meanwhile (an ignored signal stays ignored
    across ``exec``, and Python then never turns SIGINT into ``KeyboardInterrupt``)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
