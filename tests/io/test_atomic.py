"""Atomic writes: the destination appears whole or not at all."""

from __future__ import annotations

import os
import stat

import pytest

from mvtrack.io.atomic import atomic_path, write_json, write_text


def test_failed_write_leaves_no_file_and_no_temporary(tmp_path) -> None:
    dest = tmp_path / "out.txt"
    with pytest.raises(RuntimeError), atomic_path(dest) as tmp:
        tmp.write_text("half")
        raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_failed_write_keeps_the_old_file(tmp_path) -> None:
    dest = write_text(tmp_path / "out.txt", "old")
    with pytest.raises(KeyboardInterrupt), atomic_path(dest) as tmp:
        tmp.write_text("new, half")
        raise KeyboardInterrupt
    assert dest.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_written_file_has_the_umask_mode(tmp_path) -> None:
    old = os.umask(0o022)
    try:
        dest = write_json(tmp_path / "a" / "b.json", {"x": 1})
    finally:
        os.umask(old)
    assert stat.S_IMODE(dest.stat().st_mode) == 0o644
    assert dest.read_text().strip() == '{\n  "x": 1\n}'
