"""Shared fixtures: the ../shared folder beside the checkout (papers, spec, real video), and a
source without a known length."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


def _require_shared(*parts: str) -> Path:
    path = SHARED.joinpath(*parts)
    if not path.exists():
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"{path} is missing, and CI=true requires ../shared")
        pytest.skip(f"{path} not present (a fresh clone has no ../shared)")
    return path


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """The ../shared folder; skips when absent, fails under CI=true."""
    return _require_shared()


@pytest.fixture(scope="session")
def vtest_path() -> Path:
    """../shared/data/vtest.avi, the real 768×576 campus recording."""
    return _require_shared("data", "vtest.avi")


@pytest.fixture
def unknown_length(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every source opened through :func:`mvtrack.io.video.open_source` reports no length,
    as a camera or a network stream does."""
    import mvtrack.io.video as io_video

    opened = io_video.open_source

    def without_length(*args, **kwargs):  # type: ignore[no-untyped-def]
        src = opened(*args, **kwargs)
        src.frame_count = None
        return src

    monkeypatch.setattr(io_video, "open_source", without_length)
