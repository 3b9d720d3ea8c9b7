"""Fixtures of the command-line tests."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def _no_compile_notice(monkeypatch: pytest.MonkeyPatch) -> None:
    """The in-process runs here check what a command prints; the one-line notice that kernels
    are being compiled appears in whichever run of a test process compiles first, so it would
    make their output depend on the order of the tests. It has its own tests
    (``tests/test_jit.py``, and a run with an empty compile cache in ``test_bad_input.py``)."""
    monkeypatch.setattr("mvtrack.cli._compiling", lambda: None)
