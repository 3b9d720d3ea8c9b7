"""Shared fixtures: the ../shared folder beside the checkout (papers, spec, real video)."""

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
