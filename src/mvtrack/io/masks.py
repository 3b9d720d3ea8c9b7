"""Foreground masks out, one PNG a frame, so that any front end can be scored pixel-wise.

``mvtrack track --masks DIR`` writes the front end's foreground of frame ``k`` (0-based) as
``DIR/{k + 1:06d}.png``: one channel, 0 (background) or 255 (foreground), the size of the
input frame — the numbering of a MOTChallenge ``img1`` folder, so the masks sit beside the
frames they belong to, as the CDnet change-detection benchmark lays out its results. Each file
is written atomically (:func:`mvtrack.io.atomic.atomic_path`): a reader, or a run cut short,
never leaves a half-written one. A frame for which the front end has no mask yet (the first
frame of a model that starts from it) is written all background.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.io.atomic import atomic_path

Image = NDArray[np.uint8]


def mask_path(folder: str | os.PathLike[str], frame: int) -> Path:
    """Where the mask of ``frame`` (0-based) goes: ``folder/{frame + 1:06d}.png``."""
    return Path(folder) / f"{frame + 1:06d}.png"


class MaskWriter:
    """Writes each frame's foreground as a 0/255 PNG (module docstring).

    Parameters
    ----------
    folder : path
        Created if needed.

    Raises
    ------
    OSError
        The folder cannot be created, or is a file.
    """

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.written = 0

    def write(self, frame: int, mask: Image | None, size: tuple[int, int]) -> Path:
        """Write the mask of ``frame`` (non-zero = foreground; ``None``: all background) for
        a frame of ``size`` (W, H); returns its path."""
        w, h = size
        if mask is None:
            out = np.zeros((h, w), np.uint8)
        else:
            if mask.shape[:2] != (h, w):
                raise ValueError(f"mask of frame {frame} is {mask.shape[1]}×{mask.shape[0]}, "
                                 f"the frame {w}×{h}")
            out = cv2.compare(mask, 0, cv2.CMP_GT)  # 0/255 whatever the front end's values
        dest = mask_path(self.folder, frame)
        ok, data = cv2.imencode(".png", out, [cv2.IMWRITE_PNG_COMPRESSION, 1])
        if not ok:
            raise OSError(f"cannot encode the mask of frame {frame} as PNG")
        with atomic_path(dest) as tmp:
            tmp.write_bytes(data.tobytes())
        self.written += 1
        return dest


def read_mask(path: str | os.PathLike[str]) -> Image:
    """A mask written by :class:`MaskWriter`, as a boolean-valued 0/255 ``uint8`` image.

    Raises
    ------
    OSError
        The file is missing or not an image.
    """
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise OSError(f"cannot read mask {path}")
    return img
