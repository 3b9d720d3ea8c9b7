"""What the video front ends share behind the frame loop's interface
(:func:`mvtrack.video.run_frames`): the read-ahead of their ``prepare(frames)`` that starts a
background from the first frames, and their ``mask`` at the input frame's size.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

import cv2
import numpy as np
from numpy.typing import NDArray

Image = NDArray[np.uint8]

#: how a front end starts its background: from the frames read ahead (:func:`read_ahead`), or
#: from the first frame
BOOTSTRAPS = ("start", "none")


def check_bootstrap(bootstrap: str) -> None:
    """Raise ``ValueError`` unless ``bootstrap`` is one of :data:`BOOTSTRAPS`."""
    if bootstrap not in BOOTSTRAPS:
        raise ValueError(f"bootstrap must be one of {', '.join(BOOTSTRAPS)}, got {bootstrap!r}")


def read_ahead(frames: Iterable[Image], count: int,
               start: Callable[[list[Image]], None]) -> Iterator[Image]:
    """``frames`` again, ``start`` called on the first ``count`` of them before any is given.

    Lazy: nothing is read before the first frame is asked for. ``start`` gets the frames read
    ahead (fewer than ``count`` if the source ends or fails first; not called if none was
    read, nor when ``count`` is 0). A source that fails during the read-ahead with a
    ``ValueError`` or ``OSError`` gives the frames read before it, then its error (at once if
    none was read). The source is closed when the iteration ends, however it ends.

    Parameters
    ----------
    frames : iterable of uint8 images
        The source.
    count : int
        Frames to read ahead (0: none).
    start : callable
        Called once with the list of the frames read ahead.

    Yields
    ------
    uint8 image
        Every frame of ``frames``, in order.
    """
    it = iter(frames)
    try:
        head: list[Image] = []
        error: BaseException | None = None
        try:
            for _ in range(count):
                head.append(next(it))
        except StopIteration:
            pass
        except (ValueError, OSError) as exc:
            if not head:
                raise
            error = exc
        if head:
            start(head)
        yield from head
        del head
        if error is not None:
            raise error
        yield from it
    finally:
        close = getattr(it, "close", None)
        if close is not None:
            close()


def input_size_mask(mask: Image | None, shape: tuple[int, int] | None) -> Image | None:
    """``mask`` (0/255) at the input frame's size ``shape`` (rows, columns), resized by
    nearest neighbour where it is not already; None when either is unknown."""
    if mask is None or shape is None:
        return None
    h, w = shape
    if mask.shape == (h, w):
        return mask
    return cv2.resize(mask, (w, h), interpolation=cv2.INTER_NEAREST)
