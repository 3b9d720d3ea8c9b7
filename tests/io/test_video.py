"""Frames in: files, folders, truncated files, errors."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from mvtrack.errors import InputError
from mvtrack.io.video import DEFAULT_FPS, open_source


def _frames(n: int, w: int = 64, h: int = 48, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, (h, w, 3), dtype=np.uint8) for _ in range(n)]


def _write_avi(path: Path, frames: list[np.ndarray], fps: float = 10.0) -> None:
    h, w = frames[0].shape[:2]
    fourcc = cv2.VideoWriter_fourcc(*"MJPG")
    writer = cv2.VideoWriter(str(path), cv2.CAP_FFMPEG, fourcc, fps, (w, h))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()


def test_video_file_reports_fps_size_count_and_yields_bgr_frames_in_order(tmp_path: Path) -> None:
    frames = [np.full((48, 64, 3), 8 * i, np.uint8) for i in range(12)]
    path = tmp_path / "ramp.avi"
    _write_avi(path, frames, fps=12.5)
    with open_source(path) as src:
        assert src.size == (64, 48)
        assert src.fps == pytest.approx(12.5)
        assert src.fps_reported
        assert src.frame_count == 12
        got = list(src)
    assert [k for k, _ in got] == list(range(12))
    assert all(f.shape == (48, 64, 3) and f.dtype == np.uint8 for _, f in got)
    # MJPEG is lossy, but the mean grey level of each flat frame survives to within a few levels
    means = np.array([f.mean() for _, f in got])
    np.testing.assert_allclose(means, 8 * np.arange(12), atol=3)
    assert not src.ended_early and src.error is None


def test_fps_override_replaces_reported_rate(tmp_path: Path) -> None:
    path = tmp_path / "v.avi"
    _write_avi(path, _frames(3), fps=10)
    with open_source(str(path), fps=30) as src:
        assert src.fps == 30 and not src.fps_reported


def test_image_folder_reads_sorted_files_in_order(tmp_path: Path) -> None:
    # written out of order, with a non-image file that must be ignored
    for i in (3, 0, 2, 1, 10):
        cv2.imwrite(str(tmp_path / f"img_{i:03d}.png"), np.full((20, 30, 3), i * 20, np.uint8))
    (tmp_path / "notes.txt").write_text("not an image")
    with open_source(tmp_path) as src:
        assert src.kind == "folder"
        assert src.size == (30, 20)
        assert src.frame_count == 5
        assert src.fps == DEFAULT_FPS
        levels = [int(f[0, 0, 0]) for _, f in src]
    assert levels == [0, 20, 40, 60, 200]


def test_grey_images_in_a_folder_come_out_as_three_channel_bgr(tmp_path: Path) -> None:
    cv2.imwrite(str(tmp_path / "a.png"), np.full((8, 8), 77, np.uint8))
    with open_source(tmp_path) as src:
        ((_, frame),) = list(src)
    assert frame.shape == (8, 8, 3) and (frame == 77).all()


def test_missing_path_is_a_one_line_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist") as info:
        open_source(tmp_path / "nope.avi")
    assert "\n" not in str(info.value) and "nope.avi" in str(info.value)


def test_text_file_named_avi_is_a_one_line_input_error(tmp_path: Path) -> None:
    bad = tmp_path / "fake.avi"
    bad.write_text("this is not a video\n" * 50)
    with pytest.raises(InputError, match="cannot read video file") as info:
        open_source(bad)
    assert "\n" not in str(info.value) and "fake.avi" in str(info.value)


def test_empty_folder_is_an_input_error(tmp_path: Path) -> None:
    (tmp_path / "readme.txt").write_text("x")
    with pytest.raises(InputError, match="no image files") as info:
        open_source(tmp_path)
    assert "\n" not in str(info.value)


def test_video_with_zero_frames_is_an_input_error(tmp_path: Path) -> None:
    path = tmp_path / "empty.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10, (64, 48))
    writer.release()
    with pytest.raises(InputError) as info:
        open_source(path)
    assert "\n" not in str(info.value) and "empty.avi" in str(info.value)


def test_truncated_file_ends_early_with_an_error_but_keeps_the_frames_read(tmp_path: Path) -> None:
    full = tmp_path / "full.avi"
    _write_avi(full, _frames(30))
    data = full.read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[: len(data) // 2])
    with open_source(cut) as src:
        assert src.frame_count == 30  # the header still promises 30
        got = list(src)
    assert 0 < len(got) < 30
    assert src.ended_early
    assert src.error is not None and "ended early" in src.error and "\n" not in src.error


def test_corrupt_image_mid_folder_ends_iteration_with_an_error(tmp_path: Path) -> None:
    for i in range(4):
        cv2.imwrite(str(tmp_path / f"f{i}.png"), np.full((10, 10, 3), i, np.uint8))
    (tmp_path / "f2.png").write_bytes(b"garbage")
    with open_source(tmp_path) as src:
        got = list(src)
    assert len(got) == 2
    assert src.ended_early and "f2.png" in (src.error or "")


def test_frame_of_a_different_size_ends_iteration(tmp_path: Path) -> None:
    cv2.imwrite(str(tmp_path / "a.png"), np.zeros((10, 10, 3), np.uint8))
    cv2.imwrite(str(tmp_path / "b.png"), np.zeros((12, 10, 3), np.uint8))
    with open_source(tmp_path) as src:
        got = list(src)
    assert len(got) == 1 and src.ended_early and "10×12" in (src.error or "")


def test_source_can_be_iterated_only_once(tmp_path: Path) -> None:
    cv2.imwrite(str(tmp_path / "a.png"), np.zeros((4, 4, 3), np.uint8))
    src = open_source(tmp_path)
    list(src)
    with pytest.raises(RuntimeError, match="only once"):
        list(src)


def test_bad_fps_is_a_value_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="fps"):
        open_source(tmp_path, fps=0)


def test_vtest_opens_with_its_known_geometry(vtest_path: Path) -> None:
    with open_source(vtest_path) as src:
        assert src.size == (768, 576)
        assert src.fps == pytest.approx(10.0)
        assert src.frame_count == 795
        n = sum(1 for _ in src)
    assert n == 795 and not src.ended_early


class _DroppingCapture:
    """A stand-in for ``cv2.VideoCapture`` on a live stream that dies after ``n`` frames."""

    def __init__(self, n: int) -> None:
        self.left = n
        self.released = False

    def read(self) -> tuple[bool, np.ndarray | None]:
        if self.left == 0:
            return False, None
        self.left -= 1
        return True, np.zeros((6, 8, 3), np.uint8)

    def get(self, prop: int) -> float:
        return 25.0 if prop == cv2.CAP_PROP_FPS else -1.0

    def release(self) -> None:
        self.released = True


def test_stream_that_drops_mid_way_ends_cleanly_and_says_so() -> None:
    from mvtrack.io.video import CaptureSource

    cap = _DroppingCapture(5)
    src = CaptureSource(cap, "rtsp://cam/1", "stream", None)
    assert src.frame_count is None and src.fps == 25.0 and src.size == (8, 6)
    got = [k for k, _ in src]
    assert got == [0, 1, 2, 3, 4]
    assert src.ended_early and "stopped delivering frames" in (src.error or "")
    assert cap.released


def test_unreachable_stream_and_absent_camera_are_input_errors() -> None:
    with pytest.raises(InputError, match="cannot open stream"):
        open_source("rtsp://127.0.0.1:1/none")
    with pytest.raises(InputError, match="cannot open camera 97"):
        open_source("97")


def test_one_decoder_thread_gives_the_same_frames(tmp_path: Path) -> None:
    frames = [np.full((48, 64, 3), 8 * i, np.uint8) for i in range(6)]
    path = tmp_path / "ramp.avi"
    _write_avi(path, frames)
    with open_source(path) as a, open_source(path, threads=1) as b:
        for (_, fa), (_, fb) in zip(a, b, strict=True):
            np.testing.assert_array_equal(fa, fb)
    with pytest.raises(ValueError, match="threads"):
        open_source(path, threads=0)
