"""One image file in, one BGR ``uint8`` frame out: :func:`read_image`.

JPEG files (the frames of most image-sequence datasets) are decoded with ``simplejpeg``
(libjpeg-turbo): the same pixels as ``cv2.imread`` with its accurate DCT and fancy upsampling,
at about 0.8 of its CPU time on 640×480 frames (``docs/bench/vehicles.md``, table 2). Every
other file, a JPEG that carries an Exif block (``cv2.imread`` turns the picture by its
orientation tag) and a JPEG ``simplejpeg`` refuses (CMYK, damaged) go to ``cv2.imread``.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

try:  # a wheel on every common platform; without it every file goes to OpenCV
    import simplejpeg
except ImportError:  # pragma: no cover - the dependency is declared
    simplejpeg = None

Frame = NDArray[np.uint8]

_JPEG = (".jpg", ".jpeg")


def has_exif(data: bytes) -> bool:
    """Whether the JPEG ``data`` holds an APP1 ``Exif`` segment before its image data.

    Walks the marker segments from SOI to SOS; anything that is not a well-formed segment
    list counts as Exif (the caller then leaves the file to OpenCV)."""
    if data[:2] != b"\xff\xd8":
        return True
    i, n = 2, len(data)
    while i + 4 <= n:
        if data[i] != 0xFF:
            return True
        marker = data[i + 1]
        if marker == 0xFF:  # fill byte
            i += 1
            continue
        if marker == 0xDA:  # start of scan: no Exif before the image data
            return False
        size = int.from_bytes(data[i + 2:i + 4], "big")
        if marker == 0xE1 and data[i + 4:i + 10] == b"Exif\x00\x00":
            return True
        i += 2 + size
    return True


def read_image(path: str | Path) -> Frame | None:
    """The image at ``path`` as a BGR ``uint8`` array (``cv2.IMREAD_COLOR``'s result), or
    None if it cannot be read (as ``cv2.imread``)."""
    path = Path(path)
    if simplejpeg is not None and path.suffix.lower() in _JPEG:
        try:
            data = path.read_bytes()
        except OSError:
            return None
        if not has_exif(data):
            try:
                return simplejpeg.decode_jpeg(data, colorspace="BGR")
            except ValueError:
                pass  # CMYK, damaged, ...: OpenCV says what it can
    return cv2.imread(str(path), cv2.IMREAD_COLOR)
