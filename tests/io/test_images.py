"""read_image: the pixels of cv2.imread(IMREAD_COLOR) for every kind of file."""

from __future__ import annotations

import io
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

from mvtrack.io import images
from mvtrack.io.images import has_exif, read_image


def _scene(h: int = 48, w: int = 64) -> np.ndarray:
    rng = np.random.default_rng(3)
    img = cv2.GaussianBlur(rng.integers(0, 256, (h, w, 3), dtype=np.uint8), (5, 5), 1.5)
    cv2.rectangle(img, (10, 8), (40, 30), (20, 200, 90), -1)
    return img


@pytest.mark.parametrize("quality", [50, 95])
def test_colour_jpeg_equals_imread(tmp_path: Path, quality: int) -> None:
    path = tmp_path / "a.jpg"
    cv2.imwrite(str(path), _scene(), [cv2.IMWRITE_JPEG_QUALITY, quality])
    out = read_image(path)
    assert out is not None and out.dtype == np.uint8 and out.shape == (48, 64, 3)
    assert np.array_equal(out, cv2.imread(str(path), cv2.IMREAD_COLOR))


def test_grey_and_progressive_jpeg_equal_imread(tmp_path: Path) -> None:
    grey = tmp_path / "g.JPEG"
    cv2.imwrite(str(grey), cv2.cvtColor(_scene(), cv2.COLOR_BGR2GRAY))
    prog = tmp_path / "p.jpg"
    cv2.imwrite(str(prog), _scene(), [cv2.IMWRITE_JPEG_PROGRESSIVE, 1])
    for path in (grey, prog):
        out = read_image(path)
        assert out is not None and out.shape == (48, 64, 3)
        assert np.array_equal(out, cv2.imread(str(path), cv2.IMREAD_COLOR))


def test_exif_orientation_is_applied_as_opencv_does(tmp_path: Path) -> None:
    path = tmp_path / "turned.jpg"
    exif = Image.Exif()
    exif[0x0112] = 6  # rotate 90° clockwise to display
    Image.fromarray(_scene()[:, :, ::-1]).save(path, exif=exif)
    out = read_image(path)
    ref = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert out is not None and out.shape == ref.shape == (64, 48, 3)  # turned
    assert np.array_equal(out, ref)


def test_cmyk_jpeg_goes_to_opencv(tmp_path: Path) -> None:
    path = tmp_path / "cmyk.jpg"
    Image.fromarray(_scene()[:, :, ::-1]).convert("CMYK").save(path)
    out = read_image(path)
    ref = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert ref is not None and out is not None and np.array_equal(out, ref)


def test_png_and_unreadable_files(tmp_path: Path) -> None:
    png = tmp_path / "a.png"
    cv2.imwrite(str(png), _scene())
    assert np.array_equal(read_image(png), _scene())
    bad = tmp_path / "bad.jpg"
    bad.write_bytes(b"\xff\xd8\xff\xe0 not a jpeg at all")
    assert read_image(bad) is None
    assert read_image(tmp_path / "missing.jpg") is None


def test_without_simplejpeg_opencv_reads(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "a.jpg"
    cv2.imwrite(str(path), _scene())
    monkeypatch.setattr(images, "simplejpeg", None)
    assert np.array_equal(read_image(path), cv2.imread(str(path), cv2.IMREAD_COLOR))


def test_has_exif_walks_the_segments() -> None:
    buf = io.BytesIO()
    Image.fromarray(_scene()).save(buf, "JPEG")
    plain = buf.getvalue()
    assert not has_exif(plain)
    exif = Image.Exif()
    exif[0x0112] = 1
    buf = io.BytesIO()
    Image.fromarray(_scene()).save(buf, "JPEG", exif=exif)
    assert has_exif(buf.getvalue())
    assert has_exif(b"\x89PNG\r\n")  # not a JPEG: not ours to decode
    assert has_exif(plain[:4])  # cut short before the image data
